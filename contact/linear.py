"""Linear algebra of one Newton iteration in contact space.

The Jacobian of the contact-space residual is

    J = [[I + W·A·D,  E ],
         [−Eᵀ·A·D,   S_q]]

with A·D the block-diagonal (per point, dim × dim) consistent tangent of the contact law
times the tributary area. Points with a zero tangent (open) have identity columns, so the
system is block lower-triangular in (closed, open) rows: only the closed block, bordered by
the few control DOFs, has to be solved; the open rows follow by one product.

Small closed blocks are factorised directly (dense LU). Large ones are solved by GMRES
preconditioned with a dense single-precision LU of an earlier Jacobian, kept across Newton
iterations and increments: between them the closed set rarely changes and the tangent
changes little, so a few Krylov iterations (each one product with W and one triangular
solve) replace an O(n³) factorisation. The factor is rebuilt when points close that it does
not cover, or when the Krylov work lost to its age exceeds what the last rebuild cost. Work
is counted in floating-point operations, not measured in seconds: a policy driven by the
clock would make the preconditioner, and so the last digits of every result, depend on
the machine's load. The
Newton correction is exact up to the GMRES tolerance; the converged equilibrium is set by
the solver's residual test, not by this module (the condensed-versus-full test checks it).
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np
import scipy.linalg as la

from contact.law import Response
from contact.structure import ContactSpace


def tangent_blocks(response: Response, area: np.ndarray) -> np.ndarray:
    """A·∂[p, τ]/∂[h, Δs] per point, (n, dim, dim) in N/mm (forces per mm of kinematics)."""
    return response.tangent() * area[:, None, None]


@dataclass(frozen=True)
class KrylovSettings:
    """When the iterative path is used and how hard it works.

    direct_below: closed rows below which the closed block is factorised every iteration.
    relative_tolerance: GMRES stops at ‖J·x − b‖ ≤ this × ‖b‖ (rows in mm).
    fresh_iterations: Krylov iterations a solve needs with a fresh preconditioner. Every
        iteration beyond it is work lost to an aged one; once that lost work exceeds what the
        last rebuild cost, the preconditioner is rebuilt for the next solve (pay for a
        rebuild only after having wasted as much: never worse than twice the best policy).
        Both are counted in flops, not seconds, so that the policy, and the last digits of
        the results, do not depend on the machine's load.
    max_iterations: Krylov space size; if GMRES has not converged by then, the
        preconditioner is rebuilt from the current tangent and the solve repeated.
    single_precision: factorise the preconditioner and multiply by W in float32 inside
        GMRES (half the memory traffic; 1e-7 relative error, far below the Krylov tolerance);
        the Krylov vectors and the solver's residuals stay float64.
    """

    direct_below: int = 300
    relative_tolerance: float = 1e-3
    fresh_iterations: int = 3
    max_iterations: int = 40
    single_precision: bool = True


@dataclass
class KrylovCounters:
    """What the iterative path did, for benchmarks: solves, Krylov iterations, factorisations."""

    solves: int = 0
    krylov_iterations: int = 0
    factorisations: int = 0
    direct_solves: int = 0


class NewtonLinearSolver:
    """Newton corrections for one :class:`ContactSpace`, keeping a preconditioner between calls."""

    def __init__(self, space: ContactSpace, settings: KrylovSettings = KrylovSettings()):
        self.space = space
        self.settings = settings
        self.counters = KrylovCounters()
        self._control_scale = np.ones(space.n_control)
        self._closed_key: np.ndarray | None = None
        self._W_closed: np.ndarray | None = None
        self._W_closed_rows: np.ndarray | None = None
        self._factor = None
        self._stale = True
        self._rebuild_work = 0.0
        self._lost_work = 0.0

    def solve(self, blocks: np.ndarray, r_kin: np.ndarray, r_ctl: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Newton correction (Δg mm, Δq mm) for residuals r_kin (mm) and r_ctl (N)."""
        n, dim, _ = blocks.shape
        closed_points = np.flatnonzero(blocks[:, 0, 0] > 0.0)
        if closed_points.size * dim < self.settings.direct_below:
            closed = (closed_points[:, None] * dim + np.arange(dim)).ravel()
            self.counters.direct_solves += 1
            return _direct(self.space, blocks, closed_points, closed, r_kin, r_ctl)
        # Rows of open points may stay in the system: their tangent is zero, so their columns
        # are the identity and the equations stay exact. Solving on the points the
        # preconditioner was built for keeps it usable when points open.
        reference = self._closed_key
        refactor = self._stale or reference is None or not np.isin(closed_points, reference).all()
        if refactor:
            grown = closed_points if reference is None else np.union1d(reference, closed_points)
            # Keep the old points only while that costs little: a contact zone that moves
            # away should not drag all its history along.
            working = grown if grown.size <= 1.25 * closed_points.size else closed_points
        else:
            working = reference
        closed = (working[:, None] * dim + np.arange(dim)).ravel()
        space = self.space
        closed_blocks = blocks[working]
        W_cc = self._closed_compliance(closed)
        E_c = space.E[closed]

        def apply_tangent(x):
            return np.einsum("pij,pj->pi", closed_blocks, x.reshape(-1, dim)).ravel()

        def matvec(x):
            x_c, x_q = x[:closed.size], x[closed.size:]
            tangent_x = apply_tangent(x_c)
            top = x_c + W_cc @ tangent_x.astype(W_cc.dtype) + E_c @ x_q
            return np.concatenate([top, self._control_scale * (space.Sq @ x_q - E_c.T @ tangent_x)])

        def krylov():
            rhs = np.concatenate([-r_kin[closed], -self._control_scale * r_ctl])
            return _gmres(matvec, self._precondition, rhs, self.settings.relative_tolerance,
                          self.settings.max_iterations)

        if refactor:
            self._refactor(working, closed_blocks, W_cc, E_c)
        solution, iterations = krylov()
        if solution is not None and iterations > self.settings.fresh_iterations:
            aged = iterations - self.settings.fresh_iterations
            self._lost_work += aged * _krylov_iteration_flops(closed.size + space.n_control)
        if solution is None:
            self._refactor(working, closed_blocks, W_cc, E_c)
            solution, more = krylov()
            iterations += more
            if solution is None:
                raise np.linalg.LinAlgError("GMRES did not converge with a fresh preconditioner")
        self._stale = self._lost_work > self._rebuild_work
        self.counters.solves += 1
        self.counters.krylov_iterations += iterations
        delta_q = solution[closed.size:]
        delta_g = np.empty(n * dim)
        delta_g[closed] = solution[:closed.size]
        if closed.size < n * dim:
            open_rows = np.setdiff1d(np.arange(n * dim), closed)
            contact_force = np.zeros(n * dim)
            contact_force[closed] = apply_tangent(solution[:closed.size])
            delta_g[open_rows] = (-r_kin[open_rows] - (space.W @ contact_force)[open_rows]
                                  - space.E[open_rows] @ delta_q)
        return delta_g, delta_q

    def _closed_compliance(self, closed: np.ndarray) -> np.ndarray:
        """W on the closed rows, in the Krylov working precision; cached while they stay closed."""
        if self._W_closed is None or not np.array_equal(self._W_closed_rows, closed):
            W = self.space.W
            dtype = np.float32 if self.settings.single_precision else np.float64
            all_closed = closed.size == W.shape[0]
            self._W_closed = None  # free the old copy before making the new one
            self._W_closed = (W if all_closed else W[np.ix_(closed, closed)]).astype(dtype, copy=False)
            self._W_closed_rows = closed
        return self._W_closed

    def _refactor(self, closed_points, closed_blocks, W_cc, E_c) -> None:
        """Dense LU of the bordered closed Jacobian, scaled control rows, built in Fortran order."""
        dtype = np.float32 if self.settings.single_precision else np.float64
        n_c, m = W_cc.shape[0], self.space.n_control
        dim = closed_blocks.shape[1]
        matrix = np.empty((n_c + m, n_c + m), dtype=dtype, order="F")
        # W·blockdiag(D) = (blockdiag(Dᵀ)·W)ᵀ since W is symmetric: the row-block product is
        # contiguous, and its transpose is the Fortran-ordered array LAPACK factorises in place.
        transposed = matrix.T
        np.matmul(closed_blocks.transpose(0, 2, 1).astype(dtype),
                  W_cc.astype(dtype, copy=False).reshape(-1, dim, n_c),
                  out=transposed[:n_c, :n_c].reshape(-1, dim, n_c))
        transposed[np.diag_indices(n_c)] += 1.0
        # Eᵀ·blockdiag(D) = (blockdiag(Dᵀ)·E)ᵀ
        tangent_E = np.einsum("pji,pjm->pim", closed_blocks, E_c.reshape(-1, dim, m)).reshape(n_c, m)
        # Control rows are forces (N). S_q alone may vanish (a body floating until it touches),
        # so they are divided by the stiffness the closed contacts give each control DOF,
        # diag(Eᵀ·A·D·E) + |diag(S_q)|: then they read as mm like the kinematic rows. The floor
        # keeps a DOF that no contact holds yet (tangential, before any pressure) well scaled.
        stiffness = np.abs(np.einsum("rm,rm->m", E_c, tangent_E)) + np.abs(np.diag(self.space.Sq))
        floor = 1e-3 * stiffness.max(initial=0.0)
        self._control_scale = 1.0 / (np.maximum(stiffness, floor) if floor > 0.0 else np.ones(m))
        matrix[:n_c, n_c:] = E_c
        matrix[n_c:, :n_c] = -(self._control_scale[:, None] * tangent_E.T)
        matrix[n_c:, n_c:] = self._control_scale[:, None] * self.space.Sq
        self._factor = la.lu_factor(matrix, overwrite_a=True, check_finite=False)
        self._closed_key = closed_points
        self._stale = False
        self._rebuild_work = _rebuild_flops(n_c + m)
        self._lost_work = 0.0
        self.counters.factorisations += 1

    def _precondition(self, vector: np.ndarray) -> np.ndarray:
        lu, pivots = self._factor
        return la.lu_solve((lu, pivots), vector.astype(lu.dtype), check_finite=False).astype(float)


