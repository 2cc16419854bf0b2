"""Scenes with bodies read from mesh files, their surfaces and supports picked by named sets."""

import meshio
import numpy as np
import pytest
import skfem

from pipelines import scene as scenes
from pipelines.build import build
from pipelines.jobs.validate import SCENE
from reduction.errors import InputError


def _block_file(path, z0, sets):
    mesh = skfem.MeshHex.init_tensor(np.linspace(-5, 5, 6), np.linspace(-4, 4, 5), np.linspace(z0, z0 + 4, 3))
    points = mesh.p.T
    hexes = mesh.t.T[:, [0, 2, 4, 1, 3, 6, 7, 5]]  # scikit-fem order → Abaqus C3D8 order
    named = {name: np.flatnonzero(np.isclose(points[:, 2], z)) for name, z in sets.items()}
    meshio.Mesh(points, [("hexahedron", hexes)], point_sets=named).write(path)


@pytest.fixture
def blocks(tmp_path):
    _block_file(tmp_path / "upper.inp", 0.0, {"face": 0.0, "top": 4.0})
    _block_file(tmp_path / "lower.inp", -4.0, {"face": 0.0, "base": -4.0})
    return {
        "scene.dimension": 3, "scene.effects": [],
        "bodies.cylinder.mesh": {"file": str(tmp_path / "upper.inp")},
        "bodies.plane.mesh": {"file": str(tmp_path / "lower.inp")},
        "bodies.cylinder.reference_points.rp": {"nodes": {"set": "top"}, "position": [0.0, 0.0, 4.0]},
        "bodies.plane.fixed": {"nodes": {"set": "base"}, "components": ["ux", "uy", "uz"]},
        "contact.slave": {"body": "cylinder", "set": "face"},
        "contact.master": {"body": "plane", "set": "face"},
        "loads": [{"name": "press", "dof": "cylinder.rp.uz", "value": -800.0, "history": "ramp"}],
        "motions": [{"name": "hold_x", "dof": "cylinder.rp.ux", "value": 0.0, "history": "constant"},
                    {"name": "hold_y", "dof": "cylinder.rp.uy", "value": 0.0, "history": "constant"}],
    }


def test_named_sets_select_surfaces_and_supports(blocks):
    model = build(scenes.load(SCENE, blocks))
    pairing = model.assembly.pairing
    assert pairing.n_points == 30 and pairing.area.sum() == pytest.approx(80.0)
    assert np.allclose(pairing.initial_overclosure, 0.0)


def test_a_missing_named_surface_is_reported_with_the_available_sets(blocks):
    with pytest.raises(InputError, match="no node set 'contact_face'.*face"):
        build(scenes.load(SCENE, {**blocks, "contact.master": {"body": "plane", "set": "contact_face"}}))


def test_a_set_on_a_generated_mesh_is_reported():
    with pytest.raises(InputError, match="contact.slave.set.*generated"):
        build(scenes.load(SCENE, {"contact.slave": {"body": "cylinder", "set": "face"}}))
