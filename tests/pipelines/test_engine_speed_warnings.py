"""An engine speed that is likely a unit mistake is warned about once per place it was given
(the scene's [mbs] speed_rpm, `sweep --speeds`), and the command still runs (QA: 20,000 rpm
went unremarked)."""

import pytest

from mbs.model import SimulationError
from pipelines.cli.main import main
from pipelines.scene.checks import FASTEST_ENGINE_RPM, SLOWEST_ENGINE_RPM, engine_speed_warnings, plausibility


@pytest.mark.parametrize("speed", [300.0, 750.0, 8000.0, SLOWEST_ENGINE_RPM, FASTEST_ENGINE_RPM])
def test_the_speeds_of_real_engines_are_not_warned_about(speed):
    assert engine_speed_warnings([speed], "[mbs] speed_rpm") == []
    assert plausibility({"mbs": {"speed_rpm": speed}}) == []


def test_a_speed_in_hz_names_the_key_and_the_likely_units():
    warning, = plausibility({"mbs": {"speed_rpm": 12.5}})  # 750 rpm written in Hz
    assert warning == ("[mbs] speed_rpm: 12.5 rpm is below 30 rpm, slower than any engine runs: probably Hz or "
                       "rad/s (rpm expected: 12.5 Hz is 750 rpm, 12.5 rad/s is 119.4 rpm)")


def test_a_speed_above_any_engine_with_bolted_counterweights_is_warned_about():
    warning, = plausibility({"mbs": {"speed_rpm": 20000}})
    assert warning.startswith("[mbs] speed_rpm: 20000 rpm is above 10,000 rpm")
    assert "probably °/s or a digit too many (rpm expected: 20000 °/s is 3333 rpm)" in warning


def test_a_sweep_says_its_slow_and_its_fast_speeds_once_each():
    slow, fast = engine_speed_warnings([5.0, 10.0, 15.0, 20.0, 750.0, 12000.0], "--speeds 5,10,15,20,750,12000")
    assert slow.startswith("--speeds 5,10,15,20,750,12000: 4 speeds from 5 to 20 rpm are below 30 rpm")
    assert fast.startswith("--speeds 5,10,15,20,750,12000: 12000 rpm is above 10,000 rpm")


def _scene(tmp_path, speed):
    scene = tmp_path / "engine.toml"
    scene.write_text(f"[mbs]\nspeed_rpm = {speed}\nn_modes = 2\neffects = []\n"
                     "[mbs.solver]\nrevolutions = 0.2\ntime_step = 1e-4\n")
    return scene


def test_fretwork_mbs_warns_once_of_the_scenes_speed_and_still_runs(tmp_path, monkeypatch, capsys):
    import pipelines.cli.mbs as cli

    def ran(params, out, **kwargs):
        assert params.speed_rpm == 20000.0
        raise SimulationError("stopped by the test: the run was started")

    monkeypatch.setattr(cli, "run_model", ran)
    assert main(["mbs", str(_scene(tmp_path, 20000.0)), "--out", str(tmp_path / "out")]) == 1
    error = capsys.readouterr().err
    assert error.count("fretwork: warning: [mbs] speed_rpm: 20000 rpm is above 10,000 rpm") == 1
    assert "stopped by the test" in error


def test_fretwork_sweep_warns_once_of_its_speeds(tmp_path, monkeypatch, capsys):
    import pipelines.cli.mbs as cli
    from reduction.errors import InputError

    def swept(params, speeds, **kwargs):
        raise InputError("stopped by the test: the sweep was started")

    monkeypatch.setattr(cli, "speed_sweep", swept)
    scene = _scene(tmp_path, 750.0)
    assert main(["sweep", str(scene), "--speeds", "10,12.5", "--workers", "0", "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert error.count("warning") == 1  # beside the scene's 750 rpm they are Hz (tests/pipelines/test_sweep_outputs.py)
    assert ("fretwork: warning: --speeds 10,12.5: 10 and 12.5 rpm are all below a fifth of the scene's engine speed "
            "([mbs] speed_rpm = 750 rpm): probably Hz (rpm expected: 10 to 12.5 Hz is 600 to 750 rpm") in error
    assert "stopped by the test" in error


def test_fretwork_sweep_with_margins_warns_once_of_its_speeds(tmp_path, capsys):
    # this scene has no contact: the margin sweep refuses it after the speeds were judged
    scene = _scene(tmp_path, 750.0)
    assert main(["sweep", str(scene), "--speeds", "10,12.5", "--margins", "--workers", "0",
                 "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert error.count("warning") == 1
    assert "fretwork: warning: --speeds 10,12.5: 10 and 12.5 rpm are all below a fifth" in error
    assert "fretwork: error:" in error


def test_a_pretension_that_barely_stretches_its_bolt_is_said_to_be_in_kn():
    """400 N on an 8e5 N/mm screw stretches it 0.5 µm: 400 kN typed in kN (QA: no warning, then
    a Newton failure advising to prescribe a motion). Real preloads stretch tens of µm or more."""
    warning, = plausibility({"bolts": {"screw_1": {"pretension": 400.0, "stiffness": 8e5}}})
    assert warning.startswith("'bolts.screw_1.pretension' = 400 N stretches the bolt ('stiffness' = 800000 N/mm) "
                              "by 0.5 µm") and "probably kN" in warning
    assert plausibility({"bolts": {"screw_1": {"pretension": 4e5, "stiffness": 8e5}}}) == []  # 500 µm
    assert plausibility({"bolts": {"m3": {"pretension": 2000.0, "stiffness": 1e5}}}) == []  # 20 µm
