"""Every refusal of an [mbs] value names its key as the scene writes it ('[mbs] n_modes',
'[mbs.solver] time_step'), the value and what is allowed (QA: 'n_modes = 0' was refused in words
that did not read as its key)."""

import pytest

from mbs.parameters import ModelParams
from mbs.refusal import Refusal
from mbs.scene import load_model_params, mbs_table_problems
from reduction.errors import InputError

REFUSALS = [
    ("[mbs]\nn_modes = 0\n", "[mbs] n_modes = 0: must be a whole number of at least 1"),
    ("[mbs]\nn_modes = 2.5\n", "[mbs] n_modes = 2.5: must be a whole number"),
    ("[mbs]\nspeed_rpm = -750.0\n", "[mbs] speed_rpm = -750.0: must be positive (engine speed, rpm)"),
    ("[mbs]\nspeed_rpm = \"750\"\n", '[mbs] speed_rpm = "750": must be a number'),
    ("[mbs]\nmodal_damping_ratio = -0.1\n", "[mbs] modal_damping_ratio = -0.1: must not be negative"),
    ("[mbs]\nthrows = 0\n", "[mbs] throws = 0: must be a whole number of at least 1"),
    ("[mbs]\nthrows = 2\ncrank_angles_deg = [0.0]\n",
     "[mbs] crank_angles_deg = [0.0] and [mbs] throws = 2: crank_angles_deg must give one angle per throw"),
    ("[mbs]\neffects = [\"gas\"]\n", '[mbs] effects = ["gas"]: may name only flexible_crankshaft, gas_torque'),
    ("[mbs.solver]\ntime_step = 0.0\n", "[mbs.solver] time_step = 0.0: must be positive (s)"),
    ("[mbs.solver]\nrevolutions = -1.0\n", "[mbs.solver] revolutions = -1.0: must be positive"),
    ("[mbs.solver]\nspectral_radius = 1.5\n", "[mbs.solver] spectral_radius = 1.5: must lie in [0, 1]"),
    ("[mbs.solver]\ndrive = \"fast\"\n", '[mbs.solver] drive = "fast": must be "constant_speed" or "free"'),
    ("[mbs.excitation]\ngear_teeth = 0\n", "[mbs.excitation] gear_teeth = 0: must be a whole number of at least 1"),
    ("[mbs.excitation]\ngas_orders = [1.0, -2.0]\ngas_torque_amplitudes = [1.0, 2.0]\ngas_torque_phases = [0.0, 0.0]\n",
     "[mbs.excitation] gas_orders = [1.0, -2.0]: must all be positive"),
    ("[mbs.counterweight]\nwidth = 100.0\n",
     "[mbs.counterweight] width = 100.0: hub_width (220 mm) must be smaller than width (100 mm)"),
    ("[mbs.counterweight]\nelements_z = 3\n", "[mbs.counterweight] elements_z = 3: must be even"),
    ("[mbs.throw]\nflexible_modes = 0\n", "[mbs.throw] flexible_modes = 0: must be a whole number of at least 1"),
    ("[mbs]\nsolver = 3\n", "[mbs] solver = 3: must be a table, [mbs.solver]"),
]


@pytest.mark.parametrize("text, said", REFUSALS)
def test_a_scene_file_names_the_key_its_value_and_what_is_allowed(tmp_path, text, said):
    path = tmp_path / "engine.toml"
    path.write_text(text)
    with pytest.raises(InputError) as refused:
        load_model_params(path)
    assert f"{path}: {said}" in str(refused.value)


@pytest.mark.parametrize("text, said", REFUSALS)
def test_the_scene_validation_says_the_same(text, said):
    import tomllib

    assert any(said in problem for problem in mbs_table_problems(tomllib.loads(text)["mbs"]))


def test_every_refusal_is_said_at_once():
    problems = mbs_table_problems({"n_modes": 0, "speed_rpm": "fast", "solver": {"time_step": 0.0}})
    assert [problem.split(":")[0] for problem in problems] == [
        '[mbs] speed_rpm = "fast"', "[mbs] n_modes = 0", "[mbs.solver] time_step = 0.0"]


def test_the_python_interface_names_the_field():
    with pytest.raises(Refusal) as refused:
        ModelParams(n_modes=0).validate()
    assert refused.value.fields == ("n_modes",) and refused.value.values == (0,)
    assert str(refused.value).startswith("n_modes = 0: must be a whole number of at least 1")
