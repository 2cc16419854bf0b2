"""Mortar (segment-to-segment) pairing of non-matching surfaces, in 2D and 3D.

The contact points stay the slave nodes, but the kinematics of point j are mortar-weighted
averages over the intersection of the two surface meshes (Wohlmuth's dual mortar method;
MOOSE's mortar contact works the same way):

    D_jl = ∫ θ_j·N_l dΓ  (slave),      M_jk = ∫ θ_j·N^m_k dΓ  (master),      A_j = Σ_l D_jl

integrated over the mortar segments (slave facet ∩ projected master facet). θ_j is the dual
shape function ψ_j on a slave facet that the master covers (biorthogonal: D is diagonal, and
on matching meshes M = D, i.e. node-to-node), and the standard N_j on a partly covered one
(ψ_j may integrate to a negative value over part of a facet). The point's gap and slip are
``(Σ_l D_jl·u_l − Σ_k M_jk·u^m_k)/A_j`` and its nodal force is ``A_j·[p, τ]``: for a uniform
traction both bodies receive consistent nodal forces, so the contact patch test passes, and
the paper's law is evaluated at the nodes exactly as for node-to-node contact.

Units: mm (coordinates), mm² (3D) or mm per unit thickness (2D) for integrals A_j, D, M.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree
from scipy.spatial.distance import cdist

from reduction.errors import InputError

# Dunavant's 7-point rule on a triangle, exact to degree 5: barycentric (a, b) and weight.
_R15 = np.sqrt(15.0)
_A1, _A2 = (6.0 - _R15) / 21.0, (6.0 + _R15) / 21.0
_B1, _B2 = 1.0 - 2.0 * _A1, 1.0 - 2.0 * _A2
_W1, _W2 = (155.0 - _R15) / 1200.0, (155.0 + _R15) / 1200.0
_TRI_RULE = np.array([[1 / 3, 1 / 3, 9 / 40],
                      [_A1, _A1, _W1], [_A1, _B1, _W1], [_B1, _A1, _W1],
                      [_A2, _A2, _W2], [_A2, _B2, _W2], [_B2, _A2, _W2]])
_GAUSS_1D = np.polynomial.legendre.leggauss(3)
_COVERED = 1.0 - 1e-6  # a slave facet counts as covered above this fraction of its measure
_ALL_PAIRS = 40_000  # facet pairs below which candidates are found without a k-d tree


@dataclass(frozen=True)
class MortarSegments:
    """Quadrature points of all mortar segments, flat over (segment, point).

    slave_facet, master_facet: (q,) facet indices. slave_shape: (q, k_s) slave shape values;
    master_shape: (q, k_m). weight: (q,) mm² (3D) or mm (2D), measured on the slave.
    """

    slave_facet: np.ndarray
    master_facet: np.ndarray
    slave_shape: np.ndarray
    master_shape: np.ndarray
    weight: np.ndarray


def facet_measures(coordinates: np.ndarray, facets: np.ndarray) -> np.ndarray:
    """Length (2D) or area (3D, quads as two triangles) of each facet, mm or mm²."""
    vertices = coordinates[facets]
    if coordinates.shape[1] == 2:
        return np.linalg.norm(vertices[:, 1] - vertices[:, 0], axis=1)
    cross = np.cross(vertices[:, 1] - vertices[:, 0], vertices[:, 2] - vertices[:, 0])
    if facets.shape[1] == 4:
        cross = cross + np.cross(vertices[:, 2] - vertices[:, 0], vertices[:, 3] - vertices[:, 0])
    return 0.5 * np.linalg.norm(cross, axis=1)


def _candidates(slave, master) -> tuple[np.ndarray, np.ndarray]:
    """Facet pairs whose bounding spheres overlap and whose normals face each other."""
    s_vert, m_vert = slave.coordinates[slave.facets], master.coordinates[master.facets]
    s_centre, m_centre = s_vert.mean(axis=1), m_vert.mean(axis=1)
    s_radius = np.linalg.norm(s_vert - s_centre[:, None], axis=2).max(axis=1)
    m_radius = np.linalg.norm(m_vert - m_centre[:, None], axis=2).max(axis=1)
    reach = 1.5 * (s_radius + m_radius.max())
    if len(s_centre) * len(m_centre) <= _ALL_PAIRS:  # small surfaces: every pair, no tree
        distance = cdist(s_centre, m_centre)  # a broadcast norm over a last axis of 2-3 is 10× slower
        s_idx, m_idx = np.nonzero(distance <= reach[:, None])
    else:
        hits = cKDTree(m_centre).query_ball_point(s_centre, reach)
        s_idx = np.repeat(np.arange(len(hits)), [len(h) for h in hits])
        m_idx = np.concatenate([np.sort(np.asarray(h, dtype=int)) for h in hits]) if len(hits) else np.zeros(0, int)
    facing = np.einsum("ij,ij->i", slave.facet_normals[s_idx], master.facet_normals[m_idx]) < 0.0
    return s_idx[facing], m_idx[facing]


def _segments_2d(slave, master, s_idx: np.ndarray, m_idx: np.ndarray) -> MortarSegments:
    """Mortar segments of 2D surfaces: master endpoints projected on the slave segment's line
    (candidate facet pairs ``s_idx``, ``m_idx``)."""
    a, b = slave.coordinates[slave.facets[s_idx, 0]], slave.coordinates[slave.facets[s_idx, 1]]
    c, d = master.coordinates[master.facets[m_idx, 0]], master.coordinates[master.facets[m_idx, 1]]
    edge = b - a
    length2 = np.einsum("ij,ij->i", edge, edge)
    xi_c = np.einsum("ij,ij->i", c - a, edge) / length2
    xi_d = np.einsum("ij,ij->i", d - a, edge) / length2
    low = np.maximum(0.0, np.minimum(xi_c, xi_d))
    high = np.minimum(1.0, np.maximum(xi_c, xi_d))
    keep = high - low > 1e-12
    s_idx, m_idx, low, high, xi_c, xi_d = (v[keep] for v in (s_idx, m_idx, low, high, xi_c, xi_d))
    length = np.sqrt(length2[keep])
    nodes, gauss_w = _GAUSS_1D
    xi = low[:, None] + 0.5 * (nodes[None, :] + 1.0) * (high - low)[:, None]
    chi = (xi - xi_c[:, None]) / (xi_d - xi_c)[:, None]
    weight = 0.5 * gauss_w[None, :] * ((high - low) * length)[:, None]
    n_q = nodes.size
    return MortarSegments(np.repeat(s_idx, n_q), np.repeat(m_idx, n_q),
                          np.stack([1.0 - xi, xi], axis=-1).reshape(-1, 2),
                          np.stack([1.0 - chi, chi], axis=-1).reshape(-1, 2), weight.ravel())


def _plane_frames(slave) -> tuple[np.ndarray, np.ndarray]:
    """Origin (n_f, 3) and in-plane axes (n_f, 2, 3) of every slave facet's plane."""
    normal = slave.facet_normals
    axis = np.eye(3)[np.argmin(np.abs(normal), axis=1)]
    first = np.cross(axis, normal)
    first /= np.linalg.norm(first, axis=1, keepdims=True)
    return slave.coordinates[slave.facets].mean(axis=1), np.stack([first, np.cross(normal, first)], axis=1)


