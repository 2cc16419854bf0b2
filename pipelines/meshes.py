"""Generators for the shipped, documented geometries (structured, graded meshes).

Every generator returns a scikit-fem mesh in mm. Grading puts the contact-zone element size
where the contact is and grows geometrically away from it, so that closed forms (Hertz,
Cattaneo-Mindlin) are resolved without paying for a uniformly fine body.
"""

from __future__ import annotations

import numpy as np
import skfem

from reduction.errors import InputError


def graded_coordinates(fine_half_width: float, fine_size: float, total_half_width: float,
                       growth: float = 1.25) -> np.ndarray:
    """Symmetric 1D coordinates: uniform ``fine_size`` on |x| ≤ fine_half_width, then growing.

    All lengths in mm. The last interval is stretched to end exactly at total_half_width.
    """
    if not 0 < fine_size <= fine_half_width < total_half_width:
        raise InputError("graded mesh needs 0 < fine size <= fine half-width < total half-width")
    n_fine = max(1, int(round(fine_half_width / fine_size)))
    inner = np.linspace(0.0, fine_half_width, n_fine + 1)
    outer, x, h = [], fine_half_width, fine_size
    while x < total_half_width - 1e-12:
        h *= growth
        x = min(x + h, total_half_width)
        if total_half_width - x < 0.5 * h:
            x = total_half_width
        outer.append(x)
    half = np.concatenate([inner, outer])
    return np.concatenate([-half[:0:-1], half])


def one_sided_coordinates(fine_depth: float, fine_size: float, total_depth: float,
                          growth: float = 1.25) -> np.ndarray:
    """Coordinates 0 … total_depth, uniform ``fine_size`` up to fine_depth, then growing (mm)."""
    full = graded_coordinates(fine_depth, fine_size, total_depth, growth)
    return full[full >= 0.0]


def plane_block(half_width: float, depth: float, contact_half_width: float, contact_size: float,
                growth: float = 1.25) -> skfem.MeshQuad:
    """2D rectangle x ∈ [−half_width, half_width], y ∈ [−depth, 0]; contact face at y = 0."""
    x = graded_coordinates(contact_half_width, contact_size, half_width, growth)
    y = -one_sided_coordinates(contact_half_width, contact_size, depth, growth)[::-1]
    return skfem.MeshQuad.init_tensor(x, y)


def cylinder_block(radius: float, half_width: float, height: float, contact_half_width: float,
                   contact_size: float, growth: float = 1.25) -> skfem.MeshQuad:
    """2D lower part of a cylinder of ``radius`` resting on y = 0, cut flat at y = height.

    The bottom follows y = R − √(R² − x²); the top face is where a reference point is coupled.
    """
    if half_width >= radius:
        raise InputError("cylinder block half-width must be smaller than the radius")
    x = graded_coordinates(contact_half_width, contact_size, half_width, growth)
    eta = one_sided_coordinates(contact_half_width, contact_size, height, growth) / height
    mesh = skfem.MeshQuad.init_tensor(x, eta)
    px, pe = mesh.p
    profile = radius - np.sqrt(radius ** 2 - px ** 2)
    return skfem.MeshQuad(np.vstack([px, profile + pe * (height - profile)]), mesh.t)


def flat_block(size_x: float, size_y: float, height: float, n_x: int, n_y: int, n_z: int,
               z0: float = 0.0, z_growth: float = 1.0, top_fine: bool = False) -> skfem.MeshHex:
    """3D box [−sx/2, sx/2]×[−sy/2, sy/2]×[z0, z0+height] of hexahedra, n per direction.

    z_growth > 1 grades the layers away from the face at z0 (or from the top with top_fine).
    """
    x = np.linspace(-0.5 * size_x, 0.5 * size_x, n_x + 1)
    y = np.linspace(-0.5 * size_y, 0.5 * size_y, n_y + 1)
    steps = z_growth ** np.arange(n_z)
    z = np.concatenate([[0.0], np.cumsum(steps)]) / steps.sum() * height
    if top_fine:
        z = height - z[::-1]
    return skfem.MeshHex.init_tensor(x, y, z0 + z)
