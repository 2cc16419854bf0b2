"""The keys of a scene file, their types, ranges and meaning, and the validation of a parsed scene.

:func:`validate` checks the schema table by table, then the cross-references (bodies,
materials, reference points, selections, effects) of the tables the schema found sound, and
returns every problem at once, each a sentence naming its key, with "did you mean" for typos.
Units: mm, N, MPa, t, s, mJ (see the README's scene reference).
"""

from __future__ import annotations

import difflib


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


NUMBER = (int, float)
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
        "fixed": (dict, False, None, "{ nodes = selection, components = [...] }"),
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
    },
    "coupling": {
        "body": (str, True, None, "the contact body that is the counterweight"),
        "counterweight": (int, False, _integer_at_least(1), "which CW of the multibody model (1 = first)"),
        "cycle": (str, False, lambda v: None if v in ("wing_period", "revolution") else
                  "must be 'wing_period' or 'revolution'", "what one contact load cycle is"),
        "wing_amplitude": (NUMBER, False, _positive, "wing vibration amplitude, mm (default: from the multibody run)"),
        "fields": (str, False, lambda v: None if v in ("all", "wing_mode") else "must be 'all' or 'wing_mode'",
                   "which inertia fields load the CW"),
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
                           "adaptive jump: the largest J"),
        "life_cycles": (NUMBER, False, _positive, "real cycles the wear phase stands for at most"),
        "cof_during_wear": (bool, False, None, "keep COF evolving in the wear phase"),
        "wear_cap": (NUMBER, False, _positive, "largest wear increment per step, mm"),
        "stationary_window": (int, False, _integer_at_least(1), "cycles without slip for shakedown"),
        "loosening_window": (int, False, _integer_at_least(3), "cycles of falling clamp force"),
        "max_cutbacks": (int, False, _integer_at_least(0), "halvings of a failing increment"),
        "record_every": (int, False, _integer_at_least(1), "store fields every n cycles"),
        "checkpoint_every": (int, False, _integer_at_least(0), "write checkpoint.h5 every n cycles (0: never)"),
    },
}


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
            expected = types.__name__ if isinstance(types, type) else "number"
            problems.append(f"'{where}.{key}' must be a {expected} ({meaning}), got {value!r}")
            sound = sound and types is NUMBER
            continue
        if check is not None:
            message = check(value)
            if message:
                problems.append(f"'{where}.{key}' {message} ({meaning}), got {value!r}")
    return sound


def _check_selection(selection, where, dim, problems):
    if not isinstance(selection, dict):
        problems.append(f"'{where}' must be a table (a selection: box, boxes, axis and value, ring or set)")
        return
    keys = set(selection) - {"body"}
    if not keys:
        problems.append(f"'{where}' needs a selection: box = [[min...], [max...]], boxes = [box, ...], axis = ... with "
                        "value = ..., ring = {{ center, axis, inner_radius, outer_radius }}, "
                        "or set = \"name\" (a node set of the mesh file)")
    for key in keys:
        if key == "set":
            if not isinstance(selection["set"], str) or not selection["set"]:
                problems.append(f"'{where}.set' must be the name of a node set of the body's mesh file")
            continue
        if key == "ring":
            ring = selection["ring"]
            if not (isinstance(ring, dict) and isinstance(ring.get("center"), list) and len(ring["center"]) == dim
                    and ring.get("axis") in ("x", "y", "z")[:dim]
                    and isinstance(ring.get("inner_radius"), NUMBER) and isinstance(ring.get("outer_radius"), NUMBER)
                    and 0 <= ring["inner_radius"] < ring["outer_radius"]):
                problems.append(f"'{where}.ring' needs center ({dim} mm), axis, 0 <= inner_radius < outer_radius (mm)")
            continue
        if key in ("box", "boxes"):
            boxes = [selection["box"]] if key == "box" else selection["boxes"]
            if not isinstance(boxes, list) or not boxes or not all(
                    isinstance(box, list) and len(box) == 2 and all(
                        isinstance(c, list) and len(c) == dim and all(isinstance(v, NUMBER) for v in c) for c in box)
                    for box in boxes):
                shape = f"[[min x, y{', z' if dim == 3 else ''}], [max ...]]"
                problems.append(f"'{where}.{key}' must be {shape if key == 'box' else '[' + shape + ', ...]'} in mm")
        elif key == "axis":
            if selection["axis"] not in ("x", "y", "z")[:dim]:
                problems.append(f"'{where}.axis' must be one of {('x', 'y', 'z')[:dim]}")
            if not isinstance(selection.get("value"), NUMBER):
                problems.append(f"'{where}.value' must be the coordinate (mm) of the plane")
        elif key not in ("value", "tolerance"):
            problems.append(f"unknown key '{where}.{key}'{_suggest(key, ['box', 'boxes', 'axis', 'value', 'tolerance'])}")


