"""Selecting nodes by geometry: plane, box, cylinder, or given points. Coordinates in mm.

Each function takes node coordinates (n_nodes, dim) and returns sorted node indices; an empty
selection is an InputError that says where nothing was found.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from reduction.errors import InputError


def _default_tolerance(coordinates: np.ndarray) -> float:
    extent = np.ptp(coordinates, axis=0).max() if len(coordinates) else 1.0
    return 1e-6 * max(extent, 1e-12)


def _nonempty(selected: np.ndarray, where: str) -> np.ndarray:
    if selected.size == 0:
        raise InputError(f"no mesh node found {where}")
    return selected


def nodes_on_plane(coordinates, point, normal, tolerance: float | None = None) -> np.ndarray:
    """Nodes within ``tolerance`` (mm, default 1e-6 of the model size) of the plane through point, normal."""
    x = np.asarray(coordinates, dtype=float)
    n = np.asarray(normal, dtype=float)
    if np.linalg.norm(n) == 0:
        raise InputError("plane normal must not be zero")
    tol = _default_tolerance(x) if tolerance is None else tolerance
    distance = (x - np.asarray(point, dtype=float)) @ (n / np.linalg.norm(n))
    return _nonempty(np.flatnonzero(np.abs(distance) <= tol), f"within {tol:g} mm of the plane through {list(point)} "
                     f"with normal {list(normal)}")


def nodes_in_box(coordinates, lower, upper, tolerance: float | None = None) -> np.ndarray:
    """Nodes inside the axis-aligned box [lower, upper] (mm), enlarged by ``tolerance``."""
    x = np.asarray(coordinates, dtype=float)
    tol = _default_tolerance(x) if tolerance is None else tolerance
    inside = np.all((x >= np.asarray(lower, dtype=float) - tol) & (x <= np.asarray(upper, dtype=float) + tol), axis=1)
    return _nonempty(np.flatnonzero(inside), f"in the box {list(lower)} .. {list(upper)}")


def nodes_on_cylinder(coordinates, axis_point, axis_direction, radius: float, tolerance: float | None = None,
                      *, axial_range=None) -> np.ndarray:
    """Nodes on the cylinder surface of ``radius`` (mm) about the axis (3D), within ``tolerance``.

    axial_range: (start, end) in mm along the axis from axis_point, or None for unbounded.
    """
    x = np.asarray(coordinates, dtype=float)
    if x.shape[1] != 3:
        raise InputError("cylinder selection needs 3D coordinates")
    axis = np.asarray(axis_direction, dtype=float)
    if np.linalg.norm(axis) == 0:
        raise InputError("cylinder axis direction must not be zero")
    axis = axis / np.linalg.norm(axis)
    tol = _default_tolerance(x) if tolerance is None else tolerance
    relative = x - np.asarray(axis_point, dtype=float)
    along = relative @ axis
    radial = np.linalg.norm(relative - np.outer(along, axis), axis=1)
    selected = np.abs(radial - radius) <= tol
    if axial_range is not None:
        selected &= (along >= axial_range[0] - tol) & (along <= axial_range[1] + tol)
    return _nonempty(np.flatnonzero(selected), f"within {tol:g} mm of the cylinder of radius {radius} mm about "
                     f"{list(axis_point)} + s {list(axis_direction)}")


def nodes_at_points(coordinates, points, tolerance: float | None = None) -> np.ndarray:
    """For each point (mm), the index of the node at that point; InputError if a point has no node."""
    x = np.asarray(coordinates, dtype=float)
    p = np.atleast_2d(np.asarray(points, dtype=float))
    tol = _default_tolerance(x) if tolerance is None else tolerance
    distance, index = cKDTree(x).query(p)
    missing = np.flatnonzero(distance > tol)
    if missing.size:
        raise InputError(f"{missing.size} of {len(p)} points have no mesh node within {tol:g} mm, "
                         f"first {p[missing[0]].tolist()}")
    return index
