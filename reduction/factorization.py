"""Sparse symmetric positive-definite factorisations, fastest installed first.

Measured on a 48,000-DOF tet body condensed onto 4,800 face DOFs (2 cores): MKL PARDISO
(package ``pypardiso``) Schur complement 3 s; CHOLMOD (``sksparse-minimal``; ``cholespy`` alike, bundled
reference BLAS) solving all retained columns 76-112 s; scipy SuperLU 140-230 s. PARDISO is
preferred, then CHOLMOD, then SuperLU, with one warning when PARDISO is missing.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from reduction import pardiso
from reduction.errors import InputError

SOLVERS = ("pardiso", "cholmod", "splu")


@dataclass(frozen=True)
class Factor:
    """A factorised matrix A: ``solve(b)`` returns A^-1 b for b of shape (n,) or (n, m)."""

    name: str
    solve: Callable[[np.ndarray], np.ndarray]


def cholmod_available() -> bool:
    try:
        import sksparse_minimal  # noqa: F401
    except ImportError:
        return False
    return True


def solver_available(name: str) -> bool:
    """Whether the named solver ("pardiso", "cholmod", "splu") is installed."""
    return {"pardiso": pardiso.available, "cholmod": cholmod_available, "splu": lambda: True}[name]()


#: Environment variable that names the solver "auto" stands for (e.g. to compare backends).
SOLVER_VARIABLE = "FRETWORK_SPARSE_SOLVER"


def resolve_solver(solver: str) -> str:
    """Name of the solver to use for "auto" (warns once when PARDISO is missing), else checks the name.

    "auto" is ``$FRETWORK_SPARSE_SOLVER`` when set, else the fastest installed solver.
    """
    if solver == "auto" and os.environ.get(SOLVER_VARIABLE, "auto") != "auto":
        solver = os.environ[SOLVER_VARIABLE]
        if solver not in SOLVERS or not solver_available(solver):
            raise InputError(f"{SOLVER_VARIABLE}={solver} is not an installed solver; "
                             f"choose auto or one of {', '.join(s for s in SOLVERS if solver_available(s))}")
    if solver not in ("auto", *SOLVERS):
        raise InputError(f"unknown solver '{solver}'; choose auto, {', '.join(SOLVERS)}")
    if solver != "auto":
        return solver
    if pardiso.available():
        return "pardiso"
    fallback = "cholmod" if cholmod_available() else "splu"
    warnings.warn(
        f"pypardiso (MKL PARDISO) not installed: condensation falls back to {fallback}, 10-50x slower "
        "for large retained sets (pip install pypardiso)",
        stacklevel=3,
    )
    return fallback


def factorize(matrix: sp.spmatrix, *, solver: str = "auto", label: str = "matrix") -> Factor:
    """Factorise a sparse symmetric positive-definite matrix.

    solver: "auto" (fastest installed), "pardiso", "cholmod" or "splu".
    Raises InputError naming ``label`` when the matrix is singular or not positive definite.
    """
    solver = resolve_solver(solver)
    matrix = sp.csc_matrix(matrix)
    if solver == "pardiso":
        factor = pardiso.Cholesky(matrix, label)
        _check_pivots(matrix, factor.solve, label)
        return Factor(name="pardiso", solve=factor.solve)
    if solver == "cholmod":
        return _cholmod(matrix, label)
    return _superlu(matrix, label)


def _singular(label: str) -> InputError:
    return InputError(
        f"{label} is singular or not positive definite: the retained and fixed DOFs do not stop every "
        "rigid-body motion of the eliminated part (or the mesh has disconnected pieces)"
    )


def _cholmod(matrix: sp.csc_matrix, label: str) -> Factor:
    from sksparse_minimal import SparseCholesky

    try:
        factor = SparseCholesky(matrix)
    except Exception as error:  # CHOLMOD reports a failed pivot as a generic error
        raise _singular(label) from error

    def solve(rhs: np.ndarray) -> np.ndarray:
        return factor.solve_A(np.ascontiguousarray(rhs, dtype=float))

    _check_pivots(matrix, solve, label)
    return Factor(name="cholmod", solve=solve)


def _superlu(matrix: sp.csc_matrix, label: str) -> Factor:
    try:
        lu = spla.splu(matrix, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})
    except RuntimeError as error:
        raise _singular(label) from error
    _check_pivots(matrix, lu.solve, label)
    return Factor(name="splu", solve=lu.solve)


def _check_pivots(matrix: sp.csc_matrix, solve, label: str) -> None:
    """A near-singular matrix factorises without complaint; catch it by the residual of one solve."""
    probe = np.cos(np.arange(matrix.shape[0]))
    residual = matrix @ solve(probe) - probe
    if not np.all(np.isfinite(residual)) or np.linalg.norm(residual) > 1e-6 * np.linalg.norm(probe):
        raise _singular(label)
