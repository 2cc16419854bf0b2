"""The verdict of the procedure on synthetic cycle histories (SPEC §5)."""

import numpy as np

from contact.procedure import CycleSummary, Procedure
from contact.verdict import loosening_evident as _loosening, loosening_window_blocks, verdict as _verdict

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


def _jumped_history(real_cycles, loss_rate, stick_rate):
    """A wear phase at blocks ending at ``real_cycles``: the clamp force falls by
    ``loss_rate`` (N per real cycle) and the stick area by ``stick_rate`` (per real cycle)."""
    real = np.asarray(real_cycles, dtype=float)
    history = _history(1.0e6 - loss_rate * real, 0.8 - stick_rate * real, 0.2 + stick_rate * real)
    for summary, cycles in zip(history, real):
        summary.equivalent_cycles = float(cycles)
    return history


def test_loosening_window_in_real_cycles_does_not_depend_on_the_jump():
    """The same physical trend (the clamp force falls 1 % per 1e5 real cycles, the stick area
    shrinks) sampled by coarse blocks (jump 2e4) and fine blocks (jump 1e3, as on a finer mesh):
    a window of 20 blocks sees a visible loss in the coarse sampling only (20 fine blocks span
    2e4 cycles, 0.2 % of loss, under the 0.5 % that counts as visible); a window of 2e5 real
    cycles sees it in both, and holds as many blocks as span it."""
    coarse = _jumped_history(np.arange(1, 41) * 2.0e4, 0.1, 2.0e-7)
    fine = _jumped_history(np.arange(1, 401) * 1.0e3, 0.1, 2.0e-7)
    by_blocks = Procedure(loosening_window=20)
    assert _loosening(coarse, by_blocks)
    assert not _loosening(fine, by_blocks)
    by_cycles = Procedure(loosening_window=5, loosening_window_cycles=2.0e5)
    assert _loosening(coarse, by_cycles) and _loosening(fine, by_cycles)
    assert loosening_window_blocks(coarse, by_cycles) == 11  # 10 blocks of 2e4, one before the window
    assert loosening_window_blocks(fine, by_cycles) == 201
    assert not _loosening(fine[:150], by_cycles)  # 1.5e5 cycles of wear: the window is not full yet
    steady = _jumped_history(np.arange(1, 401) * 1.0e3, 0.0, 0.0)
    assert not _loosening(steady, by_cycles)
