"""A group of bodies (joined by the contact or bolts, the contact taken as tied) must be held in
every rigid-body direction by its fixed DOFs and prescribed motions; one held in some directions
only is refused when the model is built, naming the motions left free, instead of ending later
in "Newton did not converge". Build only: each scene stops before its bodies are condensed."""

import re
from pathlib import Path

import pytest

import pipelines.build
from pipelines import scene as scenes
from pipelines.build import build
from pipelines.cli.main import main
from reduction.errors import InputError

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
BOLTED_BLOCKS = Path(__file__).parent / "scenes" / "bolted_blocks.toml"

# Two flat blocks pressed together by a reference point on the upper one's top face (coupled with
# rotations: the face may turn) that carries a normal and a tangential load, no motion. The lower
# block's control point on its side (nothing acts on it) makes each body's condensed stiffness
# regular on its own, so that only the group as a whole is left free: without the check, the run
# got as far as the contact solver and stopped in its preload ("no point of the interface stays
# pressed", with the load pressing).
FLAT_ON_FLAT = """
[scene]
name = "flat_on_flat"
dimension = 3
effects = ["cof_evolution"]

[materials.steel]
youngs_modulus = 210000.0
poisson_ratio = 0.3

[bodies.upper]
material = "steel"
mesh = {{ generator = "flat_block", size_x = 20.0, size_y = 20.0, height = 5.0, n_x = 3, n_y = 3, n_z = 1 }}
reference_points.rp = {{ nodes = {{ axis = "z", value = 5.0 }}, position = [0.0, 0.0, 5.0], rotations = true }}

[bodies.lower]
material = "steel"
mesh = {{ generator = "flat_block", size_x = 20.0, size_y = 20.0, height = 5.0, n_x = 3, n_y = 3, n_z = 2, z0 = -5.0 }}
fixed = {{ nodes = {fixed_nodes}, components = {components} }}

[bodies.lower.reference_points.side]
nodes = {{ box = [[9.9, -11.0, -2.6], [11.0, 11.0, -2.4]] }}
position = [10.0, 0.0, -2.5]
rotations = true

[contact]
slave = {{ body = "upper", axis = "z", value = 0.0 }}
master = {{ body = "lower", axis = "z", value = 0.0 }}
normal_stiffness = 1.0e6
critical_slip = 1.0e-3
cof_initial = 0.2
cof_max = 0.6
cof_rate = 0.5

[[loads]]
name = "press"
dof = "upper.rp.uz"
value = -1000.0
history = "ramp"

[[loads]]
name = "shear"
dof = "upper.rp.ux"
value = 50.0
history = "cyclic"
{motions}
[procedure]
preload_increments = 2
increments_per_cycle = 8
cof_cycles = 1
"""
BOTTOM = '{ axis = "z", value = -5.0 }'


class Built(Exception):
    """Raised in place of the condensation: the scene passed every check of the build."""


@pytest.fixture
def build_only(monkeypatch):
    """build(scene) that stops where the bodies would be condensed (or the multibody stage of a
    coupled scene would run): returns True when the scene got that far."""
    def stop(*args, **kwargs):
        raise Built

    monkeypatch.setattr(pipelines.build, "assemble", stop)
    monkeypatch.setattr(pipelines.build, "multibody_loading", stop)

    def reaches_condensation(scene) -> bool:
        with pytest.raises(Built):
            build(scene)
        return True
    return reaches_condensation


def _flat_on_flat(fixed_nodes=BOTTOM, components='["ux", "uy", "uz"]', motions=""):
    return scenes.parse(FLAT_ON_FLAT.format(fixed_nodes=fixed_nodes, components=components, motions=motions))


def _free_motions(error: InputError) -> str:
    """The words between "leave free" and ", so" of a support refusal."""
    return str(error).split("leave free ", 1)[1].split(", so ", 1)[0]


def test_a_3d_joint_held_only_along_z_names_the_translations_in_plane_and_the_rotation_about_z(build_only):
    assert build_only(_flat_on_flat())
    with pytest.raises(InputError) as refusal:
        build(_flat_on_flat(components='["uz"]'))
    message = str(refusal.value)
    assert message.startswith("bodies 'upper' and 'lower' (joined by the contact or bolts")
    assert _free_motions(refusal.value) == "translation along x, translation along y and rotation about z"
    assert 'add "ux", "uy" to the components of bodies.lower.fixed' in message
    assert "a [[loads]] entry holds nothing" in message


def test_a_3d_joint_held_along_z_on_a_side_face_also_turns_about_that_face(build_only):
    """uz held on the face x = −10 leaves the group free to turn about the face's y-parallel
    edge line: not a mode of the centred frame but a combination, named by its axis."""
    with pytest.raises(InputError) as refusal:
        build(_flat_on_flat(fixed_nodes='{ axis = "x", value = -10.0 }', components='["uz"]'))
    assert _free_motions(refusal.value) == ("translation along x, translation along y, rotation about z and "
                                            "rotation about an axis parallel to y through (-10, 0, 0) mm")


