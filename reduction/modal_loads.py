"""Loads on a body from another model's modes and frame motion (the counterweight coupling).

A multibody body's modes live on its own (quadratic-tetrahedron) mesh; the contact model of
the same body has its own mesh. :func:`interpolate_modes` carries the mode shapes over, and the
unit load patterns of the body's acceleration field

    a(x, t) = a_frame + α × r + ω × (ω × r) + 2 ω × Ψ q̇ + Ψ q̈        (r = x − frame origin)

are built from them with the body's mass (:func:`inertia_patterns`), as are the steady
centrifugal load (:func:`centrifugal_pattern`) and the load of one elastic mode normalised to a
unit wing torsion (:func:`wing_mode_pattern`). Only ω_z (the spin) enters the centrifugal and
Coriolis terms. Units: mm, N, t, s; accelerations mm/s², angular velocities rad/s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import skfem

from reduction.body_loads import mode_shape_inertia, rigid_body_inertia
from reduction.elasticity import ElasticBody
from reduction.errors import InputError

_AXES = "xyz"
_SPIN_AXIS = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class ModeField:
    """Mode shapes of a body on its own mesh: points (3, n_v) mm and cells (4, n_t) of a linear
    tetrahedral mesh carrying quadratic (P2) elements; shapes (3·n_nodes, m) mm per unit modal
    coordinate, node-interleaved in the P2 DOF order of that mesh."""

    points: np.ndarray
    cells: np.ndarray
    shapes: np.ndarray

    @property
    def n_modes(self) -> int:
        return int(self.shapes.shape[1])


#: points per call of scikit-fem's probes (see :func:`interpolate_modes`)
PROBE_CHUNK = 500


def interpolate_modes(modes: ModeField, coordinates: np.ndarray) -> np.ndarray:
    """(n, 3, m) mode shapes at the points ``coordinates`` (n, 3), mm per unit modal coordinate.

    The points must lie in the body of ``modes`` (same geometry and frame)."""
    mesh = skfem.MeshTet1(modes.points, modes.cells)
    basis = skfem.Basis(mesh, skfem.ElementVector(skfem.ElementTetP2()))
    if basis.N != modes.shapes.shape[0]:
        raise InputError("the multibody CW modes do not match its mesh (stale cache?): rerun the multibody stage")
    low, high = modes.points.min(axis=1), modes.points.max(axis=1)
    tolerance = 1e-6 * float(np.max(high - low))
    outside = np.any((coordinates < low - tolerance) | (coordinates > high + tolerance), axis=1)
    if outside.any():
        raise InputError(f"{int(outside.sum())} node(s) of the counterweight contact mesh lie outside the "
                         f"multibody counterweight (box {low.round(3).tolist()} … {high.round(3).tolist()} mm); "
                         "the contact body must have the multibody CW's geometry and frame")
    # probe slightly inside the box so that points on the outer faces find their element
    centre = 0.5 * (low + high)
    points = coordinates + 1e-9 * (centre - coordinates)
    # scikit-fem's element finder maps every point of a call into every candidate element of
    # all of them (3 × points × candidates): 11,889 nodes of a refined C3D10 CW took 3.8 GB at
    # once. In chunks of PROBE_CHUNK points it stays below about 100 MB.
    chunks = []
    for start in range(0, len(points), PROBE_CHUNK):
        part = points[start:start + PROBE_CHUNK]
        values = basis.probes(part.T) @ modes.shapes  # rows: component-major (all x, all y, all z)
        chunks.append(values.reshape(3, len(part), -1).transpose(1, 0, 2))
    return np.concatenate(chunks) if chunks else np.zeros((0, 3, modes.shapes.shape[1]))


def inertia_patterns(body: ElasticBody, modes: ModeField) -> dict[str, np.ndarray]:
    """Unit load patterns (N per unit history value) of the body's acceleration field.

    frame_a{x,y,z}: per mm/s² of frame acceleration; alpha_{x,y,z}: per rad/s² of angular
    acceleration; spin_squared: per (rad/s)² of ω_z²; mode_k: per unit q̈_k; coriolis_k: per unit
    ω_z·q̇_k. The frame origin is the coordinate origin (the centre of the CW's contact face).
    """
    if body.dim != 3:
        raise InputError("the counterweight coupling needs a 3D contact model")
    patterns = {}
    for k, axis in enumerate(_AXES):
        unit = np.eye(3)[k]
        patterns[f"frame_a{axis}"] = rigid_body_inertia(body, unit)
        patterns[f"alpha_{axis}"] = rigid_body_inertia(body, np.zeros(3), unit)
    patterns["spin_squared"] = rigid_body_inertia(body, np.zeros(3), None, _SPIN_AXIS)
    if modes.n_modes == 0:  # histories without modes: the rigid-body fields only
        return patterns
    shapes = interpolate_modes(modes, body.coordinates)  # (n_nodes, 3, m)
    field = np.zeros((body.n_dofs, modes.n_modes))
    field[body.node_dofs.ravel()] = shapes.reshape(-1, modes.n_modes)
    inertia = mode_shape_inertia(body, field)
    spin_cross = np.zeros_like(field)  # e_z × Ψ_k, per node: (-ψ_y, ψ_x, 0)
    spin_cross[body.node_dofs[:, 0]] = -field[body.node_dofs[:, 1]]
    spin_cross[body.node_dofs[:, 1]] = field[body.node_dofs[:, 0]]
    coriolis = -2.0 * (body.mass @ spin_cross)
    for k in range(modes.n_modes):
        patterns[f"mode_{k + 1}"] = inertia[:, k]
        patterns[f"coriolis_{k + 1}"] = coriolis[:, k]
    return patterns


def centrifugal_pattern(body: ElasticBody, mean_frame_acceleration: np.ndarray, mean_spin_squared: float) -> np.ndarray:
    """Load (N) of the steady rotation: the mean frame acceleration (3,) mm/s² and the mean
    ω_z² (rad/s)² field."""
    load = np.zeros(body.n_dofs)
    for k in range(3):
        load += mean_frame_acceleration[k] * rigid_body_inertia(body, np.eye(3)[k])
    return load + mean_spin_squared * rigid_body_inertia(body, np.zeros(3), None, _SPIN_AXIS)


def wing_mode_load(body: ElasticBody, modes: ModeField, mode: int, frequency_hz: float) -> np.ndarray:
    """The elastic force ω² M Ψ (N per unit modal coordinate) of mode ``mode`` of ``modes``,
    interpolated onto the body, ω from ``frequency_hz``."""
    shapes = interpolate_modes(modes, body.coordinates)[:, :, mode]
    field = np.zeros(body.n_dofs)
    field[body.node_dofs.ravel()] = shapes.ravel()
    omega = 2.0 * np.pi * frequency_hz
    return omega ** 2 * (body.mass @ field)


def wing_tip_dofs(body: ElasticBody) -> tuple[np.ndarray, np.ndarray]:
    """u_z DOFs of the wing-tip edges (outer top edge at the −x and at the +x extreme)."""
    coordinates = body.coordinates
    tips = [np.flatnonzero((np.abs(coordinates[:, 0] - sign * coordinates[:, 0].max()) < 1e-6)
                           & (np.abs(coordinates[:, 1] - coordinates[:, 1].max()) < 1e-6)) for sign in (-1, 1)]
    if any(t.size == 0 for t in tips):
        raise InputError("the counterweight contact mesh has no wing-tip edge (outer face at the x extremes)")
    return body.node_dofs[tips[0], 2], body.node_dofs[tips[1], 2]


def wing_torsion(minus_tip_uz: np.ndarray, plus_tip_uz: np.ndarray) -> float:
    """Wing torsion (mm): (mean u_z of the +x tip edge − mean u_z of the −x tip edge)/2."""
    torsion = 0.5 * (float(np.mean(plus_tip_uz)) - float(np.mean(minus_tip_uz)))
    if abs(torsion) < 1e-12:
        raise InputError("the interpolated torsion mode does not twist the counterweight's wings")
    return torsion


def wing_mode_pattern(body: ElasticBody, modes: ModeField, mode: int, frequency_hz: float,
                      clamped_nodes: np.ndarray) -> np.ndarray:
    """Load (N) of one elastic mode (the wing "torsion") per mm of wing torsion.

    The elastic force ω² M Ψ (:func:`wing_mode_load`), scaled so that the body with
    ``clamped_nodes`` held deflects by a wing torsion (u_z(+x tip) − u_z(−x tip))/2 of exactly
    1 mm under it. Factorises the clamped body for this one solve; a run shares the body's
    factorisation with its condensation instead (:func:`pipelines.coupling.coupled_patterns`,
    :meth:`reduction.condensation.BoundarySchur.clamped_response`).
    """
    from reduction.factorization import factorize

    load = wing_mode_load(body, modes, mode, frequency_hz)
    fixed = np.zeros(body.n_dofs, dtype=bool)
    fixed[body.node_dofs[clamped_nodes].ravel()] = True
    free = np.flatnonzero(~fixed)
    displacement = np.zeros(body.n_dofs)
    factor = factorize(body.stiffness[free][:, free].tocsc(), label="clamped counterweight")
    displacement[free] = factor.solve(load[free])
    minus, plus = wing_tip_dofs(body)
    return load / wing_torsion(displacement[minus], displacement[plus])
