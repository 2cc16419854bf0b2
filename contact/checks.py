"""Numerical checks of the contact law, shared by the tests and ``fretwork validate``."""

from __future__ import annotations

import numpy as np

from contact.law import ContactLaw, ContactState, evaluate


def finite_difference_tangent(overclosure: np.ndarray, slip_increment: np.ndarray, state: ContactState,
                              law: ContactLaw, step: float = 1e-9) -> np.ndarray:
    """Central differences of [p, τ] with respect to [h, Δs] (step in mm), (n, dim, dim)."""
    n, n_tangent = slip_increment.shape
    jac = np.zeros((n, 1 + n_tangent, 1 + n_tangent))
    for column in range(1 + n_tangent):
        dh, ds = np.zeros(n), np.zeros((n, n_tangent))
        if column == 0:
            dh[:] = step
        else:
            ds[:, column - 1] = step
        plus = evaluate(overclosure + dh, slip_increment + ds, state, law)
        minus = evaluate(overclosure - dh, slip_increment - ds, state, law)
        jac[:, 0, column] = (plus.pressure - minus.pressure) / (2 * step)
        jac[:, 1:, column] = (plus.shear - minus.shear) / (2 * step)
    return jac


def tangent_error(overclosure, slip_increment, state, law, step: float = 1e-9) -> float:
    """Largest per-point relative difference between the consistent and the FD tangent."""
    analytic = evaluate(overclosure, slip_increment, state, law).tangent()
    numeric = finite_difference_tangent(overclosure, slip_increment, state, law, step)
    scale = np.maximum(np.abs(analytic).max(axis=(1, 2)), 1e-300)[:, None, None]
    return float(np.max(np.abs(numeric - analytic) / scale))