def _ccw(polygon: np.ndarray) -> np.ndarray:
    """Reverse the vertex order of (P, k, 2) polygons that are clockwise."""
    x, y = polygon[..., 0], polygon[..., 1]
    signed = np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1)
    return np.where((signed < 0.0)[:, None, None], polygon[:, ::-1], polygon)


def _clip(subject: np.ndarray, clipper: np.ndarray, size: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Sutherland–Hodgman: convex (P, k, 2) ``subject`` polygons clipped by convex ``clipper``
    polygons, both counter-clockwise, vectorised over P. Returns vertices (P, size, 2) and
    their counts (P,); two convex quadrilaterals intersect in at most 8 vertices."""
    n_pairs = subject.shape[0]
    poly = np.zeros((n_pairs, size, 2))
    poly[:, :subject.shape[1]] = subject
    count = np.full(n_pairs, subject.shape[1])
    rows = np.arange(n_pairs)[:, None]
    for e in range(clipper.shape[1]):
        start, end = clipper[:, e], clipper[:, (e + 1) % clipper.shape[1]]
        direction = end - start
        index = np.arange(size)[None, :]
        valid = index < count[:, None]
        following = np.where(valid, (index + 1) % np.maximum(count, 1)[:, None], 0)
        current, nxt = poly, poly[rows, following]

        def side(points):
            rel = points - start[:, None]
            return direction[:, None, 0] * rel[..., 1] - direction[:, None, 1] * rel[..., 0]

        s_cur, s_nxt = side(current), side(nxt)
        inside_cur, inside_nxt = s_cur >= 0.0, s_nxt >= 0.0
        denominator = np.where(s_cur != s_nxt, s_cur - s_nxt, 1.0)
        crossing = current + (s_cur / denominator)[..., None] * (nxt - current)
        candidates = np.stack([current, crossing], axis=2).reshape(n_pairs, 2 * size, 2)
        emit = np.stack([valid & inside_cur, valid & (inside_cur != inside_nxt)], axis=2).reshape(n_pairs, -1)
        order = np.argsort(~emit, axis=1, kind="stable")[:, :size]
        poly = candidates[rows, order]
        count = np.minimum(emit.sum(axis=1), size)
    return poly, count


def _shape(local: np.ndarray, k: int) -> np.ndarray:
    """Linear triangle (k=3) or bilinear quadrilateral (k=4, on [0,1]²) shape values (…, k)."""
    s, t = local[..., 0], local[..., 1]
    if k == 3:
        return np.stack([1.0 - s - t, s, t], axis=-1)
    return np.stack([(1 - s) * (1 - t), s * (1 - t), s * t, (1 - s) * t], axis=-1)


def _inverse_map(points: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """Local coordinates (q, 2) of in-plane points (q, 2) in facets with vertices (q, k, 2)."""
    k = vertices.shape[1]
    local = np.full(points.shape, 1.0 / 3.0 if k == 3 else 0.5)
    for _ in range(1 if k == 3 else 8):
        s, t = local[:, 0], local[:, 1]
        if k == 3:
            dN = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])[None].repeat(len(s), axis=0)
        else:
            dN = np.stack([np.stack([-(1 - t), -(1 - s)], -1), np.stack([1 - t, -s], -1),
                           np.stack([t, s], -1), np.stack([-t, 1 - s], -1)], axis=1)
        residual = np.einsum("qk,qkd->qd", _shape(local, k), vertices) - points
        jacobian = np.einsum("qkd,qke->qde", vertices, dN)
        local = local - np.linalg.solve(jacobian, residual[..., None])[..., 0]
    return local


def _segments_3d(slave, master, s_idx: np.ndarray, m_idx: np.ndarray) -> MortarSegments:
    """Mortar segments of 3D surfaces: master facets projected on each slave facet's plane,
    clipped with it, fan-triangulated and integrated with a degree-5 rule (candidate facet
    pairs ``s_idx``, ``m_idx``)."""
    origin, axes = _plane_frames(slave)
    origin, axes = origin[s_idx], axes[s_idx]

    def in_plane(points):  # (P, k, 3) → (P, k, 2)
        return np.einsum("pkd,pad->pka", points - origin[:, None], axes)

    s_poly = in_plane(slave.coordinates[slave.facets[s_idx]])
    m_poly = in_plane(master.coordinates[master.facets[m_idx]])
    clipped, count = _clip(_ccw(s_poly), _ccw(m_poly))
    valid = np.arange(clipped.shape[1])[None, :] < count[:, None]
    centre = np.sum(clipped * valid[..., None], axis=1) / np.maximum(count, 1)[:, None]
    following = np.where(valid, (np.arange(clipped.shape[1])[None] + 1) % np.maximum(count, 1)[:, None], 0)
    nxt = clipped[np.arange(len(count))[:, None], following]
    e1, e2 = clipped - centre[:, None], nxt - centre[:, None]
    area = 0.5 * np.abs(e1[..., 0] * e2[..., 1] - e1[..., 1] * e2[..., 0]) * valid  # (P, 8)
    rule_a, rule_b, rule_w = _TRI_RULE.T
    points = (centre[:, None, None] + rule_a[None, None, :, None] * e1[:, :, None]
              + rule_b[None, None, :, None] * e2[:, :, None])  # (P, 8, 7, 2)
    weight = area[..., None] * rule_w[None, None, :]
    keep = weight > 0.0
    pair = np.broadcast_to(np.arange(len(count))[:, None, None], keep.shape)[keep]
    points, weight = points[keep], weight[keep]
    s_local = _inverse_map(points, s_poly[pair])
    m_local = _inverse_map(points, m_poly[pair])
    return MortarSegments(s_idx[pair], m_idx[pair], _shape(s_local, s_poly.shape[1]),
                          _shape(m_local, m_poly.shape[1]), weight)


def dual_coefficients(coordinates: np.ndarray, facets: np.ndarray) -> np.ndarray:
    """Coefficients (n_f, k, k) of the dual basis ψ_j = Σ_l a_jl·N_l of each facet.

    a = D·M⁻¹ with M_jl = ∫N_j·N_l and D = diag(∫N_j) on the facet: then ∫ψ_j·N_l = δ_jl·∫N_j.
    """
    k = facets.shape[1]
    if coordinates.shape[1] == 2 or k == 3:
        # Affine facets: the dual coefficients do not depend on the facet's size.
        base = 2.0 * np.eye(2) - np.ones((2, 2)) * (1 - np.eye(2)) if k == 2 else 4.0 * np.eye(3) - 1.0
        return np.broadcast_to(base, (facets.shape[0], k, k)).copy()
    gauss, gauss_w = np.polynomial.legendre.leggauss(3)
    s, t = np.meshgrid(0.5 * (gauss + 1), 0.5 * (gauss + 1), indexing="ij")
    local = np.stack([s.ravel(), t.ravel()], axis=1)
    w = np.outer(0.5 * gauss_w, 0.5 * gauss_w).ravel()
    vertices = coordinates[facets]  # (n_f, 4, 3)
    ds = np.einsum("k,fkd->fd", [-1, 1, 0, 0], vertices)[:, None] * (1 - local[None, :, 1:2]) + \
        np.einsum("k,fkd->fd", [0, 0, 1, -1], vertices)[:, None] * local[None, :, 1:2]
    dt = np.einsum("k,fkd->fd", [-1, 0, 0, 1], vertices)[:, None] * (1 - local[None, :, 0:1]) + \
        np.einsum("k,fkd->fd", [0, -1, 1, 0], vertices)[:, None] * local[None, :, 0:1]
    jac = np.linalg.norm(np.cross(ds, dt), axis=-1) * w[None, :]  # (n_f, q)
    shape = _shape(local, 4)  # (q, 4)
    mass = np.einsum("fq,qj,ql->fjl", jac, shape, shape)
    lumped = np.einsum("fq,qj->fj", jac, shape)
    return lumped[:, :, None] * np.linalg.inv(mass)


def mortar_segments(slave, master) -> MortarSegments:
    """All mortar segments of two surfaces (same dimension), as quadrature points."""
    s_idx, m_idx = _candidates(slave, master)
    if not s_idx.size:
        raise InputError("the contact surfaces touch nothing of each other: no master facet faces a slave facet "
                         "within reach; check the contact selections (slave and master must face each other)")
    return (_segments_2d if slave.dim == 2 else _segments_3d)(slave, master, s_idx, m_idx)


def mortar_matrices(slave, master, segments: MortarSegments | None = None):
    """The mortar integrals D (n_s, n_s) and M (n_s, n_m) as CSR, and the averaged master
    normal (n_s, dim) of every slave node (zero where the master does not cover it).

    Test functions θ are dual on covered slave facets and standard on partly covered ones.
    """
    seg = mortar_segments(slave, master) if segments is None else segments
    n_s, n_m = slave.nodes.size, master.nodes.size
    measure = facet_measures(slave.coordinates, slave.facets)
    if slave.dim == 3:  # the segments are measured in each slave facet's plane
        measure = _projected_measure(slave)
    covered = np.bincount(seg.slave_facet, weights=seg.weight, minlength=slave.facets.shape[0])
    dual = covered >= _COVERED * measure
    coefficients = dual_coefficients(slave.coordinates, slave.facets)
    k = slave.facets.shape[1]
    coefficients[~dual] = np.eye(k)
    test = np.einsum("qjl,ql->qj", coefficients[seg.slave_facet], seg.slave_shape)  # θ_j at q
    s_nodes, m_nodes = slave.facets[seg.slave_facet], master.facets[seg.master_facet]
    weighted = test * seg.weight[:, None]

    def integral(other_shape, other_nodes, n_cols):
        values = weighted[:, :, None] * other_shape[:, None, :]
        rows = np.broadcast_to(s_nodes[:, :, None], values.shape)
        cols = np.broadcast_to(other_nodes[:, None, :], values.shape)
        return _summed(values.ravel(), rows.ravel(), cols.ravel(), (n_s, n_cols))

    D = integral(seg.slave_shape, s_nodes, n_s)
    M = integral(seg.master_shape, m_nodes, n_m)
    normal_weight = seg.slave_shape * seg.weight[:, None]
    normal = np.zeros((n_s, slave.dim))
    np.add.at(normal, s_nodes.ravel(),
              (normal_weight[:, :, None] * master.facet_normals[seg.master_facet][:, None, :]).reshape(-1, slave.dim))
    return D, M, normal


#: entries (rows × columns) up to which a mortar integral may be summed in a dense array, if
#: it has at least a quarter as many quadrature terms: a finite-sliding interface re-pairs
#: every few increments, and scipy's COO → CSR conversion and round-off pass cost 0.41 ms for
#: the cylinder's 91 × 95 (9,252 terms; dense 0.12 ms), 13 ms for 400 × 400 (180,000 terms;
#: dense 1.4 ms), but less than the dense sum on sparser ones (2,000 × 2,000 with 900,000
#: terms: 57 against 70 ms; with 100,000: 4 against 43 ms)
_DENSE_SUM = 4_000_000


def _summed(values: np.ndarray, rows: np.ndarray, cols: np.ndarray, shape: tuple[int, int]) -> sp.csr_matrix:
    """The sum of (row, column, value) entries as CSR, without round-off (:func:`_drop_round_off`)."""
    n_rows, n_cols = shape
    if n_rows * n_cols > min(_DENSE_SUM, 4 * values.size):
        return _drop_round_off(sp.csr_matrix((values, (rows, cols)), shape=shape))
    dense = np.bincount(rows * n_cols + cols, weights=values, minlength=n_rows * n_cols).reshape(shape)
    magnitude = np.abs(dense)
    row, col = np.nonzero((magnitude >= 1e-12 * magnitude.max(axis=1, keepdims=True)) & (magnitude > 0.0))
    indptr = np.zeros(n_rows + 1, dtype=np.int64)
    np.cumsum(np.bincount(row, minlength=n_rows), out=indptr[1:])
    return sp.csr_matrix((dense[row, col], col, indptr), shape=shape)


def _drop_round_off(matrix: sp.csr_matrix) -> sp.csr_matrix:
    """Remove entries below 1e-12 of their row's largest (the zero off-diagonals of the
    biorthogonal D come out of the quadrature as round-off)."""
    matrix.sum_duplicates()
    magnitude, lengths = np.abs(matrix.data), np.diff(matrix.indptr)
    row_max = np.zeros(lengths.size)
    filled = lengths > 0
    row_max[filled] = np.maximum.reduceat(magnitude, matrix.indptr[:-1][filled])
    matrix.data[magnitude < 1e-12 * np.repeat(row_max, lengths)] = 0.0
    matrix.eliminate_zeros()
    return matrix


def _projected_measure(slave) -> np.ndarray:
    """Area of each 3D slave facet projected on its own plane (the measure of its segments)."""
    origin, axes = _plane_frames(slave)
    poly = np.einsum("pkd,pad->pka", slave.coordinates[slave.facets] - origin[:, None], axes)
    x, y = poly[..., 0], poly[..., 1]
    return 0.5 * np.abs(np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1))


def padded_rows(matrix: sp.csr_matrix, scale: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows of a CSR matrix as (n, k) column indices and values divided by ``scale`` (n,),
    padded with column 0 and value 0 to the longest row."""
    matrix = matrix.tocsr()
    matrix.sum_duplicates()
    lengths = np.diff(matrix.indptr)
    width = max(int(lengths.max(initial=0)), 1)
    columns = np.zeros((matrix.shape[0], width), dtype=int)
    values = np.zeros((matrix.shape[0], width))
    slot = np.arange(matrix.nnz) - np.repeat(matrix.indptr[:-1], lengths)
    row = np.repeat(np.arange(matrix.shape[0]), lengths)
    columns[row, slot] = matrix.indices
    safe = np.where(scale > 0.0, scale, 1.0)
    values[row, slot] = matrix.data / safe[row]
    return columns, values


