"""The keys of a scene file, their types, ranges and meaning, and the validation of a parsed scene.

:func:`validate` checks the schema table by table, then the cross-references (bodies,
materials, reference points, selections, effects; in :mod:`pipelines.scene.checks`) of the
tables the schema found sound, and returns every problem at once, each a sentence naming its
key, with "did you mean" for typos.
Units: mm, N, MPa, t, s, mJ (see the README's scene reference).
"""

from __future__ import annotations

import difflib
import math


CONTACT_EFFECTS = ("cof_evolution", "wear", "bolts")


# effects of the multibody-driven loading, valid with a [coupling] table: the CW's modal
# (flexible) inertia, the spin's centrifugal part, and the multibody model's own effects
COUPLING_EFFECTS = ("flexible_counterweight", "centrifugal")
MULTIBODY_EFFECTS = ("gas_torque", "gear_mesh", "torsional_vibration", "flexible_crankshaft")
KNOWN_EFFECTS = CONTACT_EFFECTS + COUPLING_EFFECTS + MULTIBODY_EFFECTS
MESH_GENERATORS = {
    "cylinder_block": ("radius", "half_width", "height", "contact_half_width", "contact_size"),
    "plane_block": ("half_width", "depth", "contact_half_width", "contact_size"),
    "flat_block": ("size_x", "size_y", "height", "n_x", "n_y", "n_z"),
    "beam_with_hole": ("length", "width", "thickness", "hole_x", "hole_radius", "contact_size",
                       "pad_half_length"),
    "counterweight_block": ("width", "height", "thickness", "hub_width", "hub_height", "screw_x",
                            "hole_half_size", "contact_size"),
    "web_block": ("width", "depth", "thickness", "hub_width", "screw_x", "hole_half_size", "hole_depth",
                  "contact_size"),
}


NUMBER = (int, float)


def finite(value) -> bool:
    """Whether ``value`` is a finite number (not a boolean, NaN or ±inf): what every numeric
    scene value must be, in tables and in arrays alike, unless its key is :data:`UNBOUNDED`."""
    return isinstance(value, NUMBER) and not isinstance(value, bool) and math.isfinite(value)


def finite_list(value, length: int | None = None) -> bool:
    """Whether ``value`` is a list of finite numbers (of ``length`` of them, if given)."""
    return (isinstance(value, list) and (length is None or len(value) == length)
            and all(finite(entry) for entry in value))


def _positive(value):
    return None if value > 0 else "must be > 0"


def _non_negative(value):
    return None if value >= 0 else "must be >= 0"


def _poisson(value):
    return None if -1.0 < value < 0.5 else "must lie between -1 and 0.5"


def _cof(value):
    return None if 0 <= value <= 5 else "must lie between 0 and 5"


def _integer_at_least(n):
    return lambda value: None if value >= n else f"must be >= {n}"


def _cycle_jump(value):
    if isinstance(value, str):
        return None if value == "auto" else "must be a number >= 1 or \"auto\""
    return None if value >= 1 else "must be >= 1"


def _field_output(value):
    if not isinstance(value, list):
        return None if value in ("cycle", "increment") else \
            "must be \"cycle\", \"increment\" or a list of cycle fractions in (0, 1]"
    if not value:
        return "must name at least one cycle fraction in (0, 1]"
    wrong = [f for f in value if isinstance(f, bool) or not isinstance(f, (int, float)) or not 0 < f <= 1]
    return f"must hold cycle fractions in (0, 1] (0.25: a quarter into the cycle), not {wrong}" if wrong else None


