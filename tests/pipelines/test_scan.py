"""Scan and refine finds every change of verdict, and says when the verdict is not monotone."""

import pytest

from pipelines.jobs.scan import scan


def _verdicts(changes):
    """A fake study: the verdict by amplitude (mm) from sorted (start, verdict) pieces."""
    calls = []

    def evaluate(amplitudes):
        calls.append(list(amplitudes))
        return {a: [v for start, v in changes if a >= start][-1] for a in amplitudes}
    return evaluate, calls


def test_monotone_verdicts_give_the_limit_to_the_tolerance_with_every_amplitude_run_once():
    evaluate, calls = _verdicts([(0.0, "stick"), (0.2637, "damage"), (0.31, "loosening")])
    result = scan(evaluate, 0.1, 0.4, tolerance_mm=0.005, grid=7, parallel=2)
    assert result.monotone
    assert 0.2637 <= result.limit_mm <= 0.2637 + 0.005
    assert result.stuck_below_mm < 0.2637 and result.limit_mm - result.stuck_below_mm <= 0.005
    assert [(c.verdict_below, c.verdict_above) for c in result.changes] == [("stick", "damage"),
                                                                          ("damage", "loosening")]
    assert all(c.above_mm - c.below_mm <= 0.005 for c in result.changes)
    run = [a for call in calls for a in call]
    assert len(run) == len(set(run))


def test_a_verdict_that_returns_to_stick_is_found_and_called_non_monotone():
    """The measured counterweight case: loosening at 256 µm, stick again at 300 µm."""
    evaluate, _ = _verdicts([(0.0, "stick"), (0.256, "loosening"), (0.290, "stick"), (0.35, "loosening")])
    result = scan(evaluate, 0.1, 0.4, tolerance_mm=0.01, grid=13, parallel=1)  # 25 µm apart
    assert not result.monotone
    assert 0.256 <= result.limit_mm <= 0.266
    kinds = [(c.verdict_below, c.verdict_above) for c in result.changes]
    assert kinds == [("stick", "loosening"), ("loosening", "stick"), ("stick", "loosening")]
    for change, start in zip(result.changes, (0.256, 0.290, 0.35)):
        assert change.below_mm < start <= change.above_mm


def test_an_island_narrower_than_the_grid_is_not_seen():
    """What the module says: the grid spacing is the scan's resolution."""
    evaluate, _ = _verdicts([(0.0, "stick"), (0.256, "loosening"), (0.290, "stick"), (0.35, "loosening")])
    result = scan(evaluate, 0.1, 0.4, tolerance_mm=0.01, grid=7)  # 50 µm apart: 250 and 300 µm stick
    assert result.monotone and result.limit_mm > 0.3


@pytest.mark.parametrize("pieces, limit, stuck_below", [
    ([(0.0, "damage")], 0.1, None),            # not stuck even at the lowest amplitude
    ([(0.0, "stick")], None, 0.4),             # stuck over the whole range
])
def test_ranges_that_do_not_bracket_a_change(pieces, limit, stuck_below):
    evaluate, calls = _verdicts(pieces)
    result = scan(evaluate, 0.1, 0.4, tolerance_mm=0.01, grid=4)
    assert result.limit_mm == limit and result.stuck_below_mm == stuck_below
    assert result.monotone and result.changes == [] and len(calls) == 1


def test_a_grid_of_one_is_refused():
    with pytest.raises(ValueError):
        scan(lambda a: {}, 0.1, 0.4, tolerance_mm=0.01, grid=1)


def test_the_amplitudes_run_are_the_decimals_they_stand_for():
    """A grid of 20-300 µm and its bisections run 160 and 238.75 µm, not 159.99999999999997
    and 238.75000000000003 (QA: the limit was shown as 238.7 µm, and its run differed from a
    run of the scene stated at 238.75 µm in the last digits)."""
    asked = []

    def evaluate(amplitudes):
        asked.extend(amplitudes)
        return {a: ("stick" if a < 0.2375 else "damage") for a in amplitudes}

    result = scan(evaluate, 0.02, 0.3, tolerance_mm=0.005, grid=5)
    assert asked[:5] == [0.02, 0.09, 0.16, 0.23, 0.3]
    assert all(a == float(repr(round(a, 9))) and len(repr(a)) <= 11 for a in asked)
    assert result.limit_mm == 0.23875 and result.stuck_below_mm == 0.234375
