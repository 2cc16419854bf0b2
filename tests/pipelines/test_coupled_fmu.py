"""A coupled run's results.h5 holds the multibody histories that drive its loads, in the layout
of ``fretwork mbs``, and ``fretwork export-fmu`` turns them into an FMU that plays them back."""

from pathlib import Path

import h5py
import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

from mbs.loading import MultibodyLoading
from mbs.results import MODAL_UNITS, write_loading_histories
from pipelines import scene as scenes
from pipelines import stages
from pipelines.cli.main import main
from pipelines.coupling import multibody_loading
from pipelines.fmu.table import read_playback_table
from pipelines.jobs.run import run_scene

SCENE = Path(__file__).resolve().parents[2] / "examples" / "counterweight.toml"
CHEAPEST = {"bodies.counterweight.mesh.contact_size": 20.0, "bodies.web.mesh.contact_size": 20.0,
            "mbs.n_modes": 4, "mbs.solver.revolutions": 2.0, "procedure.cof_cycles": 1,
            "procedure.vibration_run_up": 0,
            "procedure.wear_cycles": 0}
SIGNALS = {"cw1_frame_acceleration": ("frame_acceleration", "mm/s^2"),
           "cw1_angular_velocity": ("angular_velocity", "rad/s"),
           "cw1_angular_acceleration": ("angular_acceleration", "rad/s^2"),
           "cw1_modal_coordinates": ("modal_coordinates", MODAL_UNITS),
           "cw1_modal_velocity": ("modal_velocities", MODAL_UNITS + "/s"),
           "cw1_modal_acceleration": ("modal_accelerations", MODAL_UNITS + "/s^2"),
           "cw1_wing_torsion": ("wing_torsion", "mm")}


@pytest.fixture(scope="module")
def coupled(tmp_path_factory):
    """(output folder, the multibody loading the run used, the run's summary) of the coupled scene at
    its cheapest."""
    cache = stages.StageCache(tmp_path_factory.mktemp("stage-cache"))
    scene = scenes.load(SCENE, CHEAPEST)
    out = tmp_path_factory.mktemp("coupled")
    outcome = run_scene(scene, out, progress=False, plots=False, cache=cache)
    return out, multibody_loading(scene, cache), outcome.summary


def test_the_run_holds_the_driving_histories_in_the_mbs_layout(coupled):
    out, loading, summary = coupled
    with h5py.File(out / "results.h5") as file:
        histories = file["histories"]
        assert sorted(histories) == sorted(["time", *SIGNALS])
        assert histories["time"].attrs["units"] == "s"
        assert np.array_equal(histories["time"][()], loading.time)
        for name, (field, units) in SIGNALS.items():
            assert np.array_equal(histories[name][()], getattr(loading, field)), name
            assert histories[name].attrs["units"] == units, name
        assert list(histories["cw1_frame_acceleration"].attrs["components"]) == [
            "x (tangential)", "y (radial)", "z (crank axis)"]
        assert list(histories["cw1_modal_coordinates"].attrs["components"]) == [
            f"mode {k + 1} ({f:.1f} Hz)" for k, f in enumerate(loading.mode_frequencies_hz)]
        assert histories.attrs["counterweight"] == 1
        # the scene states a wing amplitude: the contact cycle scales the vibration by this factor
        assert histories.attrs["vibration_scale"] == summary["vibration_scale"] != 1.0
        assert file.attrs["complete"]


def test_export_fmu_plays_a_coupled_run_back(coupled, tmp_path, capsys):
    out, loading, _ = coupled
    fmu = tmp_path / "loads.fmu"
    assert main(["export-fmu", str(out), "--signals", "cw1_wing_torsion,cw1_frame_acceleration",
                 "-o", str(fmu)]) == 0
    assert "wrote" in capsys.readouterr().out
    outputs = [v.name for v in read_model_description(str(fmu)).modelVariables if v.causality == "output"]
    assert outputs == ["cw1_wing_torsion", "cw1_frame_acceleration.'x (tangential)'",
                       "cw1_frame_acceleration.'y (radial)'", "cw1_frame_acceleration.'z (crank axis)'"]
    time = loading.time
    step = float(np.median(np.diff(time)))
    result = simulate_fmu(str(fmu), start_time=time[0], stop_time=time[-1], output_interval=step / 4)
    played = result["time"]
    expected = {"cw1_wing_torsion": loading.wing_torsion,
                **{name: loading.frame_acceleration[:, k] for k, name in enumerate(outputs[1:])}}
    nearest = np.abs(played[:, None] - time[None, :]).argmin(axis=1)
    on_sample = np.abs(played - time[nearest]) <= 1e-12 * time[-1]
    assert on_sample.sum() >= time.size // 2  # the output grid lands on the samples
    for name, values in expected.items():
        scale = np.abs(values).max()
        # exact at the samples, linear in between
        np.testing.assert_allclose(result[name][on_sample], values[nearest[on_sample]], rtol=0,
                                   atol=1e-9 * scale, err_msg=name)
        np.testing.assert_allclose(result[name], np.interp(played, time, values), rtol=0, atol=1e-9 * scale,
                                   err_msg=name)


def test_export_fmu_of_an_uncoupled_run_says_where_histories_are(coarse_cylinder, tmp_path, capsys):
    run_scene(scenes.load(coarse_cylinder), tmp_path / "run", progress=False, plots=False)
    assert main(["export-fmu", str(tmp_path / "run" / "results.h5"), "-o", str(tmp_path / "loads.fmu")]) == 2
    message = capsys.readouterr().err
    assert "no /histories group" in message and "coupled `fretwork run`" in message
    assert not (tmp_path / "loads.fmu").exists()


def test_histories_without_modes_have_no_modal_signals_and_play_back(tmp_path):
    """An interface-histories file may carry no modes: the run's /histories then has none either."""
    time = np.arange(8) / 1000.0
    motion = np.outer(np.sin(2 * np.pi * 125 * time), [1.0, 2.0, 3.0])
    empty = np.zeros((8, 0))
    loading = MultibodyLoading(speed_rpm=750.0, time=time, frame_acceleration=motion, angular_velocity=2 * motion,
                               angular_acceleration=3 * motion, modal_coordinates=empty, modal_velocities=empty,
                               modal_accelerations=empty, wing_torsion=motion[:, 0], mesh_points=np.zeros((3, 0)),
                               mesh_cells=np.zeros((4, 0), dtype=int), mode_shapes=np.zeros((0, 0)), geometry={},
                               mode_frequencies_hz=np.zeros(0), torsion_mode=0, wall_time_s=0.0)
    with h5py.File(tmp_path / "results.h5", "w") as file:
        write_loading_histories(file.create_group("histories"), loading, 2)
    table = read_playback_table(tmp_path)
    axes = ("x (tangential)", "y (radial)", "z (crank axis)")
    assert table.names == tuple(f"cw2_{signal}.'{axis}'" for signal in
                                ("angular_acceleration", "angular_velocity", "frame_acceleration")
                                for axis in axes) + ("cw2_wing_torsion",)
    assert np.array_equal(table.values[:, 6:9], motion) and np.array_equal(table.time, time)
