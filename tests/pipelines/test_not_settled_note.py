"""A run that ends before its contact is stationary says what to raise (QA: the user joint with
steel's rates ended 'damage (not yet stationary)' after 90 real cycles and said nothing more)."""

from pipelines.cli.main import _not_settled


def test_a_run_still_changing_at_its_end_says_what_to_raise():
    note = _not_settled({"stationary": False, "verdict": "damage", "stick_area_fraction": 0.3})
    assert note and "not yet stationary" in note and "cof_cycles" in note and "wear_cycles" in note


def test_a_settled_or_loosened_run_needs_no_such_note():
    assert _not_settled({"stationary": True, "verdict": "stick"}) is None
    assert _not_settled({"stationary": False, "verdict": "loosening"}) is None


def test_gross_slip_is_not_told_to_run_longer():
    """The cylinder slides everywhere for good (damage, no stick zone): more cycles change nothing."""
    assert _not_settled({"stationary": False, "verdict": "damage", "stick_area_fraction": 0.0}) is None
    assert _not_settled({"stationary": False, "verdict": "damage", "stick_area_fraction": 0.3}) is not None
