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


def _checked(table: dict, allowed: set, where: str) -> None:
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise InputError(f"{where}: unknown key(s) {unknown}; allowed: {sorted(allowed)}")


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
    if not path.is_file():
        raise InputError(f"{where}: {path} does not exist")
    return {**table, "mesh_file": str(path.resolve()), "mesh_digest": hashlib.sha256(path.read_bytes()).hexdigest()}


def model_params_from_mapping(table: dict, where: str = "[mbs]", folder: Path = Path(".")) -> ModelParams:
    """ModelParams from a mapping shaped like the scene's [mbs] table (folder: base of relative files)."""
    table = dict(table)
    pressure = table.pop("gas_pressure", None)
    top_fields = {f.name for f in fields(ModelParams)}
    _checked(table, top_fields | {"gas_pressure"}, where)
    values = {}
    for name, value in table.items():
        if name in _SUBTABLES:
            kind = _SUBTABLES[name]
            if not isinstance(value, dict):
                raise InputError(f"{where}.{name} must be a table")
            _checked(value, {f.name for f in fields(kind)}, f"{where}.{name}")
            if name == "counterweight" and "mesh_file" in value:
                value = _with_mesh_digest(value, folder, f"{where}.counterweight.mesh_file")
            values[name] = replace(kind(), **{k: _as_field_value(v) for k, v in value.items()})
        elif name == "effects":
            values[name] = frozenset(value)
        else:
            values[name] = _as_field_value(value)
    params = replace(ModelParams(), **values)
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
