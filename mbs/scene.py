"""Read the multibody part of a scene (TOML) into ModelParams.

The scene's ``[mbs]`` table holds the top-level ModelParams fields (speed_rpm, n_modes,
modal_damping_ratio, effects = ["gas_torque", "gear_mesh", "torsional_vibration",
"flexible_crankshaft"], throws = 3, crank_angles_deg = [0, 120, 240], firing_angles_deg = [0,
480, 240]) and the
sub-tables ``[mbs.counterweight]``, ``[mbs.throw]``, ``[mbs.excitation]``, ``[mbs.solver]`` with
the fields of the dataclasses of the same meaning (units as documented there). Anything not
given keeps its default; an unknown key is an error that names it.

``[mbs.counterweight]`` may name the user's own CW mesh instead of the generated block:
mesh_file (Abaqus .inp or Gmsh .msh, relative to the scene file, in the CW frame) and interface
(its node set or surface of the bolted contact face); see :mod:`mbs.counterweight`.

Instead of an order table, ``[mbs.gas_pressure]`` may give a cylinder-pressure curve:
file = CSV with two columns (crank angle deg over 0..720, gauge pressure MPa; '#' comments),
bore and conrod_length (mm), optional max_order; the order table is then computed by
mbs.excitation.gas_torque_from_pressure with the throw's crank radius.
"""

from __future__ import annotations

import difflib
import hashlib
import tomllib
from dataclasses import fields, replace
from pathlib import Path

import numpy as np

from mbs.counterweight import CounterweightGeometry
from mbs.excitation import gas_torque_from_pressure
from mbs.parameters import CrankThrowParams, ExcitationParams, ModelParams, SolverParams
from reduction.errors import InputError

_SUBTABLES = {
    "counterweight": CounterweightGeometry,
    "throw": CrankThrowParams,
    "excitation": ExcitationParams,
    "solver": SolverParams,
}


def _unknown(table: dict, allowed: set, where: str) -> str | None:
    """The sentence naming ``table``'s unknown keys (each with its likely meant key), or None."""
    unknown = sorted(set(table) - allowed)
    if not unknown:
        return None
    meant = {key: difflib.get_close_matches(key, sorted(allowed), n=1) for key in unknown}
    hints = "".join(f" ({key!r}: did you mean {meant[key][0]!r}?)" for key in unknown if meant[key])
    return f"{where}: unknown key(s) {unknown}{hints}; allowed: {sorted(allowed)}"


def _checked(table: dict, allowed: set, where: str) -> None:
    problem = _unknown(table, allowed, where)
    if problem:
        raise InputError(problem)


def _as_field_value(value):
    return tuple(value) if isinstance(value, list) else value


_PRESSURE_KEYS = {"file", "bore", "conrod_length", "max_order"}


def _with_pressure_curve(params: ModelParams, table: dict, folder: Path, where: str) -> ModelParams:
    _checked(table, _PRESSURE_KEYS, where)
    missing = sorted({"file", "bore", "conrod_length"} - set(table))
    if missing:
        raise InputError(f"{where}: missing key(s) {missing}")
    path = folder / table["file"]
    try:
        curve = np.loadtxt(path, delimiter=",", comments="#", ndmin=2)
    except (OSError, ValueError) as error:
        raise InputError(f"{where}: cannot read pressure curve {path}: {error}") from None
    if curve.shape[1] != 2:
        raise InputError(f"{where}: pressure curve {path} must have two columns (crank angle deg, pressure MPa)")
    _, orders, amplitudes, phases = gas_torque_from_pressure(
        curve[:, 0], curve[:, 1], bore=float(table["bore"]), crank_radius=params.throw.crank_radius,
        conrod_length=float(table["conrod_length"]), max_order=float(table.get("max_order", 12.0)))
    excitation = replace(params.excitation, gas_orders=tuple(orders), gas_torque_amplitudes=tuple(amplitudes),
                         gas_torque_phases=tuple(phases))
    return replace(params, excitation=excitation)


def _with_mesh_digest(table: dict, folder: Path, where: str) -> dict:
    """The counterweight table with its mesh file made absolute and its SHA-256 (cache key) added."""
    if "mesh_digest" in table:
        raise InputError(f"{where}: 'mesh_digest' is computed from the file, not given")
    path = Path(table["mesh_file"])
    path = path if path.is_absolute() else folder / path
    if path.is_dir():
        raise InputError(f"{where}: {path} is a folder, not a mesh file: name a mesh file in it "
                         "(Abaqus .inp, Gmsh .msh)")
    if not path.is_file():
        raise InputError(f"{where}: {path} does not exist")
    return {**table, "mesh_file": str(path.resolve()), "mesh_digest": hashlib.sha256(path.read_bytes()).hexdigest()}


