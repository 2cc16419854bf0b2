"""The same contact problem on the full, uncondensed sparse model: the reference for the condensed one.

Every body keeps all its DOFs. Reference points are coupled (RBE2) and held DOFs removed
exactly as in :func:`contact.assembly.assemble` (held DOFs of the contact surface, a symmetry
plane through it, simply drop out of the contact kinematics); the bodies sit in one global
numbering of their free DOFs (neither fixed nor prescribed), and Newton solves

    K·u + K_p·u_p + Gᵀ·λ(G·u) − f(t) = 0,       λ = A·[p, τ] from :mod:`contact.law`,

with the tangent ``K + Gᵀ·(A·D)·G`` factorised by a sparse LU every iteration (MKL PARDISO
when installed, else SuperLU). Line search, cutback and the history update follow
:class:`contact.solver.ContactSolver`; the kinematic tolerance applies to the Newton
correction of the contact kinematics ``G·Δu`` and the force tolerance to the residual.
Units: mm, N, MPa.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from contact.assembly import Body, component_names, control_patterns, pair_with_gap
from contact.interface import Pairing, Surface, kinematic_operator, surface_from_facets
from contact.law import ContactLaw, ContactState, Response, evaluate
from contact.linear import tangent_blocks
from contact.solver import Effects, IncrementStats, NewtonSettings, advance_with_cutbacks
from reduction import pardiso
from reduction.coupling import rigid_couplings
from reduction.errors import InputError


@dataclass(frozen=True)
class FullModel:
    """All bodies, uncondensed, on their free DOFs.

    stiffness: K (n_free, n_free) CSR, N/mm.  prescribed_stiffness: K_p (n_free, n_prescribed).
    contact_operator: G (n_points·dim, n_free), rows per point [normal, tangent(s)].
    pattern_force: (n_free, n_patterns) N at unit amplitude; pattern_motion: (n_prescribed,
    n_patterns) mm. Patterns are the loads then the motions, as in :class:`contact.structure.Structure`.
    body_dofs: body name → (n_body_dofs,) global free index of each original DOF, −1 where
    fixed or coupled; labels: control DOF name → ("free" | "prescribed", index).
    """

    stiffness: sp.csr_matrix
    prescribed_stiffness: sp.csr_matrix
    contact_operator: sp.csr_matrix
    area: np.ndarray
    initial_overclosure: np.ndarray
    dim: int
    pattern_force: np.ndarray
    pattern_motion: np.ndarray
    patterns: tuple
    pairing: Pairing
    labels: dict = field(default_factory=dict)

    @property
    def n_dofs(self) -> int:
        return self.stiffness.shape[0]

    @property
    def n_points(self) -> int:
        return self.area.size


def build(bodies: list[Body], slave: tuple[str, np.ndarray], master: tuple[str, np.ndarray], *,
          loads: dict | None = None, motions: dict | None = None, search_distance: float = np.inf,
          initial_gap: np.ndarray | None = None) -> FullModel:
    """The full model of the inputs that :func:`contact.assembly.assemble` condenses (same arguments)."""
    by_name = {b.name: b for b in bodies}
    surfaces = _contact_surfaces(by_name, slave, master)
    blocks, offsets, kept_maps, fixed_all, labels, offset = [], {}, {}, [], {}, 0
    for body in bodies:
        block, kept, fixed, body_labels = _body_block(body, surfaces.get(body.name), offset)
        labels.update(body_labels)
        if fixed is not None:
            fixed_all.append(fixed)
        blocks.append(block)
        offsets[body.name], kept_maps[body.name] = offset, kept
        offset += block.shape[0]
    n_all = offset
    stiffness_all = sp.block_diag(blocks, format="csr")

    load_vectors, motion_vectors, prescribed = control_patterns(labels, n_all, loads, motions)
    free, index = _free_numbering(n_all, fixed_all, prescribed)
    pairing = pair_with_gap(surfaces[slave[0]], surfaces[master[0]], search_distance, initial_gap)
    slave_dofs = _surface_dofs(by_name[slave[0]], surfaces[slave[0]], offsets[slave[0]], kept_maps[slave[0]], index)
    master_dofs = _surface_dofs(by_name[master[0]], surfaces[master[0]], offsets[master[0]], kept_maps[master[0]],
                                index)
    # held surface DOFs point at one extra column, dropped: they do not move
    G = kinematic_operator(pairing, slave_dofs, master_dofs, free.size + 1)[:, :free.size].tocsr()
    patterns, force, motion = _pattern_columns(load_vectors, motion_vectors, free, prescribed)
    where = _control_labels(labels, index, prescribed)
    return FullModel(stiffness=stiffness_all[free][:, free].tocsr(),
                     prescribed_stiffness=stiffness_all[free][:, prescribed].tocsr(),
                     contact_operator=G, area=pairing.area,
                     initial_overclosure=pairing.initial_overclosure, dim=pairing.normal.shape[1],
                     pattern_force=force, pattern_motion=motion, patterns=patterns, pairing=pairing,
                     labels=where)


def _contact_surfaces(by_name: dict[str, Body], slave: tuple[str, np.ndarray],
                      master: tuple[str, np.ndarray]) -> dict[str, Surface]:
    """Body name → contact surface, for the slave and the master body."""
    for role, (name, _) in (("slave", slave), ("master", master)):
        if name not in by_name:
            raise InputError(f"{role} surface names body {name!r}, which is not defined "
                             f"(bodies: {', '.join(by_name)})")
    if slave[0] == master[0]:
        raise InputError("slave and master surfaces must belong to different bodies")
    return {name: surface_from_facets(by_name[name].elastic.mesh, facets, f"{name} surface")
            for name, facets in (slave, master)}


def _body_block(body: Body, surface: Surface | None, offset: int):
    """One body's block of the global model, its DOFs numbered from ``offset``.

    Returns the stiffness (CSR, N/mm) on the kept DOFs, kept (n_body_dofs,) (index of each
    original DOF among the kept ones, −1 where coupled), the global fixed DOFs (None when the
    body has no fixed nodes) and the control DOF labels → global DOF.
    """
    elastic = body.elastic
    stiffness, kept, labels = _couple_reference_points(body, offset)
    if surface is not None and np.any(kept[elastic.node_dofs[surface.nodes]] < 0):
        raise InputError(f"body {body.name}: the contact surface shares nodes with a "
                         "reference-point coupling; couple a different node set")
    fixed = None
    if body.held_dofs().size:
        fixed = kept[body.held_dofs()]
        if np.any(fixed < 0):
            raise InputError(f"body {body.name}: fixed nodes overlap a reference-point coupling")
        fixed = offset + fixed
    return sp.csr_matrix(stiffness), kept, fixed, labels


def _couple_reference_points(body: Body, offset: int):
    """RBE2-couple the body's reference points: (stiffness, kept, labels → global DOF)."""
    elastic = body.elastic
    names = list(body.reference_points)
    labels = {}
    if not names:
        return elastic.stiffness, np.arange(elastic.n_dofs), labels
    points = [body.reference_points[n] for n in names]
    rotations = {p.rotations for p in points}
    if len(rotations) > 1:
        raise InputError(f"body {body.name}: all reference points of one body must agree on "
                         "coupling rotations")
    coupling = rigid_couplings(elastic.n_dofs, elastic.node_dofs, elastic.coordinates,
                               [(np.asarray(p.nodes), p.position) for p in points],
                               rotations=rotations.pop())
    stiffness = coupling.reduce_matrix(elastic.stiffness)
    reference = np.atleast_2d(coupling.reference_dofs)
    for k, name in enumerate(names):
        for comp, dof in zip(component_names(elastic.dim, points[k].rotations), reference[k]):
            labels[f"{body.name}.{name}.{comp}"] = offset + int(dof)
    return stiffness, coupling.kept, labels


