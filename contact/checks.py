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


ENTRY_TYPES = ("normal", "friction", "coupling")


def entry_errors(analytic: np.ndarray, numeric: np.ndarray) -> dict:
    """Largest relative difference of two tangents (n, dim, dim) per entry type.

    normal: ∂p/∂h; friction: ∂τ/∂Δs; coupling: ∂τ/∂h and ∂p/∂Δs. Each type is measured against
    its own size at each point (the largest analytic entry of that type there, at least 1e-12 of
    the point's largest entry), so that the round-off of the stiff normal entry (kn ≈ 1e6 N/mm³)
    does not hide an error in the friction or coupling entries, which are 1e3 times smaller.
    """
    masks = {"normal": np.zeros(analytic.shape[1:], dtype=bool), "friction": np.zeros(analytic.shape[1:], dtype=bool)}
    masks["normal"][0, 0] = True
    masks["friction"][1:, 1:] = True
    masks["coupling"] = ~(masks["normal"] | masks["friction"])
    floor = 1e-12 * np.abs(analytic).max(axis=(1, 2))
    out = {}
    for name in ENTRY_TYPES:
        a, d = analytic[:, masks[name]], (numeric - analytic)[:, masks[name]]
        scale = np.maximum(np.maximum(np.abs(a).max(axis=1), floor), 1e-300)
        out[name] = float(np.max(np.abs(d).max(axis=1) / scale))
    return out


def tangent_errors(overclosure, slip_increment, state, law, step: float = 1e-9) -> dict:
    """Consistent against finite-difference tangent, per entry type (:func:`entry_errors`)."""
    analytic = evaluate(overclosure, slip_increment, state, law).tangent()
    numeric = finite_difference_tangent(overclosure, slip_increment, state, law, step)
    return entry_errors(analytic, numeric)


def tangent_error(overclosure, slip_increment, state, law, step: float = 1e-9) -> float:
    """The largest of :func:`tangent_errors` over the entry types."""
    return max(tangent_errors(overclosure, slip_increment, state, law, step).values())