def test_prescribed_motions_of_a_reference_point_coupled_with_rotations_hold_the_group(build_only):
    """Loads hold nothing; motions of the reference point do, its rotation included."""
    hold = "".join(f'\n[[motions]]\nname = "hold_{c}"\ndof = "upper.rp.{c}"\nvalue = 0.0\nhistory = "constant"\n'
                   for c in ("uy", "rz"))
    scene = _flat_on_flat(components='["uz"]', motions=hold)
    scene.data["loads"] = scene.data["loads"][:1]
    scene.data["motions"].append({"name": "shear", "dof": "upper.rp.ux", "value": 1e-3, "history": "cyclic"})
    assert build_only(scene)
    scene.data["motions"] = scene.data["motions"][:1] + scene.data["motions"][2:]  # rz no longer held
    with pytest.raises(InputError) as refusal:
        build(scene)
    assert _free_motions(refusal.value) == "rotation about z"


def test_a_bolted_joint_held_only_along_z_is_refused_though_each_body_is_regular_on_its_own(build_only):
    """The bolted blocks with the lower one held along z on a strip of its bottom, the reference
    points coupled with rotations and the tip loaded, not driven: without the check the run
    ended in "Newton did not converge". With the shipped rotation-free couplings the faces they
    hold cannot turn, and the tip's prescribed ux and uy hold the rest: held."""
    text = BOLTED_BLOCKS.read_text().replace(
        'fixed = { nodes = { axis = "x", value = -10.0 }, components = ["ux", "uy", "uz"] }',
        'fixed = { nodes = { box = [[-10.01, -10.01, -5.01], [10.01, -7.0, -4.99]] }, components = ["uz"] }')
    assert build_only(scenes.parse(text))
    text = re.sub(r"(position = \[[^]]*\]) }", r"\1, rotations = true }", text)  # every reference point turns
    driven = text[text.index("[[motions]]"):text.index("[[body_loads]]")]
    loaded = '[[loads]]\nname = "tip"\ndof = "upper.tip.ux"\nvalue = 200.0\nhistory = "cyclic"\n\n'
    text = text.replace(driven, loaded)
    with pytest.raises(InputError) as refusal:
        build(scenes.parse(text))
    assert str(refusal.value).startswith("bodies 'upper' and 'lower' (joined by the contact or bolts")
    assert _free_motions(refusal.value) == "translation along x, translation along y and rotation about z"


def _cylinder(cylinder_text: str, plane_components: str | None, tangential: str, normal: str = "load",
              rotations: bool = False):
    """The shipped cylinder on plane, coarse; the plane fixed in ``plane_components`` (None: not
    fixed); the tangential drive on rp.ux and the normal one on rp.uy each a "motion" or a "load"
    (tangential 100 N, normal −0.01 mm when they are not the shipped kind)."""
    text = cylinder_text.replace("contact_size = 0.05", "contact_size = 0.4")
    fixed = 'fixed = { nodes = { axis = "y", value = -20.0 }, components = ["ux", "uy"] }\n'
    text = text.replace(fixed, "" if plane_components is None else fixed.replace('["ux", "uy"]', plane_components))
    if tangential == "load":
        text = (text.replace('[[motions]]\nname = "tangential"', '[[loads]]\nname = "tangential"')
                .replace("value = 0.107 ", "value = 100.0 "))
    if normal == "motion":
        text = (text.replace('[[loads]]\nname = "normal"', '[[motions]]\nname = "normal"')
                .replace("value = -1066.0 ", "value = -0.01 "))
    if rotations:
        text = text.replace("position = [0.0, 20.0] }", "position = [0.0, 20.0], rotations = true }")
    return scenes.parse(text)


def test_a_plane_strain_base_held_only_in_uy_is_refused_naming_the_translation_along_x(cylinder_text, build_only):
    with pytest.raises(InputError) as refusal:
        build(_cylinder(cylinder_text, '["uy"]', "load"))
    assert _free_motions(refusal.value) == "translation along x"  # the rotation is held: uy over the base
    assert 'add "ux" to the components of bodies.plane.fixed' in str(refusal.value)
    # the same base with the tangential drive a motion: the contact ties the plane to the driven cylinder
    assert build_only(_cylinder(cylinder_text, '["uy"]', "motion"))


def test_a_group_held_only_through_a_reference_point_is_held_when_its_coupling_cannot_turn(cylinder_text,
                                                                                           build_only):
    """No fixed selection; rp.ux and rp.uy prescribed. Coupled without rotations, the cylinder's
    top face cannot turn: held. Coupled with rotations, it turns about the reference point."""
    def driven(rotations):
        return _cylinder(cylinder_text, None, "motion", "motion", rotations)

    assert build_only(driven(rotations=False))
    with pytest.raises(InputError) as refusal:
        build(driven(rotations=True))
    assert _free_motions(refusal.value) == "rotation about z around the point (0, 20) mm"
    assert '"rz" of a reference point' in str(refusal.value)


def test_the_command_line_refuses_a_partly_held_scene_with_exit_2_and_no_output(tmp_path, capsys):
    scene = tmp_path / "partly_held.toml"
    scene.write_text(FLAT_ON_FLAT.format(fixed_nodes=BOTTOM, components='["uz"]', motions=""))
    out = tmp_path / "out"
    assert main(["run", str(scene), "--out", str(out), "--quiet"]) == 2
    captured = capsys.readouterr()
    assert not out.exists() and "Traceback" not in captured.err
    assert "leave free translation along x, translation along y and rotation about z" in captured.err


@pytest.mark.parametrize("path", sorted(EXAMPLES.glob("*.toml")) + [BOLTED_BLOCKS], ids=lambda path: path.stem)
def test_every_shipped_scene_is_held(path, build_only):
    assert build_only(scenes.load(path))
