"""Intel MKL PARDISO through ctypes (library found by the ``pypardiso`` package).

Two uses: the exact Schur complement of a sparse symmetric matrix onto chosen rows by
PARDISO's partial factorisation (retained rows ordered last, dense trailing block, BLAS3),
which is an order of magnitude faster than solving for every retained column; and a
Cholesky factor for repeated solves. Matrix type 2 (real symmetric positive definite).
"""

from __future__ import annotations

import ctypes
import os
import weakref
from functools import lru_cache

import numpy as np
import scipy.sparse as sp

from reduction.errors import InputError

_SPD = 2
_ANALYSE_FACTOR = 12
_SOLVE = 33
_RELEASE = -1
_ZERO_PIVOT = -4
_c_int = ctypes.c_int32
_ptr = ctypes.POINTER


def available() -> bool:
    try:
        _library()
    except (ImportError, OSError):
        return False
    return True


@lru_cache(maxsize=1)
def _library():
    # MKL's conditional numerical reproducibility, read once when MKL loads: without it MKL
    # may pick code paths by the alignment of the arrays it is given, run by run. AUTO keeps
    # the fastest path for this CPU; a user's own MKL_CBWR (e.g. COMPATIBLE, for the same bits
    # across CPU models) is left as it is.
    os.environ.setdefault("MKL_CBWR", "AUTO")
    from pypardiso.pardiso_wrapper import PyPardisoSolver

    function = PyPardisoSolver().libmkl.pardiso
    function.restype = None
    return function


class _Handle:
    """One PARDISO instance: matrix in upper-triangular zero-based CSR plus its internal state."""

    def __init__(self, matrix: sp.spmatrix, schur_rows: np.ndarray | None, label: str):
        upper = sp.triu(sp.csr_matrix(matrix), format="csr")
        upper.sort_indices()
        self.n = upper.shape[0]
        self.label = label
        self.values = np.ascontiguousarray(upper.data, dtype=np.float64)
        self.row_start = upper.indptr.astype(np.int32)
        self.columns = upper.indices.astype(np.int32)
        self.state = np.zeros(64, dtype=np.int64)
        self.iparm = np.zeros(64, dtype=np.int32)
        self.iparm[0] = 1  # own settings below, defaults for the rest
        self.iparm[1] = 2  # METIS nested dissection ordering
        self.iparm[9] = 13  # pivot perturbation 1e-13
        self.iparm[34] = 1  # zero-based indices
        self.perm = np.zeros(self.n, dtype=np.int32)
        if schur_rows is not None:
            self.iparm[35] = 1  # Schur complement of the rows flagged in perm, returned dense in x
            self.perm[schur_rows] = 1
        self._finalizer = weakref.finalize(self, _release, self.state, self.iparm)

    def release(self) -> None:
        """Free the factor now (else when the handle is garbage-collected)."""
        self._finalizer()

    def call(self, phase: int, rhs: np.ndarray, out: np.ndarray, n_rhs: int = 1) -> None:
        error = _c_int(0)
        _library()(
            self.state.ctypes.data_as(_ptr(ctypes.c_int64)),
            ctypes.byref(_c_int(1)),
            ctypes.byref(_c_int(1)),
            ctypes.byref(_c_int(_SPD)),
            ctypes.byref(_c_int(phase)),
            ctypes.byref(_c_int(self.n)),
            self.values.ctypes.data_as(_ptr(ctypes.c_double)),
            self.row_start.ctypes.data_as(_ptr(_c_int)),
            self.columns.ctypes.data_as(_ptr(_c_int)),
            self.perm.ctypes.data_as(_ptr(_c_int)),
            ctypes.byref(_c_int(n_rhs)),
            self.iparm.ctypes.data_as(_ptr(_c_int)),
            ctypes.byref(_c_int(0)),
            rhs.ctypes.data_as(_ptr(ctypes.c_double)),
            out.ctypes.data_as(_ptr(ctypes.c_double)),
            ctypes.byref(error),
        )
        # PARDISO perturbs tiny pivots instead of failing; a perturbed pivot means a singular matrix
        if error.value == _ZERO_PIVOT or (phase == _ANALYSE_FACTOR and self.iparm[13] > 0):
            raise InputError(
                f"{self.label} is singular or not positive definite: the retained and fixed DOFs do not stop "
                "every rigid-body motion of the eliminated part (or the mesh has disconnected pieces)"
            )
        if error.value != 0:
            raise RuntimeError(f"MKL PARDISO failed on {self.label} with error code {error.value}")


def _release(state: np.ndarray, iparm: np.ndarray) -> None:
    """Free PARDISO's memory of one instance (idempotent: the state is zeroed)."""
    if not state.any():
        return
    dummy = np.zeros(1)
    index = np.zeros(1, dtype=np.int32)
    _library()(
        state.ctypes.data_as(_ptr(ctypes.c_int64)), ctypes.byref(_c_int(1)), ctypes.byref(_c_int(1)),
        ctypes.byref(_c_int(_SPD)), ctypes.byref(_c_int(_RELEASE)), ctypes.byref(_c_int(1)),
        dummy.ctypes.data_as(_ptr(ctypes.c_double)), index.ctypes.data_as(_ptr(_c_int)),
        index.ctypes.data_as(_ptr(_c_int)), index.ctypes.data_as(_ptr(_c_int)), ctypes.byref(_c_int(1)),
        iparm.ctypes.data_as(_ptr(_c_int)), ctypes.byref(_c_int(0)),
        dummy.ctypes.data_as(_ptr(ctypes.c_double)), dummy.ctypes.data_as(_ptr(ctypes.c_double)),
        ctypes.byref(_c_int(0)),
    )
    state[:] = 0


def schur_complement(matrix: sp.spmatrix, rows: np.ndarray, label: str = "matrix") -> np.ndarray:
    """Dense Schur complement A_rr - A_ri A_ii^-1 A_ir, rows/columns in the order of ``rows``.

    A_ii must be positive definite; the complement itself may be singular (free bodies).
    """
    rows = np.asarray(rows, dtype=np.int64)
    handle = _Handle(matrix, rows, label)
    result = np.zeros(rows.size * rows.size)
    handle.call(_ANALYSE_FACTOR, np.zeros(handle.n), result)
    handle.release()  # the factor is not used again: free it before the complement is copied
    result = result.reshape(rows.size, rows.size)
    if np.all(np.diff(rows) > 0):
        return result
    # PARDISO returns the complement in ascending row order
    position = np.argsort(np.argsort(rows))
    return result[np.ix_(position, position)]


class Cholesky:
    """PARDISO factor of a sparse SPD matrix; ``solve(b)`` for b of shape (n,) or (n, m)."""

    def __init__(self, matrix: sp.spmatrix, label: str = "matrix"):
        self._handle = _Handle(matrix, None, label)
        self._handle.call(_ANALYSE_FACTOR, np.zeros(self._handle.n), np.zeros(self._handle.n))

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        rhs = np.asarray(rhs, dtype=np.float64)
        n_rhs = 1 if rhs.ndim == 1 else rhs.shape[1]
        if n_rhs == 0:
            return np.zeros_like(rhs)
        # PARDISO wants each right-hand side contiguous (column-major)
        columns = np.ascontiguousarray(rhs.T)
        out = np.zeros_like(columns)
        self._handle.call(_SOLVE, columns, out, n_rhs)
        return out.T.copy() if rhs.ndim == 2 else out
