"""The verdict of the procedure on synthetic cycle histories (SPEC §5)."""

import numpy as np

from contact.procedure import CycleSummary, Procedure
from contact.verdict import loosening_evident as _loosening, verdict as _verdict

PROCEDURE = Procedure(loosening_window=10, area_tolerance=0.01)


def _history(clamp, stick, slip, phase="wear"):
    cycles = []
    for k, (force, stuck, slipping) in enumerate(zip(clamp, stick, slip)):
        summary = CycleSummary(cycle=k + 1, phase=phase, equivalent_cycles=k + 1.0, pressure=None, shear=None,
                               cof=None, max_utilised_cof=None, max_shear=None, status=None, slip_range=None,
                               dissipation_in_cycle=None, state=None, clamp_force=force)
        summary.figures = {"stick_area_fraction": stuck, "slip_area_fraction": slipping}
        cycles.append(summary)
    return cycles


def test_steady_clamp_loss_with_shrinking_stick_area_is_loosening():
    n = 12
    history = _history(20000 - 150 * np.arange(n), np.linspace(0.2, 0.02, n), np.linspace(0.8, 0.98, n))
    assert _loosening(history, PROCEDURE)
    assert _verdict(history, PROCEDURE, stationary=False) == "loosening"


def test_clamp_loss_that_levels_off_is_not_loosening():
    n = 12
    force = 30000 - 1000 * (1 - np.exp(-np.arange(n) / 1.5))  # about 1 kN lost, then stable
    history = _history(force, np.linspace(0.6, 0.97, n), np.linspace(0.4, 0.0, n))
    assert not _loosening(history, PROCEDURE)
    assert _verdict(history, PROCEDURE, stationary=True) == "stick"


def test_sliding_at_cof_max_with_stable_clamp_is_damage():
    n = 12
    history = _history(np.full(n, 30000.0), np.full(n, 0.6), np.full(n, 0.4))
    assert _verdict(history, PROCEDURE, stationary=False) == "damage"


def test_loosening_needs_a_full_window_of_wear_cycles():
    history = _history(20000 - 500 * np.arange(5), np.linspace(0.2, 0.0, 5), np.ones(5))
    assert not _loosening(history, PROCEDURE)


def test_partial_slip_at_a_cof_that_never_rose_is_not_damage():
    """μ_0 = μ_max: every sliding point has the status "slip at μ_max", but no COF evolved and a
    stick zone holds (Cattaneo-Mindlin): partial slip, not damage; gross slip stays damage."""
    n = 12
    history = _history(np.full(n, 30000.0), np.full(n, 0.6), np.full(n, 0.4))
    for summary in history:
        summary.figures["cof_evolved_area_fraction"] = 0.0
    assert _verdict(history, PROCEDURE, stationary=False) == "partial_slip"
    history[-1].figures["cof_evolved_area_fraction"] = 0.3
    assert _verdict(history, PROCEDURE, stationary=False) == "damage"
    history[-1].figures.update(cof_evolved_area_fraction=0.0, stick_area_fraction=0.0, slip_area_fraction=1.0)
    assert _verdict(history, PROCEDURE, stationary=False) == "damage"


def test_loosening_evident_earlier_stays_the_verdict_unless_the_joint_shook_down():
    n = 12
    force = 30000 - 1000 * (1 - np.exp(-np.arange(n) / 1.5))  # the loss rate slows over the last window
    history = _history(force, np.full(n, 0.3), np.full(n, 0.7))
    assert not _loosening(history, PROCEDURE)
    assert _verdict(history, PROCEDURE, stationary=False) == "damage"
    assert _verdict(history, PROCEDURE, stationary=False, loosened_before=True) == "loosening"
    stuck = _history(force, np.full(n, 1.0), np.zeros(n))
    assert _verdict(stuck, PROCEDURE, stationary=True, loosened_before=True) == "stick"
