"""A coupled run's results.h5 holds the multibody histories that drive its loads, in the layout
of ``fretwork mbs``, and ``fretwork export-fmu`` turns them into an FMU that plays them back as the
run's load cycle used them: scaled to the stated wing amplitude (``fretwork mbs``'s run.h5 as it is,
its steady part by default)."""

from pathlib import Path

import h5py
import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

from mbs.loading import MultibodyLoading, cycle_loading, harmonic_fit, run_loading
from mbs.parameters import ModelParams, SolverParams
from mbs.results import MODAL_UNITS, write_loading_histories
from mbs.run import run_model
from pipelines import scene as scenes
from pipelines import stages
from pipelines.cli.main import main
from pipelines.coupling import multibody_loading
from pipelines.fmu.export import export_fmu
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
def stage_cache(tmp_path_factory):
    return stages.StageCache(tmp_path_factory.mktemp("stage-cache"))


def run_coupled(scene_path, out, cache):
    """(output folder, the multibody loading the run used, the run's summary) of a coupled scene at
    its cheapest."""
    scene = scenes.load(scene_path, CHEAPEST)
    outcome = run_scene(scene, out, progress=False, plots=False, cache=cache)
    return out, multibody_loading(scene, cache), outcome.summary


@pytest.fixture(scope="module")
def coupled(tmp_path_factory, stage_cache):
    """The coupled scene (a wing_period load cycle) at its cheapest."""
    return run_coupled(SCENE, tmp_path_factory.mktemp("coupled"), stage_cache)


@pytest.fixture(scope="module")
def coupled_revolution(tmp_path_factory, stage_cache):
    """The coupled scene with a revolution load cycle (the same multibody run) at its cheapest."""
    folder = tmp_path_factory.mktemp("revolution")
    scene = folder / "revolution.toml"
    scene.write_text(f'[scene]\nbase = "{SCENE}"\nname = "revolution"\n\n[coupling]\ncycle = "revolution"\n')
    return run_coupled(scene, folder / "out", stage_cache)


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
        # and says which cycle played them, so that export-fmu need not read it from the scene
        assert histories.attrs["load_cycle"] == summary["load_cycle"]
        assert histories.attrs["wing_amplitude"] == summary["wing_amplitude_mm"]
        assert histories.attrs["load_cycle_frequency_hz"] == summary["load_cycle_frequency_hz"]
        assert file.attrs["complete"]


def test_read_summary_reads_a_run_and_names_a_file_of_another_kind(coupled, tmp_path):
    from mbs.results import SWEEP_FORMAT
    from pipelines.output.results import read_summary
    from reduction.errors import InputError

    out, _, summary = coupled
    assert read_summary(out / "results.h5")["verdict"] == summary["verdict"]
    sweep, unfinished = tmp_path / "sweep.h5", tmp_path / "unfinished.h5"
    with h5py.File(sweep, "w") as file:
        file.attrs["fretwork_format"] = SWEEP_FORMAT
    with h5py.File(unfinished, "w") as file:
        file.attrs.update(fretwork_format="fretwork-results", ending="slid_off")
    with pytest.raises(InputError, match="speed sweep"):
        read_summary(sweep)
    with pytest.raises(InputError, match="stopped early .slid_off."):
        read_summary(unfinished)


def test_export_fmu_plays_a_coupled_run_back(coupled, tmp_path, capsys):
    """The FMU plays the table of the run's histories (as the run used them), exact at the samples."""
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
    table = read_playback_table(out, ["cw1_wing_torsion", "cw1_frame_acceleration"])
    expected = {name: table.values[:, k] for k, name in enumerate(outputs)}
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


@pytest.mark.parametrize("run", ["coupled", "coupled_revolution"])
def test_the_fmu_of_a_coupled_run_swings_the_wing_by_the_stated_amplitude(run, request, tmp_path):
    out, loading, summary = request.getfixturevalue(run)
    stated, scale = summary["wing_amplitude_mm"], summary["vibration_scale"]
    assert scale > 2.0  # the scene states more than the multibody amplitude: unscaled playback would fail
    fmu = tmp_path / "wing.fmu"
    export_fmu(out, fmu, ["cw1_wing_torsion"])
    time = loading.time
    step = float(np.median(np.diff(time)))
    played = simulate_fmu(str(fmu), start_time=time[0], stop_time=time[-1], output_interval=step / 4)
    half_swing = 0.5 * np.ptp(played["cw1_wing_torsion"])
    if summary["load_cycle"] == "wing_period":
        # the run's wing torsion is a sinusoid; its samples miss its peaks by at most this much
        tolerance = stated * (1.0 - np.cos(np.pi * summary["load_cycle_frequency_hz"] * step))
    else:
        tolerance = 1e-12 * stated
    assert abs(half_swing - stated) <= tolerance + 1e-12 * stated
    description = read_model_description(str(fmu)).description
    assert f"scaled by {scale:.6g}" in description and f"stated wing amplitude {stated:.6g} mm" in description
    assert summary["load_cycle"] in description


