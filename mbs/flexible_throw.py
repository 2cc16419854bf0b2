"""Flexible crank throw: one Craig-Bampton body per throw (half journal + web + pin + web + half
journal) for the "flexible_crankshaft" effect.

Geometry in the throw frame (x from the axis towards the pin, z along the crank axis, origin at
the throw centre), from CrankThrowParams: journals and pin are square prisms of the same
cross-section area as the round ones (side sqrt(pi) x radius; the pin takes the journal's
square width tangentially so that the tensor grid stays free of slivers); webs are full blocks
(web_width tangentially) from the CW contact face x = -counterweight_radius to the pin's outer
edge. Each journal is cut at its centre, where the neighbouring throw's body (or the bearing of
an end journal) attaches; the outer halves of the two end journals are left out (about 50 kg
each, on the axis, at a bearing). Quadratic tetrahedra from reduction.elasticity.

Interfaces (RBE2, exudyn floating-frame convention: the FIRST is the frame and is clamped in
every mode): 0 journal-1 cut face (z = -bearing_z), 1 journal-2 cut face, 2 and 3 the CW contact
faces of web 1 and web 2. The basis holds 18 constraint modes of interfaces 1-3 plus
CrankThrowParams.flexible_modes fixed-interface normal modes.

Units: mm, N, MPa, t, s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import skfem

from mbs.parameters import CrankThrowParams
from reduction.elasticity import ElasticBody, assemble_elastic_body
from reduction.errors import InputError
from reduction.exudyn_bridge import FloatingFrameModes, fem_interface, floating_frame_modes

#: side of the square of a circle's area, per unit radius
SQUARE_SIDE = math.sqrt(math.pi)


@dataclass(frozen=True)
class ReducedThrow:
    """Craig-Bampton throw body ready for exudyn (throw frame, mm).

    interface_nodes: [journal 1, journal 2, CW face 1, CW face 2] node sets; pin_nodes: nodes of
    the pin's mid-section (gas-force marker). node_coordinates (n, 3) mm, mode_shapes (3n, m),
    stiffness, mass: full FE matrices, node-interleaved (N/mm, t). eigenfrequencies: fixed-
    interface normal-mode frequencies, Hz.
    """

    throw: CrankThrowParams
    node_coordinates: np.ndarray
    mode_shapes: np.ndarray
    stiffness: sp.csr_matrix
    mass: sp.csr_matrix
    eigenfrequencies: np.ndarray
    interface_nodes: list
    pin_nodes: np.ndarray
    body: ElasticBody
    modes: FloatingFrameModes

    def fem_interface(self):
        """exudyn FEMinterface (mesh, K, M, modes, surface) for ObjectFFRFreducedOrder."""
        return fem_interface(self.body, self.modes)

    @property
    def n_modes(self) -> int:
        return int(self.mode_shapes.shape[1])


def _halves(a: float, b: float, pieces: int) -> np.ndarray:
    return np.linspace(a, b, pieces + 1)


def throw_mesh(throw: CrankThrowParams) -> skfem.MeshTet1:
    """Linear tetrahedral mesh of one throw (refined to quadratic when assembled)."""
    journal_half = 0.5 * SQUARE_SIDE * throw.journal_radius
    pin_half = 0.5 * SQUARE_SIDE * throw.pin_radius
    pin_inner, pin_outer = throw.crank_radius - pin_half, throw.crank_radius + pin_half
    if pin_inner <= journal_half * 0.2 or throw.web_width < 2.0 * journal_half:
        raise InputError("throw geometry: the pin must lie clear of the journal and the web must be wider "
                         "than the journal for the flexible-crankshaft mesh")
    x = np.unique(np.concatenate([
        _halves(-throw.counterweight_radius, -journal_half, 1), _halves(-journal_half, journal_half, 2),
        [pin_inner], _halves(max(journal_half, pin_inner), pin_outer, 2)]))
    # mirror grid lines inside the journal: the journal cut faces must be symmetric about the axis,
    # exudyn places their rigid markers at the mean of the face nodes
    x = np.unique(np.concatenate([x, -x[np.abs(x) < journal_half]]))
    y = np.unique(np.concatenate([[-0.5 * throw.web_width], _halves(-journal_half, journal_half, 2),
                                  [0.5 * throw.web_width]]))
    web_in, web_out, cut = 0.5 * throw.pin_length, 0.5 * throw.pin_length + throw.web_thickness, throw.bearing_z
    z_half = np.concatenate([_halves(0.0, web_in, 2), _halves(web_in, web_out, 2)[1:], [cut]])
    z = np.unique(np.concatenate([-z_half, z_half]))
    mesh = skfem.MeshTet1.init_tensor(np.sort(x), y, z)
    cx, cy, cz = mesh.p[:, mesh.t].mean(axis=1)
    in_web = (np.abs(cz) > web_in) & (np.abs(cz) < web_out)
    in_pin = (np.abs(cz) < web_in) & (cx > pin_inner) & (np.abs(cy) < journal_half)
    in_journal = (np.abs(cz) > web_out) & (np.abs(cx) < journal_half) & (np.abs(cy) < journal_half)
    return mesh.remove_elements(np.nonzero(~(in_web | in_pin | in_journal))[0])


def reduce_throw(throw: CrankThrowParams, n_modes: int | None = None) -> ReducedThrow:
    """Mesh, assemble (quadratic tetrahedra) and Craig-Bampton-reduce one throw.

    n_modes: fixed-interface normal modes (default throw.flexible_modes).
    """
    n_modes = throw.flexible_modes if n_modes is None else n_modes
    if n_modes < 1:
        raise InputError(f"flexible crankshaft: number of CB modes must be at least 1, got {n_modes}")
    body = assemble_elastic_body(throw_mesh(throw), throw.youngs_modulus, throw.poisson_ratio, throw.density,
                                 quadratic=True)
    xyz = body.coordinates
    n_nodes = xyz.shape[0]
    if not np.array_equal(body.node_dofs, np.arange(3 * n_nodes).reshape(n_nodes, 3)):
        raise InputError("throw DOFs are not node-interleaved as exudyn requires")
    tolerance = 1e-6 * throw.bearing_z
    on_cw_face = np.abs(xyz[:, 0] + throw.counterweight_radius) < tolerance
    interfaces = [
        np.nonzero(np.abs(xyz[:, 2] + throw.bearing_z) < tolerance)[0],
        np.nonzero(np.abs(xyz[:, 2] - throw.bearing_z) < tolerance)[0],
        np.nonzero(on_cw_face & (xyz[:, 2] < 0.0))[0],
        np.nonzero(on_cw_face & (xyz[:, 2] > 0.0))[0],
    ]
    web_center = throw.web_center_z
    reference_points = [[0.0, 0.0, -throw.bearing_z], [0.0, 0.0, throw.bearing_z],
                        [-throw.counterweight_radius, 0.0, -web_center], [-throw.counterweight_radius, 0.0, web_center]]
    for nodes, point in zip(interfaces, reference_points):
        if not np.allclose(xyz[nodes].mean(axis=0), point, atol=1e-6 * throw.bearing_z):
            raise InputError(f"flexible crankshaft mesh: interface nodes around {point} are not centred on it")
    modes = floating_frame_modes(body, interfaces, n_modes, reference_points=reference_points)
    pin_nodes = np.nonzero((np.abs(xyz[:, 2]) < tolerance) & (xyz[:, 0] > throw.crank_radius - 0.5 * SQUARE_SIDE
                                                              * throw.pin_radius - tolerance))[0]
    return ReducedThrow(
        throw=throw,
        node_coordinates=xyz,
        mode_shapes=modes.basis,
        stiffness=body.stiffness,
        mass=body.mass,
        eigenfrequencies=modes.fixed_interface_frequencies_hz,
        interface_nodes=modes.interface_nodes,
        pin_nodes=pin_nodes,
        body=body,
        modes=modes,
    )