def _krylov_iteration_flops(size: int) -> float:
    """One preconditioned Krylov iteration on ``size`` rows: a product with the dense
    Jacobian and two triangular solves, each about 2·size² flops."""
    return 4.0 * size**2


def _rebuild_flops(size: int) -> float:
    """Forming (2·size²·dim, bounded by 6·size²) and LU-factorising (2/3·size³) the dense
    bordered Jacobian of ``size`` rows."""
    return 2.0 / 3.0 * size**3 + 6.0 * size**2


def _gmres(matvec, precondition, rhs: np.ndarray, tolerance: float, max_iterations: int):
    """Right-preconditioned GMRES from zero; (solution, iterations), solution None if not converged."""
    beta = float(np.linalg.norm(rhs))
    if beta == 0.0:
        return np.zeros_like(rhs), 0
    basis = np.empty((max_iterations + 1, rhs.size))
    directions = np.empty((max_iterations, rhs.size))
    hessenberg = np.zeros((max_iterations + 1, max_iterations))
    cosines, sines = np.zeros(max_iterations), np.zeros(max_iterations)
    residual = np.zeros(max_iterations + 1)
    residual[0] = beta
    basis[0] = rhs / beta
    for j in range(max_iterations):
        directions[j] = precondition(basis[j])
        w = matvec(directions[j])
        # Classical Gram-Schmidt twice: two BLAS products instead of j vector operations.
        for _ in range(2):
            h = basis[:j + 1] @ w
            w -= basis[:j + 1].T @ h
            hessenberg[:j + 1, j] += h
        hessenberg[j + 1, j] = np.linalg.norm(w)
        if hessenberg[j + 1, j] > 0.0:
            basis[j + 1] = w / hessenberg[j + 1, j]
        for i in range(j):
            upper = cosines[i] * hessenberg[i, j] + sines[i] * hessenberg[i + 1, j]
            hessenberg[i + 1, j] = -sines[i] * hessenberg[i, j] + cosines[i] * hessenberg[i + 1, j]
            hessenberg[i, j] = upper
        radius = np.hypot(hessenberg[j, j], hessenberg[j + 1, j])
        cosines[j], sines[j] = hessenberg[j, j] / radius, hessenberg[j + 1, j] / radius
        hessenberg[j, j], hessenberg[j + 1, j] = radius, 0.0
        residual[j + 1] = -sines[j] * residual[j]
        residual[j] *= cosines[j]
        if abs(residual[j + 1]) <= tolerance * beta:
            k = j + 1
            coefficients = la.solve_triangular(hessenberg[:k, :k], residual[:k], check_finite=False)
            return directions[:k].T @ coefficients, k
    return None, max_iterations


