"""`fretwork sweep` and `fretwork mbs` as the QA found them (2026-11-28): sweep speeds in rad/s
beside the scene's 750 rpm went unremarked; `sweep --margins` wrote margins.png only, without the
sweep's plots and figures; `mbs --out bad/run.h5` made a folder named run.h5; `--amplitude` and
`--tolerance` without `--margins` were dropped silently; margins.png did not say at which speed
the limit was searched. The expensive runs are replaced where what is tested happens before them."""

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from mbs.campbell import Campbell
from mbs.model import SimulationError
from mbs.sweep import SweepResult
from pipelines.cli.main import main
from pipelines.jobs.limit import LimitResult
from pipelines.jobs.margins import MarginResult, plot_margins
from pipelines.scene.checks import OTHER_UNIT_RATIO, engine_speed_warnings
from reduction.errors import InputError

COUNTERWEIGHT = Path(__file__).resolve().parents[2] / "examples" / "counterweight.toml"


def _scene(tmp_path, speed=750.0):
    scene = tmp_path / "engine.toml"
    scene.write_text(f"[mbs]\nspeed_rpm = {speed}\nn_modes = 2\neffects = []\n"
                     "[mbs.solver]\nrevolutions = 0.2\ntime_step = 1e-4\n")
    return scene


def _stop_the_sweep(monkeypatch):
    import pipelines.cli.mbs as cli

    def swept(params, speeds, **kwargs):
        raise InputError("stopped by the test: the sweep was started")

    monkeypatch.setattr(cli, "speed_sweep", swept)


# 1. speeds in another unit than the scene's own engine speed

