"""Inputs QA found accepted (or refused only after the work): each is refused before any work,
exit status 2, with one message naming the option and what it expects."""

from __future__ import annotations

from pathlib import Path

import pytest

from pipelines.cli.main import main
from pipelines.jobs.sweep import MAX_SPEEDS, parse_speeds
from reduction.errors import InputError

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
COUNTERWEIGHT = EXAMPLES / "counterweight.toml"


@pytest.fixture
def no_work(monkeypatch):
    """Every job fails the test if it starts: a refusal must come before any work."""
    import pipelines.jobs.demo as demo
    import pipelines.jobs.limit as limit
    import pipelines.jobs.run as run
    import pipelines.jobs.sweep as sweep
    import pipelines.studies.constant_cof as constant_cof

    def started(*args, **kwargs):
        raise AssertionError("the job started")
    for module, name in ((run, "run_scene"), (limit, "find_limit"), (demo, "run_demo"), (sweep, "speed_sweep"),
                         (constant_cof, "constant_cof_comparison")):
        monkeypatch.setattr(module, name, started)
    import pipelines.cli.mbs as mbs_cli
    monkeypatch.setattr(mbs_cli, "speed_sweep", started)
    monkeypatch.setattr(mbs_cli, "run_model", started)


def refused(capsys, argv, *parts) -> str:
    assert main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("fretwork: error: ") and len(err.strip().splitlines()) == 1, err
    assert all(part in err for part in parts), err
    return err


@pytest.fixture
def coarse_step(tmp_path) -> Path:
    """The shipped coupled scene with a multibody time step of 0.01 s: 0.27 steps per gear-mesh period."""
    path = tmp_path / "ts_big.toml"
    path.write_text(f'[scene]\nbase = "{COUNTERWEIGHT}"\n[mbs.solver]\ntime_step = 0.01\n')
    return path


@pytest.mark.parametrize("command", [["run"], ["limit", "--amplitude", "100:400"], ["sweep", "--speeds", "100"],
                                     ["sweep", "--speeds", "100", "--margins"], ["mbs"]])
def test_every_command_refuses_a_multibody_step_that_cannot_follow_the_excitation(command, coarse_step, tmp_path,
                                                                                  capsys, no_work):
    out = tmp_path / "out"
    argv = [command[0], coarse_step, *command[1:], "--out", out]
    # `sweep` without --margins runs 100 rpm only (sampled: 20 steps per period); with --margins,
    # the limit search runs at the scene's 750 rpm too
    if command == ["sweep", "--speeds", "100"]:
        argv[3] = "750"
    refused(capsys, argv, "time step 0.01 s cannot follow the gear mesh", "0.27 steps per period",
            "at 750 rpm")
    assert not out.exists()


def test_the_demo_checks_its_scene_at_its_speeds(monkeypatch, tmp_path, capsys, no_work):
    import pipelines.jobs.demo as demo

    monkeypatch.setattr(demo, "DEMO_SPEEDS_RPM", [750.0, 75000.0])  # 0.5 steps per gear-mesh period
    refused(capsys, ["demo", "--out", tmp_path / "demo"], "at 75000 rpm the multibody time step")
    assert not (tmp_path / "demo").exists()


@pytest.mark.parametrize("amplitude, tolerance, named", [
    ("100:inf", "10", "--amplitude '100:inf'"), ("nan:400", "10", "--amplitude 'nan:400'"),
    ("100:400", "nan", "--tolerance nan"), ("100:400", "inf", "--tolerance inf")])
def test_limit_refuses_a_range_or_tolerance_that_is_not_finite(amplitude, tolerance, named, tmp_path, capsys,
                                                               no_work):
    refused(capsys, ["limit", COUNTERWEIGHT, "--amplitude", amplitude, "--tolerance", tolerance,
                     "--out", tmp_path / "lim"], named, "finite")
    assert not (tmp_path / "lim").exists()


def test_sweep_margins_refuses_a_tolerance_that_is_not_finite(tmp_path, capsys, no_work):
    refused(capsys, ["sweep", COUNTERWEIGHT, "--speeds", "750", "--margins", "--tolerance", "nan",
                     "--out", tmp_path / "sw"], "--tolerance nan")


def test_a_speed_list_longer_than_a_sweep_runs_is_refused_naming_count_and_step(tmp_path, capsys, no_work):
    err = refused(capsys, ["sweep", COUNTERWEIGHT, "--speeds", "600:900:1e-9", "--out", tmp_path / "sw"],
                  "300,000,000,001 speeds", "step of 1e-09 rpm", f"{MAX_SPEEDS:,}")
    assert "MemoryError" not in err
    assert len(parse_speeds(f"600:900:{300 / (MAX_SPEEDS - 1)}")) == MAX_SPEEDS  # the cap itself runs
    with pytest.raises(InputError, match="1,001 speeds"):
        parse_speeds("600:900:0.3")
    with pytest.raises(InputError, match="more than the"):
        parse_speeds(",".join(str(600 + k) for k in range(MAX_SPEEDS + 1)))


def test_sweep_checks_its_plots_folder_before_the_sweep(tmp_path, capsys, no_work):
    afile = tmp_path / "scenes_long.toml"
    afile.write_text("a file")
    refused(capsys, ["sweep", COUNTERWEIGHT, "--speeds", "750", "--out", tmp_path / "sw", "--plots", afile],
            f"--plots {afile} is a file")
    assert not (tmp_path / "sw").exists()


@pytest.mark.parametrize("probe", ["nan,0", "0,inf"])
def test_constant_cof_refuses_a_probe_that_is_not_finite(probe, tmp_path, capsys, no_work):
    refused(capsys, ["study", "constant-cof", COUNTERWEIGHT, "--probe", probe, "--out", tmp_path / "cc"],
            f"--probe '{probe}'", "finite")


@pytest.mark.parametrize("signals", [[""], [","], ["", " "]])
def test_export_fmu_says_what_signals_expects(signals, tmp_path, capsys):
    err = refused(capsys, ["export-fmu", tmp_path, "-o", tmp_path / "x.fmu", "--signals", *signals],
                  "names no signal", "/histories", "leave --signals out")
    assert "None" not in err
