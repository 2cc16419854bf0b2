"""The multibody run's steadiness check (mbs.histories.unsettled_change): a response still ringing
down from its start-up is told apart from a steady one, with the size of the change it measures."""

import numpy as np
import pytest

from mbs.histories import SETTLED_CHANGE, unsettled_change, unsettled_message

FORCED_HZ, RING_HZ, SPEED_RPM = 340.0, 355.0, 750.0


def _run(revolutions: float, ring_amplitude: float, decay_per_s: float, ring_hz: float = RING_HZ,
         samples_per_rev: int = 1600):
    """Crank angle (rad) and wing torsion (mm) of a synthetic run: a steady forced response of
    amplitude 1 plus a start-up transient ringing at ``ring_hz`` and decaying exponentially."""
    period = 60.0 / SPEED_RPM
    t = np.arange(int(revolutions * samples_per_rev) + 1) * period / samples_per_rev
    torsion = (np.sin(2 * np.pi * FORCED_HZ * t)
               + ring_amplitude * np.exp(-decay_per_s * t) * np.sin(2 * np.pi * ring_hz * t))
    return 2 * np.pi * t / period, torsion


def test_a_steady_response_counts_as_settled():
    angle, torsion = _run(12.0, 0.0, 0.0)
    assert unsettled_change(angle, torsion) < 1e-3
    assert unsettled_message(unsettled_change(angle, torsion), 12.0, SPEED_RPM) is None


def test_a_ring_down_in_the_measuring_window_is_caught_with_its_size():
    # decaying 21 /s (the shipped model's ring-down at 750 rpm) from 100 times the forced amplitude:
    # at revolution 1.5 (the measuring window of a 3-revolution run) the transient is still
    # 100·exp(-21·0.12) = 8 times the forced response, at revolution 6 it is 100·exp(-21·0.48) = 4e-3
    for short in (3.0, 4.0, 6.0):
        # a second half under two engine cycles: its first and last engine cycles would overlap
        # (at 4 revolutions they were the same samples, and the change read 0: QA, 2026-11-28)
        angle, torsion = _run(short, 100.0, 21.0)
        assert unsettled_change(angle, torsion) is None
        assert "too short to check" in unsettled_message(None, short, SPEED_RPM)
    # ringing in phase with the forced response, the amplitude over a window is its envelope at
    # the window's start, 1 + 100·exp(-21 t): closed form to within one period's decay (7 %)
    angle, torsion = _run(8.0, 100.0, 21.0, ring_hz=FORCED_HZ)
    change = unsettled_change(angle, torsion)
    t_first, t_last = 4 * 0.08, 6 * 0.08  # start of the first and of the last engine cycle, s
    envelope_first, envelope_last = 1 + 100 * np.exp(-21 * t_first), 1 + 100 * np.exp(-21 * t_last)
    assert change == pytest.approx((envelope_first - envelope_last) / envelope_first, rel=0.07)
    assert change > SETTLED_CHANGE
    assert "not steady" in unsettled_message(change, 8.0, SPEED_RPM)
    # at another frequency it beats with the forced response, and is caught all the same
    angle, torsion = _run(8.0, 100.0, 21.0)
    assert unsettled_change(angle, torsion) > SETTLED_CHANGE
    angle, torsion = _run(12.0, 100.0, 21.0)
    assert unsettled_change(angle, torsion) < 0.01


def test_the_largest_change_over_the_counterweights_counts():
    angle, steady = _run(12.0, 0.0, 0.0)
    _, ringing = _run(6.0 * 2, 1e4, 21.0)
    both = np.vstack([steady, ringing])
    assert unsettled_change(angle, both) == pytest.approx(unsettled_change(angle, ringing))
    assert unsettled_change(angle, both) > SETTLED_CHANGE
