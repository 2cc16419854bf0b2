"""Scenes refused in words before anything runs: a mesh file written in metres, a bolt whose axis,
length or ends do not make a bolt, and a ``base`` written above [scene]."""

import re
from pathlib import Path

import pytest

from pipelines import scene as scenes
from pipelines.build import build
from pipelines.cli.main import main
from pipelines.jobs.validate import SCENE
from reduction.errors import InputError

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
USER_JOINT = EXAMPLES / "user_joint.toml"


def _problems(path, overrides=None) -> str:
    with pytest.raises(InputError) as refused:
        scenes.load(path, overrides)
    return str(refused.value)


def _in_metres(source: Path, target: Path) -> Path:
    """``source`` (an Abaqus file in mm) with its node coordinates in metres."""
    lines, in_nodes = [], False
    for line in source.read_text().splitlines():
        if line.startswith("*"):
            in_nodes = line.upper().startswith("*NODE") and not line.upper().startswith("*NODE ")
        elif in_nodes and line.strip():
            number, *coordinates = line.split(",")
            line = ", ".join([number] + [repr(1e-3 * float(c)) for c in coordinates])
        lines.append(line)
    target.write_text("\n".join(lines) + "\n")
    return target


def test_a_counterweight_mesh_in_metres_is_refused_before_the_multibody_run(tmp_path, capsys, monkeypatch):
    """The user CW in metres made exudyn's time integration fail (a body 10⁹ times too light)."""
    import pipelines.coupling

    def no_run(*args):
        raise AssertionError("the multibody run started")

    monkeypatch.setattr(pipelines.coupling, "counterweight_loading", no_run)
    cw = _in_metres(EXAMPLES / "user_joint" / "cw.inp", tmp_path / "cw_m.inp")
    scene = tmp_path / "scene.toml"
    scene.write_text(f'[scene]\nbase = "{USER_JOINT}"\n[bodies.counterweight]\nmesh = {{ file = "{cw}" }}\n')
    out = tmp_path / "out"
    assert main(["run", str(scene), "--out", str(out), "--quiet"]) == 2
    error = capsys.readouterr().err
    assert "Traceback" not in error and "internal error" not in error
    assert f"'bodies.counterweight.mesh.file': {cw}: the mesh is 0.56 mm across" in error
    assert re.search(r"'bodies\.counterweight\.reference_points\.head_\d\.position' lies 1\d\d mm from it", error)
    assert "probably in metres" in error and "560 mm" in error


def test_a_mesh_file_in_metres_is_refused_at_build_naming_file_size_and_key(tmp_path):
    """Two punch meshes in metres met nothing of each other: 'check the contact selections' misled."""
    from tests.pipelines.test_mesh_files import _block_file

    _block_file(tmp_path / "upper.inp", 0.0, {"face": 0.0, "top": 4.0})
    _block_file(tmp_path / "lower.inp", -4.0, {"face": 0.0, "base": -4.0})
    upper = _in_metres(tmp_path / "upper.inp", tmp_path / "upper_m.inp")
    overrides = {
        "scene.dimension": 3, "scene.effects": [],
        "bodies.cylinder.mesh": {"file": str(upper)},
        "bodies.plane.mesh": {"file": str(tmp_path / "lower.inp")},
        "bodies.cylinder.reference_points.rp": {"nodes": {"set": "top"}, "position": [0.0, 0.0, 24.0]},
        "bodies.plane.fixed": {"nodes": {"set": "base"}, "components": ["ux", "uy", "uz"]},
        "contact.slave": {"body": "cylinder", "set": "face"},
        "contact.master": {"body": "plane", "set": "face"},
        "loads": [{"name": "press", "dof": "cylinder.rp.uz", "value": -800.0, "history": "ramp"}],
        "motions": [],
    }
    with pytest.raises(InputError) as refused:
        build(scenes.load(SCENE, overrides))
    message = str(refused.value)
    assert message.startswith(f"'bodies.cylinder.mesh.file': {upper}: the mesh is 0.01 mm across "
                              "(0.01 × 0.008 × 0.004 mm)")
    assert "'bodies.cylinder.reference_points.rp.position' lies 24 mm from it" in message
    assert "probably in metres" in message and "10 mm" in message


def test_a_small_mesh_near_its_scene_lengths_is_not_a_unit_mistake():
    from pipelines.scene.checks import mesh_unit_problem

    data = {"bodies": {"pin": {"reference_points": {"rp": {"position": [0.0, 0.0, 0.5]}}}}}
    assert mesh_unit_problem(data, "pin", [-0.3, -0.3, 0.0], [0.3, 0.3, 0.4], "pin.inp") is None
    data["bodies"]["pin"]["reference_points"]["rp"]["position"] = [0.0, 0.0, 30.0]
    assert "29.6 mm" in mesh_unit_problem(data, "pin", [-0.3, -0.3, 0.0], [0.3, 0.3, 0.4], "pin.inp")
    assert mesh_unit_problem(data, "pin", [-3.0, -3.0, 0.0], [3.0, 3.0, 4.0], "pin.inp") is None


