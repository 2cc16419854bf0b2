"""Read the multibody part of a scene (TOML) into ModelParams.

The scene's ``[mbs]`` table holds the top-level ModelParams fields (speed_rpm, n_modes,
modal_damping_ratio, effects = ["gas_torque", "gear_mesh", "torsional_vibration"]) and the
sub-tables ``[mbs.counterweight]``, ``[mbs.throw]``, ``[mbs.excitation]``, ``[mbs.solver]`` with
the fields of the dataclasses of the same meaning (units as documented there). Anything not
given keeps its default; an unknown key is an error that names it.
"""

from __future__ import annotations

import tomllib
from dataclasses import fields, replace
from pathlib import Path

from mbs.counterweight import CounterweightGeometry
from mbs.parameters import CrankThrowParams, ExcitationParams, ModelParams, SolverParams
from reduction.errors import InputError

_SUBTABLES = {
    "counterweight": CounterweightGeometry,
    "throw": CrankThrowParams,
    "excitation": ExcitationParams,
    "solver": SolverParams,
}


def _checked(table: dict, allowed: set, where: str) -> None:
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise InputError(f"{where}: unknown key(s) {unknown}; allowed: {sorted(allowed)}")


def _as_field_value(value):
    return tuple(value) if isinstance(value, list) else value


def model_params_from_mapping(table: dict, where: str = "[mbs]") -> ModelParams:
    """ModelParams from a mapping shaped like the scene's [mbs] table."""
    top_fields = {f.name for f in fields(ModelParams)}
    _checked(table, top_fields, where)
    values = {}
    for name, value in table.items():
        if name in _SUBTABLES:
            kind = _SUBTABLES[name]
            if not isinstance(value, dict):
                raise InputError(f"{where}.{name} must be a table")
            _checked(value, {f.name for f in fields(kind)}, f"{where}.{name}")
            values[name] = replace(kind(), **{k: _as_field_value(v) for k, v in value.items()})
        elif name == "effects":
            values[name] = frozenset(value)
        else:
            values[name] = value
    params = replace(ModelParams(), **values)
    params.validate()
    return params


def load_model_params(path) -> ModelParams:
    """ModelParams from the [mbs] table of a scene file (defaults where the table is absent)."""
    path = Path(path)
    try:
        with path.open("rb") as stream:
            scene = tomllib.load(stream)
    except FileNotFoundError:
        raise InputError(f"scene file {path} does not exist") from None
    except tomllib.TOMLDecodeError as error:
        raise InputError(f"scene file {path} is not valid TOML: {error}") from None
    return model_params_from_mapping(scene.get("mbs", {}), where=f"{path}: [mbs]")
