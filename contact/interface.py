"""Contact surfaces, their pairing and the kinematic operator of an interface.

Every contact point is a node of the *slave* surface, paired from the geometry with the
*master* surface in one of two ways:

* node-to-segment: the node's closest-point projection on a master facet, with
  interpolation weights over that facet's nodes (node-to-node where the meshes match);
* mortar (:mod:`contact.mortar`): weighted averages over the intersection of the two
  surface meshes, on both sides, which passes the contact patch test on non-matching meshes.

``pair_surfaces(..., method="auto")`` takes node-to-segment where the meshes match (every
slave node on a master node and every slave facet on a master facet, :func:`meshes_match`)
and mortar otherwise. The operator ``G`` then maps body displacements to the point's
overclosure change and its tangential relative displacement, ``[Δh, s₁(, s₂)] = G·u``.

Units: mm (coordinates, gaps), mm² (tributary area in 3D), mm per unit thickness in 2D.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from reduction.errors import InputError

PAIRING_METHODS = ("auto", "node_to_segment", "mortar")


@dataclass(frozen=True)
class Surface:
    """A boundary surface of one body, as nodes and facets.

    nodes: (n,) mesh node indices.  coordinates: (n, dim) mm.
    facets: (n_facets, nodes_per_facet) indices into ``nodes``.
    facet_normals: (n_facets, dim) unit outward normals.
    area: (n,) tributary area of each node (mm², or mm per unit thickness in 2D).
    """

    nodes: np.ndarray
    coordinates: np.ndarray
    facets: np.ndarray
    facet_normals: np.ndarray
    area: np.ndarray

    @property
    def dim(self) -> int:
        return self.coordinates.shape[1]


def surface_from_facets(mesh, facet_indices: np.ndarray, name: str = "surface") -> Surface:
    """Build a :class:`Surface` from boundary facets of a scikit-fem mesh.

    Outward normals point away from the element that owns each facet. Tributary areas lump
    each facet's measure equally onto its nodes (exact for linear elements).
    """
    facet_indices = np.asarray(facet_indices, dtype=int)
    if facet_indices.size == 0:
        raise InputError(f"{name}: the selection contains no facets of the mesh")
    if np.any(mesh.f2t[1, facet_indices] >= 0):
        raise InputError(f"{name}: some selected facets are interior, not on the boundary")
    points = mesh.p.T
    facet_nodes = mesh.facets[:, facet_indices].T
    dim = points.shape[1]
    vertices = points[facet_nodes]
    if dim == 2:
        edge = vertices[:, 1] - vertices[:, 0]
        measure = np.linalg.norm(edge, axis=1)
        normals = np.stack([edge[:, 1], -edge[:, 0]], axis=1) / measure[:, None]
    else:
        # Quads are split along one diagonal; the two triangle normals are averaged.
        cross = np.cross(vertices[:, 1] - vertices[:, 0], vertices[:, 2] - vertices[:, 0])
        if facet_nodes.shape[1] == 4:
            cross = cross + np.cross(vertices[:, 2] - vertices[:, 0], vertices[:, 3] - vertices[:, 0])
        measure = 0.5 * np.linalg.norm(cross, axis=1)
        normals = cross / (2.0 * measure[:, None])
    owner_centroid = points[mesh.t[:, mesh.f2t[0, facet_indices]].T].mean(axis=1)
    inward = np.einsum("ij,ij->i", normals, owner_centroid - vertices.mean(axis=1)) > 0
    normals[inward] *= -1.0

    nodes, local = np.unique(facet_nodes, return_inverse=True)
    local = local.reshape(facet_nodes.shape)
    area = np.zeros(nodes.size)
    np.add.at(area, local.ravel(), np.repeat(measure / facet_nodes.shape[1], facet_nodes.shape[1]))
    return Surface(nodes=nodes, coordinates=points[nodes], facets=local,
                   facet_normals=normals, area=area)


@dataclass(frozen=True)
class Pairing:
    """Contact points (slave nodes) paired with the master surface.

    master_nodes: (n, k) indices into ``master.nodes``; weights: (n, k) their weights.
    normal: (n, dim) unit vector from the slave into the master (against the master's
        outward normal). tangents: (n, dim-1, dim) orthonormal tangent frame.
    initial_overclosure: h₀ (n,) mm, negative where the surfaces are apart.
    slave_nodes, slave_weights: (n, k_s) the slave side likewise (mortar); None means each
        point is its own node with weight 1 (node-to-segment).
    point_area: (n,) the area each point carries (mortar: ∫θ_j over the covered slave,
        mm² or mm in 2D); None means the slave's tributary areas.
    method: "node_to_segment" or "mortar".
    """

    slave: Surface
    master: Surface
    master_nodes: np.ndarray
    weights: np.ndarray
    normal: np.ndarray
    tangents: np.ndarray
    initial_overclosure: np.ndarray
    slave_nodes: np.ndarray | None = None
    slave_weights: np.ndarray | None = None
    point_area: np.ndarray | None = None
    method: str = "node_to_segment"

    @property
    def n_points(self) -> int:
        return self.slave.nodes.size

    @property
    def area(self) -> np.ndarray:
        return self.slave.area if self.point_area is None else self.point_area

    def slave_side(self) -> tuple[np.ndarray, np.ndarray]:
        """(n, k_s) slave node indices and weights of every point."""
        if self.slave_nodes is None:
            n = self.n_points
            return np.arange(n)[:, None], np.ones((n, 1))
        return self.slave_nodes, self.slave_weights


def tangent_frame(normal: np.ndarray) -> np.ndarray:
    """Orthonormal tangents (n, dim-1, dim) for unit normals (n, dim).

    2D: t = (-n_y, n_x). 3D: t₁ ⟂ n built from the global axis least aligned with n, t₂ = n × t₁.
    """
    if normal.shape[1] == 2:
        return np.stack([-normal[:, 1], normal[:, 0]], axis=1)[:, None, :]
    axis = np.eye(3)[np.argmin(np.abs(normal), axis=1)]
    first = np.cross(axis, normal)
    first /= np.linalg.norm(first, axis=1, keepdims=True)
    return np.stack([first, np.cross(normal, first)], axis=1)


def _project_2d(points, seg_a, seg_b):
    """Closest points of (n,2) points on candidate segments (n,c,2): parameters and distances."""
    edge = seg_b - seg_a
    rel = points[:, None, :] - seg_a
    xi = np.clip(np.einsum("ncd,ncd->nc", rel, edge) / np.einsum("ncd,ncd->nc", edge, edge), 0, 1)
    closest = seg_a + xi[..., None] * edge
    return xi, np.linalg.norm(points[:, None, :] - closest, axis=2)


def _project_triangle(points, a, b, c):
    """Barycentric weights of the closest points of (n,3) points on triangles (n,c,3) each."""
    e0, e1 = b - a, c - a
    rel = points[:, None, :] - a
    d00 = np.einsum("ncd,ncd->nc", e0, e0)
    d01 = np.einsum("ncd,ncd->nc", e0, e1)
    d11 = np.einsum("ncd,ncd->nc", e1, e1)
    d20 = np.einsum("ncd,ncd->nc", rel, e0)
    d21 = np.einsum("ncd,ncd->nc", rel, e1)
    denom = d00 * d11 - d01 * d01
    v = (d11 * d20 - d01 * d21) / denom
    w = (d00 * d21 - d01 * d20) / denom
    bary = np.stack([1 - v - w, v, w], axis=-1)
    # Points outside the triangle are clamped onto it; exact enough for small sliding pairing.
    bary = np.clip(bary, 0.0, None)
    bary /= bary.sum(axis=-1, keepdims=True)
    closest = bary[..., 0:1] * a + bary[..., 1:2] * b + bary[..., 2:3] * c
    return bary, np.linalg.norm(points[:, None, :] - closest, axis=2)


def pair_surfaces(slave: Surface, master: Surface, *, method: str = "auto",
                  search_distance: float = np.inf, name: str = "interface") -> Pairing:
    """Pair the surfaces by ``method``: "node_to_segment", "mortar" or "auto" (node-to-segment
    where the meshes match node to node both ways (:func:`meshes_match`), else mortar).

    search_distance (mm): slave nodes farther than this from the master are an input error.
    """
    if method not in PAIRING_METHODS:
        raise InputError(f"{name}: pairing must be one of {', '.join(PAIRING_METHODS)}, got {method!r}")
    from contact.mortar import mortar_pairing

    _check_dimensions(slave, master, name)
    if method == "mortar" and search_distance == np.inf:
        # nothing to check and nothing to choose: the projection is only the fallback of
        # slave nodes the master does not cover, formed if there are any (a finite-sliding
        # re-pairing of the cylinder: 0.28 ms of its 2.3, and every node covered)
        return mortar_pairing(slave, master, lambda: pair_node_to_segment(slave, master, name=name))
    projection = pair_node_to_segment(slave, master, search_distance=search_distance, name=name)
    if method == "node_to_segment" or (method == "auto" and meshes_match(projection)):
        return projection
    return mortar_pairing(slave, master, lambda: projection)


def _check_dimensions(slave: Surface, master: Surface, name: str) -> None:
    if slave.dim != master.dim:
        raise InputError(f"{name}: slave surface is {slave.dim}D but master surface is {master.dim}D")


def meshes_match(projection: Pairing, tolerance: float = 1e-6) -> bool:
    """Whether a node-to-segment pairing is node-to-node, one to one both ways: every slave
    node sits on a master node (in the tangential sense: its weights are all 0 or 1), no two
    on the same one, and every slave facet lands on a master facet (the same nodes).

    The last condition leaves out nested meshes, a finer master whose every other node (or
    every fifth) carries a slave node: the master nodes in between would be paired with no
    point and get no force, and the pressure patch test fails by about 10 % (mortar passes
    it). It is checked on the facets' nodes, not the geometry, so that a curved slave on a
    flat master (the cylinder) still matches.
    """
    weights = projection.weights
    if not np.all((weights < tolerance) | (weights > 1.0 - tolerance)):
        return False
    partner = projection.master_nodes[np.arange(weights.shape[0]), np.argmax(weights, axis=1)]
    if np.unique(partner).size != partner.size:
        return False
    landed = np.sort(partner[projection.slave.facets], axis=1)
    facets = np.sort(projection.master.facets, axis=1)
    if landed.shape[1] != facets.shape[1]:
        return False
    _, label = np.unique(np.concatenate([facets, landed]), axis=0, return_inverse=True)
    label = label.ravel()
    return bool(np.all(np.isin(label[len(facets):], label[:len(facets)])))


def pair_node_to_segment(slave: Surface, master: Surface, *, search_distance: float = np.inf,
                         candidates: int = 8, name: str = "interface") -> Pairing:
    """Pair every slave node with its closest-point projection on the master facets.

    search_distance (mm): slave nodes farther than this from the master are an input error,
    so a misplaced surface is reported instead of silently producing open contact points.
    """
    _check_dimensions(slave, master, name)
    dim = slave.dim
    if dim == 2:
        facets = master.facets
    else:
        facets = master.facets if master.facets.shape[1] == 3 else np.concatenate(
            [master.facets[:, [0, 1, 2]], master.facets[:, [0, 2, 3]]])
    facet_normal = master.facet_normals if dim == 2 or master.facets.shape[1] == 3 else np.concatenate(
        [master.facet_normals, master.facet_normals])
    corners = master.coordinates[facets]
    tree = cKDTree(corners.mean(axis=1))
    count = min(candidates, len(facets))
    _, nearest = tree.query(slave.coordinates, k=count)
    nearest = np.asarray(nearest).reshape(len(slave.coordinates), count)
    cand = corners[nearest]
    if dim == 2:
        xi, dist = _project_2d(slave.coordinates, cand[:, :, 0], cand[:, :, 1])
        weights_all = np.stack([1 - xi, xi], axis=-1)
    else:
        weights_all, dist = _project_triangle(slave.coordinates, cand[:, :, 0], cand[:, :, 1],
                                              cand[:, :, 2])
    best = np.argmin(dist, axis=1)
    rows = np.arange(len(best))
    chosen = nearest[rows, best]
    if np.any(dist[rows, best] > search_distance):
        worst = float(dist[rows, best].max())
        raise InputError(f"{name}: slave nodes lie up to {worst:.4g} mm from the master surface, "
                         f"beyond the search distance {search_distance:g} mm; check the surface "
                         "selections and the body positions")
    weights = weights_all[rows, best]
    master_nodes = facets[chosen]
    projection = np.einsum("nk,nkd->nd", weights, master.coordinates[master_nodes])
    normal = -facet_normal[chosen]
    overclosure = np.einsum("nd,nd->n", slave.coordinates - projection, normal)
    return Pairing(slave=slave, master=master, master_nodes=master_nodes, weights=weights,
                   normal=normal, tangents=tangent_frame(normal), initial_overclosure=overclosure)


def kinematic_operator(pairing: Pairing, slave_dofs: np.ndarray, master_dofs: np.ndarray,
                       n_columns: int) -> sp.csr_matrix:
    """Sparse G, (n_points·dim, n_columns): rows per point [normal, tangent(s)].

    slave_dofs: (n_slave_nodes, dim) column index of each slave node's displacement
    components; master_dofs: (n_master_nodes, dim) likewise. ``G·u`` is the change of
    overclosure and the tangential displacement of the slave relative to the master.
    """
    n, dim = pairing.normal.shape
    frame = np.concatenate([pairing.normal[:, None, :], pairing.tangents], axis=1)  # (n, dim, dim)
    cols, vals = [], []
    slave_nodes, slave_weights = pairing.slave_side()
    for node_dofs, nodes, weights in ((slave_dofs, slave_nodes, slave_weights),
                                      (master_dofs, pairing.master_nodes, -pairing.weights)):
        k = weights.shape[1]
        # entries (point, row, node, component): every row of a point has the same columns
        cols.append(np.broadcast_to(node_dofs[nodes][:, None, :, :], (n, dim, k, dim)).reshape(n, dim, -1))
        vals.append((weights[:, None, :, None] * frame[:, :, None, :]).reshape(n, dim, -1))
    cols, vals = np.concatenate(cols, axis=2), np.concatenate(vals, axis=2)
    width = cols.shape[2]
    # built as CSR directly (every row has ``width`` entries), then summed where padded
    # weights repeat a node: scipy's COO → CSR conversion costs more at every re-pairing
    G = sp.csr_matrix((vals.ravel(), cols.ravel(), np.arange(n * dim + 1) * width), shape=(n * dim, n_columns))
    G.sum_duplicates()
    return G
