"""Contact space of sparse bodies: the interface solved without ever forming a dense W.

The dense path (:class:`contact.structure.ContactSpace`) condenses every body onto its
surface and forms the contact compliance W = G·K⁻¹·Gᵀ: both grow as n² (10,000 points in 3D:
a 60,000² condensed stiffness and a 30,000² W, 29 GB and 7 GB). Here the bodies are kept
whole and sparse (:func:`contact.assembly.assemble` with ``keep_interior``: the same
couplings, supports, bolts, body loads, pairing and held surface DOFs as the condensed
assembly, only nothing condensed). The free DOFs split into the control DOFs q (reference
points that no contact row touches) and all others, c (interior and contact surfaces). The
elimination is that of the dense path (:class:`contact.structure.ContactSpace`, shared):

    g − g_f + E·q + W·λ(g) = 0,       S_q·q − Eᵀ·λ(g) − f_q = 0,

with W·λ = G·K_cc⁻¹·Gᵀ·λ evaluated by one solve with a sparse Cholesky factor of K_cc
(formed once), and E = G·K_cc⁻¹·K_cq, S_q = K_qq − K_qc·K_cc⁻¹·K_cq formed with one solve
per control DOF. So the solver's residuals, line search and convergence test are those of
the dense path, and so are its answers.

A Newton correction solves J·[x, y] = [b, c] with J = [[I + W·B, E], [−Eᵀ·B, S_q]] (B the
block-diagonal tangent A·D of :mod:`contact.linear`). Writing x = b + G·w, it is exactly the
sparse system of the uncondensed tangent (the full model's Newton matrix):

    [[K_cc + Gᵀ·B·G, K_cq], [K_qc, K_qq + K_bolts]]·[w, y] = [−Gᵀ·B·b, c].

That matrix changes with the tangent; it is solved by GMRES preconditioned with a sparse
Cholesky factor (MKL PARDISO, single precision) of K + Gᵀ·B₀·G, B₀ the diagonal of an earlier
tangent: symmetric positive definite, half the memory of an LU, and as good a preconditioner
as the LU of the earlier tangent itself (measured: the same Krylov iterations within 1 %).
It is kept across Newton iterations and increments and rebuilt when the Krylov work lost
to its age exceeds what the rebuild costs (counted in the factor's flops, not in seconds:
the results do not depend on the machine's load). Memory and time grow with the sparse factors, about n·log n for these quasi-2D
interface bodies, not n².

Units: mm, N, N/mm.
"""

from __future__ import annotations

import ctypes
import weakref

import numpy as np
import scipy.sparse as sp

from contact.full_model import TangentAssembler
from contact.linear import Ageing, KrylovCounters, KrylovSettings, _gmres
from contact.structure import ContactSpace, Structure
from reduction import pardiso
from reduction.errors import InputError
from reduction.factorization import factorize

#: contact points from which the sparse path is chosen (3D), set by memory, measured with
#: the flat-on-flat benchmark on graded bodies (tests/bench/test_bench_scale.py): the dense
#: path's set-up needs 10.2 GB at 3,600 points, growing as n², so 6 GB (the target of issue
#: 14) at ~2,760; the sparse one needs 0.83 GB at 1,600 points and 1.8 GB at 3,600. In time
#: the dense path is ahead there (1,600 points: 0.150 s of CPU per increment against 0.453 s),
#: its per-increment cost growing as n² against about n for the sparse one.
SPARSE_FROM_POINTS = 2500

#: the choices of ``[contact] solver``
PATHS = ("auto", "dense", "sparse")

#: how many times faster per flop a factorisation runs than a solve (dense BLAS3 blocks
#: against a memory-bound substitution): the rebuild's work in solve flops is its flops over
#: this. Measured at 900 points (PARDISO, one thread): 1 rebuilds too late (the first
#: reference, from the contact search, is kept too long: 480 Krylov iterations in the
#: history, 0.31 s per increment), 3 gives 301 and 0.27 s, 10 rebuilds too often (0.33 s).
FACTOR_FLOP_RATE = 3.0

#: the relative GMRES tolerance of the last Newton steps at most (KrylovSettings.final_tolerance
#: is 1e-7): there the inexact correction sets where Newton stops inside its tolerance, and a
#: run should end where the dense path's exact LU ends. Measured on the bolted blocks
#: (tests/pipelines/test_contact_solver.py): 1e-7 leaves 2.4e-8 of the dissipation per cycle,
#: 1e-9 less than 1e-8 of every field, for a few more Krylov iterations in the last steps.
FINAL_TOLERANCE = 1e-9

