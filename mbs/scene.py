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
import math
import tomllib
from dataclasses import fields, replace
from pathlib import Path

import numpy as np

from mbs.counterweight import CounterweightGeometry
from mbs.excitation import gas_torque_from_pressure
from mbs.parameters import CrankThrowParams, ExcitationParams, ModelParams, SolverParams
from mbs.refusal import Refusal, shown
from reduction.errors import InputError

_SUBTABLES = {
    "counterweight": CounterweightGeometry,
    "throw": CrankThrowParams,
    "excitation": ExcitationParams,
    "solver": SolverParams,
}


def _header(where: str, sub: str | None = None) -> str:
    """The table header as the scene writes it: ``where`` ('[mbs]', or 'FILE: [mbs]') for the
    top level, '[mbs.solver]' for a sub-table."""
    if sub is None:
        return where
    return f"{where[:-1]}.{sub}]" if where.endswith("]") else f"{where}.{sub}"


def _unknown(table: dict, allowed: set, where: str) -> str | None:
    """The sentence naming ``table``'s unknown keys (each with its likely meant key), or None."""
    unknown = sorted(set(table) - allowed)
    if not unknown:
        return None
    meant = {key: difflib.get_close_matches(key, sorted(allowed), n=1) for key in unknown}
    hints = "".join(f" ({key!r}: did you mean {meant[key][0]!r}?)" for key in unknown if meant[key])
    return f"{where}: unknown key(s) {unknown}{hints}; allowed: {sorted(allowed)}"


def _as_field_value(value):
    return tuple(value) if isinstance(value, list) else value


def _number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


#: what a TOML value must be for a dataclass field of each annotation
_KINDS = {
    "float": (_number, "a number"),
    "int": (lambda v: isinstance(v, int) and not isinstance(v, bool), "a whole number"),
    "bool": (lambda v: isinstance(v, bool), "true or false"),
    "str": (lambda v: isinstance(v, str), "a string"),
    "str | None": (lambda v: isinstance(v, str), "a string"),
    "tuple[float, ...]": (lambda v: isinstance(v, list) and all(map(_number, v)), "a list of numbers"),
    "tuple[float, ...] | None": (lambda v: isinstance(v, list) and all(map(_number, v)), "a list of numbers"),
    "frozenset": (lambda v: isinstance(v, list) and all(isinstance(e, str) for e in v), "a list of names"),
}


def _not_finite(value) -> bool:
    """Whether a number, or a number of a list, is inf or NaN (what no model takes)."""
    entries = value if isinstance(value, list) else [value]
    return any(_number(entry) and not math.isfinite(entry) for entry in entries)


def _finite_sentence(where: str, key: str, value, requirement: str) -> str:
    """A non-finite number refused in the scene schema's words (pipelines.scene.schema): the key
    dotted, "'mbs.solver.time_step' must be a finite number and be positive (s), got inf";
    ``where``: the key's table as the scene writes it ('[mbs.solver]', 'FILE: [mbs.solver]')."""
    prefix, _, header = where.rpartition("[")
    return f"{prefix}'{header.removesuffix(']')}.{key}' {requirement}, got {value!r}"


def _finite_requirement(field: str, kind: str) -> str:
    """What a ModelParams field ('speed_rpm', 'solver.time_step') of annotation ``kind`` asks of a
    value that is inf or NaN: to be finite, and what the model's own refusal of NaN, which no
    bound holds, asks besides."""
    if kind.startswith("tuple"):
        return "must be a list of finite numbers"
    if kind == "int":
        return f"must be {_KINDS[kind][1]}"
    name, _, key = field.partition(".")
    refusals = table_problems({name: {key: math.nan}} if key else {name: math.nan})
    asked = next((refusal.allowed for refusal in refusals if refusal.fields[0] == field), None)
    return "must be a finite number" + (f" and {asked.removeprefix('must ')}" if asked else "")


def _infinite(table: dict, cls, where: str, sub: str | None = None) -> dict[str, str]:
    """The keys of ``table`` (fields of ``cls``, of sub-table ``sub`` of ModelParams) whose
    number is inf or NaN, each with its sentence (:func:`_finite_sentence`)."""
    kinds = {field.name: field.type for field in fields(cls) if field.name not in _SUBTABLES}
    return {key: _finite_sentence(where, key, value,
                                  _finite_requirement(key if sub is None else f"{sub}.{key}", kinds[key]))
            for key, value in table.items() if key in kinds and _not_finite(value)}