def _free_numbering(n_all: int, fixed_all: list[np.ndarray], prescribed: np.ndarray):
    """Free DOFs (neither fixed nor prescribed) and index (n_all,): free number of each DOF, −1 if none."""
    fixed = np.concatenate(fixed_all) if fixed_all else np.zeros(0, dtype=int)
    if np.intersect1d(fixed, prescribed).size:
        raise InputError("a prescribed control DOF is also held fixed")
    free = np.setdiff1d(np.arange(n_all), np.concatenate([fixed, prescribed]))
    index = np.full(n_all, -1)
    index[free] = np.arange(free.size)
    return free, index


def _surface_dofs(body: Body, surface: Surface, offset: int, kept: np.ndarray, index: np.ndarray) -> np.ndarray:
    """(n_surface_nodes, dim) free global DOFs of a body's contact surface; a DOF held by a support
    through the surface (a symmetry plane) is ``n_free``, one past the free DOFs (coupled surface
    nodes were refused in :func:`_body_block`)."""
    dofs = index[offset + kept[body.elastic.node_dofs[surface.nodes]]]
    return np.where(dofs < 0, np.count_nonzero(index >= 0), dofs)


def _pattern_columns(load_vectors: dict, motion_vectors: dict, free: np.ndarray, prescribed: np.ndarray):
    """Pattern names (loads, then motions), force (n_free, n_patterns) N, motion (n_prescribed, n_patterns) mm."""
    patterns = tuple(load_vectors) + tuple(motion_vectors)
    force = np.column_stack([load_vectors[p][free] if p in load_vectors else np.zeros(free.size)
                             for p in patterns] or [np.zeros(free.size)])[:, :len(patterns)]
    motion = np.column_stack([motion_vectors[p][prescribed] if p in motion_vectors
                              else np.zeros(prescribed.size) for p in patterns]
                             or [np.zeros(prescribed.size)])[:, :len(patterns)]
    return patterns, force, motion


