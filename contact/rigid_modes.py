"""Rigid-body modes of a group of bodies and whether supports hold them (pure: arrays in, arrays out).

A group moving as one rigid body has 3 modes in 2D (ux, uy, rotation about z) and 6 in 3D.
They are written q = (t, L·θ): a translation t (mm) and a rotation θ (rad) times the group's
extent L (mm), about the centre c of its bounding box, so that every column of the mode matrix
is of order one and a rank tolerance means the same for translations and rotations. A point x
moves by u = t + θ × (x − c). Each held DOF (fixed, or with a prescribed motion) and each
kinematic constraint is one row of a matrix H, its value under q being H·q; the supports hold
the group when H has full column rank, and the rigid motions left free span the null space of H.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from reduction.coupling import rigid_body_matrix
from reduction.errors import listed

#: Relative tolerance on the singular values of H (rows of unit length). A support spread over a
#: fraction f of the extent gives a singular value of order f, a missing one of order 1e-16·√rows.
RANK_TOLERANCE = 1e-8
#: Share of a mode in the free motions above which it counts as free on its own.
PURE_SHARE = 1.0 - 1e-6
#: Share below which a mode takes no part in a free motion.
NO_SHARE = 1e-6

AXES = ("x", "y", "z")


def mode_names(dim: int) -> tuple[str, ...]:
    """The rigid modes in words, in the order of q: translations, then rotations."""
    rotations = ("z",) if dim == 2 else AXES
    return (tuple(f"translation along {axis}" for axis in AXES[:dim])
            + tuple(f"rotation about {axis}" for axis in rotations))


@dataclass(frozen=True)
class Frame:
    """Where the modes are measured: centre (dim,) mm and extent L, mm (half the diagonal of the
    bounding box of the group's nodes; 1 mm for a single point)."""

    centre: np.ndarray
    extent: float

    @classmethod
    def around(cls, points: np.ndarray) -> Frame:
        """The frame of a point cloud (n, dim) mm."""
        low, high = points.min(axis=0), points.max(axis=0)
        half_diagonal = 0.5 * float(np.linalg.norm(high - low))
        return cls(0.5 * (low + high), half_diagonal if half_diagonal > 0.0 else 1.0)

    @property
    def dim(self) -> int:
        return self.centre.size

    @property
    def n_modes(self) -> int:
        return 3 if self.dim == 2 else 6


def point_rows(frame: Frame, points: np.ndarray, components: np.ndarray) -> np.ndarray:
    """(n, n_modes) rows: displacement component ``components[k]`` (0 = x, ...) of point
    ``points[k]`` (mm) under the rigid modes."""
    points = np.asarray(points, dtype=float).reshape(-1, frame.dim)
    modes = rigid_body_matrix((points - frame.centre) / frame.extent, rotations=True)
    return modes[np.arange(points.shape[0]) * frame.dim + np.asarray(components, dtype=int)]


def rotation_rows(frame: Frame, components: np.ndarray) -> np.ndarray:
    """(n, n_modes) rows: rotation component ``components[k]`` (0 = about x, ...; in 2D 0 =
    about z) of a rigidly coupled reference point, times L."""
    rows = np.zeros((len(components), frame.n_modes))
    rows[np.arange(len(components)), frame.dim + np.asarray(components, dtype=int)] = 1.0
    return rows


def locked_rotation_rows(frame: Frame, points: np.ndarray) -> np.ndarray:
    """(n·dim, n_modes) rows of the constraint of a coupling without rotations: its nodes
    ``points`` (n, dim) mm all move with the reference translation, so θ × (x_k − x̄) = 0."""
    points = np.asarray(points, dtype=float).reshape(-1, frame.dim)
    rows = rigid_body_matrix((points - points.mean(axis=0)) / frame.extent, rotations=True)
    rows[:, :frame.dim] = 0.0
    return rows


def free_motions(rows: np.ndarray, n_modes: int) -> np.ndarray:
    """(n_free, n_modes) orthonormal basis of the rigid motions q that every row of H
    (n, n_modes) leaves at zero; empty when the rows hold every mode."""
    rows = np.asarray(rows, dtype=float).reshape(-1, n_modes)
    lengths = np.linalg.norm(rows, axis=1)
    rows = rows[lengths > 0.0] / lengths[lengths > 0.0, None]
    if rows.shape[0] == 0:
        return np.eye(n_modes)
    # zero rows up to n_modes give the whole right basis from the thin SVD (values sorted down)
    rows = np.vstack([rows, np.zeros((max(n_modes - rows.shape[0], 0), n_modes))])
    _, values, vectors_t = np.linalg.svd(rows, full_matrices=False)
    rank = int(np.count_nonzero(values > RANK_TOLERANCE * values[0]))
    return vectors_t[rank:]


def describe(free: np.ndarray, frame: Frame) -> str:
    """The free rigid motions (rows of :func:`free_motions`) in words.

    A mode that is free on its own is named ("translation along x"); the rest of the free space
    is named by the modes it combines, and a single free rotation about a shifted axis by that
    axis ("rotation about an axis parallel to y through (-10, 0, 0) mm").
    """
    names = mode_names(frame.dim)
    share = np.einsum("fm,fm->m", free, free)  # diagonal of the projector onto the free space
    pure = share >= PURE_SHARE
    words = [names[m] for m in np.flatnonzero(pure)]
    # the free space without the pure modes: its directions combine modes
    _, values, vectors_t = np.linalg.svd(free * ~pure, full_matrices=False)
    combined = vectors_t[values > np.sqrt(NO_SHARE)]
    if combined.shape[0] == 1:
        axis = _rotation_axis(combined[0], frame)
        if axis is not None:
            return listed(words + [axis])
    if combined.shape[0]:
        involved = [names[m] for m in np.flatnonzero(~pure & (share > NO_SHARE))]
        count = "a combination" if combined.shape[0] == 1 else f"{combined.shape[0]} combinations"
        words.append(f"{count} of {listed(involved)}")
    return listed(words)


def holding_components(free: np.ndarray, dim: int) -> tuple[list[str], list[str]]:
    """What would hold the free rigid motions (rows of :func:`free_motions`): the displacement
    components ("ux", ...) they move (those of the free translations, and the two normal to each
    free rotation; in 2D ux and uy), and the rotation components ("rz", ...) they turn."""
    share = np.einsum("fm,fm->m", free, free) > NO_SHARE
    moved = share[:dim].copy()
    rotation_axes = [2] if dim == 2 else [0, 1, 2]
    for axis, free_rotation in zip(rotation_axes, share[dim:]):
        if free_rotation:
            moved |= np.arange(dim) != axis
    return ([f"u{AXES[k]}" for k in np.flatnonzero(moved)],
            [f"r{AXES[axis]}" for axis, free_rotation in zip(rotation_axes, share[dim:]) if free_rotation])


def _rotation_axis(motion: np.ndarray, frame: Frame) -> str | None:
    """A rigid motion that is a rotation about one coordinate axis's direction through a point
    p (u = θ × (x − p)) in words, or None when it is not."""
    dim = frame.dim
    translation, rotation = motion[:dim], motion[dim:] / frame.extent
    axes = np.flatnonzero(np.abs(rotation) > NO_SHARE * np.abs(rotation).max(initial=0.0))
    if axes.size != 1:
        return None
    if dim == 2:
        point = frame.centre + np.array([-translation[1], translation[0]]) / rotation[0]
        return f"rotation about z around the point {_point(point)} mm"
    spin = np.zeros(3)
    spin[axes[0]] = rotation[axes[0]]
    if abs(translation[axes[0]]) > NO_SHARE * np.linalg.norm(translation):
        return None  # a screw motion, not a rotation
    point = frame.centre + np.cross(spin, translation) / (spin @ spin)
    return f"rotation about an axis parallel to {AXES[axes[0]]} through {_point(point)} mm"


def _point(point: np.ndarray) -> str:
    return "(" + ", ".join(f"{value:.4g}" for value in np.where(np.abs(point) < 1e-9, 0.0, point)) + ")"
