"""A run whose wear_cycles budget ran out before its life_cycles says so (QA: an adaptive-jump
double beam set to a life of 3e6 cycles ended after 300 blocks at 4.4e4 cycles, 1.5 % of it,
as `completed` with a verdict and nothing said)."""

from pipelines.cli.main import _short_of_life


def _summary(**figures):
    return {"verdict": "damage", "equivalent_cycles": 4.4e4, "life_cycles": 3e6, **figures}


def test_a_run_short_of_its_life_says_how_far_it_got():
    line = _short_of_life(_summary())
    assert "NOTE: the run ended at its wear_cycles budget after 4.4e+04 real cycles, 1.5% of its life_cycles (3e+06)" in line


def test_no_note_when_the_life_was_reached_or_the_run_ended_on_a_verdict():
    assert _short_of_life(_summary(equivalent_cycles=3e6)) is None
    assert _short_of_life(_summary(shakedown_at_cycles=2e4)) is None  # shook down: stick holds on
    assert _short_of_life(_summary(verdict="loosening")) is None
    assert _short_of_life({"verdict": "damage", "equivalent_cycles": 10.0}) is None  # no life set
