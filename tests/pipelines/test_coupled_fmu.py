"""A coupled run's results.h5 holds the multibody histories that drive its loads, in the layout
of ``fretwork mbs``, and ``fretwork export-fmu`` turns them into an FMU that plays them back."""

from pathlib import Path

import h5py
import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

from mbs.results import MODAL_UNITS
from pipelines import scene as scenes
from pipelines import stages
from pipelines.cli.main import main
from pipelines.coupling import multibody_loading
from pipelines.jobs.run import run_scene

SCENE = Path(__file__).resolve().parents[2] / "examples" / "counterweight.toml"
CHEAPEST = {"bodies.counterweight.mesh.contact_size": 20.0, "bodies.web.mesh.contact_size": 20.0,
            "mbs.n_modes": 4, "mbs.solver.revolutions": 2.0, "procedure.cof_cycles": 1,
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
        assert list(histories["cw1_modal_coordinates"].attrs["components"]) == [f"mode {k}" for k in range(1, 5)]
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
