"""Scene files: a valid scene builds; every kind of bad input is named in one clear message."""

import re

import pytest

from pipelines import scene as scenes
from pipelines.build import build
from reduction.errors import InputError


def _problems(text):
    with pytest.raises(InputError) as error:
        scenes.parse(text)
    return str(error.value)


def test_shipped_scene_is_valid(cylinder_text):
    scene = scenes.parse(cylinder_text)
    assert scene.name == "cylinder_on_plane" and scene.effects == {"wear"}


def test_misspelt_key_is_named_with_a_suggestion(cylinder_text):
    message = _problems(cylinder_text.replace("normal_stiffness", "normal_stifness"))
    assert "unknown key 'contact.normal_stifness'" in message
    assert "did you mean 'normal_stiffness'" in message
    assert "missing key 'contact.normal_stiffness'" in message


def test_negative_stiffness_and_bad_poisson_reported_together(cylinder_text):
    text = cylinder_text.replace("normal_stiffness = 4.0e6", "normal_stiffness = -4.0e6").replace(
        "poisson_ratio = 0.3", "poisson_ratio = 0.7")
    message = _problems(text)
    assert "'contact.normal_stiffness' must be > 0" in message
    assert "'materials.ti64.poisson_ratio' must lie between -1 and 0.5" in message
    assert "2 problem(s)" in message


def test_wrong_type_unknown_effect_and_unknown_body(cylinder_text):
    text = (cylinder_text.replace('effects = ["wear"]', 'effects = ["wear", "cof_evolutoin"]')
            .replace('critical_slip = 1.0e-3', 'critical_slip = "1 um"')
            .replace('slave = { body = "cylinder"', 'slave = { body = "cylindre"'))
    message = _problems(text)
    assert "unknown effect 'cof_evolutoin'" in message and "did you mean 'cof_evolution'" in message
    assert "'contact.critical_slip' must be a number" in message
    assert "'contact.slave.body' must name one of the bodies" in message


def test_effect_without_its_parameters_is_refused(cylinder_text):
    message = _problems(cylinder_text.replace('effects = ["wear"]', 'effects = ["wear", "cof_evolution"]'))
    assert "cof_rate" in message


def test_invalid_toml_is_reported_with_position():
    assert "not valid TOML" in _problems("[scene\nname = 1")


def test_surface_selection_outside_the_mesh_names_the_key(coarse_cylinder):
    scene = scenes.load(coarse_cylinder, {"contact.master.box": [[50.0, 50.0], [60.0, 60.0]]})
    with pytest.raises(InputError, match="contact.master.*selects no boundary facets"):
        build(scene)


def test_effect_not_listed_allocates_no_state(coarse_cylinder):
    model = build(scenes.load(coarse_cylinder, {"scene.effects": []}))
    assert model.initial_state().wear_depth is None
    assert model.law.cof_rate == 0.0
    model = build(scenes.load(coarse_cylinder))
    assert model.initial_state().wear_depth.shape == (2, model.assembly.structure.n_points)


def test_body_load_needs_a_density_and_its_parameters(cylinder_text):
    text = cylinder_text + '''
[[body_loads]]
name = "spin"
body = "cylinder"
kind = "centrifugal"
history = "ramp"
'''
    message = _problems(text)
    assert "whose material has no density" in message
    assert "'body_loads[0].angular_velocity' is missing" in message


def test_overrides_address_arrays_of_tables_and_refuse_what_is_not_a_table():
    """Dotted overrides (``--set``, studies): an entry of [[motions]] by position or name; a
    key that runs into a value or past the array is an InputError naming what is there."""
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "examples" / "cylinder_on_plane.toml"
    assert scenes.load(path, {"motions.0.value": 0.1}).data["motions"][0]["value"] == 0.1
    assert scenes.load(path, {"motions.tangential.value": 0.2}).data["motions"][0]["value"] == 0.2
    cases = {"motions.3.value": "position (0 to 0) or a name (tangential), not '3'",
             "motions.0": "an entry of motions is a table",
             "procedure.wear_cycles.x": "procedure.wear_cycles is a value (20)",
             "scene.effects.0": "scene.effects is an array of values"}
    for key, words in cases.items():
        with pytest.raises(InputError, match=re.escape(words)):
            scenes.load(path, {key: 1.0})
