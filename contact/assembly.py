"""From elastic bodies and a pair of surfaces to a condensed :class:`Structure`.

Each body is reduced in three exact steps: its reference points are coupled to node sets
(RBE2), held DOFs are removed, and the stiffness is statically condensed onto the contact
surface DOFs plus the reference DOFs. The condensed blocks are placed in one global
numbering, body after body, and the paired surfaces give the contact operator.
Units: mm, N, MPa.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from contact.bolts import BoltSet, bolt_vector, pretension_pattern
from contact.interface import Pairing, Surface, kinematic_operator, pair_surfaces, surface_from_facets
from contact.structure import Structure
from reduction.condensation import Condensation, condense
from reduction.coupling import Coupling, rigid_couplings
from reduction.elasticity import ElasticBody
from reduction.errors import InputError


@dataclass(frozen=True)
class ReferencePoint:
    """A control point coupled rigidly (RBE2) to a node set of its body.

    nodes: mesh node indices. position: (dim,) mm. rotations: couple rotations too
    (adds one rotational DOF in 2D, three in 3D; radians).
    """

    nodes: np.ndarray
    position: np.ndarray
    rotations: bool = False


@dataclass(frozen=True)
class Body:
    """One elastic body of a contact model.

    fixed_nodes: node indices whose displacement components ``fixed_components`` are held at
    zero (e.g. the bottom of a plane specimen); supports: further (node indices, components)
    pairs held at zero (e.g. a symmetry plane, which may cut the contact surface: its contact
    DOFs are then held in the condensed model). reference_points: name → ReferencePoint.
    body_loads: pattern name → nodal force vector (n_dofs,) N at unit amplitude (gravity,
    centrifugal or inertia loads); condensed exactly with the body.
    """

    name: str
    elastic: ElasticBody
    fixed_nodes: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    fixed_components: tuple[int, ...] = (0, 1)
    reference_points: dict = field(default_factory=dict)
    body_loads: dict = field(default_factory=dict)
    supports: tuple = ()

    def held_dofs(self) -> np.ndarray:
        """Sorted DOFs (of ``elastic``) held at zero by all the body's supports."""
        pairs = ((self.fixed_nodes, self.fixed_components),) + tuple(self.supports)
        held = [self.elastic.node_dofs[np.asarray(nodes, dtype=int)][:, list(components)].ravel()
                for nodes, components in pairs if len(nodes)]
        return np.unique(np.concatenate(held)) if held else np.zeros(0, dtype=int)


@dataclass(frozen=True)
class CondensedBody:
    """A body after coupling and condensation, and where it sits in the global numbering."""

    body: Body
    coupling: Coupling | None
    condensation: Condensation
    offset: int
    reference_dofs: dict  # reference point name → global indices of its DOFs
    held: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))  # global contact DOFs held at 0

    @property
    def size(self) -> int:
        return self.condensation.retained.size

    def full_displacement(self, retained_global: np.ndarray) -> np.ndarray:
        """Nodal displacement field (n_dofs,) mm of the body from the global retained vector."""
        local = retained_global[self.offset:self.offset + self.size]
        reduced = self.condensation.expand(local)
        return reduced if self.coupling is None else self.coupling.expand(reduced)


@dataclass(frozen=True)
class Assembly:
    """The structure together with the bookkeeping to go back to bodies and fields."""

    structure: Structure
    bodies: dict  # name → CondensedBody
    pairing: Pairing
    slave_body: str
    master_body: str


def component_names(dim: int, rotations: bool) -> list[str]:
    """Labels of a reference point's DOFs: ux, uy[, uz] and, with rotations, rz or rx, ry, rz."""
    names = ["ux", "uy", "uz"][:dim]
    if rotations:
        names += ["rz"] if dim == 2 else ["rx", "ry", "rz"]
    return names