#: right-hand sides per solve when W's normal diagonal is formed: bounds the dense block to
#: this many floats (160 MB)
_DIAGONAL_BLOCK_FLOATS = 20_000_000


def choose_path(n_points: int, dim: int) -> str:
    """"dense" or "sparse" for an interface of ``n_points`` contact points in ``dim`` D."""
    return "sparse" if dim == 3 and n_points >= SPARSE_FROM_POINTS else "dense"


def decide_path(asked: str, n_points: int, dim: int) -> tuple[str, str]:
    """(path, why) for the ``[contact] solver`` choice ``asked`` ("auto", "dense" or "sparse")
    and an interface of ``n_points`` contact points in ``dim`` D; why, in words for a run
    summary, e.g. "2,704 points ≥ 2,500"."""
    if asked not in PATHS:
        raise InputError(f"contact solver must be one of {', '.join(PATHS)}, got {asked!r}")
    path = choose_path(n_points, dim) if asked == "auto" else asked
    if path == "sparse" and not pardiso.available():
        raise InputError(f"the sparse contact solver ({n_points:,} points) needs MKL PARDISO, which is not "
                         "installed (pip install pypardiso); or set [contact] solver = \"dense\"")
    if asked != "auto":
        return asked, f"asked for, {n_points:,} points"
    if dim != 3:
        return path, f"{n_points:,} points in {dim}D"
    sign = "≥" if path == "sparse" else "<"
    return path, f"{n_points:,} points {sign} {SPARSE_FROM_POINTS:,}"


def contact_space(bodies: list, slave: tuple, master: tuple, *, loads: dict | None = None,
                  motions: dict | None = None, path: str = "auto", **assembly):
    """The contact space of bodies and a surface pair (the arguments of
    :func:`contact.assembly.assemble`, ``assembly`` the further ones) on the ``path`` "dense"
    (condensed bodies, dense W), "sparse" (this module) or "auto" (:func:`choose_path` by the
    slave surface's node count, one contact point per node). Returns (space, path taken)."""
    from contact.assembly import assemble
    from contact.interface import surface_from_facets

    if path not in PATHS:
        raise InputError(f"contact path must be auto, dense or sparse, got {path!r}")
    if path == "auto":
        body = next((b for b in bodies if b.name == slave[0]), None)
        if body is None:
            raise InputError(f"slave surface names body {slave[0]!r}, which is not defined")
        surface = surface_from_facets(body.elastic.mesh, slave[1], f"{slave[0]} surface")
        path = choose_path(surface.nodes.size, body.elastic.dim)
    structure = assemble(bodies, slave, master, loads=loads, motions=motions, keep_interior=path == "sparse",
                         **assembly).structure
    return space_of(structure), path


def space_of(structure: Structure) -> ContactSpace:
    """The contact space of a structure: :class:`SparseContactSpace` for bodies kept whole
    (sparse stiffness), else the dense :class:`contact.structure.ContactSpace`."""
    return SparseContactSpace(structure) if sp.issparse(structure.stiffness) else ContactSpace(structure)