def validate(data: dict, source: str = "scene") -> list[str]:
    """All problems of a parsed scene, each a sentence naming its key; empty when valid.

    The schema is checked first, table by table; each semantic check (cross-references, effects,
    selections) then runs when the tables it reads are sound in structure (:func:`_check_table`):
    a malformed table has been reported, and its cross-references cannot be followed."""
    problems: list[str] = []
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


def _check_patterns(data, problems):
    names = set()
    for kind in ("loads", "motions"):
        entries = data.get(kind, [])
        if not isinstance(entries, list):
            problems.append(f"'{kind}' must be an array of tables ([[{kind}]])")
            continue
        for k, entry in enumerate(entries):
            _check_table(entry, PATTERN_KEYS, f"{kind}[{k}]", problems)
            name = entry.get("name") if isinstance(entry, dict) else None
            if isinstance(name, str) and name in names:
                problems.append(f"'{kind}[{k}].name' '{name}' is used twice")
            if isinstance(entry, dict):
                names.add(name if isinstance(name, str) else f"<{kind}[{k}]>")
                dof = entry.get("dof", "")
                if isinstance(dof, str) and dof.count(".") != 2:
                    problems.append(f"'{kind}[{k}].dof' must read 'body.point.component', got {dof!r}")
    for k, entry in enumerate(data.get("body_loads", []) if isinstance(data.get("body_loads", []), list) else []):
        _check_table(entry, BODY_LOAD_KEYS, f"body_loads[{k}]", problems)
        if not isinstance(entry, dict):
            continue
        name = entry.get("name")
        if isinstance(name, str) and name in names:
            problems.append(f"'body_loads[{k}].name' '{name}' is used twice")
        names.add(name if isinstance(name, str) else f"<body_loads[{k}]>")
        body = data.get("bodies", {}).get(entry["body"]) if isinstance(entry.get("body"), str) else None
        if body is None:
            problems.append(f"'body_loads[{k}].body' must name one of the bodies")
        elif "density" not in data.get("materials", {}).get(body.get("material"), {}):
            problems.append(f"'body_loads[{k}]' acts on body '{entry['body']}', whose material has no density")
        needed = "acceleration" if entry.get("kind") == "gravity" else "angular_velocity"
        if entry.get("kind") in ("gravity", "centrifugal") and needed not in entry:
            problems.append(f"'body_loads[{k}].{needed}' is missing for a {entry['kind']} load")
    if not names and "coupling" not in data:
        problems.append("the scene has no [[loads]], [[motions]] or [coupling]")


def _check_effects(data, problems):
    for effect in data["scene"]["effects"]:
        if effect not in KNOWN_EFFECTS:
            problems.append(f"unknown effect '{effect}' in 'scene.effects'{_suggest(str(effect), KNOWN_EFFECTS)}")
        elif effect not in CONTACT_EFFECTS and "coupling" not in data:
            problems.append(f"effect '{effect}' in 'scene.effects' acts through the multibody model and "
                            "needs a [coupling] table")
    if "coupling" in data:
        coupling = data["coupling"]
        body = data.get("bodies", {}).get(coupling.get("body"))
        if body is None:
            problems.append(f"'coupling.body' must name one of the bodies ({', '.join(data.get('bodies', {}))})")
        elif "density" not in data.get("materials", {}).get(body.get("material"), {}):
            problems.append(f"'coupling.body' is '{coupling['body']}', whose material has no density "
                            "(the coupling loads it with its inertia)")
        if data["scene"]["dimension"] != 3:
            problems.append("a scene with [coupling] must be 3D ('scene.dimension' = 3)")
        mbs_effects = data.get("mbs", {}).get("effects") if isinstance(data.get("mbs"), dict) else None
        if mbs_effects is not None:
            problems.append("'mbs.effects' is set by 'scene.effects' in a coupled scene: list the multibody "
                            f"effects {MULTIBODY_EFFECTS} there")