def test_sweep_speeds_in_rad_s_beside_the_scenes_rpm_are_warned_about_naming_both(tmp_path, monkeypatch, capsys):
    _stop_the_sweep(monkeypatch)
    assert main(["sweep", str(_scene(tmp_path)), "--speeds", "62.8,78.5,94.2", "--workers", "0",
                 "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert error.count("warning") == 1
    assert ("fretwork: warning: --speeds 62.8,78.5,94.2: 62.8, 78.5 and 94.2 rpm are all below a fifth of the "
            "scene's engine speed ([mbs] speed_rpm = 750 rpm): probably rad/s (rpm expected: 62.8 to 94.2 rad/s "
            "is 599.7 to 899.5 rpm, about the scene's 750 rpm)") in error
    assert "stopped by the test" in error


def test_sweep_with_margins_warns_of_rad_s_speeds_too(tmp_path, capsys):
    # this scene has no contact: the margin sweep refuses it after the speeds were judged
    assert main(["sweep", str(_scene(tmp_path)), "--speeds", "62.8,78.5,94.2", "--margins", "--workers", "0",
                 "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert error.count("warning") == 1
    assert "62.8, 78.5 and 94.2 rpm are all below a fifth of the scene's engine speed" in error


@pytest.mark.parametrize("speeds, reference, unit", [
    ([10.0, 12.5], 750.0, "probably Hz (rpm expected: 10 to 12.5 Hz is 600 to 750 rpm"),
    ([78.5], 750.0, "probably rad/s (rpm expected: 78.5 rad/s is 749.6 rpm"),
    ([4500.0, 5400.0], 750.0, "probably °/s (rpm expected: 4500 to 5400 °/s is 750 to 900 rpm"),
    # the scene's own speed in another unit: the sweep is in rpm
    ([600.0, 700.0, 800.0, 900.0], 78.5, "probably [mbs] speed_rpm is in rad/s (rpm expected: 78.5 rad/s is 749.6 rpm"),
    ([600.0, 900.0], 12.5, "probably [mbs] speed_rpm is in Hz (rpm expected: 12.5 Hz is 750 rpm"),
])
def test_the_likely_unit_is_the_one_that_brings_the_speeds_near_the_scenes(speeds, reference, unit):
    warning, = engine_speed_warnings(speeds, "--speeds S", reference_rpm=reference)
    assert "the scene's engine speed ([mbs] speed_rpm = " in warning and unit in warning


@pytest.mark.parametrize("speeds", [[600.0, 750.0, 900.0], [150.0, 450.0, 900.0], [750.0 / OTHER_UNIT_RATIO],
                                    [3000.0, 3750.0]])
def test_sweeps_about_the_scenes_speed_or_reaching_it_are_not_warned_about(speeds):
    assert engine_speed_warnings(speeds, "--speeds S", reference_rpm=750.0) == []


def test_speeds_no_unit_brings_near_the_scenes_are_judged_on_their_own():
    warning, = engine_speed_warnings([1.0, 2.0], "--speeds 1,2", reference_rpm=750.0)
    assert warning.startswith("--speeds 1,2: 1 and 2 rpm are below 30 rpm, slower than any engine runs")
    warning, = engine_speed_warnings([20000.0], "--speeds 20000", reference_rpm=750.0)
    assert warning.startswith("--speeds 20000: 20000 rpm is above 10,000 rpm")


# 2. sweep --margins draws and reports the sweep as sweep does

def _sweep_result(speeds=(700.0, 750.0)) -> SweepResult:
    speeds = np.asarray(speeds)
    n = len(speeds)
    crossing = {"order": 6.0, "mode": 0, "speed_rpm": 725.0, "frequency_hz": 72.5}
    campbell = Campbell(speeds, np.array([[70.0, 140.0]] * n), np.array([3.0, 6.0]), [crossing])
    return SweepResult(speeds, np.array([[1e-4, 2e-4], [1.2e-4, 2.1e-4]])[:n], np.full((n, 3), 72.0),
                       np.full((n, 3), 6.0), np.ones(n), np.full((n, 4), 70.0), [crossing],
                       np.array([False, True])[:n], {}, campbell, np.zeros(n), {})


def _margins(sweep: SweepResult) -> MarginResult:
    limit = LimitResult(0.2, (0.19, 0.2), 0.01, range_mm=(0.05, 0.5))
    amplitude = 1e3 * sweep.wing_amplitude[:, 0]
    # the margins divide 0.19 mm, the largest amplitude shown to stick
    return MarginResult(sweep.speeds_rpm, amplitude, 1e3, limit, 0.19 / amplitude, float(sweep.speeds_rpm.max()))


def test_sweep_with_margins_writes_the_sweeps_plots_and_reports_its_figures_as_sweep_does(tmp_path, monkeypatch,
                                                                                          capsys):
    import pipelines.cli.mbs as cli
    import pipelines.jobs.margins as margins

    sweep = _sweep_result()
    monkeypatch.setattr(cli, "speed_sweep", lambda params, speeds, **kwargs: sweep)
    monkeypatch.setattr(margins, "margin_sweep", lambda *args, **kwargs: (_margins(sweep), sweep))
    scene = COUNTERWEIGHT  # a coupled scene, as --margins needs
    plain, with_margins = tmp_path / "plain", tmp_path / "margins"
    assert main(["sweep", str(scene), "--speeds", "700,750", "--workers", "0", "--out", str(plain), "--json"]) == 0
    swept = json.loads(capsys.readouterr().out)
    assert main(["sweep", str(scene), "--speeds", "700,750", "--workers", "0", "--out", str(with_margins),
                 "--margins", "--no-cache", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert sorted(p.name for p in with_margins.iterdir() if not p.name.startswith(".")) == [
        "campbell.png", "margins.png", "sweep_wing_amplitude.png"]
    assert sorted(p.name for p in plain.iterdir() if not p.name.startswith(".")) == [
        "campbell.png", "sweep_wing_amplitude.png"]
    assert summary["sweep"] == json.loads(json.dumps(swept).replace(str(plain), str(with_margins)))
    assert summary["sweep"]["crossings"][0]["speed_rpm"] == 725.0 and summary["sweep"]["resonance"] == [False, True]
    assert summary["margin"] == pytest.approx([0.19 / 0.1, 0.19 / 0.12])
    assert summary["plot"] == str(with_margins / "margins.png")

    assert main(["sweep", str(scene), "--speeds", "700,750", "--workers", "0", "--out", str(with_margins),
                 "--margins", "--no-cache"]) == 0
    said = capsys.readouterr().out
    assert "crossing: order 6 meets mode 1 at 725.0 rpm (72.5 Hz)" in said
    assert f"{with_margins / 'campbell.png'}" in said and f"{with_margins / 'sweep_wing_amplitude.png'}" in said


# 3. mbs --out FILE.h5

def _fake_run(calls):
    def run(params, folder, **kwargs):
        folder = Path(folder)
        calls.append(folder)
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "run.h5").write_bytes(b"run")
        histories = SimpleNamespace(wing_amplitude=np.array([1e-4, 2e-4]), unsettled_change=0.001,
                                    real_time_factor=0.5)
        return SimpleNamespace(histories=histories, reduced=SimpleNamespace(torsion_frequency=80.0),
                               results_file=folder / "run.h5", plots={"campbell": folder / "campbell.png"})
    return run


@pytest.mark.parametrize("name", ["run.h5", "engine.h5"])
def test_mbs_with_an_out_ending_in_h5_writes_that_file_as_sweep_does(tmp_path, monkeypatch, capsys, name):
    import pipelines.cli.mbs as cli

    calls = []
    monkeypatch.setattr(cli, "run_model", _fake_run(calls))
    out = tmp_path / "bad" / name
    assert main(["mbs", str(_scene(tmp_path)), "--out", str(out), "--json"]) == 0
    said = capsys.readouterr()
    assert calls == [tmp_path / "bad"]
    assert out.is_file() and out.read_bytes() == b"run"
    assert json.loads(said.out)["file"] == str(out)
    assert (f"fretwork: note: --out {out} names a file: written, with the plots beside it (--out is a folder "
            f"for every command: --out {tmp_path / 'bad'} writes {tmp_path / 'bad' / 'run.h5'})") in said.err
    assert sorted(p.name for p in (tmp_path / "bad").iterdir() if not p.name.startswith(".")) == [name]


def test_mbs_into_a_folder_is_as_before(tmp_path, monkeypatch, capsys):
    import pipelines.cli.mbs as cli

    calls = []
    monkeypatch.setattr(cli, "run_model", _fake_run(calls))
    assert main(["mbs", str(_scene(tmp_path)), "--out", str(tmp_path / "out")]) == 0
    assert calls == [tmp_path / "out"] and "note" not in capsys.readouterr().err


def test_mbs_does_not_rename_over_a_run_file_already_beside_the_named_one(tmp_path, monkeypatch, capsys):
    import pipelines.cli.mbs as cli

    def refuse(*args, **kwargs):
        raise SimulationError("the run was started")

    monkeypatch.setattr(cli, "run_model", refuse)
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "run.h5").write_bytes(b"someone's")
    assert main(["mbs", str(_scene(tmp_path)), "--out", str(tmp_path / "bad" / "engine.h5")]) == 2
    assert f"the run writes {tmp_path / 'bad' / 'run.h5'} and then renames it" in capsys.readouterr().err
    assert (tmp_path / "bad" / "run.h5").read_bytes() == b"someone's"


# 4. options of --margins given without it

@pytest.mark.parametrize("options, named", [
    (["--amplitude", "100:400"], "--amplitude is"),
    (["--amplitude", "100:400", "--tolerance", "5"], "--amplitude and --tolerance are"),
    (["--tolerance", "5", "--quiet"], "--tolerance is"),  # --quiet quiets the plain sweep's progress too
    (["--amplitude", "400:100"], "--amplitude is"),  # not even checked: it is not used
])
def test_margin_options_without_margins_are_said_to_be_ignored(tmp_path, monkeypatch, capsys, options, named):
    _stop_the_sweep(monkeypatch)
    assert main(["sweep", str(_scene(tmp_path)), "--speeds", "700", "--workers", "0", "--out", str(tmp_path / "o"),
                 *options]) == 2
    error = capsys.readouterr().err
    assert (f"fretwork: warning: {named} for --margins only: ignored (the sweep runs without the amplitude limit "
            "and the margins)") in error
    assert error.count("warning") == 1 and "stopped by the test" in error


def test_a_quiet_sweep_draws_no_progress_bar(tmp_path, monkeypatch):
    import pipelines.cli.mbs as cli
    from reduction.errors import InputError

    asked = {}

    def swept(params, speeds, **kwargs):
        asked.update(kwargs)
        raise InputError("stopped by the test")

    monkeypatch.setattr(cli, "speed_sweep", swept)
    main(["sweep", str(_scene(tmp_path)), "--speeds", "700", "--workers", "0", "--out", str(tmp_path / "q"),
          "--quiet"])
    assert asked["progress"] is False


def test_a_sweep_without_margin_options_or_with_margins_says_nothing_of_them(tmp_path, monkeypatch, capsys):
    _stop_the_sweep(monkeypatch)
    assert main(["sweep", str(_scene(tmp_path)), "--speeds", "700", "--workers", "0", "--out", str(tmp_path / "o")]) == 2
    assert "warning" not in capsys.readouterr().err
    assert main(["sweep", str(_scene(tmp_path)), "--speeds", "700", "--workers", "0", "--out", str(tmp_path / "m"),
                 "--margins", "--amplitude", "100:400", "--tolerance", "5"]) == 2  # no contact: refused
    assert "for --margins only" not in capsys.readouterr().err


# 5. margins.png says where the limit was searched

def _legend_texts(monkeypatch) -> list[str]:
    from matplotlib.figure import Figure

    texts = []

    def savefig(figure, path, **kwargs):
        texts.extend(t.get_text() for axes in figure.axes if axes.get_legend() for t in axes.get_legend().get_texts())
        Path(path).write_bytes(b"png")

    monkeypatch.setattr(Figure, "savefig", savefig)
    return texts


def test_the_stick_limit_line_says_at_which_speed_the_limit_was_searched(tmp_path, monkeypatch):
    texts = _legend_texts(monkeypatch)
    result = _margins(_sweep_result())
    plot_margins(result, tmp_path / "margins.png", "cw: fretting safety margin")
    assert "sticks up to 190.0 µm, not at 200.0 µm (searched at 750 rpm)" in texts


def test_a_limit_above_the_range_is_drawn_at_its_top_saying_so(tmp_path, monkeypatch):
    texts = _legend_texts(monkeypatch)
    result = _margins(_sweep_result())
    result.limit = LimitResult(None, (0.5, None), 0.01, range_mm=(0.05, 0.5))
    plot_margins(result, tmp_path / "margins.png", "cw: fretting safety margin")
    assert ("stuck over the whole searched range, up to 500.0 µm (searched at 750 rpm): the margins are lower "
            "bounds") in [text.replace("\n", " ") for text in texts]
