"""A bolt judged against the built mesh (QA, 2026-11-28, items 5, 6 and 9): its axis against the
joint's normal where it clamps, its ends' reference points against the nodes they couple, and
node sets named by the key that asks for them.

The tilted bolt pulls the joint sideways with sin θ of its pretension: 5° is warned of (8.7 % of
the pretension, tan 5° = 44 % of μ = 0.2), 50° refused (tan θ > 1 > μ: it clamps nothing). A
position 2 mm across the axis from the centre of a ring of radius 3.85 mm changes the bearing
pressure by about ±2·2/3.85 ≈ ±100 %: warned; 15 mm away from a ring all within 4.7 mm of its
centre: refused.
"""

import math
import warnings
from pathlib import Path

import pytest

from pipelines import scene as scenes
from pipelines.build import build
from pipelines.cli.main import main
from pipelines.scene.checks import SceneWarning
from reduction.errors import InputError

ROOT = Path(__file__).resolve().parents[2]
BLOCKS = ROOT / "tests" / "pipelines" / "scenes" / "bolted_blocks.toml"
USER_JOINT = ROOT / "examples" / "user_joint.toml"
HEAD = "bodies.upper.reference_points.head"
NUT = "bodies.lower.reference_points.nut"


def _tilted(degrees: float) -> dict:
    """bolted_blocks' bolt tilted about y from its head at [0, 0, 5]; the nut's position on the
    tilted axis at the lower block's bottom (z = -5), so that axis and positions agree."""
    theta = math.radians(degrees)
    axis = [math.sin(theta), 0.0, -math.cos(theta)]
    return {"bolts.m8.axis": axis, f"{NUT}.position": [10.0 * math.tan(theta), 0.0, -5.0]}


def _scene_warnings(scene) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        build(scene)
    return [str(w.message) for w in caught if issubclass(w.category, SceneWarning)]


def test_a_bolt_square_to_its_joint_and_centred_on_its_rings_builds_without_a_warning():
    for path in (BLOCKS, ROOT / "examples" / "double_beam_high_slip.toml"):
        assert _scene_warnings(scenes.load(path)) == []


def test_a_bolt_tilted_5_degrees_from_the_joint_normal_is_warned_of_with_its_shear():
    said = _scene_warnings(scenes.load(BLOCKS, _tilted(5.0)))
    assert len(said) == 1
    assert said[0].startswith("'bolts.m8.axis' is 5° off the joint's normal (mean over the 36 contact facets "
                              "within ")
    assert "sin θ = 8.7% of its pretension" in said[0]
    assert "tan θ = 0.0875, 44% of 'contact.cof_initial' = 0.2" in said[0]


def test_a_bolt_tilted_more_than_its_friction_carries_says_so():
    said = _scene_warnings(scenes.load(BLOCKS, {**_tilted(14.0), "contact.cof_initial": 0.2}))
    assert any("tan θ = 0.249, above 'contact.cof_initial' = 0.2: friction alone cannot hold it" in s for s in said)