def _check_bodies(data, problems):
    dim = data["scene"]["dimension"]
    materials, bodies = data["materials"], data["bodies"]
    for name, body in bodies.items():
        if body["material"] not in materials:
            problems.append(f"'bodies.{name}.material' names '{body['material']}', which is not in [materials]")
        mesh = body["mesh"]
        if "generator" in mesh:
            generator = mesh["generator"]
            if not isinstance(generator, str):
                problems.append(f"'bodies.{name}.mesh.generator' must name a generator ({', '.join(MESH_GENERATORS)})")
            elif generator not in MESH_GENERATORS:
                problems.append(f"'bodies.{name}.mesh.generator' '{generator}' is unknown"
                                f"{_suggest(generator, MESH_GENERATORS)}")
            else:
                for key in MESH_GENERATORS[generator]:
                    if not isinstance(mesh.get(key), NUMBER) or mesh.get(key) <= 0:
                        problems.append(f"'bodies.{name}.mesh.{key}' must be a positive number (mm or count)")
        elif "file" not in mesh:
            problems.append(f"'bodies.{name}.mesh' needs 'generator' or 'file'")
        if "fixed" in body:
            fixed = body["fixed"]
            if "nodes" not in fixed:
                problems.append(f"'bodies.{name}.fixed.nodes' is missing (a selection)")
            else:
                _check_selection(fixed["nodes"], f"bodies.{name}.fixed.nodes", dim, problems)
            components = fixed.get("components", [])
            for comp in components if isinstance(components, list) else [components]:
                if comp not in ("ux", "uy", "uz")[:dim]:
                    problems.append(f"'bodies.{name}.fixed.components' has '{comp}'; use ux, uy{', uz' if dim == 3 else ''}")
        for ref_name, ref in body.get("reference_points", {}).items():
            where = f"bodies.{name}.reference_points.{ref_name}"
            if not isinstance(ref, dict):
                problems.append(f"'{where}' must be a table {{ nodes = selection, position = [...] }}")
                continue
            for key in ref:
                if key not in ("nodes", "position", "rotations"):
                    problems.append(f"unknown key '{where}.{key}'{_suggest(key, ['nodes', 'position', 'rotations'])}")
            if "nodes" not in ref:
                problems.append(f"'{where}.nodes' is missing (a selection)")
            else:
                _check_selection(ref["nodes"], f"{where}.nodes", dim, problems)
            position = ref.get("position")
            if not (isinstance(position, list) and len(position) == dim):
                problems.append(f"'{where}.position' must be {dim} coordinates in mm")


def _check_contact(data, problems):
    scene, bodies, dim = data["scene"], data["bodies"], data["scene"]["dimension"]
    contact = data["contact"]
    for role in ("slave", "master"):
        selection = contact[role]
        if not isinstance(selection.get("body"), str) or selection["body"] not in bodies:
            problems.append(f"'contact.{role}.body' must name one of the bodies ({', '.join(bodies)})")
        _check_selection(selection, f"contact.{role}", dim, problems)
    if (isinstance(contact["cof_max"], NUMBER) and isinstance(contact["cof_initial"], NUMBER)
            and contact["cof_max"] < contact["cof_initial"]):
        problems.append("'contact.cof_max' must be >= 'contact.cof_initial'")
    wear = contact.get("wear_coefficients", [0.0, 0.0])
    if len(wear) != 2 or not all(isinstance(w, NUMBER) and w >= 0 for w in wear):
        problems.append("'contact.wear_coefficients' must be two non-negative numbers [slave, master], mm²/N")
    if "wear" in scene["effects"] and not any(wear):
        problems.append("effect 'wear' is listed but 'contact.wear_coefficients' are zero or missing")
    if "cof_evolution" in scene["effects"] and not contact.get("cof_rate"):
        problems.append("effect 'cof_evolution' is listed but 'contact.cof_rate' is zero or missing")


def _check_bolts(data, problems):
    bolts, effects = data.get("bolts", {}), data["scene"]["effects"]
    if bolts and "bolts" not in effects:
        problems.append("[bolts] are defined but 'bolts' is not in 'scene.effects'")
    if "bolts" in effects and not bolts:
        problems.append("effect 'bolts' is listed but no [bolts.NAME] table defines a bolt")
    dim = data["scene"]["dimension"]
    for name, bolt in bolts.items():
        axis = bolt["axis"]
        if len(axis) != dim or not any(axis):
            problems.append(f"'bolts.{name}.axis' must be a nonzero vector of {dim} numbers")
        for end in ("head", "nut"):
            body, _, point = bolt[end].partition(".")
            if point not in data["bodies"].get(body, {}).get("reference_points", {}):
                problems.append(f"'bolts.{name}.{end}' names '{bolt[end]}', which is not a reference point")


#: Semantic checks and the tables each reads (run when the schema found those tables sound).
SEMANTIC_CHECKS = ((_check_effects, ("scene", "materials", "bodies", "coupling")),
                   (_check_bodies, ("scene", "materials", "bodies")),
                   (_check_contact, ("scene", "bodies", "contact")),
                   (_check_bolts, ("scene", "bodies", "bolts")),
                   (_check_patterns, ("materials", "bodies")))
