"""A scene that extends a base: a missing base is named by the key that asked for it, and a body's
mesh of another kind (a file instead of a generated block) replaces the base's mesh table."""

from pathlib import Path

import pytest

from pipelines import scene as scenes
from reduction.errors import InputError

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_a_missing_or_folder_base_is_named_by_scene_base(tmp_path):
    child = tmp_path / "child.toml"
    child.write_text('[scene]\nbase = "nowhere.toml"\nname = "child"\n')
    with pytest.raises(InputError, match=r"child.toml: 'scene.base' names .*nowhere.toml, which does not exist"):
        scenes.tables(child)
    (tmp_path / "folder").mkdir()
    child.write_text('[scene]\nbase = "folder"\nname = "child"\n')
    with pytest.raises(InputError, match="'scene.base' names .*folder, which is a folder"):
        scenes.tables(child)


def test_a_mesh_file_in_the_child_replaces_the_base_generator(tmp_path):
    base = scenes.tables(EXAMPLES / "counterweight.toml")
    name, body = next((n, b) for n, b in base["bodies"].items() if "generator" in b["mesh"])
    child = tmp_path / "child.toml"
    child.write_text(f'[scene]\nbase = "{EXAMPLES / "counterweight.toml"}"\nname = "child"\n\n'
                     f'[bodies.{name}]\nmesh = {{ file = "web.inp" }}\n')
    mesh = scenes.tables(child)["bodies"][name]["mesh"]
    assert mesh == {"file": "web.inp"}  # the child's own paths stay as written (relative to it)
    # a table of the same kind still merges key by key
    child.write_text(f'[scene]\nbase = "{EXAMPLES / "counterweight.toml"}"\nname = "child"\n\n'
                     f'[bodies.{name}.mesh]\ncontact_size = 5.0\n')
    merged = scenes.tables(child)["bodies"][name]["mesh"]
    assert merged["contact_size"] == 5.0
    assert {k: v for k, v in merged.items() if k != "contact_size"} == {
        k: v for k, v in body["mesh"].items() if k != "contact_size"}


def test_a_missing_counterweight_mesh_file_is_named_by_the_scene_key(tmp_path):
    from pipelines.coupling import multibody_params

    child = tmp_path / "child.toml"
    child.write_text(f'[scene]\nbase = "{EXAMPLES / "user_joint.toml"}"\nname = "child"\n\n'
                     '[bodies.counterweight]\nmesh = { file = "missing.inp" }\n')
    with pytest.raises(InputError, match=r"'bodies.counterweight.mesh.file': .*missing.inp does not exist"):
        multibody_params(scenes.load(child))