def test_a_tiny_mesh_loaded_like_a_joint_is_a_unit_mistake_wherever_its_points_are():
    """A 2D pad in metres (20 x 10 mm written as 0.02 x 0.01) with its reference point on its own
    top face ran to 'stick' at 10 GPa (QA, 2026-11-28): the load over the section says metres."""
    from pipelines.scene.checks import mesh_unit_problem

    data = {"scene": {"dimension": 2}, "materials": {"steel": {"youngs_modulus": 210000.0}},
            "bodies": {"pad": {"material": "steel", "reference_points": {"rp": {"position": [0.0, 0.01]}}}},
            "loads": [{"name": "press", "dof": "pad.rp.uy", "value": -200.0}]}
    message = mesh_unit_problem(data, "pad", [-0.01, 0.0], [0.01, 0.01], "pad.inp")
    assert message == ("pad.inp: the mesh is 0.02 mm across (0.02 × 0.01 mm), but 'loads[0].value' (200 N per mm) "
                       "on it is 1e+04 MPa over its largest section, 4.8 % of its Young's modulus: the mesh is "
                       "probably in metres (fretwork reads mm, so 0.02 m would be 20 mm); export it in mm or scale "
                       "its coordinates by 1000")
    data["loads"][0]["value"] = -20.0  # 1,000 MPa: 0.48 % strain, a small but possible body
    assert mesh_unit_problem(data, "pad", [-0.01, 0.0], [0.01, 0.01], "pad.inp") is None
    # in 3D a bolt's pretension counts as well: 20 kN over 0.04 x 0.01 mm
    data = {"materials": {"steel": {"youngs_modulus": 210000.0}}, "bodies": {"plate": {"material": "steel"}},
            "bolts": {"m10": {"head": "plate.head", "nut": "base.nut", "pretension": 20000.0}}}
    assert "'bolts.m10.pretension' (20000 N)" in mesh_unit_problem(data, "plate", [0, 0, 0], [0.04, 0.01, 0.005],
                                                                  "plate.inp")


@pytest.mark.parametrize("overrides, expected", [
    ({"bolts.screw_1.axis": [0.0, 1.0, 0.0]},
     "'bolts.screw_1.axis' = [0.0, 1.0, 0.0] points from the nut to the head: the reference points' positions "
     "('counterweight.head_1' at [60.0, 160.0, 0.0], 'web.thread_1' at [60.0, -35.0, 0.0] mm) give the direction "
     "[0.0, -1.0, 0.0]; the axis must point from the head to the nut"),
    ({"bolts.screw_2.axis": [1.0, 0.0, 0.0]}, "'bolts.screw_2.axis' = [1.0, 0.0, 0.0] is 90° off the line from "
                                             "head to nut"),
    ({"bolts.screw_1.axis": [0.0, -0.9998, 0.02]}, "'bolts.screw_1.axis' = [0.0, -0.9998, 0.02] is 1.15° off"),
    ({"bolts.screw_1.axis": [0.0, -0.999, 0.0]}, "'bolts.screw_1.axis' = [0.0, -0.999, 0.0] has length 0.999:"),
    ({"bolts.screw_1.axis": [0.0, -2.0, 0.0]},
     "'bolts.screw_1.axis' = [0.0, -2.0, 0.0] has length 2: it must be a unit vector (from head to nut), "
     "e.g. [0.0, -1.0, 0.0]"),
    ({"bolts.screw_1.nut": "counterweight.head_2"},
     "'bolts.screw_1.head' ('counterweight.head_1') and 'bolts.screw_1.nut' ('counterweight.head_2') are on the "
     "same body 'counterweight'"),
])
def test_a_bolt_that_does_not_clamp_its_joint_is_refused(overrides, expected):
    assert expected in _problems(USER_JOINT, overrides)


def test_a_bolt_axis_within_a_degree_of_its_ends_is_accepted():
    """0.5° off the head-to-nut line, a unit vector: the positions are rounded, the axis is not wrong."""
    import math

    tilt = math.radians(0.5)
    scenes.load(USER_JOINT, {"bolts.screw_1.axis": [math.sin(tilt), -math.cos(tilt), 0.0]})


@pytest.mark.parametrize("name", ["counterweight.toml", "user_joint.toml", "double_beam_low_slip.toml",
                                  "double_beam_high_slip.toml"])
def test_the_shipped_bolted_scenes_are_valid(name):
    assert scenes.load(EXAMPLES / name).data["bolts"]


def test_a_base_above_the_scene_table_is_said_once(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text(f'base = "{USER_JOINT}"\n\n[scene]\nname = "extended"\n\n[procedure]\ncof_cycles = 2\n')
    message = _problems(path)
    assert message == (f"{path}: 'base = \"{USER_JOINT}\"' stands above the first table, so it is no key of "
                       "[scene] and no base is read: move it to a line below [scene]; the scene's other problems "
                       "are listed once its base is read")
    path.write_text(f'[scene]\nbase = "{USER_JOINT}"\nname = "extended"\n\n[procedure]\ncof_cycles = 2\n')
    assert scenes.load(path).data["procedure"]["cof_cycles"] == 2
