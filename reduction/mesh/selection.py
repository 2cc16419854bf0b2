"""Selecting nodes and boundary facets by geometry: plane, box, ring, cylinder, given points, or
a named node set of a mesh file. Coordinates in mm.

The geometric tests (:func:`in_box`, :func:`near_plane`, :func:`on_ring`) are written once. The
``nodes_*`` functions take node coordinates (n_nodes, dim) and return sorted node indices; a
scene's selection table (``box``, ``boxes``, ``ring``, ``axis``/``value``, ``set``) goes through
:func:`select_points`, :func:`select_body_nodes` (a body's nodes, mid-edge nodes of quadratic
elements included) and :func:`select_facets`. An empty selection is an InputError that says where
nothing was found.
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


AXES = {"x": 0, "y": 1, "z": 2}


def in_box(coordinates: np.ndarray, lower, upper, tolerance: float = 0.0) -> np.ndarray:
    """Mask of the points inside the axis-aligned box [lower, upper] (mm), enlarged by ``tolerance``."""
    low, high = np.asarray(lower, dtype=float) - tolerance, np.asarray(upper, dtype=float) + tolerance
    return np.all((coordinates >= low) & (coordinates <= high), axis=1)


def near_plane(coordinates: np.ndarray, point, unit_normal, tolerance: float) -> np.ndarray:
    """Mask of the points within ``tolerance`` (mm) of the plane through ``point`` with unit normal."""
    return np.abs((coordinates - np.asarray(point, dtype=float)) @ np.asarray(unit_normal, dtype=float)) <= tolerance


def on_ring(coordinates: np.ndarray, center, axis: int, inner_radius: float, outer_radius: float,
            tolerance: float) -> np.ndarray:
    """Mask of the points in the plane through ``center`` normal to coordinate ``axis`` (within
    ``tolerance``) whose distance from ``center`` lies in [inner_radius, outer_radius] (mm)."""
    offset = coordinates - np.asarray(center, dtype=float)
    radial = np.linalg.norm(np.delete(offset, axis, axis=1), axis=1)
    in_plane = np.abs(offset[:, axis]) <= tolerance
    return in_plane & (radial >= inner_radius - 1e-9) & (radial <= outer_radius + 1e-9)


def nodes_on_plane(coordinates, point, normal, tolerance: float | None = None) -> np.ndarray:
    """Nodes within ``tolerance`` (mm, default 1e-6 of the model size) of the plane through point, normal."""
    x = np.asarray(coordinates, dtype=float)
    n = np.asarray(normal, dtype=float)
    if np.linalg.norm(n) == 0:
        raise InputError("plane normal must not be zero")
    tol = _default_tolerance(x) if tolerance is None else tolerance
    return _nonempty(np.flatnonzero(near_plane(x, point, n / np.linalg.norm(n), tol)), f"within {tol:g} mm of the plane through {list(point)} "
                     f"with normal {list(normal)}")


def nodes_in_box(coordinates, lower, upper, tolerance: float | None = None) -> np.ndarray:
    """Nodes inside the axis-aligned box [lower, upper] (mm), enlarged by ``tolerance``."""
    x = np.asarray(coordinates, dtype=float)
    tol = _default_tolerance(x) if tolerance is None else tolerance
    return _nonempty(np.flatnonzero(in_box(x, lower, upper, tol)), f"in the box {list(lower)} .. {list(upper)}")


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


def select_points(coordinates: np.ndarray, selection: dict, where: str, sets=None) -> np.ndarray:
    """Boolean mask of points (n, dim) for a scene's selection table: a named node set of the mesh
    file (``sets``, a :class:`reduction.mesh.io.MeshModel`), a box, a union of boxes, a ring or
    a plane (mm, tolerance 1e-6·size). ``where`` names the table in error messages."""
    if "set" in selection:
        if sets is None:
            raise InputError(f"'{where}.set' names a node set, but the body's mesh is generated, "
                             "not read from a file with named sets")
        name = selection["set"]
        if name not in sets.node_sets:
            raise InputError(f"'{where}.set': no node set '{name}' in the mesh file ({sets.source})"
                             f"{_named_like(name, sets.node_sets)}; its node sets: "
                             f"{', '.join(sorted(sets.node_sets)) or 'none'}")
        # the set's nodes are numbered as the body's (vertices first); a vertex-only
        # ``coordinates`` (the corner mesh of Hex20) takes the set's vertices
        nodes = sets.node_set(name)
        mask = np.zeros(len(coordinates), dtype=bool)
        mask[nodes[nodes < len(coordinates)]] = True
        return mask
    if "box" in selection or "boxes" in selection:
        mask = np.zeros(len(coordinates), dtype=bool)
        for low, high in ([selection["box"]] if "box" in selection else selection["boxes"]):
            mask |= in_box(coordinates, low, high)
        return mask
    span = float(np.ptp(coordinates)) or 1.0
    if "ring" in selection:
        ring = selection["ring"]
        return on_ring(coordinates, ring["center"], AXES[ring["axis"]], ring["inner_radius"], ring["outer_radius"],
                       ring.get("tolerance", 1e-6 * span))
    axis = AXES[selection["axis"]]
    tolerance = selection.get("tolerance", 1e-6 * span)
    return np.abs(coordinates[:, axis] - selection["value"]) <= tolerance


def _named_like(name: str, names) -> str:
    """': did you mean 'X'?' for a set name that differs from one of ``names`` only in case
    (sets are named case-sensitively here, though Abaqus ignores case), else ''."""
    alike = [other for other in names if other.lower() == name.lower()]
    return f": did you mean '{alike[0]}'? (set names are case-sensitive)" if alike else ""


def select_body_nodes(coordinates: np.ndarray, mesh, selection: dict, where: str, sets=None) -> np.ndarray:
    """Rows of a body's node ``coordinates`` (:attr:`reduction.elasticity.ElasticBody.coordinates`:
    the vertices of ``mesh``, then, for quadratic elements, one mid-edge node per mesh edge) in a
    scene's selection (:func:`select_points`).

    A geometric selection tests every node, mid-edge nodes included. A named set (numbered as
    the body's nodes, :class:`reduction.mesh.io.MeshModel`) takes its nodes and, on quadratic
    elements, the mid-edge node of every boundary edge whose two corners it holds: a set that
    lists corners only would otherwise leave the faces it clamps or couples partly free.
    """
    nodes = np.flatnonzero(select_points(coordinates, selection, where, sets))
    if "set" in selection:
        nodes = with_mid_edge_nodes(nodes, mesh, len(coordinates))
    if nodes.size == 0:
        raise InputError(f"'{where}' selects no nodes of the mesh; check its coordinates")
    return nodes


def with_mid_edge_nodes(nodes: np.ndarray, mesh, n_nodes: int) -> np.ndarray:
    """``nodes`` and the mid-edge nodes of the boundary edges of ``mesh`` whose two corners are in
    ``nodes``, for a body of ``n_nodes`` nodes numbered vertices first, then one node per edge
    (edges of a 3D mesh, facets of a 2D one); unchanged for linear elements."""
    edges = mesh.edges if mesh.dim() == 3 else mesh.facets
    n_vertices = mesh.nvertices
    if n_nodes != n_vertices + edges.shape[1]:
        return nodes
    boundary = mesh.boundary_edges() if mesh.dim() == 3 else mesh.boundary_facets()
    selected = np.zeros(n_vertices, dtype=bool)
    selected[nodes[nodes < n_vertices]] = True
    between = boundary[np.all(selected[edges[:, boundary]], axis=0)]
    return np.union1d(nodes, n_vertices + between)


def select_facets(mesh, selection: dict, where: str, sets=None) -> np.ndarray:
    """Boundary facets of ``mesh`` whose vertices all lie in a scene's selection."""
    boundary = mesh.boundary_facets()
    inside = select_points(mesh.p.T, selection, where, sets)
    facets = boundary[np.all(inside[mesh.facets[:, boundary]], axis=0)]
    if facets.size == 0:
        raise InputError(f"'{where}' selects no boundary facets of the mesh; check the box or plane")
    return facets
