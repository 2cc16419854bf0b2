"""The adaptive cycle jump against the closed form of wear that relieves its own pressure.

A sliding point at the edge of a large stuck zone (which carries the load at the mean
pressure p̄ = P0 and barely notices the edge) is pressed by a spring, p = P0 − k·r with
k ≤ kn, and slides s per cycle. Archard, dr/dN = w·s·p, gives p(N) = P0·exp(−w·s·k·N) and
r(N) = (P0/k)·(1 − exp(−w·s·k·N)). Blocks of J cycles integrate it explicitly, as the wear
phase does.
"""

import math

import numpy as np
import pytest

from contact.cycle_jump import AdaptiveJump, next_jump, wear_rate

KN = 1e6  # N/mm³, the penalty stiffness
P0 = 200.0  # MPa
SLIP = 2e-3  # mm of irreversible slip per cycle
STEEL = 3e-8  # mm²/N


def _closed_form(cycles, w, k):
    return P0 / k * (1.0 - math.exp(-w * SLIP * k * cycles))


def _blocks(total, w, k, jumps):
    """Explicit blocks up to ``total`` cycles; ``jumps(rate, previous)`` → next J.
    Returns the final wear (mm), the number of blocks and (cycles, wear) after each block."""
    r, done, jump, count, history = 0.0, 0.0, None, 0, []
    while done < total:
        rate = w * SLIP * max(P0 - k * r, 0.0)
        jump = min(jumps(rate, jump), total - done)
        r += jump * rate
        done += jump
        count += 1
        history.append((done, r))
    return r, count, np.array(history)


def _adaptive(settings):
    return lambda rate, previous: (settings.initial if previous is None else
                                   next_jump(np.array([rate]), P0, KN, previous, settings))


def test_adaptive_blocks_follow_the_closed_form_to_engine_lives():
    settings = AdaptiveJump(tolerance=0.05)
    k = 0.3 * KN  # the bodies in series soften the penalty
    total = 2e7  # cycles: 7.4 h at 750 rpm, 1 load cycle a revolution
    r, blocks, history = _blocks(total, STEEL, k, _adaptive(settings))
    assert r == pytest.approx(_closed_form(total, STEEL, k), rel=0.03)
    exact = np.array([_closed_form(n, STEEL, k) for n, _ in history])
    assert np.all(np.abs(history[:, 1] - exact) <= 0.03 * exact)  # on the way, too
    assert blocks < 400  # a few hundred simulated cycles stand for twenty million


def test_adaptive_blocks_match_a_fixed_small_jump_reference():
    """The issue's check: the adaptive answer against fixed J = 10 at a 100x accelerated wear."""
    w, k, total = 100 * STEEL, 0.5 * KN, 2e5
    reference, fixed_blocks, _ = _blocks(total, w, k, lambda rate, previous: 10.0)
    adaptive, blocks, _ = _blocks(total, w, k, _adaptive(AdaptiveJump(tolerance=0.05)))
    assert adaptive == pytest.approx(reference, rel=0.03)
    assert blocks < fixed_blocks / 20


def test_a_fixed_jump_past_the_stability_bound_wears_through_where_the_adaptive_one_does_not():
    w, k = 100 * STEEL, KN
    unstable_jump = 2.5 / (w * SLIP * k)  # J·w·s·k = 2.5 > 2: explicit Euler overshoots
    total = 4 * unstable_jump
    fixed, _, _ = _blocks(total, w, k, lambda rate, previous: unstable_jump)
    adaptive, _, history = _blocks(total, w, k, _adaptive(AdaptiveJump(tolerance=0.05)))
    exact = _closed_form(total, w, k)
    assert fixed > 1.4 * P0 / k  # worn 150 % through the overclosure: the contact opens
    assert adaptive == pytest.approx(exact, rel=0.03)
    # once its pressure is far below p̄ a point may overshoot, by at most θ·p̄/kn of gap
    assert np.all(history[:, 1] <= P0 / k + 0.05 * P0 / KN)


def test_jump_grows_at_most_by_the_growth_factor_and_respects_its_bounds():
    settings = AdaptiveJump(tolerance=0.05, initial=1.0, growth=2.0, maximum=1e4)
    tiny = np.array([1e-20, 0.0])
    assert next_jump(tiny, 100.0, KN, previous=8.0, settings=settings) == 16.0
    assert next_jump(tiny, 100.0, KN, previous=8e3, settings=settings) == 1e4
    assert next_jump(np.zeros(2), 100.0, KN, previous=3.0, settings=settings) == 6.0  # nothing wears
    fast = np.array([1e-3, 0.0])  # kn·ṙ = 1000 MPa per cycle: even J = 1 is too much, J stays 1
    assert next_jump(fast, 100.0, KN, previous=4.0, settings=settings) == 1.0
    # allowed = θ·p̄/(kn·ṙ) exactly, per-point kn honoured
    rate = np.array([1e-9, 2e-9])
    assert next_jump(rate, 100.0, np.array([KN, 0.5 * KN]), previous=1e6, settings=AdaptiveJump()) == \
        pytest.approx(0.05 * 100.0 / (KN * 1e-9))
    assert np.array_equal(wear_rate(np.array([4e-6, 2e-6]), 2.0), [2e-6, 1e-6])


@pytest.mark.parametrize("bad", [{"tolerance": 0.0}, {"initial": 0.5}, {"growth": 0.9},
                                 {"initial": 10.0, "maximum": 5.0}])
def test_bad_settings_are_refused(bad):
    with pytest.raises(ValueError):
        AdaptiveJump(**bad)