def _condense_body(body: Body, surface: Surface | None, offset: int, condenser=None,
                   keep_interior: bool = False) -> CondensedBody:
    elastic = body.elastic
    stiffness = elastic.stiffness
    coupling = None
    kept = np.arange(elastic.n_dofs)
    names = list(body.reference_points)
    if names:
        groups = [(np.asarray(body.reference_points[n].nodes), body.reference_points[n].position)
                  for n in names]
        rotations = {body.reference_points[n].rotations for n in names}
        if len(rotations) > 1:
            raise InputError(f"body {body.name}: all reference points of one body must agree on "
                             "coupling rotations")
        coupling = rigid_couplings(elastic.n_dofs, elastic.node_dofs, elastic.coordinates, groups,
                                   rotations=rotations.pop())
        stiffness = coupling.reduce_matrix(stiffness)
        kept = coupling.kept
    surface_dofs = np.zeros(0, dtype=int)
    if surface is not None:
        surface_dofs = kept[elastic.node_dofs[surface.nodes]].ravel()
        if np.any(surface_dofs < 0):
            raise InputError(f"body {body.name}: the contact surface shares nodes with a "
                             "reference-point coupling; couple a different node set")
    reference = [] if coupling is None else [np.atleast_2d(coupling.reference_dofs)[k]
                                             for k in range(len(names))]
    retained = np.concatenate([surface_dofs] + reference).astype(int)
    fixed = kept[body.held_dofs()]
    if np.any(fixed < 0):
        raise InputError(f"body {body.name}: fixed nodes overlap a reference-point coupling")
    # held DOFs of the contact surface (a symmetry plane through it) stay retained and are held
    # in the condensed model: the same as holding them before condensing
    on_surface = np.isin(fixed, surface_dofs)
    held = offset + np.flatnonzero(np.isin(retained, fixed[on_surface]))
    fixed = fixed[~on_surface]
    loads = {name: vector if coupling is None else coupling.reduce_vector(vector)
             for name, vector in body.body_loads.items()}
    if keep_interior:
        condensation = _kept_whole(stiffness, retained, fixed, loads)
    elif condenser is None:
        condensation = condense(stiffness, retained, fixed, loads or None)
    else:
        transformation = None if coupling is None else coupling.transformation
        condensation = condenser(stiffness, transformation, retained, fixed, loads or None)
    reference_dofs, start = {}, offset + surface_dofs.size
    for name, dofs in zip(names, reference):
        reference_dofs[name] = np.arange(start, start + dofs.size)
        start += dofs.size
    return CondensedBody(body, coupling, condensation, offset, reference_dofs, held)


def _kept_whole(stiffness, first: np.ndarray, fixed: np.ndarray, loads: dict) -> Condensation:
    """A body kept whole in the shape of a :class:`Condensation`: every DOF not fixed is
    retained, ``first`` (contact surface, reference points) in front as condensing would
    retain them, then the interior in order; the stiffness (N/mm) stays sparse (CSR) and the
    loads (N) are the body's own, nothing condensed."""
    matrix = sp.csr_matrix(stiffness)
    rest = np.ones(matrix.shape[0], dtype=bool)
    rest[first] = False
    rest[fixed] = False
    retained = np.concatenate([first, np.flatnonzero(rest)]).astype(int)
    return Condensation(retained=retained, stiffness=matrix[retained][:, retained].tocsr(),
                        loads={name: np.asarray(vector, dtype=float)[retained] for name, vector in loads.items()},
                        interior=np.zeros(0, dtype=int), fixed=np.asarray(fixed, dtype=int),
                        n_dofs=matrix.shape[0], solver="none", interior_loads={},
                        interior_retained_coupling=sp.csr_matrix((0, retained.size)),
                        solve_interior=lambda rhs: rhs)


