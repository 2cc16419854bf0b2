"""The condensed structure an interface lives in, and its contact-space operators.

A :class:`Structure` is the statically condensed stiffness of all bodies on their retained
DOFs (contact surfaces and control points, in one global numbering), the contact operator
``G`` of the paired surfaces, load patterns (forces) and motion patterns (prescribed
displacements). The solver does not work on it directly: :class:`ContactSpace` eliminates
the body DOFs exactly so that the unknowns are the contact kinematics ``g = G·u`` plus the
few free control DOFs ``q`` that keep a floating body (a cylinder under force control, a
bolted counterweight) in equilibrium:

    g − g_f + E·q + W·λ(g) = 0          W = G·K_cc⁻¹·Gᵀ   (contact compliance, mm/N)
    S_q·q − Eᵀ·λ(g) − f_q = 0            E = G·K_cc⁻¹·K_cq,  S_q = K_qq − K_qc·K_cc⁻¹·K_cq

with λ = A·[p, τ] the nodal contact forces (N). K_cc must be invertible: each body must be
held by fixed DOFs, prescribed DOFs or its control DOFs.
Units: mm, N, N/mm.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as la
from scipy.linalg import blas, lapack
import scipy.sparse as sp

from reduction.errors import InputError
from reduction.threads import single_threaded_blas


@dataclass(frozen=True)
class Structure:
    """Condensed bodies and their contact interface in one global DOF numbering.

    stiffness: (n, n) N/mm, the condensed stiffness of all bodies: dense, or sparse CSR for
        bodies kept whole (``assemble(..., keep_interior=True)``, :mod:`contact.sparse`).
    contact_operator: G, sparse (n_points·dim, n); rows per point [normal, tangent(s)].
    area: (n_points,) tributary area A (mm², or mm per unit thickness in 2D).
    initial_overclosure: h₀ (n_points,) mm.
    prescribed: indices of displacement-controlled DOFs (held at the motion patterns).
    loads: name → (n,) force pattern, N. motions: name → (n,) displacement pattern, mm,
        nonzero only on prescribed DOFs. A load history scales each pattern in time.
    labels: name → DOF index, for control DOFs worth reporting (e.g. "cylinder.rp.uy").
    surface_dofs: DOFs eliminated with the contact DOFs even where no point is paired with
        them (finite sliding: the surfaces' DOFs, so that every pairing eliminates the same
        set and a re-paired space keeps the bodies' factor), or None.
    """

    stiffness: np.ndarray
    contact_operator: sp.csr_matrix
    area: np.ndarray
    initial_overclosure: np.ndarray
    dim: int
    prescribed: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    loads: dict = field(default_factory=dict)
    motions: dict = field(default_factory=dict)
    labels: dict = field(default_factory=dict)
    bolts: object = None  # contact.bolts.BoltSet, or None without bolts
    surface_dofs: np.ndarray | None = None

    @property
    def n_dofs(self) -> int:
        return self.stiffness.shape[0]

    @property
    def n_points(self) -> int:
        return self.area.size

    @property
    def patterns(self) -> tuple[str, ...]:
        """Names of all load and motion patterns, in the order of amplitude vectors."""
        return tuple(self.loads) + tuple(self.motions)


def _columns(matrix: sp.csr_matrix, columns: np.ndarray) -> sp.csr_matrix:
    """matrix[:, columns] for sorted ``columns``, by a map of the CSR entries (scipy's fancy
    column indexing and slicing cost several times more than the products on a small operator
    re-formed at every re-pairing)."""
    position = np.full(matrix.shape[1], -1)
    position[columns] = np.arange(columns.size)
    new = position[matrix.indices]
    kept = new >= 0
    counts = np.bincount(np.repeat(np.arange(matrix.shape[0]), np.diff(matrix.indptr))[kept],
                         minlength=matrix.shape[0])
    return sp.csr_matrix((matrix.data[kept], new[kept], np.concatenate([[0], np.cumsum(counts)])),
                         shape=(matrix.shape[0], columns.size))


def _diagonal_blocks(matrix: np.ndarray, index: np.ndarray) -> list[np.ndarray]:
    """Split ``index`` into runs whose rows and columns of ``matrix`` couple only within the run.

    Bodies are numbered one after the other, so their blocks are contiguous runs; a run ends
    where no row so far reaches past it (found from each row's last coupled column, without
    forming a sparse copy of the dense matrix)."""
    last = np.empty(index.size, dtype=int)
    for start in range(0, index.size, 2048):  # row chunks keep the boolean temporary small
        rows = matrix[np.ix_(index[start:start + 2048], index)] != 0.0
        reach = index.size - 1 - np.argmax(rows[:, ::-1], axis=1)
        last[start:start + 2048] = np.where(rows.any(axis=1), reach, np.arange(start, start + len(rows)))
    ends = np.flatnonzero(np.maximum.accumulate(last) == np.arange(index.size))
    starts = np.concatenate([[0], ends[:-1] + 1])
    return [index[a:b + 1] for a, b in zip(starts, ends)]


class _BlockFactor:
    """Inverses of the block-diagonal contact-DOF stiffness, one per body block.

    Each block is symmetric positive definite when its body is supported (held by fixed,
    prescribed or control DOFs): its Cholesky factor and from it the inverse (LAPACK potrf,
    potri: n³ flops in all) are formed in place. The contact operator is sparse, so the
    congruence G·K⁻¹·Gᵀ then costs a few products per nonzero of G instead of the 2n³ of
    solving for every column, and a solve is one symmetric product with the inverse.
    """

    def __init__(self, stiffness: np.ndarray, index: np.ndarray):
        self.index = index
        position = np.empty(stiffness.shape[0], dtype=int)
        position[index] = np.arange(index.size)
        self.blocks = [position[block] for block in _diagonal_blocks(stiffness, index)]
        self.inverses = [_spd_inverse(stiffness[np.ix_(index[block], index[block])]) for block in self.blocks]

    def solve(self, rhs: np.ndarray, wanted: np.ndarray | None = None) -> np.ndarray:
        """K⁻¹·rhs (rhs (n,) or (n, m)); with ``wanted`` (positions among the eliminated DOFs)
        only the blocks that hold them are solved, the others left zero. A vector is
        multiplied by the upper triangle of each inverse (:func:`symmetric_product`: half the
        bytes read; at 2.5 mm on the counterweight's pads two 4,728-row inverses, 25 ms)."""
        out = np.zeros_like(rhs, dtype=float)
        holds = None
        if wanted is not None:
            holds = np.zeros(self.index.size, dtype=bool)
            holds[wanted] = True
        for block, inverse in zip(self.blocks, self.inverses):
            if holds is None or holds[block].any():
                out[block] = symmetric_product(inverse, rhs[block])
        return out

    def congruence(self, operator: sp.csr_matrix) -> np.ndarray:
        """operator·K⁻¹·operatorᵀ, one body block at a time (no dense global operator)."""
        result = np.zeros((operator.shape[0], operator.shape[0]))
        operator = operator.tocsr()
        for block, inverse in zip(self.blocks, self.inverses):
            part = _columns(operator, block)  # a block is a run of consecutive eliminated DOFs
            touched = np.flatnonzero(np.diff(part.indptr))
            if touched.size == 0:
                continue
            if 2 * touched.size < operator.shape[0]:  # a body few rows touch: those rows only
                rows = part[touched]
                result[np.ix_(touched, touched)] += np.asarray(rows @ np.asarray(rows @ inverse).T)
            else:
                # G·(G·K⁻¹)ᵀ = G·K⁻¹·Gᵀ (K⁻¹ symmetric), both products sparse times dense
                result += np.asarray(part @ np.asarray(part @ inverse).T)
        # symmetrised, as the round-off of the two sides is not
        return _symmetric(result)


def _spd_inverse(matrix: np.ndarray) -> np.ndarray:
    """Inverse of a symmetric positive definite block, in place (C order: LAPACK sees Aᵀ = A)."""
    matrix = np.ascontiguousarray(matrix)
    # matrix.T is the Fortran-ordered view LAPACK works on in place; its upper triangle is
    # the lower one of ``matrix``
    factor, info = lapack.dpotrf(matrix.T, lower=0, overwrite_a=1, clean=0)
    pivots = np.diag(factor) ** 2 if info == 0 else np.zeros(1)
    if info != 0 or pivots.min() <= 1e-12 * pivots.max():
        raise InputError("a body is not supported: its stiffness is singular with the "
                         "contact surfaces free and its control points held; fix a "
                         "boundary, prescribe a motion or add a control point")
    inverse, info = lapack.dpotri(factor, lower=0, overwrite_c=1)
    if not np.shares_memory(inverse, matrix):
        matrix = np.ascontiguousarray(inverse.T)
    return _mirror(matrix)


def _mirror(matrix: np.ndarray, chunk: int = 1024) -> np.ndarray:
    """Fill the strict upper triangle of a square array from its lower triangle (the one a
    Fortran-ordered 'upper' LAPACK result holds when read in C order), chunk by chunk."""
    n = matrix.shape[0]
    for start in range(0, n, chunk):
        stop = min(start + chunk, n)
        upper = np.triu_indices(stop - start, 1)
        tile = matrix[start:stop, start:stop]
        tile[upper] = tile.T[upper]
        matrix[start:stop, stop:] = matrix[stop:, start:stop].T
    return matrix


def _symmetric(matrix: np.ndarray) -> np.ndarray:
    matrix += matrix.T.copy()
    matrix *= 0.5
    return matrix


#: a symmetric matrix from this size (bytes) up is multiplied reading one triangle: half the
#: memory traffic once it no longer stays in cache. Measured (one thread, best of five):
#: 4,776 rows 15.4 -> 8.1 ms in double and 6.1 -> 3.9 ms in single precision; 1,260 rows in
#: double (12 MB) 0.23 -> 0.14 ms alone (1,236 rows inside the counterweight run at 5 mm:
#: 0.58 -> 0.53 ms); in single at 1,200-1,260 rows (6 MB) no gain (0.09-0.13 ms either way).
SYMMETRIC_PRODUCT_BYTES = 8 << 20


def symmetric_product(matrix: np.ndarray, vector: np.ndarray) -> np.ndarray:
    """matrix·vector for a symmetric ``matrix`` (float32 or float64; the vector is cast to
    its type), reading only its upper triangle when it is large (``SYMMETRIC_PRODUCT_BYTES``).
    The kernel depends only on the size, so the last digits do not depend on the machine's
    load."""
    vector = vector.astype(matrix.dtype, copy=False)
    if (matrix.nbytes < SYMMETRIC_PRODUCT_BYTES or vector.ndim != 1
            or matrix.dtype not in (np.float32, np.float64)):
        return matrix @ vector
    symv = blas.dsymv if matrix.dtype == np.float64 else blas.ssymv
    # BLAS reads a Fortran-ordered matrix without a copy: a C-ordered one through its
    # transpose, whose lower triangle is its upper one (W[rows][:, rows] comes out in
    # Fortran order; copying it would cost ten products)
    if matrix.flags.f_contiguous:
        return symv(1.0, matrix, vector, lower=0)
    if matrix.flags.c_contiguous:
        return symv(1.0, matrix.T, vector, lower=1)
    return matrix @ vector


def dense_block(matrix, rows: np.ndarray, columns: np.ndarray) -> np.ndarray:
    """matrix[rows, columns] as a dense array, for a dense or a sparse ``matrix``."""
    if sp.issparse(matrix):
        return matrix[rows][:, columns].toarray()
    return matrix[np.ix_(rows, columns)]


class ContactSpace:
    """Exact elimination of a :class:`Structure` onto contact kinematics and control DOFs.

    The dense path: the bodies are condensed, W is formed. :class:`contact.sparse.SparseContactSpace`
    shares this elimination with the bodies kept whole and W implicit (the hooks
    ``_split_free``, ``_factorise``, ``_form_compliance``).
    """

    def __init__(self, structure: Structure):
        with single_threaded_blas():
            self._eliminate(structure)

    def _split_free(self, free: np.ndarray, in_contact: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(eliminated DOFs c, control DOFs q) of the free DOFs: here every free DOF that no
        contact row touches is a control DOF (reference points, surface nodes outside the pairing)."""
        return free[in_contact[free]], free[~in_contact[free]]

    def _factorise(self, stiffness, eliminated: np.ndarray):
        """A factor of K_cc with ``solve(rhs)`` (rhs (n_c,) or (n_c, m), N → mm)."""
        return _BlockFactor(stiffness, eliminated)

    def _form_compliance(self) -> None:
        """W = G_c·K_cc⁻¹·G_cᵀ (mm/N), dense."""
        self.W = self._Kcc.congruence(self.Gc)

    def _eliminate(self, structure: Structure) -> None:
        self.structure = structure
        prescribed = np.asarray(structure.prescribed, dtype=int)
        self.contact_dofs, self.control_dofs = self._split(structure)
        self.prescribed = prescribed
        K = structure.stiffness
        c, q, p = self.contact_dofs, self.control_dofs, prescribed
        self._Kcc = self._factorise(K, c)
        self._Kcq = dense_block(K, c, q)
        # K_cp stays sparse with sparse bodies (held surface DOFs make many columns)
        self._Kcp = K[c][:, p].tocsr() if sp.issparse(K) else K[np.ix_(c, p)]
        self.compliance_Kcq = self._Kcc.solve(self._Kcq)
        self.Sq = dense_block(K, q, q) - self._Kcq.T @ self.compliance_Kcq
        self.control_stiffness = np.zeros((q.size, q.size))  # locked bolts add to it
        self._Kqp = dense_block(K, q, p)
        # Each pattern, at unit amplitude, as a contact-space load: g_f and f_q columns.
        n_patterns = len(structure.patterns)
        self.pattern_force_c = np.zeros((c.size, n_patterns))
        self.pattern_force_q = np.zeros((q.size, n_patterns))
        self.pattern_motion = np.zeros((p.size, n_patterns))
        for k, name in enumerate(structure.patterns):
            if name in structure.loads:
                self.pattern_force_c[:, k] = structure.loads[name][c]
                self.pattern_force_q[:, k] = structure.loads[name][q]
            else:
                self.pattern_motion[:, k] = structure.motions[name][p]
        effective_c = self.pattern_force_c - self._Kcp @ self.pattern_motion
        self.compliance_f = self._Kcc.solve(effective_c)
        self.pattern_fq = (self.pattern_force_q - self._Kqp @ self.pattern_motion
                           - self._Kcq.T @ self.compliance_f)
        self._pair(structure)

    def _split(self, structure: Structure) -> tuple[np.ndarray, np.ndarray]:
        """(eliminated DOFs c, control DOFs q) of a structure's free DOFs."""
        n = structure.n_dofs
        is_free = np.ones(n, dtype=bool)
        is_free[np.asarray(structure.prescribed, dtype=int)] = False
        free = np.flatnonzero(is_free)
        in_contact = np.zeros(n, dtype=bool)
        in_contact[structure.contact_operator.tocsr().indices] = True
        if structure.surface_dofs is not None:
            in_contact[structure.surface_dofs] = True
        return self._split_free(free, in_contact)

    def _pair(self, structure: Structure) -> None:
        """The operators that depend on the pairing: G_c, W, E and the pattern gaps g_f."""
        self.structure = structure
        self.Gc = _columns(structure.contact_operator.tocsr(), self.contact_dofs)
        self._GcT = self.Gc.T.tocsr()
        self._form_compliance()
        self.E = np.asarray(self.Gc @ self.compliance_Kcq)
        self.pattern_gf = np.asarray(self.Gc @ self.compliance_f)

    def with_control_stiffness(self, extra: np.ndarray) -> "ContactSpace":
        """The same space with ``extra`` (n_control, n_control) N/mm added to the control
        block (locked bolts): contact compliance and load images are unchanged."""
        locked = copy.copy(self)
        locked.Sq = self.Sq + extra
        locked.control_stiffness = self.control_stiffness + extra
        return locked

    @property
    def n_rows(self) -> int:
        return self.W.shape[0]

    @property
    def stiffness_scale(self) -> float:
        """The largest diagonal stiffness of the condensed bodies, N/mm (a scale for tolerances)."""
        return float(np.abs(self.structure.stiffness.diagonal()).max())

    def compliance(self, forces: np.ndarray) -> np.ndarray:
        """W·λ (mm) for nodal contact forces λ (N)."""
        return symmetric_product(self.W, forces)

    def compliance_of_change(self, rows: np.ndarray, change: np.ndarray) -> np.ndarray:
        """W·Δλ (mm) for a change Δλ (N) on ``rows`` only (W is symmetric: its rows are read)."""
        return self.W[rows].T @ change

    def normal_compliance(self) -> np.ndarray:
        """W's normal diagonal (n_points,) mm/N: each point's normal displacement under a unit
        normal force of its own (the bodies' local compliance, :mod:`contact.cycle_jump`)."""
        return np.diagonal(self.W)[0::self.structure.dim].copy()

    def repaired(self, structure: Structure) -> ContactSpace:
        """The space of ``structure``, the same bodies with a new pairing (finite sliding).

        When the bodies, supports and patterns are this space's and the new pairing
        eliminates the same DOFs (``Structure.surface_dofs`` keeps them fixed), only the
        pairing's operators are formed again (G_c, W, E, g_f): K_cc's factor, S_q and the
        load images are shared. Otherwise the space is built anew."""
        old = self.structure
        same_bodies = (structure.stiffness is old.stiffness and structure.loads is old.loads
                       and structure.motions is old.motions
                       and np.array_equal(structure.prescribed, self.prescribed))
        if same_bodies:
            contact_dofs, control_dofs = self._split(structure)
            if np.array_equal(contact_dofs, self.contact_dofs) and np.array_equal(control_dofs, self.control_dofs):
                space = copy.copy(self)
                with single_threaded_blas():
                    space._pair(structure)
                return space
        return type(self)(structure)

    def linear_solver(self, settings=None):
        """The solver of this space's Newton corrections (:class:`contact.linear.NewtonLinearSolver`)."""
        # contact.linear imports this module
        from contact.linear import KrylovSettings, NewtonLinearSolver

        return NewtonLinearSolver(self, KrylovSettings() if settings is None else settings)

    @property
    def n_control(self) -> int:
        return self.control_dofs.size

    def driving(self, amplitudes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """g_f (mm) and f_q (N) for a vector of pattern amplitudes."""
        return self.pattern_gf @ amplitudes, self.pattern_fq @ amplitudes

    def solve_contact_block(self, rhs: np.ndarray, wanted: np.ndarray | None = None) -> np.ndarray:
        """K_cc⁻¹·rhs (mm) for forces ``rhs`` (N) on the contact DOFs, body block by body block;
        with ``wanted`` (positions among the contact DOFs) only the blocks that hold them."""
        return self._Kcc.solve(rhs, wanted)

    def displacements(self, control: np.ndarray, forces: np.ndarray, amplitudes: np.ndarray,
                      dofs: np.ndarray | None = None) -> np.ndarray:
        """All retained displacements (n,) mm from control DOFs q and contact forces λ (N), or
        only those at ``dofs`` (retained-DOF indices), for which only the bodies that hold them
        are solved (the damage observer's slave surface: one body of two)."""
        s = self.structure
        u = np.zeros(s.n_dofs)
        motion = self.pattern_motion @ amplitudes
        rhs = (self.pattern_force_c @ amplitudes - self._Kcp @ motion - self._Kcq @ control
               - self._GcT @ forces)
        wanted = None
        if dofs is not None:
            position = np.full(s.n_dofs, -1)
            position[self.contact_dofs] = np.arange(self.contact_dofs.size)
            wanted = position[dofs]
            wanted = wanted[wanted >= 0]
        u[self.contact_dofs] = self.solve_contact_block(rhs, wanted)
        u[self.control_dofs] = control
        u[self.prescribed] = motion
        return u if dofs is None else u[dofs]

    def external_forces(self, displacement: np.ndarray, forces: np.ndarray,
                        amplitudes: np.ndarray) -> np.ndarray:
        """Forces (n,) N the surroundings apply: the loads, and the reactions at prescribed DOFs."""
        s = self.structure
        applied = np.zeros(s.n_dofs)
        for k, name in enumerate(s.patterns):
            if name in s.loads:
                applied += amplitudes[k] * s.loads[name]
        # Only the prescribed rows of the internal forces are needed; locked bolts act on
        # control DOFs, which are never prescribed.
        p = self.prescribed
        applied[p] = s.stiffness[p] @ displacement + s.contact_operator[:, p].T @ forces
        return applied
