"""The tangent check of contact.checks sees an error in any entry type, not only the normal one."""

import numpy as np
import pytest

from contact.checks import entry_errors, finite_difference_tangent
from contact.law import ContactLaw, ContactState, evaluate

LAW = ContactLaw(normal_stiffness=4e6, critical_slip=1e-3, cof_max=0.7)


def _slipping(n=50, seed=2):
    rng = np.random.default_rng(seed)
    overclosure = 1e-4 * (1.0 + rng.random(n))
    increment = 2e-3 * rng.normal(size=(n, 2))
    state = ContactState.initial(n, 2, 0.4, n_wear_bodies=None)
    return overclosure, increment, state


@pytest.mark.parametrize("kind, entry", [("friction", (1, 2)), ("coupling", (2, 0)), ("normal", (0, 0))])
def test_a_small_error_in_one_entry_type_shows_in_that_type_only(kind, entry):
    overclosure, increment, state = _slipping()
    analytic = evaluate(overclosure, increment, state, LAW).tangent()
    numeric = finite_difference_tangent(overclosure, increment, state, LAW)
    clean = entry_errors(analytic, numeric)
    assert max(clean.values()) < 1e-6
    wrong = analytic.copy()
    i, j = entry
    wrong[7, i, j] += 1e-4 * np.abs(analytic[7, i, j]) + 1e-4 * np.abs(analytic[7][1:, 1:]).max()
    errors = entry_errors(wrong, numeric)
    assert errors[kind] > 1e-5, f"an error of 1e-4 in a {kind} entry must show"
    for other in set(errors) - {kind}:
        assert errors[other] == clean[other]
