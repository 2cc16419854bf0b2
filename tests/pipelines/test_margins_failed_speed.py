"""A speed whose multibody run failed has no wing amplitude: its margin is not judged, never
called safe (it was: NaN amplitude → infinite margin → "safe", green in margins.png)."""

from types import SimpleNamespace

import matplotlib.pyplot as plt
import numpy as np
import pytest

from pipelines.jobs import margins
from pipelines.jobs.limit import LimitResult


@pytest.fixture
def result(monkeypatch):
    monkeypatch.setattr(margins, "calibration_factor", lambda scene, cache: (2.0, None))
    monkeypatch.setattr(margins.CouplingSettings, "of", staticmethod(lambda scene: SimpleNamespace(counterweight=1)))
    sweep = SimpleNamespace(speeds_rpm=np.array([600.0, 750.0, 900.0]),
                            wing_amplitude=np.array([[0.15], [np.nan], [0.05]]),  # mm; 750 rpm failed
                            unsettled={})
    limit = LimitResult(0.2, (0.19, 0.2), 0.01, range_mm=(0.05, 0.5))
    return margins.margins_of(None, sweep, limit, None)


def test_a_failed_speed_has_no_margin_and_is_not_judged(result):
    np.testing.assert_allclose(result.margin[[0, 2]], [0.19 / 0.3, 0.19 / 0.1])  # 0.19 mm stuck, 0.2 not
    assert np.isnan(result.margin[1])
    assert [result.state(k) for k in range(3)] == ["unsafe", "not judged", "safe"]
    assert not result.unsafe[1] and not result.at_limit[1]
    said = margins.describe_margins(result)
    assert said.startswith("NOT JUDGED at 750 rpm: the multibody run failed there")
    assert "UNSAFE at 600 rpm" in said and "safe at every speed" not in said
    summary = result.to_json()
    assert summary["failed_speeds"] == [750.0] and summary["margin"][1] is None
    assert summary["unsafe_speeds"] == [600.0] and summary["smallest_margin_speed_rpm"] == 600.0


def test_only_failed_speeds_besides_safe_ones_are_not_called_safe_at_every_speed(monkeypatch):
    monkeypatch.setattr(margins, "calibration_factor", lambda scene, cache: (1.0, None))
    monkeypatch.setattr(margins.CouplingSettings, "of", staticmethod(lambda scene: SimpleNamespace(counterweight=1)))
    sweep = SimpleNamespace(speeds_rpm=np.array([600.0, 900.0]), wing_amplitude=np.array([[0.01], [np.nan]]),
                            unsettled={})
    result = margins.margins_of(None, sweep, LimitResult(0.2, (0.19, 0.2), 0.01, range_mm=(0.05, 0.5)), None)
    assert margins.describe_margins(result) == ("NOT JUDGED at 900 rpm: the multibody run failed there (the "
                                                "sweep's failures), so there is no wing amplitude to judge; "
                                                "safe at the others; the margins judge CW1 ([coupling] "
                                                "counterweight = 1)")


def test_the_margins_plot_marks_a_failed_speed(result, tmp_path, monkeypatch):
    kept = []
    monkeypatch.setattr(plt, "close", kept.append)
    margins.plot_margins(result, tmp_path / "margins.png", "test")
    top, bottom = kept[0].axes
    marked = [line for line in bottom.get_lines() if line.get_label() == "multibody run failed: not judged"]
    assert len(marked) == 1 and marked[0].get_xdata()[0] == 750.0
    # no coloured point at the failed speed
    for collection in bottom.collections:
        assert 750.0 not in collection.get_offsets()[:, 0]