def test_a_bolt_nearer_the_joint_plane_than_its_normal_is_refused_in_one_line(tmp_path, capsys):
    scene = tmp_path / "tilted.toml"
    tilt = _tilted(50.0)
    axis = ", ".join(repr(a) for a in tilt["bolts.m8.axis"])
    nut = ", ".join(repr(a) for a in tilt[f"{NUT}.position"])
    scene.write_text(f'[scene]\nbase = "{BLOCKS}"\nname = "tilted"\n[bolts.m8]\naxis = [{axis}]\n'
                     f'[bodies.lower]\nreference_points.nut = {{ nodes = {{ box = [[-6.0, -6.0, -5.01], '
                     f'[6.0, 6.0, -4.99]] }}, position = [{nut}] }}\n')
    assert main(["run", str(scene), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and error.startswith("fretwork: error: 'bolts.m8.axis' is 50° off the joint's "
                                                       "normal")
    assert "40° from its plane: a bolt that far from the normal clamps nothing" in error


def test_a_bolt_along_the_joint_is_refused_before_anything_runs():
    with pytest.raises(InputError, match=r"'bolts\.m8\.axis' is 90° off the joint's normal"):
        build(scenes.load(BLOCKS, {"bolts.m8.axis": [1.0, 0.0, 0.0], f"{HEAD}.position": [-5.0, 0.0, 0.0],
                                   f"{NUT}.position": [5.0, 0.0, 0.0]}))


def test_a_reference_point_off_the_centre_of_its_ring_is_warned_of_naming_both_positions():
    moved = {f"{HEAD}.position": [2.0, 0.0, 5.0], f"{NUT}.position": [2.0, 0.0, -5.0]}
    said = _scene_warnings(scenes.load(BLOCKS, moved))
    head = [s for s in said if s.startswith(f"'{HEAD}.position'")]
    assert len(head) == 1 and len(said) == 2
    assert head[0].startswith(f"'{HEAD}.position' [2.0, 0.0, 5.0] is 2 mm from the centre [0.0, 0.0, 5.0] of the "
                              f"nodes it couples ('{HEAD}.nodes', a ring of radius 3.85 mm), 2 mm across the "
                              "bolt's axis")
    assert "±104%" in head[0]


def test_a_reference_point_far_beyond_its_ring_is_refused():
    moved = {f"{HEAD}.position": [15.0, 0.0, 5.0], f"{NUT}.position": [15.0, 0.0, -5.0]}
    with pytest.raises(InputError) as refused:
        build(scenes.load(BLOCKS, moved))
    message = str(refused.value)
    assert (f"'{HEAD}.position' [15.0, 0.0, 5.0] is 15 mm from the centre [0.0, 0.0, 5.0] of the nodes it couples "
            f"('{HEAD}.nodes', a ring of radius 3.85 mm, all within 4.71 mm of its centre): the position or the "
            "node set belongs to another bolt end") in message
    assert f"'{NUT}.position' [15.0, 0.0, -5.0] is 15 mm" in message


@pytest.fixture
def no_multibody_run(monkeypatch):
    import pipelines.coupling

    def no_run(*args):
        raise AssertionError("the multibody run started")

    monkeypatch.setattr(pipelines.coupling, "counterweight_loading", no_run)


def test_screw_ends_placed_at_the_other_screw_are_refused_before_the_multibody_run(no_multibody_run):
    """QA F_uj_wrongpos: head_1 and thread_1 positions at screw 2, 120 mm from their sets."""
    with pytest.raises(InputError) as refused:
        build(scenes.load(USER_JOINT, {"bodies.counterweight.reference_points.head_1.position": [-60.0, 160.0, 0.0],
                                       "bodies.web.reference_points.thread_1.position": [-60.0, -35.0, 0.0]}))
    assert ("'bodies.counterweight.reference_points.head_1.position' [-60.0, 160.0, 0.0] is 120 mm from the "
            "centre [60.0, 160.0, 0.0]") in str(refused.value)


def test_a_missing_node_set_names_the_reference_point_key_and_the_set(no_multibody_run):
    with pytest.raises(InputError) as refused:
        build(scenes.load(USER_JOINT, {"bodies.counterweight.reference_points.head_1.nodes": {"set": "HEAD_9"}}))
    message = str(refused.value)
    assert message.startswith("'bodies.counterweight.reference_points.head_1.nodes.set': no node set 'HEAD_9' in "
                              "the mesh file ('bodies.counterweight.mesh.file': ")
    assert message.endswith("cw.inp); its node sets: CONTACT, HEAD_1, HEAD_2")


def test_a_node_set_named_in_another_case_is_suggested(no_multibody_run):
    with pytest.raises(InputError, match=r"no node set 'head_1' in .*: did you mean 'HEAD_1'\? \(set names are "
                                         r"case-sensitive\)"):
        build(scenes.load(USER_JOINT, {"bodies.counterweight.reference_points.head_1.nodes": {"set": "head_1"}}))


def test_two_reference_points_on_one_node_set_name_both_keys(no_multibody_run):
    """QA F_uj_headswap: head_1 given HEAD_2, the set of head_2."""
    with pytest.raises(InputError) as refused:
        build(scenes.load(USER_JOINT, {"bodies.counterweight.reference_points.head_1.nodes": {"set": "HEAD_2"}}))
    assert str(refused.value) == (
        "'bodies.counterweight.reference_points.head_1.nodes' and 'bodies.counterweight.reference_points.head_2.nodes' "
        "both name node set 'HEAD_2': a node follows one reference point only; give each reference point its own "
        "nodes")


def test_two_reference_points_on_overlapping_boxes_name_both_keys_and_the_count():
    with pytest.raises(InputError) as refused:
        build(scenes.load(BLOCKS, {"bodies.upper.reference_points.tip.nodes": {"box": [[-6.0, -6.0, 4.99],
                                                                                         [10.01, 10.01, 5.01]]}}))
    message = str(refused.value)
    assert message.startswith(f"'{HEAD}.nodes' and 'bodies.upper.reference_points.tip.nodes' select ")
    assert message.endswith(" of the same nodes: a node follows one reference point only; give each reference "
                            "point its own nodes")
