"""The margins divide the largest wing amplitude shown to stick (the lower end of the limit's
bracket), never the lowest amplitude found not stuck; where the whole searched range stuck they
are lower bounds (its top), where none of it did, upper bounds (its bottom), and no speed is then
called safe. limit.png says the search speed and that its runs are not at equal cycles."""

import json

import matplotlib.pyplot as plt
import numpy as np
import pytest

from pipelines.jobs.limit import AmplitudeRun, LimitResult, plot_limit, write_limit
from pipelines.jobs.margins import MarginResult, describe_margins, plot_margins

SPEEDS = np.array([600.0, 750.0, 900.0])
AMPLITUDE = np.array([0.05, 0.17, 0.19])  # mm


def _margins(limit: LimitResult) -> MarginResult:
    return MarginResult(SPEEDS, AMPLITUDE, 1.0, limit, limit.margin_limit_mm / AMPLITUDE, 900.0)


def test_the_margins_divide_the_largest_amplitude_that_stuck():
    limit = LimitResult(0.2, (0.1833, 0.2), 0.025, range_mm=(0.1, 0.4))  # 183.3 µm stuck, 200 µm did not
    result = _margins(limit)
    assert limit.margin_limit_mm == 0.1833 and limit.margin_bound == "stuck"
    np.testing.assert_allclose(result.margin, [0.1833 / 0.05, 0.1833 / 0.17, 0.1833 / 0.19])
    # 190 µm lies inside the bracket: not shown to stick, so unsafe though below the limit
    assert [result.state(k) for k in range(3)] == ["safe", "at the limit", "unsafe"]
    summary = result.to_json()
    assert summary["margin_amplitude_um"] == pytest.approx(183.3) and summary["limit_um"] == pytest.approx(200.0)
    assert summary["margin_bound"] == "stuck" and summary["bracket_um"] == pytest.approx([183.3, 200.0])
    assert "exceeds 183.3 µm, the largest amplitude shown to stick" in describe_margins(result)


def test_a_range_that_stuck_throughout_gives_lower_bounds_and_no_limit_to_be_at():
    limit = LimitResult(None, (0.4, None), 0.025, range_mm=(0.1, 0.4))
    result = _margins(limit)
    assert limit.margin_limit_mm == 0.4 and limit.margin_bound == "lower bound"
    np.testing.assert_allclose(result.margin, 0.4 / AMPLITUDE)
    assert not result.at_limit.any() and [result.state(k) for k in range(3)] == ["safe"] * 3
    assert describe_margins(result).endswith("the margins are lower bounds (the whole range stuck); "
                                             "the margins judge CW1 ([coupling] counterweight = 1)")


def test_a_range_that_never_stuck_gives_upper_bounds_and_calls_no_speed_safe():
    limit = LimitResult(0.1, (None, 0.1), 0.025, range_mm=(0.1, 0.4))
    result = _margins(limit)
    assert limit.margin_limit_mm == 0.1 and limit.margin_bound == "upper bound"
    np.testing.assert_allclose(result.margin, 0.1 / AMPLITUDE)
    # 50 µm: a margin of 2 at most; nothing was shown to stick, so it is not safe either
    assert [result.state(k) for k in range(3)] == ["at the limit", "unsafe", "unsafe"]
    said = describe_margins(result)
    assert "not shown safe at 600 rpm" in said and said.endswith(
        "the margins are upper bounds (nothing stuck); the margins judge CW1 ([coupling] counterweight = 1)")
    assert "safe at every speed" not in said


def test_the_margins_plot_labels_the_amplitude_it_divides(tmp_path, monkeypatch):
    kept = []
    monkeypatch.setattr(plt, "close", kept.append)
    plot_margins(_margins(LimitResult(0.2, (0.1833, 0.2), 0.025, range_mm=(0.1, 0.4))), tmp_path / "m.png", "t")
    top = kept[0].axes[0]
    labels = [text.get_text().replace("\n", " ") for text in top.get_legend().get_texts()]
    assert "sticks up to 183.3 µm, not at 200.0 µm (searched at 900 rpm)" in labels
    line = next(line for line in top.get_lines() if line.get_linestyle() == "--")
    assert line.get_ydata()[0] == pytest.approx(183.3)


def test_limit_png_says_the_search_speed_and_each_runs_cycles(tmp_path, monkeypatch):
    runs = [AmplitudeRun(0.1833, "stick", {"equivalent_cycles": 1.05e6, "engine_speed_rpm": 900.0,
                                           "clamp_force_loss_fraction": 7.6e-4}),
            AmplitudeRun(0.2, "damage", {"equivalent_cycles": 2.56e6, "engine_speed_rpm": 900.0,
                                         "clamp_force_loss_fraction": 9.4e-4}),
            AmplitudeRun(0.4, "damage", {"equivalent_cycles": 1.5e4, "engine_speed_rpm": 900.0,
                                         "clamp_force_loss_fraction": 4.8e-3})]
    result = LimitResult(0.2, (0.1833, 0.2), 0.025, runs, (0.1, 0.4))
    kept = []
    monkeypatch.setattr(plt, "close", kept.append)
    plot_limit(result, tmp_path / "limit.png", "cw")
    top = kept[0].axes[0]
    assert "searched at 900 rpm" in top.get_title()
    assert sorted(t.get_text() for t in top.texts) == ["1.0e6", "1.5e4", "2.6e6"]
    assert any("not at equal cycles" in t.get_text() for t in kept[0].texts)
    written = json.loads(write_limit(result, tmp_path / "limit.json").read_text())
    assert written["speed_rpm"] == 900.0 and written["margin_amplitude_um"] == pytest.approx(183.3)