def _widen(columns: np.ndarray, values: np.ndarray, width: int) -> tuple[np.ndarray, np.ndarray]:
    """Pad (n, k) columns and values with zeros to (n, width)."""
    if columns.shape[1] == width:
        return columns, values
    wide_columns = np.zeros((columns.shape[0], width), dtype=columns.dtype)
    wide_values = np.zeros((values.shape[0], width))
    wide_columns[:, :columns.shape[1]], wide_values[:, :values.shape[1]] = columns, values
    return wide_columns, wide_values


def mortar_pairing(slave, master, projection, segments: MortarSegments | None = None):
    """The mortar :class:`contact.interface.Pairing` of two surfaces.

    projection: a function that returns the node-to-segment pairing of the same surfaces,
    called only if some slave node needs it: slave nodes the master does not cover at all
    keep it (with their full tributary area), so that a slave surface that overhangs the
    master behaves as before. Normals are the master normals averaged over each node's
    segments; the initial overclosure is the mortar-weighted gap along them.
    """
    from contact.interface import Pairing, tangent_frame

    D, M, normal_sum = mortar_matrices(slave, master, segments)
    area = np.asarray(D.sum(axis=1)).ravel()
    norm = np.linalg.norm(normal_sum, axis=1)
    covered = (area > 1e-9 * slave.area) & (norm > 0.0)
    slave_nodes, slave_weights = padded_rows(D, area)
    master_nodes, master_weights = padded_rows(M, area)
    # a projection's rows hold one master segment (2D) or triangle (3D): dim nodes
    width = max(master_nodes.shape[1], slave.dim)
    master_nodes, master_weights = _widen(master_nodes, master_weights, width)
    normal = -normal_sum / np.where(norm > 0.0, norm, 1.0)[:, None]
    if not covered.all():
        projection = projection()
        fallback_nodes, fallback_weights = _widen(projection.master_nodes, projection.weights, width)
        identity = np.zeros_like(slave_weights)
        identity[:, 0] = 1.0
        keep = covered[:, None]
        slave_nodes = np.where(keep, slave_nodes, np.arange(area.size)[:, None])
        slave_weights = np.where(keep, slave_weights, identity)
        master_nodes = np.where(keep, master_nodes, fallback_nodes)
        master_weights = np.where(keep, master_weights, fallback_weights)
        normal = np.where(keep, normal, projection.normal)
    position = (np.einsum("nk,nkd->nd", slave_weights, slave.coordinates[slave_nodes])
                - np.einsum("nk,nkd->nd", master_weights, master.coordinates[master_nodes]))
    return Pairing(slave=slave, master=master, master_nodes=master_nodes, weights=master_weights,
                   normal=normal, tangents=tangent_frame(normal),
                   initial_overclosure=np.einsum("nd,nd->n", position, normal),
                   slave_nodes=slave_nodes, slave_weights=slave_weights,
                   point_area=np.where(covered, area, slave.area), method="mortar")