def assemble(bodies: list[Body], slave: tuple[str, np.ndarray], master: tuple[str, np.ndarray], *,
             loads: dict | None = None, motions: dict | None = None,
             search_distance: float = np.inf,
             initial_gap: np.ndarray | None = None, bolts: tuple = (),
             pairing: str = "auto", condensers: dict | None = None,
             keep_interior: bool = False) -> Assembly:
    """Condense the bodies and pair ``slave`` = (body name, facet indices) with ``master``.

    loads / motions: pattern name → list of (body, reference point, component, value);
    components are "ux", "uy", "uz", "rz", ...; values in N (N·mm for moments) or mm (rad).
    A DOF driven by a motion pattern is prescribed. initial_gap (n_slave_points,) mm, when
    given, replaces the geometric gap (e.g. an analytic profile on flat meshes).
    bolts: :class:`contact.bolts.Bolt` items; each adds a pretension load pattern
    "bolt.<name>" that ramps in the preload and is locked afterwards.
    pairing: "auto", "node_to_segment" or "mortar" (see :func:`contact.interface.pair_surfaces`).
    condensers: body name → callable (stiffness, transformation, retained, fixed, loads) →
    Condensation used instead of :func:`reduction.condensation.condense` (a body whose
    factorisation is shared with another load case, :class:`pipelines.coupling.SharedCondenser`).
    keep_interior: keep every body whole instead (:func:`_kept_whole`:
    the contact surface and reference DOFs first, as condensed, then the interior); the
    structure's stiffness is then sparse, for :class:`contact.sparse.SparseContactSpace`.
    Condensers do not apply then.
    """
    surfaces = _contact_surfaces(bodies, slave, master)
    condensed, n = _condense_bodies(bodies, surfaces, {} if keep_interior else (condensers or {}), keep_interior)
    stiffness = _block_stiffness(condensed, n)
    pairing = pair_with_gap(surfaces[slave[0]], surfaces[master[0]], search_distance, initial_gap, pairing)
    dim = pairing.normal.shape[1]
    G = kinematic_operator(pairing, _surface_dofs(condensed[slave[0]], surfaces[slave[0]], dim),
                           _surface_dofs(condensed[master[0]], surfaces[master[0]], dim), n)
    labels = _reference_labels(condensed, dim)

    load_vectors, motion_vectors, prescribed = control_patterns(labels, n, loads, motions)
    prescribed = np.union1d(prescribed, np.concatenate([item.held for item in condensed.values()])).astype(int)
    bolt_set = _add_bolt_patterns(bolts, labels, n, load_vectors) if bolts else None
    _add_body_loads(condensed, n, load_vectors)
    structure = Structure(stiffness=stiffness, contact_operator=G, area=pairing.area,
                          initial_overclosure=pairing.initial_overclosure, dim=dim,
                          prescribed=prescribed, loads=load_vectors, motions=motion_vectors,
                          labels=labels, bolts=bolt_set)
    return Assembly(structure, condensed, pairing, slave[0], master[0])


def _contact_surfaces(bodies: list[Body], slave: tuple[str, np.ndarray],
                      master: tuple[str, np.ndarray]) -> dict[str, Surface]:
    """Body name → contact surface, for the slave and the master body."""
    by_name = {b.name: b for b in bodies}
    for role, (name, _) in (("slave", slave), ("master", master)):
        if name not in by_name:
            raise InputError(f"{role} surface names body {name!r}, which is not defined "
                             f"(bodies: {', '.join(by_name)})")
    surfaces = {slave[0]: surface_from_facets(by_name[slave[0]].elastic.mesh, slave[1], f"{slave[0]} surface"),
                master[0]: surface_from_facets(by_name[master[0]].elastic.mesh, master[1], f"{master[0]} surface")}
    if slave[0] == master[0]:
        raise InputError("slave and master surfaces must belong to different bodies")
    return surfaces


def _condense_bodies(bodies: list[Body], surfaces: dict[str, Surface], condensers: dict,
                     keep_interior: bool = False) -> tuple[dict[str, CondensedBody], int]:
    """Condense each body in order; returns body name → condensed body and the total DOF count."""
    condensed, offset = {}, 0
    for body in bodies:
        item = _condense_body(body, surfaces.get(body.name), offset, condensers.get(body.name), keep_interior)
        condensed[body.name] = item
        offset += item.size
    return condensed, offset


def _block_stiffness(condensed: dict[str, CondensedBody], n: int) -> np.ndarray | sp.csr_matrix:
    """(n, n) block-diagonal stiffness of the condensed bodies, N/mm: dense, or sparse CSR when
    the bodies were kept whole."""
    blocks = [item.condensation.stiffness for item in condensed.values()]
    if any(sp.issparse(block) for block in blocks):
        return sp.block_diag(blocks, format="csr")
    stiffness = np.zeros((n, n))
    for item in condensed.values():
        index = slice(item.offset, item.offset + item.size)
        stiffness[index, index] = item.condensation.stiffness
    return stiffness


