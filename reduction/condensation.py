"""Exact static condensation (Schur complement) of a sparse stiffness onto retained DOFs.

K u = f split into retained r, interior i and fixed (held at zero, removed) DOFs:
    S = K_rr - K_ri K_ii^-1 K_ir,      f_r* = f_r - K_ri K_ii^-1 f_i,
    u_i = K_ii^-1 (f_i - K_ir u_r).
Units: stiffness N/mm, loads N, displacements mm.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.sparse as sp

from reduction.errors import InputError
from reduction import pardiso
from reduction.factorization import factorize, resolve_solver

#: columns of K_ir solved per block; bounds the dense work array to n_interior x 512 floats.
_RHS_BLOCK = 512


@dataclass(frozen=True)
class Condensation:
    """A body condensed onto its retained DOFs.

    retained: (n_r,) DOF indices into the condensed matrix, in the order of the rows of ``stiffness``.
    stiffness: (n_r, n_r) dense symmetric Schur complement, N/mm.
    loads: condensed load vectors (n_r,), N, by name.
    interior: DOFs eliminated; fixed: DOFs held at zero.
    solver: name of the sparse factorisation used.
    """

    retained: np.ndarray
    stiffness: np.ndarray
    loads: dict[str, np.ndarray]
    interior: np.ndarray
    fixed: np.ndarray
    n_dofs: int
    solver: str
    interior_load_response: dict[str, np.ndarray] = field(repr=False)
    interior_retained_coupling: sp.csr_matrix = field(repr=False)
    solve_interior: Callable[[np.ndarray], np.ndarray] = field(repr=False, compare=False)

    def expand(self, retained_displacement, load_factors: dict[str, float] | None = None) -> np.ndarray:
        """Full displacement vector (mm), shape (n,) or (n, m) for (n_r,) or (n_r, m) input.

        load_factors scale the named condensed loads that act together with the retained
        displacements (the interior part of those loads is recovered exactly).
        """
        u_r = np.asarray(retained_displacement, dtype=float)
        if u_r.shape[0] != self.retained.size:
            raise InputError(
                f"retained displacement has {u_r.shape[0]} entries, the condensation retains {self.retained.size} DOFs"
            )
        u = np.zeros((self.n_dofs,) + u_r.shape[1:])
        u[self.retained] = u_r
        if self.interior.size:
            u_i = -self.solve_interior(self.interior_retained_coupling @ u_r)
            for name, factor in (load_factors or {}).items():
                if name not in self.interior_load_response:
                    raise InputError(f"load '{name}' was not condensed; known loads: {sorted(self.loads)}")
                response = self.interior_load_response[name]
                u_i = u_i + factor * (response if u_r.ndim == 1 else response[:, None])
            u[self.interior] = u_i
        return u


def as_dof_index(dofs, n_dofs: int, label: str) -> np.ndarray:
    index = np.asarray(dofs, dtype=np.int64).ravel()
    if index.size and (index.min() < 0 or index.max() >= n_dofs):
        raise InputError(f"{label} DOF index out of range 0..{n_dofs - 1}")
    if np.unique(index).size != index.size:
        raise InputError(f"{label} DOFs contain duplicates")
    return index


def condense(stiffness, retained, fixed=(), loads=None, *, solver: str = "auto") -> Condensation:
    """Condense a sparse symmetric stiffness (N/mm) exactly onto the retained DOFs.

    retained: DOF indices kept (any order; the result follows it). fixed: DOFs held at zero.
    loads: named full load vectors (n,), N. solver: "auto" (fastest installed), "pardiso", "cholmod" or "splu".
    The interior block K_ii must be non-singular: retained plus fixed DOFs must stop every
    rigid-body motion of the interior. Otherwise InputError, raised here or, with PARDISO (whose
    Schur complement is still right then), at the first interior solve (loads, ``expand``).
    """
    matrix = sp.csr_matrix(stiffness)
    n_dofs = matrix.shape[0]
    if matrix.shape != (n_dofs, n_dofs):
        raise InputError(f"stiffness must be square, got shape {matrix.shape}")
    retained = as_dof_index(retained, n_dofs, "retained")
    fixed = as_dof_index(fixed, n_dofs, "fixed")
    if np.intersect1d(retained, fixed).size:
        raise InputError("a DOF is both retained and fixed")
    loads = {} if loads is None else dict(loads)
    for name, vector in loads.items():
        if np.shape(vector) != (n_dofs,):
            raise InputError(f"load '{name}' must have shape ({n_dofs},), got {np.shape(vector)}")

    is_interior = np.ones(n_dofs, dtype=bool)
    is_interior[retained] = False
    is_interior[fixed] = False
    interior = np.flatnonzero(is_interior)

    solver = resolve_solver(solver)
    k_ir = matrix[interior][:, retained].tocsc()
    loads = {name: np.asarray(vector, dtype=float) for name, vector in loads.items()}
    condensed_loads = {name: vector[retained].copy() for name, vector in loads.items()}
    responses: dict[str, np.ndarray] = {}
    solve = _no_interior
    if not interior.size:
        schur = matrix[retained][:, retained].toarray()
    else:
        k_ii = matrix[interior][:, interior]
        solve = lazy_interior_solver(k_ii, solver)
        if solver == "pardiso":
            kept = np.concatenate([retained, interior])
            schur = pardiso.schur_complement(
                matrix[kept][:, kept], np.arange(retained.size), label="interior stiffness K_ii"
            )
        else:
            schur = _schur_complement(matrix[retained][:, retained].toarray(), k_ir, solve)
        if loads:
            responses = dict(zip(loads, solve(np.column_stack([v[interior] for v in loads.values()])).T))
            for name in loads:
                condensed_loads[name] -= k_ir.T @ responses[name]
            if solver == "pardiso":
                solve.release()
    return Condensation(
        retained=retained,
        stiffness=0.5 * (schur + schur.T),
        loads=condensed_loads,
        interior=interior,
        fixed=fixed,
        n_dofs=n_dofs,
        solver=solver if interior.size else "none",
        interior_load_response=responses,
        interior_retained_coupling=k_ir.tocsr(),
        solve_interior=solve,
    )


class InteriorSolver:
    """K_ii^-1 b, factorising on first use: a PARDISO Schur complement alone does not need it.

    :meth:`release` frees the factor (a 3D body of 400k DOFs holds gigabytes in it); the next
    solve factorises again. Condensation releases it once the loads are condensed, so that a
    run does not carry every body's factor for the few field expansions at its end.
    """

    def __init__(self, k_ii: sp.csr_matrix, solver: str):
        self.k_ii, self.solver = k_ii, solver
        self._factor = None

    def __call__(self, rhs: np.ndarray) -> np.ndarray:
        if self._factor is None:
            self._factor = factorize(self.k_ii, solver=self.solver, label="interior stiffness K_ii")
        return self._factor.solve(rhs)

    def release(self) -> None:
        self._factor = None


def lazy_interior_solver(k_ii: sp.csr_matrix, solver: str, *, eager: bool | None = None) -> InteriorSolver:
    """An :class:`InteriorSolver` for K_ii. eager (default: unless PARDISO) factorises at once,
    so a singular K_ii is reported at once."""
    solve = InteriorSolver(k_ii, solver)
    if eager is None:
        eager = solver != "pardiso"
    if eager:
        solve(np.zeros(k_ii.shape[0]))  # factorise now so a singular K_ii is reported at once
    return solve


def _no_interior(rhs: np.ndarray) -> np.ndarray:
    return np.zeros((0,) + rhs.shape[1:])


def _schur_complement(k_rr: np.ndarray, k_ir: sp.csc_matrix, solve) -> np.ndarray:
    """K_rr - K_ri K_ii^-1 K_ir, solving for blocks of columns of K_ir."""
    schur = k_rr.copy()
    k_ri = k_ir.T.tocsr()
    for start in range(0, k_ir.shape[1], _RHS_BLOCK):
        block = slice(start, start + _RHS_BLOCK)
        schur[:, block] -= k_ri @ solve(k_ir[:, block].toarray())
    return schur
