"""A scene written back resolved (its base chain merged, its files absolute) is the same scene
read from anywhere; a run's results file keeps it, so the run can be made again from it alone."""

import tomllib
from pathlib import Path

import h5py
import pytest
from hypothesis import given, strategies as st

from pipelines import scene as scenes
from pipelines.jobs.run import run_scene
from pipelines.scene.writer import dumps

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

_scalars = (st.booleans() | st.integers(-2**63, 2**63 - 1) | st.floats(allow_nan=False)
            | st.text() | st.dates() | st.times() | st.datetimes())
_values = st.recursive(_scalars, lambda inner: st.lists(inner, max_size=3)
                       | st.dictionaries(st.text(max_size=5), inner, max_size=3), max_leaves=12)


@given(st.dictionaries(st.text(max_size=5), _values, max_size=4))
def test_written_tables_read_back_the_same(tables):
    assert tomllib.loads(dumps(tables)) == tables


@pytest.mark.parametrize("path", sorted(EXAMPLES.glob("*.toml")), ids=lambda path: path.stem)
def test_every_shipped_scene_reads_back_the_same(path):
    tables = scenes.tables(path)
    assert tomllib.loads(dumps(tables)) == tables


def test_a_resolved_scene_is_the_same_scene_from_another_folder(tmp_path):
    """A scene extending user_joint.toml (its meshes relative to the example, one of them set
    relative to the derived scene) written resolved and read from elsewhere: the same tables."""
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "cw.inp").write_text((EXAMPLES / "user_joint" / "cw.inp").read_text())
    derived = tmp_path / "derived.toml"
    derived.write_text(f'[scene]\nbase = "{EXAMPLES / "user_joint.toml"}"\nname = "derived"\n'
                       '[bodies.counterweight.mesh]\nfile = "meshes/cw.inp"\n')
    scene = scenes.load(derived)
    elsewhere = tmp_path / "elsewhere" / "resolved.toml"
    elsewhere.parent.mkdir()
    elsewhere.write_text(scenes.resolved_text(scene))
    again = scenes.load(elsewhere)
    assert "base" not in again.data["scene"]
    assert scenes.resolved(again) == scenes.resolved(scene)
    assert again.data["bodies"]["counterweight"]["mesh"]["file"] == str(tmp_path / "meshes" / "cw.inp")
    assert again.data["bodies"]["web"]["mesh"]["file"] == str(EXAMPLES / "user_joint" / "web.inp")


def test_the_results_file_keeps_the_resolved_scene(coarse_cylinder, tmp_path):
    """``scene_toml`` of results.h5 is the whole scene, not the derived file that names its base."""
    derived = tmp_path / "derived" / "child.toml"
    derived.parent.mkdir()
    derived.write_text('[scene]\nbase = "../coarse.toml"\nname = "child"\n[contact]\ncof_max = 0.7\n')
    scene = scenes.load(derived)
    outcome = run_scene(scene, tmp_path / "out", progress=False, plots=False)
    with h5py.File(outcome.results_path, "r") as file:
        text = file.attrs["scene_toml"]
    stored = tmp_path / "stored.toml"
    stored.write_text(text)
    assert scenes.resolved(scenes.load(stored)) == scenes.resolved(scene)
    assert scenes.load(stored).section("contact")["cof_max"] == 0.7


def test_differences_name_the_changed_keys():
    old = {"contact": {"cof_max": 0.56}, "loads": [{"value": 1.0}], "scene": {"name": "a"}}
    new = {"contact": {"cof_max": 0.7}, "loads": [{"value": 2.0}], "scene": {"name": "a", "base": "b.toml"}}
    assert scenes.differences(old, new) == ["contact.cof_max", "loads.0.value", "scene.base"]
    assert scenes.differences(old, old) == []