def _surface_dofs(item: CondensedBody, surface: Surface, dim: int) -> np.ndarray:
    """(n_surface_nodes, dim) global DOFs of a condensed body's contact surface."""
    return item.offset + np.arange(surface.nodes.size * dim).reshape(-1, dim)


def _reference_labels(condensed: dict[str, CondensedBody], dim: int) -> dict[str, int]:
    """Label "body.reference.component" → global DOF, for every reference point."""
    labels = {}
    for item in condensed.values():
        for ref_name, dofs in item.reference_dofs.items():
            rotations = item.body.reference_points[ref_name].rotations
            for comp, dof in zip(component_names(dim, rotations), dofs):
                labels[f"{item.body.name}.{ref_name}.{comp}"] = int(dof)
    return labels


def _add_bolt_patterns(bolts: tuple, labels: dict[str, int], n: int, load_vectors: dict) -> BoltSet:
    """Add a "bolt.<name>" pretension pattern to ``load_vectors`` per bolt; returns the bolt set."""
    vectors = np.array([bolt_vector(bolt, labels, n) for bolt in bolts])
    names = tuple(f"bolt.{bolt.name}" for bolt in bolts)
    for name, bolt, vector in zip(names, bolts, vectors):
        load_vectors[name] = pretension_pattern(bolt, vector)
    return BoltSet(tuple(bolts), vectors, names)


def _add_body_loads(condensed: dict[str, CondensedBody], n: int, load_vectors: dict) -> None:
    """Add each body's condensed body loads to the pattern of the same name in ``load_vectors``."""
    # Body loads act everywhere; where a DOF is prescribed its share goes to the reaction.
    for item in condensed.values():
        for name, vector in item.condensation.loads.items():
            load_vectors.setdefault(name, np.zeros(n))[item.offset:item.offset + item.size] += vector


def pair_with_gap(slave: Surface, master: Surface, search_distance: float,
                  initial_gap: np.ndarray | None, method: str = "auto") -> Pairing:
    """Pair the surfaces by ``method``; ``initial_gap`` (n_slave_points,) mm, when given,
    replaces the geometric gap (an analytic profile on flat meshes)."""
    pairing = pair_surfaces(slave, master, method=method, search_distance=search_distance)
    if initial_gap is None:
        return pairing
    gap = np.asarray(initial_gap, dtype=float)
    if gap.shape != pairing.initial_overclosure.shape:
        raise InputError(f"initial gap has {gap.size} values for {pairing.n_points} contact points")
    return Pairing(**{**pairing.__dict__, "initial_overclosure": -gap})


def control_patterns(labels: dict, n_dofs: int, loads: dict | None, motions: dict | None):
    """Load and motion patterns on named control DOFs, and the prescribed DOFs.

    loads / motions: pattern name → list of (body, reference point, component, value).
    Every DOF a motion names is prescribed, also with value 0 (a DOF held in place); a load
    on a prescribed DOF is an input error. Returns (load vectors, motion vectors, prescribed).
    """
    def vectors_of(spec, kind):
        vectors, named = {}, set()
        for pattern, entries in (spec or {}).items():
            vector = np.zeros(n_dofs)
            for body_name, ref_name, comp, value in entries:
                label = f"{body_name}.{ref_name}.{comp}"
                if label not in labels:
                    raise InputError(f"{kind} {pattern!r}: no control DOF {label!r} "
                                     f"(available: {', '.join(labels) or 'none'})")
                vector[labels[label]] += value
                named.add(labels[label])
            vectors[pattern] = vector
        return vectors, named

    load_vectors, _ = vectors_of(loads, "load")
    motion_vectors, moved = vectors_of(motions, "motion")
    prescribed = np.array(sorted(moved), dtype=int)
    for pattern, vector in load_vectors.items():
        if np.any(vector[prescribed]):
            raise InputError(f"load {pattern!r} acts on a DOF whose motion is prescribed")
    return load_vectors, motion_vectors, prescribed


def stored_energy(structure: Structure, displacement: np.ndarray) -> float:
    """Elastic strain energy of the condensed bodies, ½·uᵀ·K·u, mJ (exact for unloaded interiors)."""
    return 0.5 * float(displacement @ (structure.stiffness @ displacement))