def _direct(space: ContactSpace, blocks, closed_points, closed, r_kin, r_ctl):
    """Dense LU of the closed block every iteration, control DOFs by a small Schur complement."""
    n, dim, _ = blocks.shape
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
        W_cc = W[np.ix_(closed, closed)]
        matrix = np.empty((closed.size, closed.size), order="F")
        np.matmul(closed_blocks.transpose(0, 2, 1), W_cc.reshape(-1, dim, closed.size),
                  out=matrix.T.reshape(-1, dim, closed.size))
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


_solvers: "weakref.WeakKeyDictionary[ContactSpace, NewtonLinearSolver]" = weakref.WeakKeyDictionary()


def solver_for(space: ContactSpace) -> NewtonLinearSolver:
    """The linear solver attached to ``space`` (created on first use, freed with the space)."""
    solver = _solvers.get(space)
    if solver is None:
        solver = _solvers[space] = NewtonLinearSolver(space)
    return solver


def attach(space: ContactSpace, settings: KrylovSettings) -> NewtonLinearSolver:
    """Use ``settings`` for every Newton solve on ``space`` from now on; returns the new solver."""
    solver = _solvers[space] = NewtonLinearSolver(space, settings)
    return solver


def solve_newton_system(space: ContactSpace, blocks: np.ndarray, r_kin: np.ndarray,
                        r_ctl: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Newton correction (Δg mm, Δq mm) for residuals r_kin (mm) and r_ctl (N)."""
    return solver_for(space).solve(blocks, r_kin, r_ctl)