class SparseContactSpace(ContactSpace):
    """Contact-space operators of a structure whose bodies are kept whole, W kept implicit.

    The interface of :class:`contact.structure.ContactSpace` (E (n_rows, n_control) mm/mm,
    S_q (n_control, n_control) N/mm, ``driving``, ``compliance`` (W·λ), ``displacements``,
    ``normal_compliance``, ``linear_solver``, ...), with no ``W`` attribute. ``contact_dofs``
    are all eliminated DOFs (interior included). A re-paired space (:meth:`repaired`) shares
    the bodies' factor.
    """

    def __init__(self, structure: Structure):
        super().__init__(structure)
        order = np.concatenate([self.contact_dofs, self.control_dofs])
        self._stiffness_cq = structure.stiffness.tocsr()[order][:, order].tocsr()

    def _pair(self, structure: Structure) -> None:
        super()._pair(structure)
        self._G_cq = sp.hstack([self.Gc, sp.csr_matrix((self.Gc.shape[0], self.control_dofs.size))], format="csr")
        self._normal_compliance = None

    def _split_free(self, free: np.ndarray, in_contact: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Control DOFs: the reference points' free DOFs (no contact row touches them); every
        other free DOF, interior or surface, is eliminated."""
        labelled = np.zeros(in_contact.size, dtype=bool)
        labelled[np.fromiter(self.structure.labels.values(), dtype=int, count=len(self.structure.labels))] = True
        control = free[labelled[free] & ~in_contact[free]]
        return np.setdiff1d(free, control), control

    def _factorise(self, stiffness, eliminated: np.ndarray):
        """The sparse Cholesky factor of K_cc (PARDISO when installed)."""
        return factorize(stiffness.tocsr()[eliminated][:, eliminated],
                         label="stiffness of the bodies with their control points held")

    def _form_compliance(self) -> None:
        pass  # W stays implicit

    def solve_contact_block(self, rhs: np.ndarray, wanted: np.ndarray | None = None) -> np.ndarray:
        """K_cc⁻¹·rhs (mm): one factor of all the bodies, solved whole whatever is ``wanted``."""
        return self._Kcc.solve(rhs)

    @property
    def n_rows(self) -> int:
        return self.Gc.shape[0]

    def compliance(self, forces: np.ndarray) -> np.ndarray:
        """W·λ (mm) for nodal contact forces λ (N): one solve with the bodies' sparse factor."""
        return np.asarray(self.Gc @ self._Kcc.solve(self._GcT @ forces))

    def compliance_of_change(self, rows: np.ndarray, change: np.ndarray) -> np.ndarray:
        """W·Δλ (mm) for a change Δλ (N) on ``rows`` only."""
        forces = np.zeros(self.n_rows)
        forces[rows] = change
        return self.compliance(forces)

    def normal_compliance(self) -> np.ndarray:
        """W's normal diagonal (n_points,) mm/N, by solves with the points' normal rows of G
        as right-hand sides, in blocks (formed once per space; shared by its locked copies)."""
        if self._normal_compliance is None:
            dim = self.structure.dim
            rows = self.Gc[0::dim]
            per_block = max(1, min(rows.shape[0], _DIAGONAL_BLOCK_FLOATS // max(rows.shape[1], 1)))
            diagonal = np.empty(rows.shape[0])
            for start in range(0, rows.shape[0], per_block):
                block = rows[start:start + per_block]
                solved = self._Kcc.solve(block.T.toarray())
                diagonal[start:start + per_block] = np.asarray(block.multiply(solved.T).sum(axis=1)).ravel()
            self._normal_compliance = diagonal
        return self._normal_compliance

    def tangent_operators(self) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        """(K on the free DOFs in the order [c, q], with the locked bolts' stiffness in the
        control block, N/mm; G in that order): the uncondensed Newton matrix is
        K + Gᵀ·B·G."""
        stiffness = self._stiffness_cq
        if np.any(self.control_stiffness):
            n_c = self.contact_dofs.size
            extra = sp.bmat([[sp.csr_matrix((n_c, n_c)), None], [None, sp.csr_matrix(self.control_stiffness)]])
            stiffness = (stiffness + extra).tocsr()
            stiffness.sort_indices()
        return stiffness, self._G_cq

    def linear_solver(self, settings: KrylovSettings | None = None) -> SparseNewtonSolver:
        """The solver of this space's Newton corrections."""
        return SparseNewtonSolver(self, settings)


class SparseNewtonSolver:
    """Newton corrections of a :class:`SparseContactSpace` (the interface of
    :class:`contact.linear.NewtonLinearSolver`): GMRES on the uncondensed tangent,
    preconditioned by a PARDISO factor of an earlier one.

    reference: "diagonal" (the default: Cholesky of K + Gᵀ·diag(B)·G, B the tangent blocks
    clipped at zero) or "tangent" (LU of the earlier tangent itself).

    settings: relative_tolerance / final_tolerance (at most :data:`FINAL_TOLERANCE`) bound the
    residual of the sparse system relative to its right-hand side; fresh_iterations, max_iterations and single_precision (of
    the preconditioner's factor) as in :class:`contact.linear.KrylovSettings` (direct_below
    does not apply: the dense path is the one for small interfaces, see :func:`choose_path`).
    """

    def __init__(self, space: SparseContactSpace, settings: KrylovSettings | None = None,
                 reference: str = "diagonal"):
        self.space = space
        self.settings = KrylovSettings() if settings is None else settings
        self.counters = KrylovCounters()
        self._assembler = TangentAssembler(*space.tangent_operators(), space.structure.dim)
        pattern = self._assembler.matrix(np.zeros((space.structure.n_points, space.structure.dim,
                                                   space.structure.dim)))
        entry_rows = np.repeat(np.arange(pattern.shape[0]), np.diff(pattern.indptr))
        # the upper triangle's entries of the pattern, and its CSR row pointers (the Cholesky
        # preconditioner is given the upper triangle; the pattern never changes)
        self._upper = np.flatnonzero(entry_rows <= pattern.indices)
        self._upper_indptr = np.concatenate([[0], np.cumsum(np.bincount(entry_rows[self._upper],
                                                                        minlength=pattern.shape[0]))])
        self.reference = reference
        self._factor = None
        self._stale = True
        self._age: Ageing | None = None

    def description(self) -> str:
        """Which path solves this interface's Newton systems, in words (for run summaries)."""
        precision = "single" if self.settings.single_precision else "double"
        n_free = self.space.contact_dofs.size + self.space.control_dofs.size
        return (f"sparse bodies ({n_free} DOFs, no dense W): GMRES on the uncondensed "
                f"tangent preconditioned by a {precision}-precision PARDISO factor of an earlier one "
                f"({self.reference}); "
                "W·λ by a sparse Cholesky solve")

    def solve(self, blocks: np.ndarray, r_kin: np.ndarray, r_ctl: np.ndarray,
              final: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Newton correction (Δg mm, Δq mm) for residuals r_kin (mm) and r_ctl (N)."""
        space = self.space
        matrix = self._assembler.matrix(blocks)
        b = -r_kin
        tangent_b = np.matmul(blocks, b.reshape(-1, blocks.shape[1], 1)).reshape(-1)
        rhs = np.concatenate([-(space._GcT @ tangent_b), -r_ctl])
        tolerance = (min(self.settings.final_tolerance, FINAL_TOLERANCE) if final
                     else self.settings.relative_tolerance)
        if self._stale or self._factor is None:
            self._refactor(blocks)
        solution, iterations = _gmres(lambda x: matrix @ x, self._precondition, rhs, tolerance,
                                      self.settings.max_iterations)
        if solution is None:
            self._refactor(blocks)
            solution, more = _gmres(lambda x: matrix @ x, self._precondition, rhs, tolerance,
                                    self.settings.max_iterations)
            iterations += more
            if solution is None:
                raise np.linalg.LinAlgError("GMRES did not converge with a fresh preconditioner")
        self._stale = self._age.charge(iterations, self.settings.fresh_iterations)
        self.counters.solves += 1
        self.counters.krylov_iterations += iterations
        n_a = space.contact_dofs.size
        return b + space.Gc @ solution[:n_a], solution[n_a:]

    def _refactor(self, blocks: np.ndarray) -> None:
        if self.reference == "diagonal":
            # K + Gᵀ·B₀·G with B₀ the diagonal of the tangent, clipped at zero: symmetric
            # positive definite (a Cholesky factor, half an LU), and it does not age with the
            # normal-tangential coupling dτ/dh, which changes sign with the slip direction.
            dim = blocks.shape[1]
            diagonal = np.zeros_like(blocks)
            diagonal[:, np.arange(dim), np.arange(dim)] = np.maximum(np.diagonal(blocks, axis1=1, axis2=2), 0.0)
            matrix = self._assembler.matrix(diagonal)
            upper = sp.csr_matrix((matrix.data[self._upper], matrix.indices[self._upper], self._upper_indptr),
                                  shape=matrix.shape)
            if self._factor is None:
                self._factor = _SparseLU(upper, self.settings.single_precision, mtype=2)
            self._factor.factorise(upper)
        else:
            matrix = self._assembler.matrix(blocks)
            if self._factor is None:
                self._factor = _SparseLU(matrix, self.settings.single_precision)
            self._factor.factorise(matrix)
        self._age = Ageing(self._factor.solve_flops, self._factor.factor_flops / FACTOR_FLOP_RATE)
        self._stale = False
        self.counters.factorisations += 1

    def _precondition(self, vector: np.ndarray) -> np.ndarray:
        return self._factor.solve(vector)


class _SparseLU:
    """MKL PARDISO factor of matrices on one sparsity pattern: the ordering and symbolic
    analysis once, then a numeric factorisation per :meth:`factorise`. mtype 11: LU of a real
    unsymmetric matrix; 2: Cholesky of a symmetric positive definite one, given by its upper
    triangle.

    single: factorise and solve in single precision (half the memory and memory traffic of
    the factor; a preconditioner needs no more than its 1e-7 relative accuracy).
    factor_flops and solve_flops: the work of one factorisation (as PARDISO reports it) and of
    one solve (4 flops per factor entry: forward and backward substitution)."""

    def __init__(self, pattern: sp.csr_matrix, single: bool = True, mtype: int = 11):
        self._MTYPE = mtype  # 11 real unsymmetric, 2 symmetric positive definite (upper triangle)
        if not pardiso.available():
            raise RuntimeError("the sparse contact path needs MKL PARDISO (pip install pypardiso)")
        pattern.sort_indices()
        self.n = pattern.shape[0]
        self.row_start = pattern.indptr.astype(np.int32)
        self.columns = pattern.indices.astype(np.int32)
        self.state = np.zeros(64, dtype=np.int64)
        self.iparm = np.zeros(64, dtype=np.int32)
        self.iparm[0] = 1  # own settings below
        self.iparm[1] = 2  # METIS nested dissection ordering
        self.iparm[9] = 13  # pivot perturbation 1e-13
        self.iparm[10] = int(mtype == 11)  # scaling and ...
        self.iparm[12] = int(mtype == 11)  # ... weighted matching, the defaults for unsymmetric matrices
        self.iparm[17] = -1  # report the factor's nonzeros ...
        self.iparm[18] = -1  # ... and its Mflops
        self.iparm[27] = int(single)  # a, b and x in single precision
        self.iparm[34] = 1  # zero-based indices
        self.dtype = np.float32 if single else np.float64
        self.values = np.ascontiguousarray(pattern.data, dtype=self.dtype)
        self._finalizer = weakref.finalize(self, _release, self.state, self.iparm, self._MTYPE)
        self._call(11, np.zeros(self.n, self.dtype), np.zeros(self.n, self.dtype))
        self.factor_flops = 1e6 * float(self.iparm[18])
        self.solve_flops = 4.0 * float(self.iparm[17])

    def factorise(self, matrix: sp.csr_matrix) -> None:
        """Numeric LU of ``matrix`` (same sparsity pattern as the one analysed)."""
        self.values = np.ascontiguousarray(matrix.data, dtype=self.dtype)
        self._call(22, np.zeros(self.n, self.dtype), np.zeros(self.n, self.dtype))
        self.factor_flops = 1e6 * float(self.iparm[18])

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        rhs = np.ascontiguousarray(rhs, dtype=self.dtype)
        out = np.zeros_like(rhs)
        self._call(33, rhs, out)
        return out.astype(np.float64, copy=False)

    def _call(self, phase: int, rhs: np.ndarray, out: np.ndarray) -> None:
        error = ctypes.c_int32(0)
        integer = ctypes.POINTER(ctypes.c_int32)
        pardiso._library()(
            self.state.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)), ctypes.byref(ctypes.c_int32(1)),
            ctypes.byref(ctypes.c_int32(1)), ctypes.byref(ctypes.c_int32(self._MTYPE)),
            ctypes.byref(ctypes.c_int32(phase)), ctypes.byref(ctypes.c_int32(self.n)),
            self.values.ctypes.data_as(ctypes.c_void_p),
            self.row_start.ctypes.data_as(integer), self.columns.ctypes.data_as(integer),
            np.zeros(1, dtype=np.int32).ctypes.data_as(integer), ctypes.byref(ctypes.c_int32(1)),
            self.iparm.ctypes.data_as(integer), ctypes.byref(ctypes.c_int32(0)),
            rhs.ctypes.data_as(ctypes.c_void_p), out.ctypes.data_as(ctypes.c_void_p), ctypes.byref(error))
        if error.value != 0:
            raise np.linalg.LinAlgError(f"MKL PARDISO failed on the contact tangent (error {error.value})")


def _release(state: np.ndarray, iparm: np.ndarray, mtype: int) -> None:
    """Free PARDISO's memory of one handle (phase −1)."""
    if not state.any():
        return
    integer = ctypes.POINTER(ctypes.c_int32)
    dummy, index = np.zeros(1), np.zeros(1, dtype=np.int32)
    pardiso._library()(
        state.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)), ctypes.byref(ctypes.c_int32(1)),
        ctypes.byref(ctypes.c_int32(1)), ctypes.byref(ctypes.c_int32(mtype)), ctypes.byref(ctypes.c_int32(-1)),
        ctypes.byref(ctypes.c_int32(1)), dummy.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
        index.ctypes.data_as(integer), index.ctypes.data_as(integer), index.ctypes.data_as(integer),
        ctypes.byref(ctypes.c_int32(1)), iparm.ctypes.data_as(integer), ctypes.byref(ctypes.c_int32(0)),
        dummy.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), dummy.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
        ctypes.byref(ctypes.c_int32(0)))
