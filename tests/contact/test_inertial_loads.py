"""Inertial body loads are condensed with the body: the contact carries their resultant."""

import numpy as np
import pytest

from contact.solver import ContactSolver, Effects
from contact.structure import ContactSpace
from pipelines import scene as scenes
from pipelines.build import build
from pipelines.jobs.validate import SCENE

DENSITY = 4.43e-9  # t/mm³, Ti-6Al-4V
BLOCKS = {
    "scene.dimension": 3, "scene.effects": [], "materials.ti64.density": DENSITY,
    "bodies.cylinder.mesh": {"generator": "flat_block", "size_x": 10.0, "size_y": 8.0, "height": 4.0,
                             "n_x": 5, "n_y": 4, "n_z": 2, "z0": 0.0},
    "bodies.plane.mesh": {"generator": "flat_block", "size_x": 10.0, "size_y": 8.0, "height": 4.0,
                          "n_x": 5, "n_y": 4, "n_z": 2, "z0": -4.0},
    "bodies.cylinder.reference_points.rp": {"nodes": {"axis": "z", "value": 4.0}, "position": [0.0, 0.0, 4.0]},
    "bodies.plane.fixed": {"nodes": {"axis": "z", "value": -4.0}, "components": ["ux", "uy", "uz"]},
    "contact.slave": {"body": "cylinder", "axis": "z", "value": 0.0},
    "contact.master": {"body": "plane", "axis": "z", "value": 0.0},
    "loads": [],
    "motions": [{"name": "hold_x", "dof": "cylinder.rp.ux", "value": 0.0, "history": "constant"},
                {"name": "hold_y", "dof": "cylinder.rp.uy", "value": 0.0, "history": "constant"}],
}


def _normal_force(overrides):
    model = build(scenes.load(SCENE, {**BLOCKS, **overrides}))
    solver = ContactSolver(ContactSpace(model.assembly.structure), model.law, model.settings)
    equilibrium, state = solver.initial_equilibrium(), model.initial_state()
    for k in range(1, 4):
        equilibrium, state, _, _ = solver.increment(equilibrium, state, model.program.preload(k / 3), Effects())
    return equilibrium.forces.reshape(-1, 3)[:, 0].sum()


def test_gravity_presses_the_block_with_its_weight():
    acceleration = 9810.0 * 1e4  # 10,000 g, mm/s², so the load is well above round-off
    force = _normal_force({"body_loads": [{"name": "weight", "body": "cylinder", "kind": "gravity",
                                           "acceleration": [0.0, 0.0, -acceleration], "history": "ramp"}]})
    assert force == pytest.approx(DENSITY * 10 * 8 * 4 * acceleration, rel=1e-8)


def test_centrifugal_load_is_m_omega_squared_r():
    # 750 rpm about an axis along x, 230 mm above the joint face: the block (centroid at
    # z = 2 mm) is flung away from the axis, onto the plane, with m·ω²·(R − 2).
    omega, radius = 2 * np.pi * 750 / 60, 230.0
    force = _normal_force({"body_loads": [{"name": "spin", "body": "cylinder", "kind": "centrifugal",
                                           "angular_velocity": [omega, 0.0, 0.0], "axis_point": [0.0, 0.0, radius],
                                           "history": "ramp"}]})
    mass = DENSITY * 10 * 8 * 4
    assert force == pytest.approx(mass * omega ** 2 * (radius - 2.0), rel=1e-8)
