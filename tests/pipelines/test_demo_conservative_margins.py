"""The demo's account of its margins names the amplitude they divide, the largest shown to stick
(the lower end of the limit's bracket), not the limit; its operating point is judged by the
margins' own bracket rule; where nothing of the searched range stuck, no margin is called safe.
Built from a LimitResult and a MarginResult, without running the demo."""

import json

import numpy as np
import pytest

from pipelines.jobs.demo import DemoResult, _summary, describe
from pipelines.jobs.limit import LimitResult
from pipelines.jobs.margins import MarginResult
from pipelines.output.jsonfile import json_text

SPEEDS = np.array([600.0, 750.0, 900.0])
AMPLITUDE = np.array([0.05, 0.12, 0.15])  # mm
TIMES = {"cof_phase_s": 1.0}


def _run(amplitude_mm: float) -> dict:
    return {"engine_speed_rpm": 750.0, "wing_amplitude_mm": amplitude_mm, "verdict": "stick",
            "cof_evolved_area_fraction": 0.1, "bolt_force_initial_N": None}


def _demo(limit: LimitResult, operating_mm: float) -> DemoResult:
    margins = MarginResult(SPEEDS, AMPLITUDE, 1.0, limit, limit.margin_limit_mm / AMPLITUDE, 900.0)
    return DemoResult(_summary("cw", _run(operating_mm), limit, margins, TIMES), TIMES)


BRACKETED = LimitResult(0.2, (0.1833, 0.2), 0.025, range_mm=(0.1, 0.4))  # 183.3 µm stuck, 200 µm not


def test_the_demo_says_the_margins_divide_the_lower_end_of_the_bracket():
    result = _demo(BRACKETED, 0.15)
    s = result.summary
    assert s["margin_amplitude_um"] == pytest.approx(183.3) and s["margin_bound"] == "stuck"
    assert s["margin_at_operating_point"] == pytest.approx(0.1833 / 0.15)
    said = describe(result)
    assert "sticks up to 183.3 µm, not at 200.0 µm (searched at 900 rpm): margin 1.22 at the operating point" in said
    assert "amplitude limit 200" not in said
    assert json.loads(json_text({"summary": s}))["summary"]["margin_amplitude_um"] == pytest.approx(183.3)


@pytest.mark.parametrize("operating_mm, state", [
    (0.19, "unsafe"),        # inside the bracket, below the limit: not shown to stick
    (0.17, "at the limit"),  # below 183.3 µm by less than the tolerance of 25 µm; 200 µm is 30 µm away
    (0.15, "safe"),          # 33 µm below what stuck
])
def test_the_operating_point_is_at_the_limit_within_the_tolerance_of_the_bracket(operating_mm, state):
    s = _demo(BRACKETED, operating_mm).summary
    assert s["operating_point"] == state


def test_nothing_stuck_the_operating_point_is_not_called_safe():
    limit = LimitResult(0.1, (None, 0.1), 0.025, range_mm=(0.1, 0.4))
    result = _demo(limit, 0.05)
    s = result.summary
    assert s["margin_at_operating_point"] == pytest.approx(2.0)  # an upper bound, not a shown margin
    assert s["margin_bound"] == "upper bound" and s["operating_point"] == "not shown safe"
    said = describe(result)
    assert "(NOT SHOWN SAFE)" in said and "the margins are upper bounds" in said
    assert "(safe)" not in said and "safe at every speed" not in said


def test_everything_stuck_the_margins_are_said_to_be_lower_bounds():
    limit = LimitResult(None, (0.4, None), 0.025, range_mm=(0.1, 0.4))
    result = _demo(limit, 0.2)
    s = result.summary
    assert s["amplitude_limit_um"] is None and s["margin_amplitude_um"] == pytest.approx(400.0)
    assert s["operating_point"] == "safe" and s["margin_at_operating_point"] == pytest.approx(2.0)
    assert "up to 400.0 µm (searched at 900 rpm): the margins are lower bounds; margin 2.00" in describe(result)


# `fretwork sweep --margins` says the amplitude its margins divide and lists limit.png

def test_sweep_with_margins_prints_the_amplitude_the_margins_divide_and_the_limit_plot(tmp_path, monkeypatch,
                                                                                      capsys):
    import pipelines.cli.mbs as cli
    import pipelines.jobs.margins as margins
    from pipelines.cli.main import main
    from test_sweep_outputs import COUNTERWEIGHT, _sweep_result

    sweep = _sweep_result()
    amplitude = np.array([0.15, 0.185])  # mm: 185 µm inside the bracket 183.3…200 µm
    result = MarginResult(sweep.speeds_rpm, amplitude, 2.5, BRACKETED, 0.1833 / amplitude, 750.0)
    monkeypatch.setattr(margins, "margin_sweep", lambda *args, **kwargs: (result, sweep))
    drawn = {}

    def plot_sweep(speeds, amplitude, path, **kwargs):
        drawn.update(kwargs)
        return path

    monkeypatch.setattr(cli, "plot_sweep", plot_sweep)
    out = tmp_path / "margins"
    assert main(["sweep", str(COUNTERWEIGHT), "--speeds", "700,750", "--workers", "0", "--out", str(out),
                 "--margins", "--no-cache"]) == 0
    said = capsys.readouterr().out
    assert "margins divide 183.3 µm: sticks up to 183.3 µm, not at 200.0 µm (searched at 750 rpm)" in said
    assert "amplitude limit 200" not in said
    assert f"{out / 'limit_runs' / 'limit.png'}" in said.splitlines()[-1]
    # the amplitude plot is calibrated as the margins were, the factor handed over, not read back
    assert drawn["calibration"] == 2.5 and "the scene's stated 100" in drawn["calibration_note"]
    assert main(["sweep", str(COUNTERWEIGHT), "--speeds", "700,750", "--workers", "0", "--out", str(out),
                 "--margins", "--no-cache", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["margin_amplitude_um"] == pytest.approx(183.3) and summary["margin_bound"] == "stuck"
    assert summary["limit_plot"] == str(out / "limit_runs" / "limit.png")
    # the margins' summary in words, as printed without --json
    assert summary["margins"].startswith("UNSAFE at 750 rpm") and "the margins judge CW1" in summary["margins"]
