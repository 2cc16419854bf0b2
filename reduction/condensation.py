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
import scipy.linalg
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
    interior_loads: dict[str, np.ndarray] = field(repr=False)
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
            rhs = -(self.interior_retained_coupling @ u_r)
            for name, factor in (load_factors or {}).items():
                if name not in self.interior_loads:
                    raise InputError(f"load '{name}' was not condensed; known loads: {sorted(self.loads)}")
                load = self.interior_loads[name]
                rhs = rhs + factor * (load if u_r.ndim == 1 else load[:, None])
            u[self.interior] = self.solve_interior(rhs)
        return u


def as_dof_index(dofs, n_dofs: int, label: str) -> np.ndarray:
    index = np.asarray(dofs, dtype=np.int64).ravel()
    if index.size and (index.min() < 0 or index.max() >= n_dofs):
        raise InputError(f"{label} DOF index out of range 0..{n_dofs - 1}")
    if np.unique(index).size != index.size:
        raise InputError(f"{label} DOFs contain duplicates")
    return index


@dataclass(frozen=True)
class BoundarySchur:
    """A body's stiffness condensed exactly onto a boundary set B, with its loads: the one
    sparse factorisation of the body, from which every problem that differs from another only
    on B is answered by dense algebra (the static condensation onto any subset of B, couplings
    of B's nodes, a clamped load case with read-outs on B).

    boundary: (n_B,) DOF indices, sorted. stiffness: (n_B, n_B) dense Schur complement
    K_BB − K_BI K_II^-1 K_IB, N/mm. loads: name → condensed load f_B − K_BI K_II^-1 f_I (n_B,), N.
    fixed: DOFs held at zero (removed). n_dofs: size of K. solver: the factorisation used.
    """

    boundary: np.ndarray
    stiffness: np.ndarray
    loads: dict[str, np.ndarray]
    fixed: np.ndarray
    n_dofs: int
    solver: str

    def clamped_response(self, clamped, load: str) -> np.ndarray:
        """Displacements (n_B,) mm on the boundary of the body loaded by ``load`` with the boundary
        DOFs ``clamped`` (a subset of it) and the fixed DOFs held, the rest of B free: exact."""
        held = np.isin(self.boundary, clamped)
        if held.sum() != np.unique(clamped).size:
            raise InputError("clamped DOFs must lie on the condensation boundary")
        free = np.flatnonzero(~held)
        u = np.zeros(self.boundary.size)
        u[free] = scipy.linalg.solve(self.stiffness[np.ix_(free, free)], self.loads[load][free], assume_a="pos")
        return u


def boundary_schur(stiffness, boundary, fixed=(), loads=None, *, solver: str = "auto") -> BoundarySchur:
    """Condense a sparse symmetric stiffness (N/mm) exactly onto ``boundary`` with its loads (N),
    by ONE factorisation of the interior block K_II (see :class:`BoundarySchur`).

    With PARDISO the loads are extra bordered rows of the partially factorised matrix
    [[K, F], [Fᵀ, I]]: their block of the Schur complement is the condensed loads, so nothing
    is solved with K_II afterwards and its factor is released at once. Other solvers factorise
    K_II once and solve for the boundary columns and the loads with that factor. The
    interior must be non-singular (InputError otherwise).
    """
    matrix = sp.csr_matrix(stiffness)
    n_dofs = matrix.shape[0]
    if matrix.shape != (n_dofs, n_dofs):
        raise InputError(f"stiffness must be square, got shape {matrix.shape}")
    boundary = np.sort(as_dof_index(boundary, n_dofs, "retained"))
    fixed = as_dof_index(fixed, n_dofs, "fixed")
    if np.intersect1d(boundary, fixed).size:
        raise InputError("a DOF is both retained and fixed")
    loads = {name: np.asarray(vector, dtype=float) for name, vector in (loads or {}).items()}
    for name, vector in loads.items():
        if vector.shape != (n_dofs,):
            raise InputError(f"load '{name}' must have shape ({n_dofs},), got {vector.shape}")
    is_interior = np.ones(n_dofs, dtype=bool)
    is_interior[boundary] = False
    is_interior[fixed] = False
    interior = np.flatnonzero(is_interior)
    solver = resolve_solver(solver)
    if not interior.size:
        schur = matrix[boundary][:, boundary].toarray()
        condensed = {name: vector[boundary].copy() for name, vector in loads.items()}
        return BoundarySchur(boundary, schur, condensed, fixed, n_dofs, "none")
    if solver == "pardiso":
        schur, condensed = _pardiso_boundary(matrix, interior, boundary, loads)
    else:
        schur, condensed = _factor_boundary(matrix, interior, boundary, loads, solver)
    _symmetrise(schur)
    return BoundarySchur(boundary, schur, condensed, fixed, n_dofs, solver)