# key → (types, required, check, meaning with units). "*" marks a table of named entries.
SCHEMA = {
    "scene": {
        "name": (str, True, None, "scene name"),
        "description": (str, False, None, "one-line description"),
        "dimension": (int, True, lambda v: None if v in (2, 3) else "must be 2 or 3", "2 (plane strain) or 3"),
        "effects": (list, True, None, f"list of effects from {KNOWN_EFFECTS}"),
        "base": (str, False, None, "scene file this one extends (its tables, then these on top)"),
    },
    "materials.*": {
        "youngs_modulus": (NUMBER, True, _positive, "Young's modulus E, MPa"),
        "poisson_ratio": (NUMBER, True, _poisson, "Poisson's ratio"),
        "density": (NUMBER, False, _positive, "density, t/mm³"),
    },
    "bodies.*": {
        "material": (str, True, None, "name of a [materials] entry"),
        "mesh": (dict, True, None, "{ generator = ..., ... } or { file = ... }"),
        "fixed": ((dict, list), False, None, "{ nodes = selection, components = [...] }, or a list of such "
                  "supports ([[bodies.NAME.fixed]]), e.g. a base and a symmetry plane"),
        "reference_points": (dict, False, None, "named control points"),
    },
    "bolts.*": {
        "head": (str, True, None, "head control point 'body.point'"),
        "nut": (str, True, None, "nut control point 'body.point'"),
        "axis": (list, True, None, "unit vector from head to nut"),
        "stiffness": (NUMBER, True, _positive, "axial stiffness k_b = E·A_s/L, N/mm"),
        "pretension": (NUMBER, True, _positive, "pretension F, N"),
    },
    "contact": {
        "slave": (dict, True, None, "{ body = ..., box/plane selection of facets }"),
        "master": (dict, True, None, "{ body = ..., box/plane selection of facets }"),
        "normal_stiffness": (NUMBER, True, _positive, "kn, N/mm³"),
        "critical_slip": (NUMBER, True, _positive, "γ_crit, mm"),
        "cof_initial": (NUMBER, True, _cof, "μ₀"),
        "cof_max": (NUMBER, True, _cof, "μ_max"),
        "cof_rate": (NUMBER, False, _non_negative, "k, mm/N"),
        "wear_coefficients": (list, False, None, "[w_slave, w_master], mm²/N"),
        "pressure_limit": (NUMBER, False, _non_negative, "p_lim, MPa"),
        "wear_form": (str, False, lambda v: None if v in ("pressure", "shear") else
                      "must be 'pressure' or 'shear'", "Archard driver"),
        "search_distance": (NUMBER, False, _positive, "largest slave-master distance, mm"),
        "pairing": (str, False, lambda v: None if v in ("auto", "node_to_segment", "mortar") else
                    "must be 'auto', 'node_to_segment' or 'mortar'",
                    "surface pairing; auto: node-to-segment on matching meshes, else mortar"),
        "sliding": (str, False, lambda v: None if v in ("auto", "small", "finite") else
                    "must be 'auto', 'small' or 'finite'",
                    "pairing fixed (small) or following the bodies (finite); auto: finite once "
                    "the slip reaches an element"),
        "solver": (str, False, lambda v: None if v in ("auto", "dense", "sparse") else
                   "must be 'auto', 'dense' or 'sparse'",
                   ("contact solver: dense (condensed bodies, dense contact compliance W) or sparse "
                   "(bodies kept whole and sparse, no dense W: memory and time about linear in the "
                   "points); auto: sparse from 2,500 contact points in 3D")),
    },
    "coupling": {
        "body": (str, True, None, "the contact body that is the counterweight"),
        "counterweight": (int, False, _integer_at_least(1), "which CW of the multibody model (1 = first)"),
        "cycle": (str, False, lambda v: None if v in ("wing_period", "revolution") else
                  "must be 'wing_period' or 'revolution'", "what one contact load cycle is"),
        "wing_amplitude": (NUMBER, False, _positive, "wing vibration amplitude, mm (default: from the multibody run)"),
        "fields": (str, False, lambda v: None if v in ("all", "wing_mode") else "must be 'all' or 'wing_mode'",
                   "which inertia fields load the CW"),
        "histories": (str, False, None, "interface-histories file (.h5 or .csv, docs/histories_format.md) read "
                      "instead of running the multibody model"),
    },
    "procedure": {
        "preload_increments": (int, False, _integer_at_least(1), "increments of the preload"),
        "increments_per_cycle": (int, False, _integer_at_least(2), "increments per load cycle"),
        "cof_cycles": (int, False, _integer_at_least(0), "COF stabilisation cycles"),
        "wear_cycles": (int, False, _integer_at_least(0), "simulated wear cycles"),
        "cycle_jump": (NUMBER + (str,), False, _cycle_jump,
                       "J, real cycles per simulated wear cycle, or \"auto\" (adaptive)"),
        "jump_tolerance": (NUMBER, False, lambda v: None if 0 < v <= 0.5 else "must lie in (0, 0.5]",
                           "adaptive jump: largest pressure change per block / mean pressure"),
        "max_cycle_jump": (NUMBER, False, lambda v: None if v >= 1 else "must be >= 1",
                           "adaptive jump: the largest J (default inf: no limit)"),
        "life_cycles": (NUMBER, False, _positive,
                        "real cycles the wear phase stands for at most (default inf: no limit)"),
        "cof_during_wear": (bool, False, None, "keep COF evolving in the wear phase"),
        "cof_jump": (bool, False, None, "scale the wear phase's COF change by the cycle jump, as its wear (default true)"),
        "vibration_run_up": (int, False, _integer_at_least(0),
                             "COF-phase cycles over which the vibration grows from 0 to full amplitude"),
        "wear_cap": (NUMBER, False, _positive, "largest wear increment per step, mm"),
        "stationary_window": (int, False, _integer_at_least(1), "cycles without slip for shakedown"),
        "loosening_window": (int, False, _integer_at_least(3),
                             "wear blocks of falling clamp force (with loosening_window_cycles: at least)"),
        "loosening_window_cycles": (NUMBER, False, _positive,
                                    "real cycles of falling clamp force (the window in engine running time)"),
        "stop_at_loosening": (bool, False, None, "end the run once loosening is evident (default true)"),
        "clamp_loss_limit": (NUMBER, False, lambda v: None if 0 < v < 1 else "must lie in (0, 1)",
                             "fraction of the clamp force whose loss is loosening at once (default 0.5)"),
        "max_cutbacks": (int, False, _integer_at_least(0), "halvings of a failing increment"),
        "record_every": (int, False, _integer_at_least(1), "store fields every n cycles"),
        "field_output": (NUMBER + (str, list), False, _field_output,
                         ("fields within the recorded cycles: \"cycle\" (at their ends only), \"increment\" "
                          "(every increment) or a list of cycle fractions, e.g. [0.25, 0.5, 0.75, 1.0]")),
        "checkpoint_every": (int, False, _integer_at_least(0), "write checkpoint.h5 every n cycles (0: never)"),
    },
}