#: load-cycle pattern -> (signal under /histories, column)
CYCLE_SIGNALS = {**{f"frame_a{axis}": ("cw1_frame_acceleration", k) for k, axis in enumerate("xyz")},
                 **{f"alpha_{axis}": ("cw1_angular_acceleration", k) for k, axis in enumerate("xyz")},
                 **{f"mode_{k + 1}": ("cw1_modal_acceleration", k) for k in range(CHEAPEST["mbs.n_modes"])},
                 "wing_mode": ("cw1_wing_torsion", 0)}


@pytest.mark.parametrize("run", ["coupled", "coupled_revolution"])
def test_the_fmu_plays_the_load_cycle_the_run_used(run, request):
    """At the times of the run's load cycle (mbs.loading.cycle_loading), the played histories are
    the cycle's pattern amplitudes."""
    out, loading, summary = request.getfixturevalue(run)
    cycle = cycle_loading(loading, summary["load_cycle"], summary["wing_amplitude_mm"], 360)
    phases = np.arange(1, 361) / 360
    time = loading.time
    step = float(np.median(np.diff(time)))
    if cycle.cycle == "revolution":
        at = time[-1] - loading.revolution_period + phases * loading.revolution_period
        interpolation = 0.0
    else:
        frequency = cycle.frequency_hz
        _, cosine, sine = harmonic_fit(time, loading.wing_torsion, frequency)
        at = time[0] + np.mod(phases - np.arctan2(cosine, sine) / (2 * np.pi), 1.0) / frequency
        # linear interpolation of a sinusoid between samples: at most (pi f dt)^2 / 2 of its amplitude
        interpolation = 0.5 * (np.pi * frequency * step) ** 2
    table = read_playback_table(out)
    for pattern, (signal, column) in CYCLE_SIGNALS.items():
        names = [name for name in table.names if name == signal or name.startswith(signal + ".")]
        values = table.values[:, table.names.index(names[column])]
        expected = cycle.tables[pattern]
        swing = np.ptp(expected)
        np.testing.assert_allclose(np.interp(at, time, values), expected, rtol=0,
                                   atol=interpolation * swing + 1e-9 * np.abs(expected).max(), err_msg=pattern)


def test_the_fmu_of_an_mbs_run_plays_its_steady_part_as_it_is(tmp_path):
    """The steady part a coupled run takes from the same multibody run (mbs.loading.run_loading),
    unscaled; whole=True plays the run from its start."""
    params = ModelParams(n_modes=2, solver=SolverParams(revolutions=2.0, time_step=1e-4))
    outputs = run_model(params, tmp_path)
    results = outputs.results_file
    signals = ["cw1_wing_torsion", "cw1_frame_acceleration"]
    fmu = export_fmu(results, tmp_path / "mbs.fmu", signals)
    table = read_playback_table(results, signals)
    loading = run_loading(params, outputs.reduced, outputs.histories, 1)
    assert table.scaling is None and np.array_equal(table.time, loading.time)
    assert np.array_equal(table.values, np.column_stack([loading.wing_torsion, loading.frame_acceleration]))
    assert read_model_description(str(fmu)).description.startswith(
        f"Playback of 4 load history outputs sampled at {loading.time.size} times, the steady second half of "
        f"the multibody run (from t = {loading.time[0]:.6g} s)")
    whole = read_playback_table(results, signals, whole=True)
    with h5py.File(results) as file:
        stored = np.column_stack([file["histories/cw1_wing_torsion"][()], file["histories/cw1_frame_acceleration"][()]])
        assert np.array_equal(whole.time, file["histories/time"][()])
    assert whole.scaling is None and np.array_equal(whole.values, stored)


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
