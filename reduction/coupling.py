"""Couplings of node sets to reference points: RBE2 (rigid, kinematic) and RBE3 (distributing).

Units: mm for coordinates and displacements, rad for rotations.
A reference point has the translations ux, uy[, uz] and, with ``rotations=True``, the
rotation(s) rz (2D) or rx, ry, rz (3D), in that order.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from reduction.errors import InputError


@dataclass(frozen=True)
class Coupling:
    """A kinematic (RBE2) coupling as a DOF transformation ``u_full = transformation @ u_reduced``.

    transformation: (n_dofs, n_reduced) CSR. The reduced vector holds the original DOFs that
    were not coupled, in their original order, followed LAST by the reference-point DOFs.
    reference_dofs: indices of the reference DOFs in the reduced vector; shape (n_ref,) for one
    reference point, (n_points, n_ref) from ``rigid_couplings``.
    kept: (n_dofs,) new index of each original DOF in the reduced vector, -1 where eliminated.
    coupled_dofs: original DOF indices that became dependent on a reference point.
    """

    transformation: sp.csr_matrix
    reference_dofs: np.ndarray
    kept: np.ndarray
    coupled_dofs: np.ndarray

    @property
    def n_reduced(self) -> int:
        return int(self.transformation.shape[1])

    def reduce_matrix(self, matrix: sp.spmatrix) -> sp.csr_matrix:
        """T^T A T: stiffness (N/mm) or mass (t) in the reduced DOFs."""
        t = self.transformation
        return (t.T @ matrix @ t).tocsr()

    def reduce_vector(self, vector: np.ndarray) -> np.ndarray:
        """T^T f: nodal forces (N) in the reduced DOFs (reference DOFs get resultant force and moment)."""
        return self.transformation.T @ vector

    def expand(self, reduced_vector: np.ndarray) -> np.ndarray:
        """T q: full nodal displacement vector (mm) from the reduced one."""
        return self.transformation @ reduced_vector


def rigid_body_matrix(offsets: np.ndarray, rotations: bool) -> np.ndarray:
    """(n_nodes*dim, n_ref) matrix A with u_nodes = A @ [u_ref, theta_ref] for small rotations.

    offsets: (n_nodes, dim) node position minus reference point, mm. Rows are node-interleaved.
    """
    n_nodes, dim = offsets.shape
    translations = np.tile(np.eye(dim), (n_nodes, 1))
    if not rotations:
        return translations
    if dim == 2:
        # theta_z x r = (-theta * ry, theta * rx)
        spin = np.stack([-offsets[:, 1], offsets[:, 0]], axis=1).reshape(-1, 1)
    else:
        # theta x r = -[r]_x theta: block rows of the negative cross-product matrix of r
        rx, ry, rz = offsets.T
        zero = np.zeros_like(rx)
        spin = -np.stack(
            [
                np.stack([zero, -rz, ry], axis=1),
                np.stack([rz, zero, -rx], axis=1),
                np.stack([-ry, rx, zero], axis=1),
            ],
            axis=1,
        ).reshape(-1, 3)
    return np.hstack([translations, spin])


def _check_nodes(node_dofs: np.ndarray, coupled_nodes, label: str) -> np.ndarray:
    nodes = np.unique(np.asarray(coupled_nodes, dtype=np.int64).ravel())
    if nodes.size == 0:
        raise InputError(f"{label}: the coupled node set is empty")
    if nodes.min() < 0 or nodes.max() >= node_dofs.shape[0]:
        raise InputError(f"{label}: node index out of range 0..{node_dofs.shape[0] - 1}")
    return nodes


def rigid_couplings(
    n_dofs: int,
    node_dofs: np.ndarray,
    coordinates: np.ndarray,
    groups: list[tuple[np.ndarray, np.ndarray]],
    *,
    rotations: bool,
) -> Coupling:
    """Several RBE2 couplings at once: ``groups`` is a list of (coupled_nodes, reference_point mm).

    Node sets must not overlap. Reference DOFs are appended in group order.
    """
    node_dofs = np.asarray(node_dofs)
    coordinates = np.asarray(coordinates, dtype=float)
    dim = node_dofs.shape[1]
    n_ref = dim + (0 if not rotations else (1 if dim == 2 else 3))
    node_sets = [_check_nodes(node_dofs, nodes, f"rigid coupling {k}") for k, (nodes, _) in enumerate(groups)]
    all_nodes = np.concatenate(node_sets)
    if np.unique(all_nodes).size != all_nodes.size:
        raise InputError("rigid couplings: a node belongs to more than one coupled node set")
    coupled_dofs = node_dofs[all_nodes].ravel()
    kept = np.full(n_dofs, -1, dtype=np.int64)
    free = np.ones(n_dofs, dtype=bool)
    free[coupled_dofs] = False
    kept_dofs = np.flatnonzero(free)
    kept[kept_dofs] = np.arange(kept_dofs.size)
    n_reduced = kept_dofs.size + n_ref * len(groups)

    rows = [kept_dofs]
    cols = [np.arange(kept_dofs.size)]
    vals = [np.ones(kept_dofs.size)]
    reference_dofs = []
    for k, (nodes, (_, point)) in enumerate(zip(node_sets, groups)):
        point = np.asarray(point, dtype=float).ravel()
        if point.size != dim:
            raise InputError(f"rigid coupling {k}: reference point needs {dim} coordinates, got {point.size}")
        first = kept_dofs.size + n_ref * k
        ref = np.arange(first, first + n_ref)
        reference_dofs.append(ref)
        block = rigid_body_matrix(coordinates[nodes] - point, rotations)
        block_rows, block_cols = np.nonzero(block)
        rows.append(node_dofs[nodes].ravel()[block_rows])
        cols.append(ref[block_cols])
        vals.append(block[block_rows, block_cols])
    transformation = sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n_dofs, n_reduced)
    )
    return Coupling(
        transformation=transformation,
        reference_dofs=np.array(reference_dofs),
        kept=kept,
        coupled_dofs=coupled_dofs,
    )


def rigid_coupling(
    n_dofs: int,
    node_dofs: np.ndarray,
    coordinates: np.ndarray,
    coupled_nodes,
    reference_point,
    *,
    rotations: bool,
) -> Coupling:
    """RBE2: the coupled nodes follow the reference point rigidly (small rotations).

    node_dofs: (n_nodes, dim) global DOF per node and component; coordinates: (n_nodes, dim) mm;
    coupled_nodes: node indices; reference_point: (dim,) mm. With ``rotations=False`` only
    translations are coupled (each coupled node moves with the reference translation).
    """
    coupling = rigid_couplings(
        n_dofs, node_dofs, coordinates, [(coupled_nodes, reference_point)], rotations=rotations
    )
    return Coupling(
        transformation=coupling.transformation,
        reference_dofs=coupling.reference_dofs[0],
        kept=coupling.kept,
        coupled_dofs=coupling.coupled_dofs,
    )


@dataclass(frozen=True)
class DistributingCoupling:
    """RBE3: the reference point moves with the weighted least-squares rigid fit of its nodes.

    averaging: (n_ref, n_dofs) CSR, u_ref = averaging @ u (translations in mm, rotations in rad).
    Its transpose distributes a reference force/moment (N, N mm) onto the nodes as nodal forces
    without stiffening the bearing area: f_nodes = averaging.T @ f_ref.
    """

    averaging: sp.csr_matrix
    coupled_dofs: np.ndarray

    def distribute(self, reference_load: np.ndarray) -> np.ndarray:
        """Nodal force vector (N) equivalent to a reference force [and moment]."""
        return self.averaging.T @ np.asarray(reference_load, dtype=float)

    def reference_motion(self, displacement: np.ndarray) -> np.ndarray:
        """Reference displacement [and rotation] from a full displacement vector (mm)."""
        return self.averaging @ displacement


def distributing_coupling(
    n_dofs: int,
    node_dofs: np.ndarray,
    coordinates: np.ndarray,
    coupled_nodes,
    reference_point,
    *,
    rotations: bool,
    weights=None,
) -> DistributingCoupling:
    """RBE3 (averaging) coupling of a bearing area to a reference point.

    weights: per coupled node (e.g. tributary areas, mm^2); uniform when None.
    """
    node_dofs = np.asarray(node_dofs)
    nodes = _check_nodes(node_dofs, coupled_nodes, "distributing coupling")
    w = np.ones(nodes.size) if weights is None else np.asarray(weights, dtype=float).ravel()
    if w.size != nodes.size or np.any(w < 0) or w.sum() <= 0:
        raise InputError("distributing coupling: need one non-negative weight per coupled node, not all zero")
    dim = node_dofs.shape[1]
    offsets = np.asarray(coordinates, dtype=float)[nodes] - np.asarray(reference_point, dtype=float).ravel()
    a = rigid_body_matrix(offsets, rotations)
    weighted = a * np.repeat(w, dim)[:, None]
    normal = a.T @ weighted
    if np.linalg.matrix_rank(normal) < normal.shape[0]:
        raise InputError(
            "distributing coupling: the coupled nodes cannot carry a moment (collinear or a single node); "
            "use rotations=False"
        )
    averaging = np.linalg.solve(normal, weighted.T)
    coupled_dofs = node_dofs[nodes].ravel()
    rows = np.repeat(np.arange(averaging.shape[0]), coupled_dofs.size)
    cols = np.tile(coupled_dofs, averaging.shape[0])
    matrix = sp.csr_matrix((averaging.ravel(), (rows, cols)), shape=(averaging.shape[0], n_dofs))
    return DistributingCoupling(averaging=matrix, coupled_dofs=coupled_dofs)