#: keys whose value may be inf, where it means "no limit" (their default); every other number
#: must be finite (an infinite stiffness, modulus, load or jump is no model)
UNBOUNDED = frozenset({"procedure.max_cycle_jump", "procedure.life_cycles"})


PATTERN_KEYS = {
    "name": (str, True, None, "pattern name"),
    "dof": (str, True, None, "control DOF 'body.point.component'"),
    "value": (NUMBER, True, None, "full amplitude, N or mm"),
    "history": (str, True, lambda v: None if v in ("ramp", "cyclic", "constant") else
                "must be 'ramp', 'cyclic' or 'constant'", "time shape"),
}


# [mbs] is the multibody model's table, validated by mbs.scene.
BODY_LOAD_KEYS = {
    "name": (str, True, None, "pattern name"),
    "body": (str, True, None, "body it acts on"),
    "kind": (str, True, lambda v: None if v in ("gravity", "centrifugal") else "must be 'gravity' or 'centrifugal'",
             "load kind"),
    "acceleration": (list, False, None, "gravity acceleration vector, mm/s²"),
    "angular_velocity": (list, False, None, "rotation vector, rad/s (centrifugal)"),
    "axis_point": (list, False, None, "a point of the rotation axis, mm"),
    "history": (str, True, lambda v: None if v in ("ramp", "cyclic", "constant") else
                "must be 'ramp', 'cyclic' or 'constant'", "time shape"),
}


TOP_LEVEL = ("scene", "materials", "bodies", "bolts", "contact", "loads", "motions", "body_loads",
             "procedure", "mbs", "coupling")


OPTIONAL_TABLES = ("bolts",)


def _suggest(key: str, known) -> str:
    close = difflib.get_close_matches(key, list(known), n=1, cutoff=0.6)
    return f" (did you mean '{close[0]}'?)" if close else ""


def _check_table(table, schema, where, problems) -> bool:
    """Report the table's problems; True when its structure is sound: a table with every required
    key, and every key that is not a number of the right type (numbers out of range or of the
    wrong type are problems, but the cross-reference checks do not read them as containers)."""
    if not isinstance(table, dict):
        problems.append(f"'{where}' must be a table")
        return False
    sound = True
    for key in table:
        if key not in schema:
            problems.append(f"unknown key '{where}.{key}'{_suggest(key, schema)}")
    for key, (types, required, check, meaning) in schema.items():
        if key not in table:
            if required:
                problems.append(f"missing key '{where}.{key}' ({meaning})")
                sound = False
            continue
        value = table[key]
        if isinstance(value, bool) and types is not bool and bool not in (types if isinstance(types, tuple) else (types,)):
            problems.append(f"'{where}.{key}' must be a number, got {value!r}")
            sound = sound and types is NUMBER
            continue
        if not isinstance(value, types):
            expected = _type_name(types)
            problems.append(f"'{where}.{key}' must be {expected} ({meaning}), got {value!r}")
            sound = sound and types is NUMBER
            continue
        if isinstance(value, float) and not math.isfinite(value) and not (
                value == math.inf and f"{where}.{key}" in UNBOUNDED):
            # a key that also takes words or lists (cycle_jump = "auto") says its own alternatives
            said = check(value) if check is not None and types not in (NUMBER, float) else None
            problems.append(f"'{where}.{key}' {said or _finite_requirement(check)} ({meaning}), got {value!r}")
            continue
        if check is not None:
            message = check(value)
            if message:
                problems.append(f"'{where}.{key}' {message} ({meaning}), got {value!r}")
    return sound


