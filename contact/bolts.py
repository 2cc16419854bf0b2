"""Bolts: axial elements between two reference points, pretensioned and then locked.

Like an FE "bolt load": during the preload the bolt carries exactly its pretension F (a
pair of forces pulling head and nut together, the length free); then it is locked at its
current length and acts as an axial spring, so its force becomes

    T = F + k_b·(ε − ε_lock),      ε = b·u  (elongation, mm),  b = [−e at head, +e at nut]

with e the unit axis from head to nut and k_b = E·A_s/L the bolt's axial stiffness (N/mm).
Both reference points must be free control DOFs, so locking changes only the control block
of the contact-space system, never the contact compliance. Units: mm, N.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from reduction.errors import InputError


@dataclass(frozen=True)
class Bolt:
    """An axial bolt between ``head`` and ``nut`` control points ("body.point" labels).

    axis: unit vector from head to nut. stiffness: k_b, N/mm. pretension: F, N.
    """

    name: str
    head: str
    nut: str
    axis: np.ndarray
    stiffness: float
    pretension: float


def bolt_vector(bolt: Bolt, labels: dict, n_dofs: int) -> np.ndarray:
    """b (n_dofs,): elongation ε = b·u of the bolt from the global displacement."""
    axis = np.asarray(bolt.axis, dtype=float)
    axis = axis / np.linalg.norm(axis)
    vector = np.zeros(n_dofs)
    for point, sign in ((bolt.head, -1.0), (bolt.nut, 1.0)):
        for component, direction in zip(("ux", "uy", "uz"), axis):
            label = f"{point}.{component}"
            if label not in labels:
                if direction != 0.0:
                    raise InputError(f"bolt {bolt.name}: no control DOF {label!r} "
                                     f"(available: {', '.join(labels)})")
                continue
            vector[labels[label]] += sign * direction
    return vector


def pretension_pattern(bolt: Bolt, vector: np.ndarray) -> np.ndarray:
    """External-load image of the pretension at unit amplitude: −F·b (N)."""
    return -bolt.pretension * vector


def lock_pattern(vector: np.ndarray) -> np.ndarray:
    """Load image of a locked bolt's length offset: b per N of k_b·ε_lock."""
    return vector.copy()


class BoltSet:
    """The bolts of a structure: their vectors b, pretension patterns, locking and forces."""

    def __init__(self, bolts: tuple, vectors: np.ndarray, patterns: tuple[str, ...],
                 locked_elongation: np.ndarray | None = None):
        self.bolts = bolts
        self.vectors = vectors  # (n_bolts, n_dofs)
        self.patterns = patterns  # load pattern name of each bolt's pretension
        self.locked_elongation = locked_elongation

    @property
    def names(self) -> list[str]:
        return [b.name for b in self.bolts]

    @property
    def stiffness(self) -> np.ndarray:
        return np.array([b.stiffness for b in self.bolts], dtype=float)

    @property
    def pretension(self) -> np.ndarray:
        return np.array([b.pretension for b in self.bolts], dtype=float)

    def _control_vectors(self, space) -> np.ndarray:
        vectors = self.vectors
        outside = np.concatenate([space.contact_dofs, space.prescribed])
        if np.any(vectors[:, outside] != 0.0):
            raise InputError("bolt reference points must be free control points: not on a "
                             "contact surface and without a prescribed motion")
        return vectors[:, space.control_dofs]

    def elongation(self, space, control: np.ndarray) -> np.ndarray:
        """ε (n_bolts,) mm from the control DOFs of an equilibrium."""
        return self._control_vectors(space) @ control

    def lock_at(self, space, elongation: np.ndarray):
        """Lock every bolt at the elongation ε_lock (mm); returns (locked set, locked space).

        The locked space has the bolts' axial stiffness in its control block.
        """
        control_vectors = self._control_vectors(space)
        extra = np.einsum("b,bi,bj->ij", self.stiffness, control_vectors, control_vectors)
        locked = BoltSet(self.bolts, self.vectors, self.patterns, np.asarray(elongation, dtype=float))
        return locked, space.with_control_stiffness(extra)

    def locked_amplitudes(self, space, equilibrium) -> np.ndarray:
        """Pattern amplitudes after locking: each pretension pattern becomes 1 − k_b·ε_lock/F,
        so the equilibrium at the moment of locking is unchanged."""
        amplitudes = equilibrium.amplitudes.copy()
        names = space.structure.patterns
        for k, pattern in enumerate(self.patterns):
            amplitudes[names.index(pattern)] = (1.0 - self.stiffness[k] * self.locked_elongation[k]
                                                / self.pretension[k])
        return amplitudes

    def forces(self, space, equilibrium) -> np.ndarray:
        """Axial bolt forces T (n_bolts,) N at an equilibrium."""
        if self.locked_elongation is None:
            names = space.structure.patterns
            return np.array([self.pretension[k] * equilibrium.amplitudes[names.index(p)]
                             for k, p in enumerate(self.patterns)])
        return self.pretension + self.stiffness * (self.elongation(space, equilibrium.control)
                                                   - self.locked_elongation)


