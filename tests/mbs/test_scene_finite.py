"""Every number of a scene's [mbs] table must be finite (QA): inf and NaN are refused naming the
key, in the scene schema's words ("'mbs.speed_rpm' must be a finite number ..., got inf"), by the
scene loader and by `fretwork mbs`'s reader alike. Before, most throw and excitation keys ran
with inf, and speed_rpm = inf was said to be 'not positive'."""

from dataclasses import fields
from pathlib import Path

import pytest

from mbs.parameters import ModelParams
from mbs.scene import _SUBTABLES, load_model_params
from pipelines.scene import load as load_scene
from reduction.errors import InputError

BASE = Path(__file__).resolve().parents[2] / "examples" / "counterweight.toml"
NUMERIC = ("float", "int", "tuple[float, ...]", "tuple[float, ...] | None")
#: every numeric key of [mbs] and its sub-tables, (sub-table or None, key, annotation)
KEYS = ([(None, f.name, f.type) for f in fields(ModelParams) if f.type in NUMERIC]
        + [(sub, f.name, f.type) for sub, cls in _SUBTABLES.items() for f in fields(cls) if f.type in NUMERIC])


def _scene(tmp_path, sub, key, text) -> Path:
    path = tmp_path / "scene.toml"
    path.write_text(f'[scene]\nbase = "{BASE.as_posix()}"\n\n[mbs{"." + sub if sub else ""}]\n{key} = {text}\n')
    return path


def _refusals(path) -> list[str]:
    messages = []
    for load in (load_scene, load_model_params):
        with pytest.raises(InputError) as refused:
            load(path)
        messages.append(str(refused.value))
    return messages


def test_every_numeric_key_is_found():
    """The enumeration below covers the keys QA found running with inf (a field renamed to a type
    not in NUMERIC would drop out silently)."""
    names = {f"{sub}.{key}" if sub else key for sub, key, _ in KEYS}
    assert {"speed_rpm", "modal_damping_ratio", "crank_angles_deg", "throw.crank_radius", "throw.pin_stiffness",
            "excitation.torsional_stiffness", "excitation.gas_orders", "solver.newton_tolerance",
            "counterweight.poisson_ratio", "n_modes"} <= names
    assert len(KEYS) > 40


@pytest.mark.parametrize("value", ["inf", "nan"])
@pytest.mark.parametrize("sub, key, kind", KEYS, ids=[f"{s or ''}.{k}".lstrip(".") for s, k, _ in KEYS])
def test_a_non_finite_number_is_refused_naming_its_key(tmp_path, sub, key, kind, value):
    text = f"[{value}, 1.0]" if kind.startswith("tuple") else value
    dotted = ".".join(["mbs"] + ([sub] if sub else []) + [key])
    for message in _refusals(_scene(tmp_path, sub, key, text)):
        assert f"'{dotted}' must be a" in message, message
        assert f"got {text}" in message, message
        expected = ("a list of finite numbers" if kind.startswith("tuple") else
                    "a whole number" if kind == "int" else "a finite number")
        assert f"must be {expected}" in message, message
        assert "problem(s)" not in message, message  # one sentence: not also 'not positive' or a length


def test_the_wording_is_the_schemas_with_the_models_own_bound(tmp_path):
    """speed_rpm = inf was '[mbs] speed_rpm = inf: must be positive' (inf is positive)."""
    scene, own = _refusals(_scene(tmp_path, None, "speed_rpm", "inf"))
    assert scene == own == (f"{tmp_path / 'scene.toml'}: 'mbs.speed_rpm' must be a finite number and be "
                            "positive (engine speed, rpm), got inf")
    _, ramp = _refusals(_scene(tmp_path, "solver", "ramp_revolutions", "-inf"))
    assert ramp.endswith("'mbs.solver.ramp_revolutions' must be a finite number and not be negative (shaft "
                         "revolutions; 0: full excitation from t = 0), got -inf")
    # the schema's own sentence for a key of another table, for comparison
    path = tmp_path / "scene.toml"
    path.write_text(f'[scene]\nbase = "{BASE.as_posix()}"\n[contact]\nnormal_stiffness = inf\n')
    with pytest.raises(InputError, match=r"'contact.normal_stiffness' must be a finite number .*, got inf"):
        load_scene(path)


def test_finite_values_out_of_range_keep_their_sentence(tmp_path):
    _, message = _refusals(_scene(tmp_path, None, "speed_rpm", "-5.0"))
    assert message.endswith("[mbs] speed_rpm = -5.0: must be positive (engine speed, rpm)")


@pytest.mark.parametrize("key", ["bore", "conrod_length", "max_order"])
def test_a_pressure_curves_numbers_must_be_finite(tmp_path, key):
    values = {"bore": "320.0", "conrod_length": "800.0", "max_order": "6.0", key: "inf"}
    path = tmp_path / "scene.toml"
    path.write_text('[mbs.gas_pressure]\nfile = "pressure.csv"\n' + "".join(f"{k} = {v}\n" for k, v in values.items()))
    with pytest.raises(InputError, match=rf"'mbs.gas_pressure.{key}' must be a finite number and be positive "
                                         r"\(.*\), got inf"):
        load_model_params(path)


def test_several_non_finite_keys_are_named_at_once(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text(f'[scene]\nbase = "{BASE.as_posix()}"\n[mbs]\nspeed_rpm = nan\n[mbs.throw]\ncrank_radius = inf\n'
                    "[mbs.excitation]\ntorsional_stiffness = -inf\n")
    message = str(pytest.raises(InputError, load_scene, path).value)
    for sentence in ("'mbs.speed_rpm' must be a finite number", "'mbs.throw.crank_radius' must be a finite number",
                     "'mbs.excitation.torsional_stiffness' must be a finite number"):
        assert sentence in message
