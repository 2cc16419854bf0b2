"""Stiffness of the bolted counterweight joint for CrankThrowParams.joint_stiffness.

The multibody model joins each CW interface (the floating frame of the reduced CW) to its web
marker; both sides are rigid there (RBE2 interface, rigid web), so the only compliance between
them is the contact layer itself. This module lumps that layer into the 6-DOF spring of
``joint_stiffness`` with the contact law's own stiffnesses, spread uniformly over a flat
rectangular face less its screw holes:

* normal: kn per unit area (the penalty stiffness of the law, N/mm³): k_n = kn·A, and the face
  tilts against kn·∫x² dA (about the axial z axis) and kn·∫z² dA (about the tangential x axis);
* tangential: the law's stick stiffness μ·p/γ_crit per unit area at the clamp pressure
  p = clamp_force / A: k_t = μ·p·A/γ_crit in x and z, and the face twists about its normal
  (y) against (μ·p/γ_crit)·∫(x² + z²) dA.

Valid while the face stays closed and sticks (preload above the separating load, shear below
μ·p). CW frame: x tangential, y normal (radial outward), z axial; origin at the face centre.
Units: mm, N, MPa, N/mm³; stiffnesses N/mm and N mm/rad.
"""

from __future__ import annotations

import numpy as np

from reduction.errors import InputError


def contact_face_stiffness(*, width: float, depth: float, normal_stiffness: float, critical_slip: float,
                           cof: float, clamp_force: float, hole_centers_x: tuple[float, ...] = (),
                           hole_size: float = 0.0) -> tuple[float, ...]:
    """(k_x, k_y, k_z, k_rx, k_ry, k_rz) of a bolted contact face, the layout of joint_stiffness.

    width: face extent along x (tangential), depth: along z (axial), mm; the face is centred on
    the origin. hole_centers_x: x of square screw holes (side hole_size, mm) centred at z = 0.
    normal_stiffness: kn, N/mm³. critical_slip: γ_crit, mm. cof: μ of the sticking face (-).
    clamp_force: total screw preload pressing the face, N.
    """
    half_width, half_hole = 0.5 * width, 0.5 * hole_size
    for name, value in (("width", width), ("depth", depth), ("normal_stiffness", normal_stiffness),
                        ("critical_slip", critical_slip), ("cof", cof), ("clamp_force", clamp_force)):
        if not value > 0:
            raise InputError(f"joint face {name} must be positive, got {value}")
    centers = np.asarray(hole_centers_x, dtype=float)
    if hole_size < 0 or hole_size >= depth or np.any(np.abs(centers) + half_hole > half_width):
        raise InputError(f"joint face screw holes (size {hole_size} mm at x = {list(centers)} mm) must lie "
                         f"inside the {width} × {depth} mm face")
    # Area and second moments of the rectangle less the holes (parallel-axis terms for x).
    hole_area = hole_size ** 2
    area = width * depth - centers.size * hole_area
    moment_x = depth * width ** 3 / 12.0 - np.sum(hole_size ** 4 / 12.0 + hole_area * centers ** 2)  # ∫x² dA
    moment_z = width * depth ** 3 / 12.0 - centers.size * hole_size ** 4 / 12.0  # ∫z² dA
    stick_per_area = cof * (clamp_force / area) / critical_slip
    return (stick_per_area * area, normal_stiffness * area, stick_per_area * area,
            normal_stiffness * moment_z, stick_per_area * (moment_x + moment_z), normal_stiffness * moment_x)



def generic_joint_stiffness() -> tuple[float, ...]:
    """contact_face_stiffness of the generic CW–web joint of examples/counterweight.toml: hub
    face 220 × 80 mm, two hydraulically tensioned M42 screws at x = ±65 mm in 44 mm square
    holes, 2 × 540 kN; law kn 1e6 N/mm³, γ_crit 1 µm, μ0 0.2. Normal 1.37e10 N/mm,
    tangential 2.16e8 N/mm, tilt 8.8e12 (about x) / 5.4e13 (about z) N mm/rad, twist 9.9e11 N mm/rad."""
    return contact_face_stiffness(width=220.0, depth=80.0, normal_stiffness=1.0e6, critical_slip=1.0e-3, cof=0.2,
                                  clamp_force=2.0 * 540.0e3, hole_centers_x=(65.0, -65.0), hole_size=44.0)
