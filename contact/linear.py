"""Linear algebra of one Newton iteration in contact space.

The Jacobian of the contact-space residual is

    J = [[I + W·A·D,  E ],
         [−Eᵀ·A·D,   S_q]]

with A·D the block-diagonal (per point, dim × dim) consistent tangent of the contact law
times the tributary area. Points with a zero tangent (open) have identity columns, so the
system is block lower-triangular in (closed, open) rows: only the closed block is factorised.
The few control DOFs are eliminated by a small Schur complement.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as la

from contact.law import Response
from contact.structure import ContactSpace


def tangent_blocks(response: Response, area: np.ndarray) -> np.ndarray:
    """A·∂[p, τ]/∂[h, Δs] per point, (n, dim, dim) in N/mm (forces per mm of kinematics)."""
    n, n_tangent = response.shear.shape
    dim = n_tangent + 1
    blocks = np.zeros((n, dim, dim))
    blocks[:, 0, 0] = response.dpressure_dh
    blocks[:, 1:, 0] = response.dshear_dh
    blocks[:, 1:, 1:] = response.dshear_ds
    return blocks * area[:, None, None]


def solve_newton_system(space: ContactSpace, blocks: np.ndarray, r_kin: np.ndarray,
                        r_ctl: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Newton correction (Δg mm, Δq mm) for residuals r_kin (mm) and r_ctl (N)."""
    n, dim, _ = blocks.shape
    closed_points = np.flatnonzero(blocks[:, 0, 0] > 0.0)
    closed = (closed_points[:, None] * dim + np.arange(dim)).ravel()
    open_rows = np.setdiff1d(np.arange(n * dim), closed)
    W, E = space.W, space.E
    closed_blocks = blocks[closed_points]

    def apply_tangent(vectors):  # A·D on closed rows; vectors (n_closed·dim, k)
        k = vectors.shape[1]
        stacked = vectors.reshape(closed_points.size, dim, k)
        return np.einsum("pij,pjk->pik", closed_blocks, stacked).reshape(-1, k)

    m = E.shape[1]
    rhs = np.column_stack([-r_kin, -E]) if m else -r_kin[:, None]
    solution = np.zeros((n * dim, 1 + m))
    if closed.size:
        # W_cc · blockdiag(A·D): column block p of the product is W_cc[:, rows of p] @ D_p.
        product = np.einsum("rpj,pjk->rpk", W[np.ix_(closed, closed)].reshape(closed.size, -1, dim),
                            closed_blocks)
        matrix = product.reshape(closed.size, closed.size)
        matrix[np.diag_indices_from(matrix)] += 1.0
        factor = la.lu_factor(matrix, check_finite=False, overwrite_a=True)
        solution[closed] = la.lu_solve(factor, rhs[closed], check_finite=False)
    if open_rows.size:
        coupling = W[np.ix_(open_rows, closed)] @ apply_tangent(solution[closed]) if closed.size else 0.0
        solution[open_rows] = rhs[open_rows] - coupling
    if not m:
        return solution[:, 0], np.zeros(0)
    tangent_times = np.zeros((n * dim, 1 + m))
    if closed.size:
        tangent_times[closed] = apply_tangent(solution[closed])
    schur = space.Sq - E.T @ tangent_times[:, 1:]
    delta_q = np.linalg.solve(schur, -r_ctl + E.T @ tangent_times[:, 0])
    return solution[:, 0] + solution[:, 1:] @ delta_q, delta_q