def _field_values(table: dict, where: str, folder: Path | None) -> dict:
    """The ModelParams fields an [mbs] table gives: a value per top-level field, a dict of values
    per sub-table; unknown keys refused. With ``folder`` the counterweight's mesh file is made
    absolute and digested (:func:`_with_mesh_digest`); without it no file is read."""
    top_fields = {f.name for f in fields(ModelParams)}
    # every table's unknown keys in one message, not the first table's alone
    problems = [_unknown(table, top_fields | {"gas_pressure"}, where)]
    problems += [_unknown(value, {f.name for f in fields(_SUBTABLES[name])}, f"{where}.{name}")
                 for name, value in table.items() if name in _SUBTABLES and isinstance(value, dict)]
    problems = [problem for problem in problems if problem]
    if problems:
        raise InputError("; ".join(problems))
    values = {}
    for name, value in table.items():
        if name == "gas_pressure":
            continue
        if name in _SUBTABLES:
            if not isinstance(value, dict):
                raise InputError(f"{where}.{name} must be a table")
            _checked(value, {f.name for f in fields(_SUBTABLES[name])}, f"{where}.{name}")
            if folder is not None and name == "counterweight" and "mesh_file" in value:
                value = _with_mesh_digest(value, folder, f"{where}.counterweight.mesh_file")
            values[name] = {k: _as_field_value(v) for k, v in value.items()}
        elif name == "effects":
            values[name] = frozenset(value) if isinstance(value, list) else value
        else:
            values[name] = _as_field_value(value)
    return values


def _params(values: dict) -> ModelParams:
    return replace(ModelParams(), **{name: replace(_SUBTABLES[name](), **value) if name in _SUBTABLES else value
                                     for name, value in values.items()})


def _refusal(values: dict) -> str | None:
    """Why ModelParams refuses these values (its first complaint), or None."""
    try:
        _params(values).validate()
    except InputError as error:
        return str(error)
    except (TypeError, ValueError) as error:  # a string or list where a number belongs
        return f"a value of the wrong type ({error})"
    return None


def _without(values: dict, key: tuple) -> dict:
    """``values`` without one key: (field,) or (sub-table, field)."""
    if len(key) == 1:
        return {name: value for name, value in values.items() if name != key[0]}
    return {**values, key[0]: {k: v for k, v in values[key[0]].items() if k != key[1]}}


def table_problems(values: dict) -> list[tuple[list[str], str]]:
    """Every refusal of ModelParams, as (the dotted keys within [mbs] at fault, its reason).
    ModelParams says why but not which key: at fault is a key that alone (the others at their
    defaults) is refused for the same reason, or else, for a combination (crank_angles_deg of
    another length than throws), each key whose default changes the answer. Each refusal's keys
    are set aside before the next is sought."""
    found = []
    while (reason := _refusal(values)) is not None:
        keys = [(name,) for name in values if name not in _SUBTABLES]
        keys += [(name, key) for name in values if name in _SUBTABLES for key in values[name]]
        culprits = ([key for key in keys if _refusal(_only(values, key)) == reason]
                    or [key for key in keys if _refusal(_without(values, key)) != reason])
        found.append(([".".join(key) for key in culprits], reason))
        if not culprits:
            break
        for key in culprits:
            values = _without(values, key)
    return found


def _only(values: dict, key: tuple) -> dict:
    """One key of ``values``: (field,) or (sub-table, field)."""
    return {key[0]: values[key[0]]} if len(key) == 1 else {key[0]: {key[1]: values[key[0]][key[1]]}}


def _named(keys: list[str], reason: str, where: str, quote: str) -> str:
    names = " or ".join(f"{quote}{where}.{key}{quote}" for key in keys) or f"{quote}{where}{quote}"
    return f"{names}: {reason}"


def mbs_table_problems(table, where: str = "mbs") -> list[str]:
    """The problems of a scene's [mbs] table, each naming its key ('mbs.speed_rpm'), without
    reading the files it names (the scene's validation)."""
    if not isinstance(table, dict):
        return [f"'{where}' must be a table"]
    try:
        values = _field_values(table, where, None)
    except InputError as error:
        return [str(error)]
    return [_named(keys, reason, where, "'") for keys, reason in table_problems(values)]


def model_params_from_mapping(table: dict, where: str = "[mbs]", folder: Path = Path(".")) -> ModelParams:
    """ModelParams from a mapping shaped like the scene's [mbs] table (folder: base of relative files)."""
    table = dict(table)
    pressure = table.get("gas_pressure")
    values = _field_values(table, where, folder)
    problems = table_problems(values)
    if problems:
        raise InputError("; ".join(_named(keys, reason, where, "") for keys, reason in problems))
    params = _params(values)
    if pressure is not None:
        params = _with_pressure_curve(params, pressure, folder, f"{where}.gas_pressure")
    params.validate()
    return params


def load_model_params(path) -> ModelParams:
    """ModelParams from the [mbs] table of a scene file (defaults for keys the table leaves out);
    a scene without an [mbs] table is refused: it does not describe a multibody model."""
    path = Path(path)
    try:
        with path.open("rb") as stream:
            scene = tomllib.load(stream)
    except FileNotFoundError:
        raise InputError(f"scene file {path} does not exist") from None
    except tomllib.TOMLDecodeError as error:
        raise InputError(f"scene file {path} is not valid TOML: {error}") from None
    if not isinstance(scene.get("mbs"), dict):
        raise InputError(f"{path} has no [mbs] table: it does not describe a multibody model "
                         "(an empty [mbs] table runs the default generic engine)")
    return model_params_from_mapping(scene["mbs"], where=f"{path}: [mbs]", folder=path.parent)