_TYPE_NAMES = {int: "an integer", float: "a number", str: "a string", bool: "true or false", list: "a list",
               dict: "a table"}


def _type_name(types) -> str:
    """'a number', 'a table or a list': what a key of ``types`` must be, in words."""
    if types == NUMBER or not isinstance(types, tuple):
        return _TYPE_NAMES.get(types, "a number")
    names = ["a number"] if set(NUMBER) <= set(types) else []
    names += [_TYPE_NAMES[t] for t in types if t not in NUMBER or not names]
    return " or ".join(names)


def _finite_requirement(check) -> str:
    """'must be a finite number > 0': the finiteness every number needs, with what ``check``
    asks (said as it refuses NaN, which no range holds)."""
    asked = check(math.nan) if check is not None else None
    if not asked:
        return "must be a finite number"
    if asked.startswith("must be "):
        return "must be a finite number " + asked.removeprefix("must be ")
    return "must be a finite number and " + asked.removeprefix("must ")


#: arrays of tables and the keys of their entries
ENTRY_KEYS = {"loads": PATTERN_KEYS, "motions": PATTERN_KEYS, "body_loads": BODY_LOAD_KEYS}


def unknown_key(dotted: str) -> str | None:
    """Why the dotted key of an override ("procedure.cof_cycles", "bodies.plane.mesh.contact_size",
    "motions.0.value") names no key a scene has, with "did you mean"; None when it may name one.
    Below a key whose value is a table of free form (a mesh, a selection) and in [mbs] (its own
    module's keys) anything goes: validation judges the scene it makes."""
    keys = dotted.split(".")
    if keys[0] not in TOP_LEVEL:
        return f"a scene has no table '{keys[0]}'{_suggest(keys[0], TOP_LEVEL)}"
    if keys[0] in SCHEMA:
        schema, depth = SCHEMA[keys[0]], 1
    elif f"{keys[0]}.*" in SCHEMA:
        schema, depth = SCHEMA[f"{keys[0]}.*"], 2
    elif keys[0] in ENTRY_KEYS:
        schema, depth = ENTRY_KEYS[keys[0]], 2
    else:
        return None
    if len(keys) <= depth or keys[depth] in schema:
        return None
    table = ".".join(keys[:depth])
    return f"'{table}' has no key '{keys[depth]}'{_suggest(keys[depth], schema)}"


def _misplaced_base(data: dict) -> str:
    """The one problem of a scene with ``base`` above its tables: the base is not read, so the
    tables it would give are missing, and saying each of them would bury the cause."""
    line = f'base = "{data["base"]}"' if isinstance(data["base"], str) else "base = \"...\""
    return (f"'{line}' stands above the first table, so it is no key of [scene] and no base is read: move "
            "it to a line below [scene]; the scene's other problems are listed once its base is read")


def validate(data: dict, source: str = "scene") -> list[str]:
    """All problems of a parsed scene, each a sentence naming its key; empty when valid.

    The schema is checked first, table by table; each semantic check (cross-references, effects,
    selections) then runs when the tables it reads are sound in structure (:func:`_check_table`):
    a malformed table has been reported, and its cross-references cannot be followed. A ``base``
    above the first table is the one problem said (:func:`_misplaced_base`)."""
    # checks.py reads this module's tables, so it is imported here rather than at the top
    from pipelines.scene.checks import SEMANTIC_CHECKS

    problems: list[str] = []
    if "base" in data:
        return [_misplaced_base(data)]
    for key in data:
        if key not in TOP_LEVEL:
            problems.append(f"unknown table '{key}'{_suggest(key, TOP_LEVEL)}")
    broken = set()
    for section in ("scene", "contact"):
        if section not in data:
            problems.append(f"missing table '[{section}]'")
            broken.add(section)
    for section, schema in SCHEMA.items():
        if section.endswith(".*"):
            parent = section[:-2]
            entries = data.get(parent, {})
            if parent in OPTIONAL_TABLES and parent not in data:
                continue
            if not isinstance(entries, dict) or not entries:
                problems.append(f"'[{parent}]' must define at least one named entry")
                broken.add(parent)
                continue
            sound = [_check_table(table, schema, f"{parent}.{name}", problems) for name, table in entries.items()]
            if not all(sound):
                broken.add(parent)
        elif section in data and not _check_table(data[section], schema, section, problems):
            broken.add(section)
    for check, tables in SEMANTIC_CHECKS:
        if not broken.intersection(tables):
            check(data, problems)
    return problems