def _mistyped(table: dict, cls) -> dict[str, str]:
    """The keys of ``table`` whose value is not of their ``cls`` field's kind, each with that kind."""
    found = {}
    for field in fields(cls):
        check, kind = _KINDS.get(field.type, (None, None))
        if field.name in table and check is not None and not check(table[field.name]):
            found[field.name] = kind
    return found


_PRESSURE_KEYS = {"file", "bore", "conrod_length", "max_order"}


def _pressure_problems(table, where: str) -> list[str]:
    """The problems of a [mbs.gas_pressure] table that show without reading its file."""
    if not isinstance(table, dict):
        return [f"{where} must be a table (file, bore, conrod_length, max_order), got {shown(table)}"]
    missing = sorted({"file", "bore", "conrod_length"} - set(table))
    found = [_unknown(table, _PRESSURE_KEYS, where)] + ([f"{where}: missing key(s) {missing}"] if missing else [])
    for key in ("bore", "conrod_length", "max_order"):
        meaning = "highest engine order" if key == "max_order" else "mm"
        if key in table and _not_finite(table[key]):
            found.append(_finite_sentence(where, key, table[key],
                                          f"must be a finite number and be positive ({meaning})"))
        elif key in table and not (_number(table[key]) and table[key] > 0):
            found.append(f"{where} {key} = {shown(table[key])}: must be a positive number ({meaning})")
    if "file" in table and not isinstance(table["file"], str):
        found.append(f"{where} file = {shown(table['file'])}: must be a string (a CSV file)")
    return [problem for problem in found if problem]


def _with_pressure_curve(params: ModelParams, table: dict, folder: Path, where: str) -> ModelParams:
    problems = _pressure_problems(table, where)
    if problems:
        raise InputError("; ".join(problems))
    path = folder / table["file"]
    try:
        curve = np.loadtxt(path, delimiter=",", comments="#", ndmin=2)
    except (OSError, ValueError) as error:
        raise InputError(f"{where} file: cannot read pressure curve {path}: {error}") from None
    if curve.shape[1] != 2:
        raise InputError(f"{where} file: pressure curve {path} must have two columns (crank angle deg, pressure MPa)")
    _, orders, amplitudes, phases = gas_torque_from_pressure(
        curve[:, 0], curve[:, 1], bore=float(table["bore"]), crank_radius=params.throw.crank_radius,
        conrod_length=float(table["conrod_length"]), max_order=float(table.get("max_order", 12.0)))
    excitation = replace(params.excitation, gas_orders=tuple(orders), gas_torque_amplitudes=tuple(amplitudes),
                         gas_torque_phases=tuple(phases))
    return replace(params, excitation=excitation)


def _with_mesh_digest(table: dict, folder: Path, where: str) -> dict:
    """The counterweight table with its mesh file made absolute and its SHA-256 (cache key) added."""
    if "mesh_digest" in table:
        raise InputError(f"{where} mesh_digest: is computed from the mesh file, not given")
    path = Path(table["mesh_file"])
    path = path if path.is_absolute() else folder / path
    named = f"{where} mesh_file = {shown(table['mesh_file'])}"
    if path.is_dir():
        raise InputError(f"{named}: {path} is a folder, not a mesh file: name a mesh file in it "
                         "(Abaqus .inp, Gmsh .msh)")
    if not path.is_file():
        raise InputError(f"{named}: {path} does not exist")
    return {**table, "mesh_file": str(path.resolve()), "mesh_digest": hashlib.sha256(path.read_bytes()).hexdigest()}


def _field_values(table: dict, where: str, folder: Path | None) -> tuple[dict, list[str]]:
    """The ModelParams fields an [mbs] table gives (a value per top-level field, a dict of values
    per sub-table), and the problems of the keys left out: unknown keys, values of the wrong kind,
    a [mbs.gas_pressure] table's keys. With ``folder`` the counterweight's mesh file is made
    absolute and digested (:func:`_with_mesh_digest`); without it no file is read."""
    top_fields = {f.name for f in fields(ModelParams)}
    problems = [_unknown(table, top_fields | {"gas_pressure"}, where)]
    mistyped = _mistyped({k: v for k, v in table.items() if k not in _SUBTABLES}, ModelParams)
    infinite = _infinite(table, ModelParams, where)
    values = {}
    for name, value in table.items():
        sub = _header(where, name)
        if name in infinite:
            problems.append(infinite[name])
        elif name == "gas_pressure":
            problems += _pressure_problems(value, sub)
        elif name in _SUBTABLES and not isinstance(value, dict):
            problems.append(f"{where} {name} = {shown(value)}: must be a table, {sub.rpartition(': ')[2]}")
        elif name in _SUBTABLES:
            allowed = {f.name for f in fields(_SUBTABLES[name])}
            problems.append(_unknown(value, allowed, sub))
            not_finite = _infinite(value, _SUBTABLES[name], sub, name)
            wrong = {**_mistyped(value, _SUBTABLES[name]), **not_finite}
            problems += [not_finite.get(key) or f"{sub} {key} = {shown(value[key])}: must be {kind}"
                         for key, kind in wrong.items()]
            value = {k: v for k, v in value.items() if k in allowed and k not in wrong}
            if folder is not None and name == "counterweight" and "mesh_file" in value:
                value = _with_mesh_digest(value, folder, sub)
            values[name] = {k: _as_field_value(v) for k, v in value.items()}
        elif name in mistyped:
            problems.append(f"{where} {name} = {shown(value)}: must be {mistyped[name]}")
        elif name in top_fields:
            values[name] = frozenset(value) if name == "effects" else _as_field_value(value)
    return values, [problem for problem in problems if problem]


