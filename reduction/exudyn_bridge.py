"""Hand-over of reduced bodies to exudyn's floating-frame object ``ObjectFFRFreducedOrder``.

exudyn's convention (as its ``FEMinterface.ComputeHurtyCraigBamptonModes``, RBE2 mode): the
floating frame carries the rigid-body motion, so the mode basis has none; the FIRST interface
is clamped in every mode and thereby defines the frame. The other interfaces contribute six
(three without rotations) constraint modes each, then come fixed-interface normal modes.

Typical use by the multibody model (3D bodies only; units mm, t, N, s throughout):

    modes = floating_frame_modes(body, [hub_nodes, wing_nodes], n_modes=20)
    item = add_floating_body(mbs, body, modes, position=[0, 0, 0])
    wing = mbs.AddMarker(MarkerSuperElementRigid(        # frame at the centroid of the wing nodes
        bodyNumber=item.object, meshNodeNumbers=modes.interface_nodes[1],
        weightingFactors=modes.interface_weights[1]))
    # displacement / acceleration of a mesh node: SensorSuperElement(bodyNumber=item.object,
    #     meshNodeNumber=k, outputVariableType=exu.OutputVariableType.Displacement)

The body frame (``item.rigid_body_node``) has its origin at the mesh origin, placed at
``position``; interface 0 moves rigidly with it (it is clamped in every mode), so a joint there
may use ``MarkerNodeRigid`` on that node or a ``MarkerSuperElementRigid`` on interface 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from reduction.coupling import rigid_couplings
from reduction.craig_bampton import CraigBampton, craig_bampton
from reduction.elasticity import ElasticBody
from reduction.errors import InputError


@dataclass(frozen=True)
class FloatingFrameModes:
    """Mode basis for a floating-frame body.

    basis: (n_dofs, n_q) full mesh DOFs (node-interleaved, rows as ``body.node_dofs``), columns
    = constraint modes of interfaces 2..n, then fixed-interface normal modes; mm per unit q.
    interface_nodes / interface_weights: node indices of each interface and equal weights summing
    to one (for exudyn ``MarkerSuperElement*``). reference_points: (n_interfaces, 3) mm.
    reduction: the Craig-Bampton reduction in the coupled DOFs (eigenvalues, reduced K and M).
    """

    basis: np.ndarray
    interface_nodes: list[np.ndarray]
    interface_weights: list[np.ndarray]
    reference_points: np.ndarray
    reduction: CraigBampton

    @property
    def fixed_interface_frequencies_hz(self) -> np.ndarray:
        return self.reduction.fixed_interface_frequencies_hz


def floating_frame_modes(
    body: ElasticBody,
    interface_nodes: list,
    n_modes: int,
    *,
    reference_points=None,
    rotations: bool = True,
    solver: str = "auto",
) -> FloatingFrameModes:
    """Craig-Bampton modes in exudyn's floating-frame convention (first interface clamped).

    interface_nodes: list of node index arrays, each RBE2-coupled to a reference point
    (default: the centroid of its nodes, mm). Needs a mass matrix (assemble with a density).
    """
    if body.dim != 3:
        raise InputError(f"exudyn floating-frame bodies are 3D; this body is {body.dim}D")
    if body.mass is None:
        raise InputError("the body has no mass matrix: assemble it with a density (t/mm^3)")
    if not interface_nodes:
        raise InputError("a floating-frame body needs at least one interface node set (it defines the frame)")
    coordinates = body.coordinates
    node_sets = [np.unique(np.asarray(nodes, dtype=np.int64).ravel()) for nodes in interface_nodes]
    if reference_points is None:
        reference_points = np.array([coordinates[nodes].mean(axis=0) for nodes in node_sets])
    reference_points = np.asarray(reference_points, dtype=float).reshape(len(node_sets), body.dim)
    coupling = rigid_couplings(
        body.n_dofs, body.node_dofs, coordinates, list(zip(node_sets, reference_points)), rotations=rotations
    )
    reduction = craig_bampton(
        coupling.reduce_matrix(body.stiffness),
        coupling.reduce_matrix(body.mass),
        coupling.reference_dofs[1:].ravel(),
        n_modes,
        fixed=coupling.reference_dofs[0],
        solver=solver,
    )
    return FloatingFrameModes(
        basis=np.asarray(coupling.transformation @ reduction.basis),
        interface_nodes=node_sets,
        interface_weights=[np.full(nodes.size, 1.0 / nodes.size) for nodes in node_sets],
        reference_points=reference_points,
        reduction=reduction,
    )


def surface_triangles(body: ElasticBody) -> np.ndarray:
    """(n_triangles, 3) vertex indices of the boundary, outward-oriented (quads split in two)."""
    mesh = body.mesh
    facets = mesh.boundary_facets()
    corners = mesh.facets[:, facets].T
    if corners.shape[1] == 4:
        # skfem stores quad facets as a cycle; split along the 0-2 diagonal
        corners = np.concatenate([corners[:, [0, 1, 2]], corners[:, [0, 2, 3]]])
        facets = np.concatenate([facets, facets])
    points = mesh.p.T
    normal = np.cross(points[corners[:, 1]] - points[corners[:, 0]], points[corners[:, 2]] - points[corners[:, 0]])
    element_centre = points[mesh.t[:, mesh.f2t[0, facets]].T].mean(axis=1)
    inward = np.einsum("ij,ij->i", normal, points[corners[:, 0]] - element_centre) < 0
    corners[inward] = corners[inward][:, [0, 2, 1]]
    return corners


def fem_interface(body: ElasticBody, modes: FloatingFrameModes):
    """An ``exudyn.FEM.FEMinterface`` holding our mesh, K, M (CSR, node-interleaved) and modes."""
    from exudyn.FEM import FEMinterface

    if body.dim != 3:
        raise InputError(f"exudyn floating-frame bodies are 3D; this body is {body.dim}D")
    order = body.node_dofs.ravel()
    interleaved = np.array_equal(order, np.arange(body.n_dofs))
    stiffness = body.stiffness if interleaved else body.stiffness[order][:, order]
    mass = body.mass if interleaved else body.mass[order][:, order]

    fem = FEMinterface()
    fem.nodes = {"Position": body.coordinates}
    fem.stiffnessMatrix = sp.csr_matrix(stiffness)
    fem.massMatrix = sp.csr_matrix(mass)
    fem.surface = [{"Name": "boundary", "Trigs": surface_triangles(body)}]
    fem.modeBasis = {"matrix": modes.basis[order], "type": "HCBmodes"}
    fem.eigenValues = modes.reduction.fixed_interface_eigenvalues
    fem.nodeSets = [
        {"Name": f"interface{k}", "NodeNumbers": nodes, "NodeWeights": weights, "type": "boundary"}
        for k, (nodes, weights) in enumerate(zip(modes.interface_nodes, modes.interface_weights))
    ]
    return fem


@dataclass(frozen=True)
class FloatingBodyItems:
    """exudyn item numbers of an added floating-frame body and the interface object behind it."""

    object: int
    rigid_body_node: int
    modal_node: int
    interface: object


def add_floating_body(
    mbs,
    body: ElasticBody,
    modes: FloatingFrameModes,
    *,
    position=(0.0, 0.0, 0.0),
    rotation_matrix=None,
    velocity=(0.0, 0.0, 0.0),
    angular_velocity=(0.0, 0.0, 0.0),
    gravity=(0.0, 0.0, 0.0),
    stiffness_proportional_damping: float = 0.0,
    name: str = "",
) -> FloatingBodyItems:
    """Add an ``ObjectFFRFreducedOrder`` (C++ terms, no user functions) to ``mbs``.

    position mm, velocity mm/s, angular_velocity rad/s, gravity mm/s^2, damping factor s.
    """
    from exudyn.FEM import ObjectFFRFreducedOrderInterface

    interface = ObjectFFRFreducedOrderInterface(fem_interface(body, modes))
    items = interface.AddObjectFFRFreducedOrder(
        mbs,
        positionRef=list(position),
        rotationMatrixRef=[] if rotation_matrix is None else np.asarray(rotation_matrix),
        initialVelocity=list(velocity),
        initialAngularVelocity=list(angular_velocity),
        gravity=list(gravity),
        stiffnessProportionalDamping=stiffness_proportional_damping,
        name=name,
    )
    return FloatingBodyItems(
        object=items["oFFRFreducedOrder"],
        rigid_body_node=items["nRigidBody"],
        modal_node=items["nGenericODE2"],
        interface=interface,
    )
