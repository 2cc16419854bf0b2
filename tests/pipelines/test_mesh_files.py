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


BLOCKS = """
[scene]
name = "blocks"
dimension = 3
effects = []

[materials.steel]
youngs_modulus = 210000.0
poisson_ratio = 0.3

[bodies.cylinder]
material = "steel"
mesh = { file = "upper.inp" }
reference_points.rp = { nodes = { set = "top" }, position = [0.0, 0.0, 4.0] }

[bodies.plane]
material = "steel"
mesh = { file = "meshes/lower.inp" }
fixed = { nodes = { set = "base" }, components = ["ux", "uy", "uz"] }

[contact]
slave = { body = "cylinder", set = "face" }
master = { body = "plane", set = "face" }
normal_stiffness = 1.0e6
critical_slip = 1.0e-3
cof_initial = 0.3
cof_max = 0.3

[[loads]]
name = "press"
dof = "cylinder.rp.uz"
value = -800.0
history = "ramp"

[[motions]]
name = "hold_x"
dof = "cylinder.rp.ux"
value = 0.0
history = "constant"

[[motions]]
name = "hold_y"
dof = "cylinder.rp.uy"
value = 0.0
history = "constant"

[procedure]
cof_cycles = 1
"""


def test_a_base_scene_in_another_folder_finds_its_own_mesh_files(tmp_path):
    """Relative files resolve from the folder of the scene file that names them: the base's mesh
    files from the base's folder, the extending scene's from its own."""
    joint, study = tmp_path / "joint", tmp_path / "studies" / "stiffer"
    (joint / "meshes").mkdir(parents=True)
    study.mkdir(parents=True)
    _block_file(joint / "upper.inp", 0.0, {"face": 0.0, "top": 4.0})
    _block_file(joint / "meshes" / "lower.inp", -4.0, {"face": 0.0, "base": -4.0})
    (joint / "base.toml").write_text(BLOCKS)
    (study / "scene.toml").write_text('[scene]\nbase = "../../joint/base.toml"\nname = "stiffer"\n\n'
                                      '[contact]\nnormal_stiffness = 2.0e6\n')
    scene = scenes.load(study / "scene.toml")
    assert scene.data["contact"]["normal_stiffness"] == 2.0e6 and scene.data["contact"]["cof_max"] == 0.3
    assert scene.data["bodies"]["plane"]["mesh"]["file"] == str(joint / "meshes" / "lower.inp")
    assert build(scene).assembly.pairing.n_points == 30
    # the extending scene's own relative files stay relative to it
    _block_file(study / "lower.inp", -4.0, {"face": 0.0, "base": -4.0})
    (study / "own.toml").write_text('[scene]\nbase = "../../joint/base.toml"\n\n'
                                    '[bodies.plane.mesh]\nfile = "lower.inp"\n')
    assert build(scenes.load(study / "own.toml")).assembly.pairing.n_points == 30