@dataclass(frozen=True)
class RingOffset:
    """Where a bolt end's coupled nodes (its ring) lie against its reference point, mm.

    centre: (dim,) the middle of the nodes' extent along each coordinate: the centre of a ring or
    patch symmetric about its bolt, however its mesh is graded (the mean of the nodes would lean
    towards the finer side). distance: from the reference point to the centre; lever: its part
    across the bolt's axis (the lever arm of the bolt's force about the ring's centre). radius:
    root-mean-square distance of the nodes from the line through the centre along the axis;
    extent: the largest distance of a node from the centre.
    """

    centre: np.ndarray
    distance: float
    lever: float
    radius: float
    extent: float


def ring_offset(coordinates: np.ndarray, position: np.ndarray, axis: np.ndarray) -> RingOffset:
    """The :class:`RingOffset` of nodes at ``coordinates`` (n, dim) mm coupled to a reference point
    at ``position`` (dim,) mm, for a bolt along ``axis`` (dim,)."""
    coordinates = np.asarray(coordinates, dtype=float)
    centre = 0.5 * (coordinates.min(axis=0) + coordinates.max(axis=0))
    relative = coordinates - centre
    offset = np.asarray(position, dtype=float) - centre
    return RingOffset(centre, float(np.linalg.norm(offset)), float(np.linalg.norm(_across(offset[None], axis)[0])),
                      float(np.sqrt(np.mean(np.sum(_across(relative, axis) ** 2, axis=1)))),
                      float(np.max(np.linalg.norm(relative, axis=1))))


def _across(vectors: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """The parts of ``vectors`` (n, dim) across ``axis`` (dim,): their components along it removed."""
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    return vectors - np.outer(vectors @ axis, axis)


def joint_tilt(axis: np.ndarray, facet_normals: np.ndarray, facet_areas: np.ndarray) -> float:
    """Angle (degrees, 0…90) between a bolt's axis and the joint's normal: the area-weighted
    mean of ``facet_normals`` (n, dim), unit, with ``facet_areas`` (n,) mm² (mm in 2D).
    The axis's sense does not matter (head to nut may point either way through the joint)."""
    mean = np.asarray(facet_areas, dtype=float) @ np.asarray(facet_normals, dtype=float)
    axis = np.asarray(axis, dtype=float)
    cosine = abs(float(mean @ axis)) / (np.linalg.norm(mean) * np.linalg.norm(axis))
    return float(np.degrees(np.arccos(min(1.0, cosine))))


def facets_near_axis(centroids: np.ndarray, point: np.ndarray, axis: np.ndarray, radius: float) -> np.ndarray:
    """Boolean mask of facet ``centroids`` (n, dim) mm within ``radius`` mm of the line through
    ``point`` along ``axis`` (a bolt's axis through its head)."""
    relative = np.asarray(centroids, dtype=float) - np.asarray(point, dtype=float)
    return np.linalg.norm(_across(relative, axis), axis=1) <= radius