def _params(values: dict) -> ModelParams:
    return replace(ModelParams(), **{name: replace(_SUBTABLES[name](), **value) if name in _SUBTABLES else value
                                     for name, value in values.items()})


def _given(values: dict, field: str) -> bool:
    """Whether ``values`` give a ModelParams field ('n_modes', 'solver.time_step')."""
    name, _, key = field.partition(".")
    return name in values and (not key or key in values[name])


def _without(values: dict, field: str) -> dict:
    """``values`` without one field ('n_modes', 'solver.time_step')."""
    name, _, key = field.partition(".")
    if not key:
        return {k: v for k, v in values.items() if k != name}
    return {**values, name: {k: v for k, v in values[name].items() if k != key}}


def table_problems(values: dict) -> list[Refusal]:
    """Every refusal of ModelParams (:class:`mbs.refusal.Refusal`), each with only the fields the
    table gives: a refusal names the field refused and the fields its bound comes from, and of
    those the table gives at least one (the defaults are valid together). Each refusal's fields
    are set aside (back to their defaults) before the next is sought."""
    found = []
    while True:
        try:
            _params(values).validate()
            return found
        except Refusal as refusal:
            given = [(field, value) for field, value in zip(refusal.fields, refusal.values) if _given(values, field)]
            found.append(Refusal(*zip(*given), refusal.allowed) if given else refusal)
            if not given:
                return found
            for field, _ in given:
                values = _without(values, field)


def _key(field: str, header: str) -> str:
    """A ModelParams field as the scene writes it: 'n_modes' -> '[mbs] n_modes',
    'solver.time_step' -> '[mbs.solver] time_step' (header: '[mbs]')."""
    name, _, key = field.partition(".")
    return f"{header} {name}" if not key else f"{_header(header, name)} {key}"


def _named(refusal: Refusal, where: str) -> str:
    """The refusal's sentence: each field as the scene writes it, with its value, then what is
    allowed ('FILE: [mbs] n_modes = 0: must be a whole number of at least 1 ...')."""
    prefix, bracket, header = where.rpartition("[")
    names = " and ".join(f"{_key(field, bracket + header)} = {shown(value)}"
                         for field, value in zip(refusal.fields, refusal.values))
    return f"{prefix}{names}: {refusal.allowed}"


def mbs_table_problems(table, where: str = "[mbs]") -> list[str]:
    """The problems of a scene's [mbs] table, each naming its key as the scene writes it
    ('[mbs] speed_rpm = 0: ...', '[mbs.solver] time_step = 0: ...'), without reading the files
    it names (the scene's validation)."""
    if not isinstance(table, dict):
        return [f"{where} must be a table"]
    values, problems = _field_values(table, where, None)
    return problems + [_named(refusal, where) for refusal in table_problems(values)]


def model_params_from_mapping(table: dict, where: str = "[mbs]", folder: Path = Path(".")) -> ModelParams:
    """ModelParams from a mapping shaped like the scene's [mbs] table (folder: base of relative
    files; where: how messages name the table, '[mbs]' or 'FILE: [mbs]')."""
    table = dict(table)
    pressure = table.get("gas_pressure")
    values, problems = _field_values(table, where, folder)
    problems += [_named(refusal, where) for refusal in table_problems(values)]
    if problems:
        raise InputError("; ".join(problems))
    params = _params(values)
    if pressure is not None:
        params = _with_pressure_curve(params, pressure, folder, _header(where, "gas_pressure"))
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
