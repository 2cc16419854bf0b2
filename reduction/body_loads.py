"""Consistent nodal loads (N) from acceleration fields, via the mass matrix (t).

Accelerations in mm/s^2, angular velocities in rad/s, angular accelerations in rad/s^2.
Inertia loads follow d'Alembert: a body whose material points accelerate with a(x) carries
the load -M a. Pass the results to ``condense(..., loads=...)`` to get condensed load vectors
that the contact solver scales in time.
"""

from __future__ import annotations

import numpy as np

from reduction.elasticity import ElasticBody
from reduction.errors import InputError


def _mass(body: ElasticBody):
    if body.mass is None:
        raise InputError("body loads need the mass matrix: assemble the body with a density (t/mm^3)")
    return body.mass


def _field(body: ElasticBody, nodal_vectors: np.ndarray) -> np.ndarray:
    """Full DOF vector from per-node vectors (n_nodes, dim)."""
    vector = np.zeros(body.n_dofs)
    vector[body.node_dofs] = nodal_vectors
    return vector


def _vector(value, dim: int, name: str) -> np.ndarray:
    array = np.asarray(value, dtype=float).ravel()
    if array.size != dim:
        raise InputError(f"{name} needs {dim} components, got {array.size}")
    return array


def _rotation_vector(value, dim: int, name: str) -> np.ndarray:
    """Angular quantity as a 3-vector (None: zero); in 2D a scalar about z."""
    if value is None:
        return np.zeros(3)
    array = np.asarray(value, dtype=float).ravel()
    if dim == 2:
        if array.size != 1:
            raise InputError(f"{name} in 2D is one value about z, got {array.size}")
        return np.array([0.0, 0.0, array[0]])
    return _vector(array, 3, name)


def _positions3(body: ElasticBody, origin) -> np.ndarray:
    relative = body.coordinates - _vector(origin, body.dim, "origin")
    return relative if body.dim == 3 else np.column_stack([relative, np.zeros(len(relative))])


def gravity(body: ElasticBody, acceleration) -> np.ndarray:
    """Weight of the body in a uniform gravity field ``acceleration`` (mm/s^2, e.g. [0, 0, -9810])."""
    g = _vector(acceleration, body.dim, "gravity acceleration")
    return _mass(body) @ _field(body, np.tile(g, (len(body.node_dofs), 1)))


def rigid_body_inertia(body: ElasticBody, linear_acceleration, angular_acceleration=None, angular_velocity=None,
                       origin=None) -> np.ndarray:
    """Inertia load -M a(x) of a rigid motion of the body frame.

    a(x) = a0 + alpha x r + omega x (omega x r), r = x - origin (mm, default the coordinate origin).
    The centripetal part is the centrifugal load of a rotating part.
    """
    dim = body.dim
    origin = np.zeros(dim) if origin is None else origin
    a0 = _vector(linear_acceleration, dim, "linear acceleration")
    alpha = _rotation_vector(angular_acceleration, dim, "angular acceleration")
    omega = _rotation_vector(angular_velocity, dim, "angular velocity")
    r = _positions3(body, origin)
    acceleration = np.cross(alpha, r) + np.cross(omega, np.cross(omega, r))
    acceleration = acceleration[:, :dim] + a0
    return -(_mass(body) @ _field(body, acceleration))


def centrifugal(body: ElasticBody, angular_velocity, axis_point=None) -> np.ndarray:
    """Centrifugal load of steady rotation ``angular_velocity`` (rad/s, vector; scalar in 2D) about an
    axis through ``axis_point`` (mm): -M omega x (omega x r), pointing away from the axis."""
    return rigid_body_inertia(body, np.zeros(body.dim), None, angular_velocity, origin=axis_point)


def mode_shape_inertia(body: ElasticBody, modes: np.ndarray) -> np.ndarray:
    """Inertia loads -M phi_k per unit modal acceleration q_k'' (1/s^2), N, shape (n_dofs, n_modes).

    modes: (n_dofs, n_modes) shapes in mm per unit modal coordinate. To condense them name each
    column, e.g. ``loads={f"mode {k}": f[:, k] for k in range(f.shape[1])}``.
    """
    modes = np.asarray(modes, dtype=float)
    if modes.shape[0] != body.n_dofs:
        raise InputError(f"mode shapes have {modes.shape[0]} rows, the body has {body.n_dofs} DOFs")
    return -(_mass(body) @ modes)
