"""Non-matching meshes paired node-to-segment (``contact.pairing = "node_to_segment"``):
points project onto the master facets with interpolation weights. The automatic choice on
these meshes is mortar (tests/contact/test_mortar.py)."""

import numpy as np
import pytest

from pipelines import scene as scenes
from pipelines.build import build
from pipelines.jobs.validate import SCENE, check_hertz


def test_hertz_holds_on_non_matching_meshes():
    # Cylinder at 0.05 mm, plane at 0.043 mm (both finer than a/25): nodes do not match.
    model = build(scenes.load(SCENE, {"bodies.plane.mesh.contact_size": 0.043,
                                      "contact.pairing": "node_to_segment"}))
    pairing = model.assembly.pairing
    weights = pairing.weights
    assert np.allclose(weights.sum(axis=1), 1.0)
    interior = (weights > 1e-6).all(axis=1)
    assert interior.mean() > 0.8  # most points fall between two master nodes
    for record in check_hertz(model):
        assert record["passed"], record


def test_force_balance_on_non_matching_flat_blocks():
    """A block pressed on a block with a 7×7 against a 10×10 face mesh.

    Force and mean pressure are exact. Node-to-segment contact on non-matching meshes does
    not pass the patch test: point pressures scatter (here up to 28 % in the middle); mortar
    pairing, the default on non-matching meshes, does not have this."""
    text = {
        "scene.dimension": 3, "scene.effects": [],
        "bodies.cylinder.mesh": {"generator": "flat_block", "size_x": 10.0, "size_y": 10.0, "height": 4.0,
                                 "n_x": 7, "n_y": 7, "n_z": 3, "z0": 0.0},
        "bodies.plane.mesh": {"generator": "flat_block", "size_x": 10.0, "size_y": 10.0, "height": 4.0,
                              "n_x": 10, "n_y": 10, "n_z": 3, "z0": -4.0},
        "bodies.cylinder.reference_points.rp": {"nodes": {"axis": "z", "value": 4.0}, "position": [0.0, 0.0, 4.0]},
        "bodies.plane.fixed": {"nodes": {"axis": "z", "value": -4.0}, "components": ["ux", "uy", "uz"]},
        "contact.slave": {"body": "cylinder", "axis": "z", "value": 0.0},
        "contact.master": {"body": "plane", "axis": "z", "value": 0.0},
        "contact.pairing": "node_to_segment",
        "loads": [{"name": "press", "dof": "cylinder.rp.uz", "value": -1000.0, "history": "ramp"}],
        "motions": [{"name": "hold", "dof": "cylinder.rp.ux", "value": 0.0, "history": "constant"},
                    {"name": "hold_y", "dof": "cylinder.rp.uy", "value": 0.0, "history": "constant"}],
    }
    model = build(scenes.load(SCENE, text))
    from contact.solver import ContactSolver, Effects
    from contact.structure import ContactSpace

    solver = ContactSolver(ContactSpace(model.assembly.structure), model.law, model.settings)
    equilibrium, state = solver.initial_equilibrium(), model.initial_state()
    for k in range(1, 4):
        equilibrium, state, _, _ = solver.increment(equilibrium, state, model.program.preload(k / 3), Effects())
    normal_force = equilibrium.forces.reshape(-1, 3)[:, 0]
    assert normal_force.sum() == pytest.approx(1000.0, rel=1e-8)
    area = model.assembly.structure.area
    assert area.sum() == pytest.approx(100.0, rel=1e-12)
    pressure = normal_force / area
    assert np.sum(pressure * area) / area.sum() == pytest.approx(10.0, rel=1e-8)
    centre = np.linalg.norm(model.assembly.pairing.slave.coordinates[:, :2], axis=1) < 2.5
    assert np.all(np.abs(pressure[centre] / 10.0 - 1.0) < 0.3)
