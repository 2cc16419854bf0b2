"""A joint judged partial_slip, damage or stick while its clamp force is still visibly falling
is said to be so (contact.verdict.clamp_still_falling): QA ran the double beam at constant COF
and tips ±2.8 mm, lost 6.3 % of the clamp force in 1e5 cycles, still falling at a slowing rate
with the stick area regrowing, and the verdict partial_slip then meant "clamp force stable"."""

from types import SimpleNamespace

import pytest

from contact.procedure import Procedure
from contact.verdict import VERDICT_MEANINGS, clamp_still_falling, loosening_evident, verdict

PROCEDURE = Procedure(cof_cycles=1, wear_cycles=10, loosening_window=10)
INITIAL = 30_000.0  # N


def _history(losses_per_block, stick):
    """Wear blocks of 1e4 real cycles each, losing these forces (N) and with these stick areas."""
    force, cycles = [INITIAL], []
    for k, (loss, stuck) in enumerate(zip(losses_per_block, stick)):
        force.append(force[-1] - loss)
        cycles.append(SimpleNamespace(phase="wear", clamp_force=force[-1], equivalent_cycles=1e4 * (k + 1),
                                      figures={"stick_area_fraction": stuck, "slip_area_fraction": 1 - stuck,
                                               "active_slip_area_fraction": 0.5,
                                               "cof_evolved_area_fraction": 0.0}))
    return cycles


def test_a_slowing_loss_with_a_regrowing_stick_zone_is_no_evident_loosening_but_is_said():
    history = _history([292, 250, 215, 185, 160, 140, 125, 115, 110, 106], [0.26 + 0.003 * k for k in range(10)])
    assert not loosening_evident(history, PROCEDURE)  # the loss slows and the stick zone regrows
    assert verdict(history, PROCEDURE, stationary=False) == "partial_slip"
    falling = clamp_still_falling(history, PROCEDURE, INITIAL)
    assert falling["clamp_loss_recent_fraction"] == pytest.approx((1698 - 292) / INITIAL)  # over the window
    assert falling["clamp_loss_recent_cycles"] == pytest.approx(9e4)
    assert falling["clamp_loss_rate_ratio"] < 0.8  # slowing
    assert "clamp force is stable" not in VERDICT_MEANINGS["partial_slip"]
    assert "clamp force stable" not in VERDICT_MEANINGS["damage"]


def test_a_settled_clamp_force_is_not_said_to_fall():
    history = _history([300, 100, 30, 10, 3, 1, 0.3, 0.1, 0.0, 0.0], [0.5] * 10)
    assert clamp_still_falling(history, PROCEDURE, INITIAL) == {}  # under 0.5 % over the window
    flat = _history([0.0] * 10, [0.5] * 10)
    assert clamp_still_falling(flat, PROCEDURE, INITIAL) == {}