def _pardiso_boundary(matrix: sp.csr_matrix, interior, boundary, loads: dict):
    """PARDISO Schur complement of [[K, F], [Fᵀ, I]] onto (boundary, load rows): (S, loads)."""
    kept = np.concatenate([interior, boundary])
    block = matrix[kept][:, kept]
    if loads:
        columns = sp.csr_matrix(np.column_stack([vector[kept] for vector in loads.values()]))
        block = sp.bmat([[block, columns], [columns.T, sp.identity(len(loads))]], format="csr")
    rows = np.arange(interior.size, block.shape[0])
    full = pardiso.schur_complement(block, rows, label="interior stiffness K_ii")
    n_b = boundary.size
    condensed = {name: full[:n_b, n_b + k].copy() for k, name in enumerate(loads)}
    if not loads:
        return full, condensed
    schur = np.array(full[:n_b, :n_b])  # the bordered rows are dropped: one (n_B, n_B) copy
    del full
    return schur, condensed


def _factor_boundary(matrix: sp.csr_matrix, interior, boundary, loads: dict, solver: str):
    """S and condensed loads with one factor of K_II (blocks of boundary columns solved with it)."""
    solve = lazy_interior_solver(matrix[interior][:, interior], solver, eager=True)
    k_ib = matrix[interior][:, boundary].tocsc()
    schur = _schur_complement(matrix[boundary][:, boundary].toarray(), k_ib, solve)
    condensed = {}
    if loads:
        responses = solve(np.column_stack([v[interior] for v in loads.values()]))
        condensed = {name: vector[boundary] - k_ib.T @ responses[:, k]
                     for k, (name, vector) in enumerate(loads.items())}
    return schur, condensed


def _symmetrise(a: np.ndarray, block: int = 1024) -> None:
    """a ← (a + aᵀ)/2 in place, block by block (no second (n, n) array)."""
    n = a.shape[0]
    for i in range(0, n, block):
        for j in range(i, n, block):
            mean = 0.5 * (a[i:i + block, j:j + block] + a[j:j + block, i:i + block].T)
            a[i:i + block, j:j + block] = mean
            a[j:j + block, i:i + block] = mean.T


def condense(stiffness, retained, fixed=(), loads=None, *, solver: str = "auto") -> Condensation:
    """Condense a sparse symmetric stiffness (N/mm) exactly onto the retained DOFs.

    retained: DOF indices kept (any order; the result follows it). fixed: DOFs held at zero.
    loads: named full load vectors (n,), N. solver: "auto" (fastest installed), "pardiso", "cholmod" or "splu".
    One factorisation (:func:`boundary_schur`). The interior block K_ii must be non-singular:
    retained plus fixed DOFs must stop every rigid-body motion of the interior. Otherwise
    InputError, raised here or, with PARDISO (whose Schur complement is still right then), at
    the first interior solve (``expand``).
    """
    matrix = sp.csr_matrix(stiffness)
    retained = as_dof_index(retained, matrix.shape[0], "retained")
    schur = boundary_schur(matrix, retained, fixed, loads, solver=solver)
    order = np.searchsorted(schur.boundary, retained)  # the boundary is sorted, retained any order
    stiffness_r = schur.stiffness if np.array_equal(order, np.arange(order.size)) \
        else schur.stiffness[np.ix_(order, order)]
    condensed = {name: vector[order] for name, vector in schur.loads.items()}
    return _condensation(matrix, retained, schur.fixed, stiffness_r, condensed, loads, schur.solver)