def _control_labels(labels: dict[str, int], index: np.ndarray, prescribed: np.ndarray) -> dict:
    """Control DOF name → ("free" | "prescribed", index); fixed control DOFs are left out."""
    return {label: ("prescribed", int(np.searchsorted(prescribed, dof))) if dof in prescribed
            else ("free", int(index[dof])) for label, dof in labels.items() if index[dof] >= 0 or dof in prescribed}


@dataclass(frozen=True)
class FullEquilibrium:
    """A converged configuration of the full model.

    displacement: u (n_free,) mm.  kinematics: G·u (n_rows,) mm, relative to h₀ (as the
    condensed ``Equilibrium.kinematics``).  forces: λ (n_rows,) N.  amplitudes: pattern amplitudes.
    """

    displacement: np.ndarray
    kinematics: np.ndarray
    forces: np.ndarray
    amplitudes: np.ndarray


class TangentAssembler:
    """K + Gᵀ·blockdiag(A·D)·G on one fixed sparsity pattern, as one sparse product per iteration.

    The pattern is that of K + Gᵀ·B·G with B full dim×dim blocks, so it does not change when
    tangent entries vanish (open points, zero trial slip); the sparse LU can then keep its
    ordering and symbolic analysis. ``values(blocks)`` are K's entries plus L·vec(blocks),
    L mapping every per-point tangent entry onto the matrix entries it feeds.
    """

    def __init__(self, stiffness: sp.csr_matrix, operator: sp.csr_matrix, dim: int):
        n = stiffness.shape[0]
        G = operator.tocoo()
        order = np.argsort(G.row, kind="stable")
        rows, cols, vals = G.row[order], G.col[order], G.data[order]
        point = rows // dim
        counts = np.bincount(point, minlength=operator.shape[0] // dim)
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        # All pairs (e1, e2) of G entries of the same point: e1 repeated, e2 running over the point.
        first = np.repeat(np.arange(rows.size), counts[point])
        offsets = np.arange(first.size) - np.repeat(np.cumsum(counts[point]) - counts[point], counts[point])
        second = starts[point[first]] + offsets
        keys_contact = cols[first].astype(np.int64) * n + cols[second]
        K = stiffness.tocoo()
        keys_stiffness = K.row.astype(np.int64) * n + K.col
        keys = np.unique(np.concatenate([keys_stiffness, keys_contact]))
        self.indices = (keys % n).astype(np.int32)
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(keys // n, minlength=n))]).astype(np.int32)
        self.stiffness_values = np.bincount(np.searchsorted(keys, keys_stiffness), weights=K.data,
                                            minlength=keys.size)
        block_entry = point[first] * dim * dim + (rows[first] % dim) * dim + rows[second] % dim
        self.spread = sp.csr_matrix((vals[first] * vals[second], (np.searchsorted(keys, keys_contact), block_entry)),
                                    shape=(keys.size, counts.size * dim * dim))
        self.shape = (n, n)

    def matrix(self, blocks: np.ndarray) -> sp.csr_matrix:
        """The tangent for per-point blocks (n_points, dim, dim), N/mm."""
        values = self.stiffness_values + self.spread @ blocks.ravel()
        return sp.csr_matrix((values, self.indices, self.indptr), shape=self.shape)


class SparseLU:
    """Repeated LU solves of matrices with one sparsity pattern (unsymmetric).

    MKL PARDISO when installed: the ordering and symbolic analysis are done once, then each
    call refactorises numerically and solves. Otherwise SciPy's SuperLU from scratch each call.
    """

    def __init__(self, pattern: sp.csr_matrix):
        self.name = "pardiso" if pardiso.available() else "splu"
        if self.name == "pardiso":
            from pypardiso import PyPardisoSolver

            self._pardiso = PyPardisoSolver(mtype=11)
            self._pardiso._check_A(pattern)
            self._pardiso.set_phase(11)
            self._pardiso._call_pardiso(pattern, np.zeros(pattern.shape[0]))

    def solve(self, matrix: sp.csr_matrix, rhs: np.ndarray) -> np.ndarray:
        if self.name == "pardiso":
            self._pardiso.set_phase(23)
            return self._pardiso._call_pardiso(matrix, np.asfortranarray(rhs, dtype=float))
        return spla.splu(matrix.tocsc()).solve(rhs)


class FullModelSolver:
    """Newton on the full model with the interface of :class:`contact.solver.ContactSolver`."""

    def __init__(self, model: FullModel, law: ContactLaw, settings: NewtonSettings = NewtonSettings()):
        self.model = model
        self.law = law
        self.settings = settings
        self.dim = model.dim
        self.n_points = model.n_points
        self.area = model.area
        self.h0 = model.initial_overclosure
        self.G = model.contact_operator.tocsr()
        self.GT = self.G.T.tocsr()
        self._assembler = TangentAssembler(model.stiffness, self.G, self.dim)
        self._lu = SparseLU(self._assembler.matrix(np.ones((self.n_points, self.dim, self.dim))))

    def initial_equilibrium(self) -> FullEquilibrium:
        rows = self.n_points * self.dim
        return FullEquilibrium(np.zeros(self.model.n_dofs), np.zeros(rows), np.zeros(rows),
                               np.zeros(len(self.model.patterns)))

    def _response(self, kinematics, reference, state) -> Response:
        per_point = kinematics.reshape(self.n_points, self.dim)
        slip = per_point[:, 1:] - reference.reshape(self.n_points, self.dim)[:, 1:]
        return evaluate(self.h0 + per_point[:, 0], slip, state, self.law)

    def _forces(self, response: Response) -> np.ndarray:
        traction = np.concatenate([response.pressure[:, None], response.shear], axis=1)
        return (self.area[:, None] * traction).ravel()

    def _residual(self, u, external, state, reference):
        kinematics = self.G @ u
        response = self._response(kinematics, reference, state)
        forces = self._forces(response)
        return self.model.stiffness @ u + self.GT @ forces - external, kinematics, response, forces

    def _solve_to(self, start: FullEquilibrium, state: ContactState, amplitudes: np.ndarray,
                  stats: IncrementStats, position: tuple[int, int] | None = None):
        """Newton from ``start`` (no predictors here: ``position`` is not used)."""
        model, settings = self.model, self.settings
        external = model.pattern_force @ amplitudes - model.prescribed_stiffness @ (model.pattern_motion @ amplitudes)
        force_scale = max(1.0, float(np.max(np.abs(model.pattern_force @ amplitudes), initial=0.0)),
                          float(np.max(np.abs(start.forces), initial=0.0)))
        force_tolerance = settings.force_tolerance * force_scale
        reference = start.kinematics
        u = start.displacement.copy()
        residual, kinematics, response, forces = self._residual(u, external, state, reference)
        merit = float(np.linalg.norm(residual)) / force_tolerance
        for iteration in range(1, settings.max_iterations + 1):
            delta = -self._lu.solve(self._assembler.matrix(tangent_blocks(response, self.area)), residual)
            step = 1.0
            while True:
                trial = self._residual(u + step * delta, external, state, reference)
                trial_merit = float(np.linalg.norm(trial[0])) / force_tolerance
                if trial_merit <= (1.0 - 1e-4 * step) * merit or step < 1.0 / 64:
                    break
                step *= 0.5
            u = u + step * delta
            residual, kinematics, response, forces = trial
            merit = trial_merit
            if not np.all(np.isfinite(u)):
                break
            # Residual-only test: 1e-10 mm of contact kinematics is kn·A·1e-10 ≈ 1e-5 N here,
            # the order of the force tolerance, so it also bounds the kinematic error.
            if np.max(np.abs(residual), initial=0.0) <= force_tolerance:
                stats.iterations += iteration
                stats.max_iterations = max(stats.max_iterations, iteration)
                return FullEquilibrium(u, kinematics, forces, amplitudes.copy()), response
        stats.iterations += settings.max_iterations
        return None

    def _failure_reason(self) -> tuple[str, str]:
        return "diverged", "Newton did not converge on the full model"

    def increment(self, start: FullEquilibrium, state: ContactState, amplitudes: np.ndarray,
                  effects: Effects, position: tuple[int, int] | None = None
                  ) -> tuple[FullEquilibrium, ContactState, np.ndarray, IncrementStats]:
        """Advance to the load ``amplitudes`` through the sub-steps of :meth:`ContactSolver.increment`."""
        return advance_with_cutbacks(self, start, state, amplitudes, effects, position)
