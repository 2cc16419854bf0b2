"""Random and mutated scenes: the loader either accepts the scene or raises one InputError
with a message; nothing else escapes, and the CLI turns it into exit status 2."""

import os
import tomllib
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pipelines import scene as scenes
from pipelines.cli.main import main
from reduction.errors import InputError

# CI replays a fixed set of examples (a landing never depends on a lucky draw); local runs
# keep exploring new ones.
settings.register_profile("ci", derandomize=True)
if os.environ.get("CI"):
    settings.load_profile("ci")

SHIPPED = Path(__file__).resolve().parents[2] / "examples" / "cylinder_on_plane.toml"
BASE = tomllib.loads(SHIPPED.read_text())

values = st.recursive(
    st.none() | st.booleans() | st.integers(-10**6, 10**6) | st.floats(allow_nan=True) | st.text(max_size=8),
    lambda children: st.lists(children, max_size=3) | st.dictionaries(st.text(max_size=6), children, max_size=3),
    max_leaves=6)


def _paths(node, prefix=()):
    if isinstance(node, dict):
        for key, value in node.items():
            yield prefix + (key,)
            yield from _paths(value, prefix + (key,))
    elif isinstance(node, list):
        for index, value in enumerate(node):
            yield prefix + (index,)
            yield from _paths(value, prefix + (index,))


PATHS = list(_paths(BASE))


def _mutated(path, value, delete):
    import copy

    data = copy.deepcopy(BASE)
    node = data
    for key in path[:-1]:
        node = node[key]
    if delete and isinstance(node, dict):
        node.pop(path[-1], None)
    else:
        node[path[-1]] = value
    return data


def _check(data):
    try:
        problems = scenes.validate(data)
    except Exception as error:  # noqa: BLE001 - the property is that nothing escapes
        raise AssertionError(f"validate raised {type(error).__name__}: {error}") from error
    assert isinstance(problems, list) and all(isinstance(p, str) and p for p in problems)
    return problems


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(PATHS), values, st.booleans())
def test_mutated_scene_is_valid_or_reported(path, value, delete):
    _check(_mutated(path, value, delete))


@settings(max_examples=100, deadline=None)
@given(st.dictionaries(st.text(max_size=10), values, max_size=5))
def test_random_scene_is_reported(data):
    assert _check(data)  # a random table is never a valid scene


LINES = SHIPPED.read_text().splitlines()
EDITS = st.sampled_from(["drop", "typo", "value"])


def _edit_text(line_index, edit, token):
    lines = list(LINES)
    line = lines[line_index]
    if edit == "drop":
        del lines[line_index]
    elif edit == "typo" and "=" in line:
        key, rest = line.split("=", 1)
        lines[line_index] = key.rstrip()[:-1] + key.rstrip()[-1:] * 2 + " =" + rest
    elif "=" in line:
        key = line.split("=", 1)[0]
        lines[line_index] = f"{key}= {token}"
    return "\n".join(lines) + "\n"


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.integers(0, len(LINES) - 1), EDITS,
       st.sampled_from(["-1", "0", "1e30", '"text"', "[1, 2]", "nan", "{ a = 1 }", "true", "= =", ""]))
def test_cli_gives_exit_status_2_and_no_output_for_bad_scenes(tmp_path_factory, capsys, line_index, edit, token):
    text = _edit_text(line_index, edit, token)
    try:
        scenes.parse(text)
        return  # still a valid scene (a comment line, a harmless value): not bad input
    except InputError as error:
        assert str(error)
    folder = tmp_path_factory.mktemp("fuzz")
    scene = folder / "bad.toml"
    scene.write_text(text)
    capsys.readouterr()
    assert main(["run", str(scene), "--out", str(folder / "out"), "--quiet"]) == 2
    error = capsys.readouterr().err
    assert error.startswith("fretwork: error:") and "Traceback" not in error
    assert not (folder / "out").exists()