def condense_from_boundary(schur: BoundarySchur, stiffness, transformation, retained, fixed=(),
                           loads=None) -> Condensation:
    """The condensation that :func:`condense` gives for ``stiffness`` = Tᵀ K T onto ``retained``,
    from the :class:`BoundarySchur` of K (no new factorisation).

    transformation: T (n × n_reduced, sparse), e.g. an RBE2 coupling's; identity (None) allowed.
    Every DOF that T mixes (the coupled nodes) must lie on the boundary, and each retained DOF
    must come from it. The loads (reduced vectors Tᵀ f, N) are taken by name from
    ``schur.loads`` (condensed from the same f). Exact: condensing the interior commutes with a
    change of variables on the boundary, and the boundary DOFs not retained are eliminated
    from the dense complement.
    """
    matrix = sp.csr_matrix(stiffness)
    n_reduced = matrix.shape[0]
    t = sp.identity(schur.n_dofs, format="csr") if transformation is None else sp.csr_matrix(transformation)
    retained = as_dof_index(retained, n_reduced, "retained")
    fixed = as_dof_index(fixed, n_reduced, "fixed")
    on_boundary = np.zeros(schur.n_dofs, dtype=bool)
    on_boundary[schur.boundary] = True
    interior_rows = t[~on_boundary]
    reduced_boundary = np.unique(t[schur.boundary].indices)
    if np.intersect1d(interior_rows.indices, reduced_boundary).size or np.any(np.diff(interior_rows.indptr) > 1):
        raise InputError("the condensation boundary must hold every coupled node and the DOFs they drive")
    raw_fixed = np.unique(t[schur.fixed].indices)
    if not np.array_equal(np.sort(fixed), raw_fixed):
        raise InputError("the fixed DOFs differ from those of the shared factorisation")
    t_b = t[schur.boundary][:, reduced_boundary]
    position = np.searchsorted(reduced_boundary, retained)
    if np.any(position >= reduced_boundary.size) or np.any(reduced_boundary[np.minimum(position, reduced_boundary.size - 1)] != retained):
        raise InputError("a retained DOF is not on the condensation boundary")
    full = (t_b.T @ (t_b.T @ schur.stiffness.T).T)  # Tᵀ S T, (n_b', n_b')
    other = np.setdiff1d(np.arange(reduced_boundary.size), position)
    names = list(loads or {})
    missing = [name for name in names if name not in schur.loads]
    if missing:
        raise InputError(f"load(s) {missing} were not condensed with the shared factorisation")
    f = np.column_stack([t_b.T @ schur.loads[name] for name in names]) if names else np.zeros((reduced_boundary.size, 0))
    s_rr, f_r = full[np.ix_(position, position)], f[position]
    if other.size:
        factor = scipy.linalg.cho_factor(full[np.ix_(other, other)])
        coupling = full[np.ix_(other, position)]
        s_rr = s_rr - coupling.T @ scipy.linalg.cho_solve(factor, coupling)
        f_r = f_r - coupling.T @ scipy.linalg.cho_solve(factor, f[other])
    del full
    _symmetrise(s_rr)
    condensed = {name: f_r[:, k] for k, name in enumerate(names)}
    return _condensation(matrix, retained, fixed, s_rr, condensed, loads, schur.solver)


def _condensation(matrix: sp.csr_matrix, retained, fixed, schur: np.ndarray, condensed: dict, loads,
                  solver: str) -> Condensation:
    """The :class:`Condensation` of ``matrix`` with its Schur complement and condensed loads
    given; the interior is factorised only if a field is expanded."""
    n_dofs = matrix.shape[0]
    is_interior = np.ones(n_dofs, dtype=bool)
    is_interior[retained] = False
    is_interior[fixed] = False
    interior = np.flatnonzero(is_interior)
    solve = _no_interior
    if interior.size:
        solve = lazy_interior_solver(matrix[interior][:, interior], resolve_solver("auto")
                                     if solver == "none" else solver, eager=False)
    interior_loads = {name: np.asarray(vector, dtype=float)[interior] for name, vector in (loads or {}).items()}
    return Condensation(
        retained=retained,
        stiffness=schur,
        loads=condensed,
        interior=interior,
        fixed=fixed,
        n_dofs=n_dofs,
        solver=solver if interior.size else "none",
        interior_loads=interior_loads,
        interior_retained_coupling=matrix[interior][:, retained].tocsr(),
        solve_interior=solve,
    )


class InteriorSolver:
    """K_ii^-1 b, factorising on first use: the condensation itself (:func:`boundary_schur`)
    does not need it, only a field expansion does.

    :meth:`release` frees the factor (a 3D body of 400k DOFs holds gigabytes in it); the next
    solve factorises again.
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
