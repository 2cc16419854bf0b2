"""Generic counterweight (CW) geometry, its finite-element mesh and Craig-Bampton reduction.

The CW of a 320 mm-bore medium-speed engine is modelled as a block with a raised hub. Local
frame of the CW (origin at the centre of the bolted contact face):

* x: tangential (the direction in which the two wings extend from the hub),
* y: radial, pointing away from the crank axis,
* z: along the crank axis.

The hub (|x| <= hub_width/2, 0 <= y <= hub_height) carries the flat contact face y = 0 that
is bolted to the crankshaft web. Above it, the wing plate (|x| <= width/2, hub_height <= y <=
height) overhangs the hub on both sides: these overhangs are the "wings". In the paper's
"torsion" mode the wings vibrate along the crank axis (z) in opposite phase, i.e. the CW
twists about its radial axis.

A user's own CW (``mesh_file``, an Abaqus .inp or Gmsh .msh file in the CW frame above: origin
at the centre of the contact face, y radial outward, z along the crank axis) replaces the block:
its corner mesh (hexahedra split into tetrahedra, mid-edge nodes of Tet10/Hex20 files put back on
straight edges) carries quadratic tetrahedra, its node set or surface ``interface`` is the
rigid interface, and its wing tips are the nodes nearest to the ends of the top edge
(x extremes, y largest, z mid-plane).

Craig-Bampton (Hurty) reduction with the contact face as one rigid (RBE2) interface, done by
reduction.exudyn_bridge.floating_frame_modes: the interface is the floating frame of the reduced
body, so the mode basis holds only the fixed-interface normal modes and the body's reference
node IS the interface.

Units: mm, N, MPa, t, s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse as sp
import skfem

from mbs.refusal import Refusal, refuse
from reduction.elasticity import ElasticBody, assemble_elastic_body
from reduction.errors import InputError
from reduction.mesh.generators import cells_inside, counterweight_solids
from reduction.exudyn_bridge import FloatingFrameModes, fem_interface, floating_frame_modes


@dataclass(frozen=True)
class CounterweightGeometry:
    """Block counterweight with a raised hub (all lengths mm, material MPa and t/mm^3).

    width: tangential extent of the wing plate (wing tip to wing tip).
    height: radial extent from the contact face to the outer face.
    thickness: axial extent (along the crank axis).
    hub_width: tangential extent of the hub, i.e. of the bolted contact face.
    hub_height: radial height of the hub below the wing plate (the relief under the wings).
    elements_*: number of mesh cells along x, y, z (tetrahedra from a tensor grid).
    mesh_file: a mesh file of the user's own CW (module doc) instead of the block; the block's
    sizes are then unused. interface: name of the node set or surface of that file that is the
    bolted contact face. mesh_digest: SHA-256 of the file (set by the scene reader, so that a
    changed file is a changed model for the stage cache).
    """

    width: float = 700.0
    height: float = 200.0
    thickness: float = 80.0
    hub_width: float = 220.0
    hub_height: float = 30.0
    youngs_modulus: float = 210000.0
    poisson_ratio: float = 0.3
    density: float = 7.85e-9
    elements_x: int = 14
    elements_y: int = 4
    elements_z: int = 2
    mesh_file: str | None = None
    interface: str | None = None
    mesh_digest: str | None = None

    def validate(self) -> None:
        """Raise :class:`mbs.refusal.Refusal` for the first value the model cannot use."""
        if self.mesh_file is not None:
            if not self.interface:
                raise Refusal(("counterweight.mesh_file",), (self.mesh_file,),
                              "needs 'interface': the node set or surface of the file that is the bolted contact face")
            positive = ("youngs_modulus", "density")
        else:
            positive = ("width", "height", "thickness", "hub_width", "hub_height", "youngs_modulus", "density")
        for name in positive:
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise refuse(f"counterweight.{name}", value, f"must be positive ({_UNITS.get(name, 'mm')})")
        if self.mesh_file is not None:
            return
        for small, large, why in (("hub_width", "width", ": the wings need an overhang"), ("hub_height", "height", "")):
            if not getattr(self, small) < getattr(self, large):
                raise Refusal((f"counterweight.{small}", f"counterweight.{large}"),
                              (getattr(self, small), getattr(self, large)),
                              f"{small} ({getattr(self, small):g} mm) must be smaller than {large} "
                              f"({getattr(self, large):g} mm){why}")
        for name in ("elements_x", "elements_y", "elements_z"):
            if getattr(self, name) < 1:
                raise refuse(f"counterweight.{name}", getattr(self, name), "must be at least 1 (mesh cells)")
        if self.elements_z % 2:
            raise refuse("counterweight.elements_z", self.elements_z,
                         "must be even, so that the wing-tip nodes lie on the mid-plane")


#: units of the CounterweightGeometry fields that are not lengths (mm)
_UNITS = {"youngs_modulus": "MPa", "density": "t/mm³"}


@dataclass(frozen=True)
class ReducedCounterweight:
    """Craig-Bampton counterweight ready for exudyn.

    node_coordinates: (n_nodes, 3) mm, local CW frame. mode_shapes: (3 n_nodes, n_modes)
    node-interleaved fixed-interface modes, mass-normalised (1/sqrt(t)).
    stiffness, mass: full FE matrices (N/mm, t), node-interleaved.
    eigenfrequencies: (n_modes,) Hz, fixed-interface. interface_nodes: contact-face nodes.
    wing_tip_nodes: (2,) nodes at the -x and +x wing tips (outer face, mid-plane).
    torsion_mode: index of the wing "torsion" mode in mode_shapes.
    total_mass: t. center_of_mass: (3,) mm in the CW frame.
    body, modes: the assembled FE body and the floating-frame modes (reduction/ objects).
    """

    geometry: CounterweightGeometry
    node_coordinates: np.ndarray
    mode_shapes: np.ndarray
    stiffness: sp.csr_matrix
    mass: sp.csr_matrix
    eigenfrequencies: np.ndarray
    interface_nodes: np.ndarray
    wing_tip_nodes: np.ndarray
    torsion_mode: int
    total_mass: float
    center_of_mass: np.ndarray
    body: ElasticBody
    modes: FloatingFrameModes

    def fem_interface(self):
        """exudyn FEMinterface (mesh, K, M, modes, surface) for ObjectFFRFreducedOrder."""
        return fem_interface(self.body, self.modes)

    @property
    def n_modes(self) -> int:
        return int(self.mode_shapes.shape[1])

    @property
    def torsion_frequency(self) -> float:
        """Fixed-interface eigenfrequency of the wing torsion mode, Hz."""
        return float(self.eigenfrequencies[self.torsion_mode])

    def wing_tip_axial_shapes(self) -> np.ndarray:
        """(2, n_modes): axial (z) displacement of the two wing tips per unit modal coordinate."""
        return self.mode_shapes[3 * self.wing_tip_nodes + 2, :]


def counterweight_mesh(geometry: CounterweightGeometry) -> skfem.MeshTet1:
    """Tetrahedral mesh of the CW block: the tensor grid cut to the CW's shape
    (:func:`reduction.mesh.generators.counterweight_solids`), which removes the relief under the wings.
    With ``mesh_file``, the linear tetrahedral mesh of that file (module doc)."""
    geometry.validate()
    if geometry.mesh_file is not None:
        return _file_mesh(geometry)[0]
    g = geometry
    half_hub = 0.5 * g.hub_width
    # Grid lines on the hub edges and on the hub-height level keep the relief boundary exact.
    n_wing = max(1, round(g.elements_x * (g.width - g.hub_width) / (2.0 * g.width)))
    n_hub = max(2, g.elements_x - 2 * n_wing)
    x = np.concatenate([
        np.linspace(-0.5 * g.width, -half_hub, n_wing + 1)[:-1],
        np.linspace(-half_hub, half_hub, n_hub + 1)[:-1],
        np.linspace(half_hub, 0.5 * g.width, n_wing + 1),
    ])
    y = np.concatenate([[0.0], np.linspace(g.hub_height, g.height, g.elements_y + 1)])
    z = np.linspace(-0.5 * g.thickness, 0.5 * g.thickness, g.elements_z + 1)
    mesh = skfem.MeshTet1.init_tensor(x, y, z)
    shape = counterweight_solids(g.width, g.height, g.thickness, g.hub_width, g.hub_height)
    return mesh.remove_elements(np.flatnonzero(~cells_inside(mesh, shape)))


def corner_tetrahedra(mesh: skfem.Mesh) -> skfem.MeshTet1:
    """The linear tetrahedral mesh on the corner nodes of a 3D scikit-fem mesh: mid-edge nodes
    dropped (Tet10, Hex20), hexahedra split into tetrahedra."""
    corners = np.unique(mesh.t)
    compact = np.full(mesh.p.shape[1], -1)
    compact[corners] = np.arange(corners.size)
    kind = skfem.MeshHex1 if isinstance(mesh, skfem.MeshHex1) else skfem.MeshTet1
    linear = kind(np.ascontiguousarray(mesh.p[:, corners]), np.ascontiguousarray(compact[mesh.t]))
    return linear.to_meshtet() if kind is skfem.MeshHex1 else linear


def wing_tip_points(coordinates: np.ndarray) -> list[tuple[float, float, float]]:
    """Where a CW mesh's wing tips are looked for (mm): the two ends of its top edge (x extremes,
    y largest, z mid-plane)."""
    low, high = coordinates.min(axis=0), coordinates.max(axis=0)
    return [(float(x), float(high[1]), float(0.5 * (low[2] + high[2]))) for x in (low[0], high[0])]


def _file_mesh(geometry: CounterweightGeometry) -> tuple[skfem.MeshTet1, np.ndarray]:
    """The linear tetrahedral mesh of the CW file (corner nodes; hexahedra split into tetrahedra)
    and the mask of its vertices that belong to the interface set."""
    from scipy.spatial import cKDTree

    from reduction.mesh.io import read_mesh

    model = read_mesh(geometry.mesh_file)
    if model.mesh.dim() != 3:
        raise InputError(f"{geometry.mesh_file}: the counterweight mesh must be 3D")
    linear = corner_tetrahedra(model.mesh)
    positions = model.points[model.node_set(geometry.interface)]
    distance, index = cKDTree(positions).query(linear.p.T)
    return linear, distance <= 1e-6 * float(np.ptp(linear.p, axis=1).max())


def _face_nodes(mesh: skfem.MeshTet1, face: np.ndarray, geometry: CounterweightGeometry) -> np.ndarray:
    """P2 nodes (vertices, then one per edge) of the boundary facets whose vertices all lie on
    the interface: the rigid interface of the CW file."""
    boundary = mesh.boundary_facets()
    facets = boundary[np.all(face[mesh.facets[:, boundary]], axis=0)]
    if facets.size == 0:
        raise InputError(f"{geometry.mesh_file}: the set '{geometry.interface}' covers no boundary face of the "
                         "counterweight mesh; name the node set or surface of its bolted contact face")
    return np.union1d(np.unique(mesh.facets[:, facets]), mesh.p.shape[1] + np.unique(mesh.f2e[:, facets]))


def _nodes_near(coordinates: np.ndarray, point, tolerance: float) -> int:
    distance = np.linalg.norm(coordinates - np.asarray(point, dtype=float), axis=1)
    node = int(np.argmin(distance))
    if distance[node] > tolerance:
        raise InputError(f"counterweight mesh has no node within {tolerance} mm of {list(point)}")
    return node


def torsion_mode_index(tip_axial: np.ndarray, mode_shapes: np.ndarray) -> int:
    """Lowest mode whose wing tips move axially in opposite phase and dominate the mode.

    The tetrahedral split of the grid is not mirror-symmetric, so "opposite phase" allows a
    symmetric part of up to 10 % of the antisymmetric one.
    """
    antisymmetric = tip_axial[0] * tip_axial[1] < 0
    symmetric_part = np.abs(tip_axial[0] + tip_axial[1])
    opposite = np.abs(tip_axial[0] - tip_axial[1])
    largest = np.abs(mode_shapes).max(axis=0)
    candidates = np.nonzero(antisymmetric & (symmetric_part < 0.1 * opposite) & (opposite > 0.5 * largest))[0]
    if candidates.size == 0:
        raise InputError(
            "no wing torsion mode (wing tips moving along the crank axis in opposite phase) among the "
            f"{mode_shapes.shape[1]} counterweight modes; increase the number of CB modes"
        )
    return int(candidates[0])


def reduce_counterweight(geometry: CounterweightGeometry, n_modes: int = 6) -> ReducedCounterweight:
    """Mesh, assemble (quadratic tetrahedra) and Craig-Bampton-reduce the CW.

    n_modes: number of fixed-interface normal modes kept (the contact face is the rigid interface).
    """
    if n_modes < 1:
        raise InputError(f"number of CB modes must be at least 1, got {n_modes}")
    geometry.validate()
    if geometry.mesh_file is None:
        mesh = counterweight_mesh(geometry)
    else:
        mesh, face = _file_mesh(geometry)
    body = assemble_elastic_body(mesh, geometry.youngs_modulus, geometry.poisson_ratio, geometry.density,
                                 quadratic=True)
    coordinates = body.coordinates
    n_nodes = coordinates.shape[0]
    if not np.array_equal(body.node_dofs, np.arange(3 * n_nodes).reshape(n_nodes, 3)):
        raise InputError("counterweight DOFs are not node-interleaved as exudyn requires")
    if geometry.mesh_file is None:
        tolerance = 1e-6 * geometry.width
        interface_nodes = np.nonzero(np.abs(coordinates[:, 1]) < tolerance)[0]
        tips = [(sign * 0.5 * geometry.width, geometry.height, 0.0) for sign in (-1.0, 1.0)]
    else:
        interface_nodes = _face_nodes(mesh, face, geometry)
        tolerance = float(np.linalg.norm(np.ptp(coordinates, axis=0)))  # the nearest nodes, wherever they are
        tips = wing_tip_points(coordinates)
    modes = floating_frame_modes(body, [interface_nodes], n_modes, reference_points=[[0.0, 0.0, 0.0]])
    mode_shapes = modes.basis
    wing_tip_nodes = np.array([_nodes_near(coordinates, tip, tolerance) for tip in tips])
    torsion = torsion_mode_index(mode_shapes[3 * wing_tip_nodes + 2, :], mode_shapes)
    ones = np.zeros((3 * n_nodes, 3))
    for j in range(3):
        ones[j::3, j] = 1.0
    mass_per_direction = ones.T @ (body.mass @ ones)
    total_mass = float(mass_per_direction[0, 0])
    center_of_mass = (ones.T @ (body.mass @ coordinates.ravel())) / total_mass
    return ReducedCounterweight(
        geometry=geometry,
        node_coordinates=coordinates,
        mode_shapes=mode_shapes,
        stiffness=body.stiffness,
        mass=body.mass,
        eigenfrequencies=modes.fixed_interface_frequencies_hz,
        interface_nodes=interface_nodes,
        wing_tip_nodes=wing_tip_nodes,
        torsion_mode=torsion,
        total_mass=total_mass,
        center_of_mass=center_of_mass,
        body=body,
        modes=modes,
    )


def reduced_matrices(reduced: ReducedCounterweight) -> tuple[np.ndarray, np.ndarray]:
    """Modal stiffness (N/mm per unit modal coordinate) and mass (t) of the reduced CW."""
    psi = reduced.mode_shapes
    return psi.T @ (reduced.stiffness @ psi), psi.T @ (reduced.mass @ psi)


def reduced_eigenfrequencies(reduced: ReducedCounterweight) -> np.ndarray:
    """Eigenfrequencies (Hz) of the reduced body with its interface fixed, from its own matrices."""
    stiffness, mass = reduced_matrices(reduced)
    eigenvalues = scipy.linalg.eigh(stiffness, mass, eigvals_only=True)
    return np.sqrt(np.abs(eigenvalues)) / (2.0 * np.pi)
