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

from pathlib import Path

import numpy as np
import tomllib

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


def scene_joint_stiffness(scene_toml: Path, body: str = "counterweight") -> tuple[float, ...]:
    """contact_face_stiffness of the CW joint a contact scene describes (e.g. the shipped
    examples/counterweight.toml): face = the hub face of ``body``'s counterweight_block mesh
    (hub_width × thickness, square holes of side 2·hole_half_size at x = ±screw_x), law from
    [contact] (normal_stiffness, critical_slip, cof_initial), clamp force = sum of the [bolts]
    pretensions."""
    with open(scene_toml, "rb") as handle:
        scene = tomllib.load(handle)
    try:
        mesh = scene["bodies"][body]["mesh"]
        contact = scene["contact"]
        clamp_force = sum(float(bolt["pretension"]) for bolt in scene["bolts"].values())
        return contact_face_stiffness(
            width=float(mesh["hub_width"]), depth=float(mesh["thickness"]),
            normal_stiffness=float(contact["normal_stiffness"]), critical_slip=float(contact["critical_slip"]),
            cof=float(contact["cof_initial"]), clamp_force=clamp_force,
            hole_centers_x=(float(mesh["screw_x"]), -float(mesh["screw_x"])),
            hole_size=2.0 * float(mesh["hole_half_size"]))
    except KeyError as missing:
        raise InputError(f"scene {scene_toml} lacks {missing} needed for the CW joint stiffness "
                         f"(bodies.{body}.mesh hub_width/thickness/screw_x/hole_half_size, contact "
                         f"normal_stiffness/critical_slip/cof_initial, bolts.*.pretension)") from None
