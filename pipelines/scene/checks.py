"""The semantic checks of a scene: cross-references between its tables (bodies, materials,
reference points, bolts, patterns), node selections and effects.

Each check appends its problems, sentences naming their key, to a list; :func:`pipelines.scene.schema.validate`
runs a check only when the schema found the tables it reads (:data:`SEMANTIC_CHECKS`) sound in structure.
:func:`plausibility` warns of magnitudes that are likely unit mistakes; :func:`mesh_unit_problem`
compares a mesh file's size, once it is read, with the scene's lengths for its body (a mesh in metres);
:func:`bolt_tilt_finding` and :func:`ring_offset_finding` judge a bolt against the built mesh (its axis
against the joint's normal, its ends' reference points against the nodes they couple), refusing or
warning (:class:`SceneWarning`).
Units: mm, N, MPa, t, s, mJ (see the README's scene reference).
"""

from __future__ import annotations

import inspect
import math

from contact.procedure import Procedure
from mbs.scene import mbs_table_problems
from reduction.errors import listed
from reduction.mesh import generators
from reduction.mesh.generators import MAX_GENERATED_NODES, least_nodes
from pipelines.scene.schema import (
    BODY_LOAD_KEYS,
    CONTACT_EFFECTS,
    KNOWN_EFFECTS,
    MESH_GENERATORS,
    MULTIBODY_EFFECTS,
    NUMBER,
    PATTERN_KEYS,
    _check_table,
    _suggest,
    finite,
    finite_list,
)


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
            if not (isinstance(ring, dict) and finite_list(ring.get("center"), dim)
                    and ring.get("axis") in ("x", "y", "z")[:dim]
                    and finite(ring.get("inner_radius")) and finite(ring.get("outer_radius"))
                    and 0 <= ring["inner_radius"] < ring["outer_radius"]):
                problems.append(f"'{where}.ring' needs center ({dim} finite numbers, mm), axis, "
                                "0 <= inner_radius < outer_radius (finite, mm)")
            continue
        if key in ("box", "boxes"):
            boxes = [selection["box"]] if key == "box" else selection["boxes"]
            if not isinstance(boxes, list) or not boxes or not all(
                    isinstance(box, list) and len(box) == 2 and all(finite_list(c, dim) for c in box)
                    for box in boxes):
                shape = f"[[min x, y{', z' if dim == 3 else ''}], [max ...]]"
                problems.append(f"'{where}.{key}' must be {shape if key == 'box' else '[' + shape + ', ...]'}: finite "
                                f"numbers in mm, got {boxes if key == 'boxes' else boxes[0]!r}")
            else:
                problems += [f"'{where}.{key}' has its min corner {low} above its max corner {high} in "
                             f"{listed(['xyz'[i] for i in range(dim) if low[i] > high[i]])}: it selects nothing; "
                             "give [[min x, y...], [max x, y...]]" for low, high in boxes
                             if any(lo > hi for lo, hi in zip(low, high))]
        elif key == "axis":
            if selection["axis"] not in ("x", "y", "z")[:dim]:
                problems.append(f"'{where}.axis' must be one of {('x', 'y', 'z')[:dim]}")
            if not finite(selection.get("value")):
                problems.append(f"'{where}.value' must be the coordinate (mm, a finite number) of the plane, "
                                f"got {selection.get('value')!r}")
        elif key == "tolerance":
            if not (finite(selection["tolerance"]) and selection["tolerance"] >= 0):
                problems.append(f"'{where}.tolerance' must be a finite number >= 0 (mm), "
                                f"got {selection['tolerance']!r}")
        elif key != "value":
            problems.append(f"unknown key '{where}.{key}'{_suggest(key, ['box', 'boxes', 'axis', 'value', 'tolerance'])}")


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
    problems += _loaded_and_moved(data)
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
        for key in ("acceleration", "angular_velocity", "axis_point"):
            if key in entry and not finite_list(entry[key]):
                problems.append(f"'body_loads[{k}].{key}' must be a list of finite numbers, got {entry[key]!r}")
        needed = "acceleration" if entry.get("kind") == "gravity" else "angular_velocity"
        if entry.get("kind") in ("gravity", "centrifugal") and needed not in entry:
            problems.append(f"'body_loads[{k}].{needed}' is missing for a {entry['kind']} load")
    if not names and "coupling" not in data:
        problems.append("the scene has no [[loads]], [[motions]] or [coupling]")


def _loaded_and_moved(data) -> list[str]:
    """A control DOF both loaded (a force, nonzero) and moved (its motion prescribed): the motion
    decides where it goes, and the force would act on nothing."""
    def entries(kind):
        found = data.get(kind, [])
        return [(k, e) for k, e in enumerate(found) if isinstance(e, dict)] if isinstance(found, list) else []

    moved = {}
    for k, motion in entries("motions"):
        if isinstance(motion.get("dof"), str):
            moved.setdefault(motion["dof"], (k, motion.get("name")))
    found = []
    for k, load in entries("loads"):
        dof, value = load.get("dof"), load.get("value")
        if isinstance(dof, str) and dof in moved and not (finite(value) and value == 0):
            m, name = moved[dof]
            found.append(f"'loads[{k}]' ('{load.get('name')}') acts on '{dof}', a DOF whose motion 'motions[{m}]' "
                         f"('{name}') prescribes: a DOF is either loaded (a force) or moved (a motion), not both; "
                         "load another component or drop the motion of this one")
    return found


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
        if "histories" in coupling and set(data["scene"]["effects"]) & set(MULTIBODY_EFFECTS):
            problems.append("'coupling.histories' replaces the multibody run: remove the multibody effects "
                            f"{sorted(set(data['scene']['effects']) & set(MULTIBODY_EFFECTS))} from 'scene.effects'")
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
                problems += _generator_key_problems(name, generator, mesh)
                bad = [key for key in MESH_GENERATORS[generator] if not (finite(mesh.get(key)) and mesh[key] > 0)]
                problems += [f"'bodies.{name}.mesh.{key}' must be a finite number > 0 (mm or count), got {mesh[key]!r}"
                             if key in mesh else f"missing key 'bodies.{name}.mesh.{key}' (a finite number > 0, mm "
                             f"or count) of the mesh generator {generator}" for key in bad]
                if not bad:  # their order (contact_size <= contact_half_width < half_width) is the generator's
                    problems += _mesh_size_problems(name, mesh)
        elif "file" not in mesh:
            problems.append(f"'bodies.{name}.mesh' needs 'generator' or 'file'")
        fixed = body.get("fixed", [])
        for where, table in ([("fixed", fixed)] if isinstance(fixed, dict) else
                             [(f"fixed[{k}]", table) for k, table in enumerate(fixed)]):
            if not isinstance(table, dict):
                problems.append(f"'bodies.{name}.{where}' must be a table {{ nodes = selection, components = [...] }}")
            elif "nodes" not in table:
                problems.append(f"'bodies.{name}.{where}.nodes' is missing (a selection)")
            else:
                _check_selection(table["nodes"], f"bodies.{name}.{where}.nodes", dim, problems)
            components = table.get("components", []) if isinstance(table, dict) else []
            for comp in components if isinstance(components, list) else [components]:
                if comp not in ("ux", "uy", "uz")[:dim]:
                    problems.append(f"'bodies.{name}.{where}.components' has '{comp}'; use ux, uy{', uz' if dim == 3 else ''}")
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
            if not finite_list(position, dim):
                problems.append(f"'{where}.position' must be {dim} coordinates in mm (finite numbers), got {position!r}")


def _generator_key_problems(name: str, generator: str, mesh: dict) -> list[str]:
    """Keys of a generated mesh that its generator does not take (a typo: 'raduis')."""
    accepted = list(inspect.signature(getattr(generators, generator)).parameters)
    return [f"unknown key 'bodies.{name}.mesh.{key}'{_suggest(key, accepted)}: the mesh generator {generator} of "
            f"body '{name}' takes {listed(accepted)}" for key in mesh if key != "generator" and key not in accepted]


def _mesh_size_problems(name: str, mesh: dict) -> list[str]:
    """A generated mesh too large to build (:data:`MAX_GENERATED_NODES`), counted before meshing:
    most likely a contact size in metres."""
    args = {key: value for key, value in mesh.items() if key != "generator"}
    try:
        found = least_nodes(mesh["generator"], args)
    except (TypeError, ValueError, ZeroDivisionError):  # an extra argument of the wrong type: make_mesh says so
        return []
    if found is None or not found[0] > MAX_GENERATED_NODES:  # not: a NaN size is no count
        return []
    nodes, key = found
    value = mesh[key]
    hint = (f"{key} is in mm: if {value:g} was meant in metres, write {1e3 * value:g}" if key == "contact_size"
            else "use fewer elements")
    return [f"'bodies.{name}.mesh.{key}' = {value:g} would generate a mesh of at least {nodes:,.0f} nodes in its "
            f"contact zone alone, more than the {MAX_GENERATED_NODES:,} a generated mesh may have (it would not "
            f"fit in memory); {hint}"]


def _check_contact(data, problems):
    scene, bodies, dim = data["scene"], data["bodies"], data["scene"]["dimension"]
    contact = data["contact"]
    for role in ("slave", "master"):
        selection = contact[role]
        if not isinstance(selection.get("body"), str) or selection["body"] not in bodies:
            problems.append(f"'contact.{role}.body' must name one of the bodies ({', '.join(bodies)})")
        _check_selection(selection, f"contact.{role}", dim, problems)
    if contact["slave"].get("body") == contact["master"].get("body") and contact["slave"].get("body") in bodies:
        problems.append(f"'contact.slave.body' and 'contact.master.body' select the same body "
                        f"'{contact['slave']['body']}': the contact is between two bodies; name the other one "
                        f"({', '.join(b for b in bodies if b != contact['slave']['body']) or 'none defined'}) "
                        "in one of them")
    if (isinstance(contact["cof_max"], NUMBER) and isinstance(contact["cof_initial"], NUMBER)
            and contact["cof_max"] < contact["cof_initial"]):
        problems.append("'contact.cof_max' must be >= 'contact.cof_initial'")
    wear = contact.get("wear_coefficients", [0.0, 0.0])
    if not (finite_list(wear, 2) and all(w >= 0 for w in wear)):
        problems.append(f"'contact.wear_coefficients' must be two finite numbers >= 0 [slave, master], mm²/N, "
                        f"got {wear!r}")
        wear = None  # said above: whether it is zero is no question
    if "wear" in scene["effects"] and wear is not None and not any(wear):
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
        if not finite_list(axis, dim) or not any(axis):
            problems.append(f"'bolts.{name}.axis' must be a nonzero vector of {dim} finite numbers, got {axis!r}")
            axis = None
        elif not abs(math.hypot(*axis) - 1.0) <= _UNIT_TOLERANCE:  # not: a NaN component is no unit vector
            problems.append(f"'bolts.{name}.axis' = {axis} has length {math.hypot(*axis):g}: it must be a unit "
                            f"vector (from head to nut), e.g. {[round(a / math.hypot(*axis), 6) + 0.0 for a in axis]}")
            axis = None
        ends = {}
        for end in ("head", "nut"):
            body, _, point = bolt[end].partition(".")
            reference = data["bodies"].get(body, {}).get("reference_points", {}).get(point)
            if reference is None:
                problems.append(f"'bolts.{name}.{end}' names '{bolt[end]}', which is not a reference point")
            else:
                ends[end] = (body, reference)
        if len(ends) < 2:
            continue
        (head_body, head), (nut_body, nut) = ends["head"], ends["nut"]
        if head_body == nut_body:
            problems.append(f"'bolts.{name}.head' ('{bolt['head']}') and 'bolts.{name}.nut' ('{bolt['nut']}') are on "
                            f"the same body '{head_body}': a bolt clamps two bodies, its head on one and its nut "
                            "(or thread) on the other")
        elif axis is not None:
            positions = [end.get("position") if isinstance(end, dict) else None for end in (head, nut)]
            problems += _bolt_axis_problems(name, bolt, axis, *positions, dim)


#: |axis| within this of 1; the axis within this angle of the head-to-nut direction, degrees
_UNIT_TOLERANCE = 1e-6
_AXIS_ANGLE_DEG = 1.0


def _bolt_axis_problems(name, bolt, axis, head, nut, dim) -> list[str]:
    """The bolt's axis against the direction from its head's reference-point position to its
    nut's, when both are known (a bolt whose axis points the other way pulls its ends apart, and
    a tilted one shears the joint instead of clamping it)."""
    if not all(isinstance(p, list) and len(p) == dim and all(finite(c) for c in p) for p in (head, nut)):
        return []
    span = [b - a for a, b in zip(head, nut)]
    length = math.hypot(*span)
    if length == 0.0:
        return []
    cosine = sum(a * d for a, d in zip(axis, span)) / length
    angle = math.degrees(math.acos(max(-1.0, min(1.0, cosine))))
    if angle <= _AXIS_ANGLE_DEG:
        return []
    direction = [round(d / length, 6) + 0.0 for d in span]
    how = "points from the nut to the head" if angle > 179.0 else f"is {angle:.3g}° off the line from head to nut"
    return [f"'bolts.{name}.axis' = {axis} {how}: the reference points' positions "
            f"('{bolt['head']}' at {head}, '{bolt['nut']}' at {nut} mm) give the direction {direction}; "
            "the axis must point from the head to the nut"]


class SceneWarning(UserWarning):
    """A scene that builds and runs but most likely does not model what was meant (a bolt that
    shears its joint, a reference point away from the nodes it couples). Issued with
    :func:`warnings.warn` while the model is built; the command line says it as
    ``fretwork: warning: ...``."""


#: A bolt whose axis is tilted by θ from the joint's normal pulls the clamped parts sideways,
#: against each other, with sin θ of its force, and clamps them with only cos θ of it: friction
#: must carry that shear before any load does (it slips once tan θ exceeds μ). Above
#: BOLT_TILT_WARN_DEG the shear is over 5 % of the pretension, a quarter of the friction at
#: μ = 0.2, and the joint reads weaker than its bolt makes it; a drawing or mesh tolerance stays
#: well below. Beyond BOLT_TILT_REFUSED_DEG the axis lies nearer the joint's plane than its
#: normal: the shear exceeds the clamp force, which no friction coefficient of a metal joint
#: (μ < 1) carries, so the bolt clamps nothing.
BOLT_TILT_WARN_DEG = 3.0
BOLT_TILT_REFUSED_DEG = 45.0
#: The joint's normal at a bolt is the mean over the contact facets within this many ring radii
#: (:func:`contact.bolts.ring_offset`) of its axis: a few bolt diameters, where it clamps.
BOLT_NEAR_RINGS = 3.0


def bolt_tilt_finding(name: str, tilt: float, where: str, cof: float) -> tuple[str | None, str | None]:
    """(problem, warning) of bolt ``name`` whose axis lies ``tilt`` degrees off the joint's
    normal (``where``: over which facets it was taken); ``cof``: the initial μ."""
    said = (f"'bolts.{name}.axis' is {tilt:.3g}° off the joint's normal ({where}), "
            f"{90.0 - tilt:.3g}° from its plane")
    if tilt > BOLT_TILT_REFUSED_DEG:
        return (said + ": a bolt that far from the normal clamps nothing (it pulls the parts along the "
                "joint more than across it); give the axis across the joint, from head to nut"), None
    if tilt > BOLT_TILT_WARN_DEG:
        shear, ratio = math.sin(math.radians(tilt)), math.tan(math.radians(tilt))
        against = (f"above 'contact.cof_initial' = {cof:g}: friction alone cannot hold it" if ratio > cof else
                   f"{ratio / cof:.0%} of 'contact.cof_initial' = {cof:g}")
        return None, (said + f": it pulls the joint sideways with sin θ = {shear:.1%} of its pretension, which "
                      f"friction must carry before any load (tan θ = {ratio:.3g}, {against}); if the bolt is meant "
                      "square to the joint, correct its axis and its reference points' positions")
    return None, None


#: A bolt end's reference point off the centre of the ring it couples (RBE2 with rotations)
#: puts the bolt's force on the ring with a lever arm d across the axis: for nodes at radius r
#: around the centre the moment F·d changes the bearing pressure by about ±2·d/r, ±50 % at
#: RING_OFFSET_WARN = 1/4 of the ring's radius, so the head bears on one side (a reference point
#: meant at the ring's centre, misplaced or on a node set of another bolt). A position farther
#: from the centre than RING_OFFSET_REFUSED times the ring's largest extent (its farthest node)
#: lies beyond any part of a ring (a half or quarter ring on symmetry planes stays within it):
#: the position or the node set belongs to another bolt end. Below RING_OFFSET_FLOOR (mm), the
#: rounding of a position written to two decimals, nothing is said, and below RING_REFUSED_FLOOR
#: (mm) nothing refused (a ring of a node or two has no extent to measure against).
RING_OFFSET_WARN = 0.25
RING_OFFSET_REFUSED = 2.0
RING_OFFSET_FLOOR = 0.01
RING_REFUSED_FLOOR = 1.0


def ring_offset_finding(key: str, position, ring) -> tuple[str | None, str | None]:
    """(problem, warning) of the reference point ``key`` ('bodies.B.reference_points.P') of a bolt
    end at ``position`` (mm) against the ring of nodes it couples, a
    :class:`contact.bolts.RingOffset`."""
    def at(point):
        return [round(float(c), 3) + 0.0 for c in point]

    said = (f"'{key}.position' {at(position)} is {ring.distance:.3g} mm from the centre {at(ring.centre)} "
            f"of the nodes it couples ('{key}.nodes', a ring of radius {ring.radius:.3g} mm")
    if ring.distance > max(RING_OFFSET_REFUSED * ring.extent, RING_REFUSED_FLOOR):
        return (said + f", all within {ring.extent:.3g} mm of its centre): the position or the node set "
                "belongs to another bolt end; give the centre of the ring as the position, or the ring's own "
                "node set"), None
    if ring.lever > max(RING_OFFSET_WARN * ring.radius, RING_OFFSET_FLOOR):
        pressure = f"about ±{2 * ring.lever / ring.radius:.0%}" if ring.radius > 0 else "all of it"
        return None, (said + f"), {ring.lever:.3g} mm across the bolt's axis: the bolt pulls the ring off its "
                      f"centre and, with rotations coupled, tilts it (bearing pressure {pressure} round the "
                      "ring); give the centre of the ring as the position, or couple nodes centred on it")
    return None, None


def held_groups(data) -> list[list[str]]:
    """The bodies in groups joined by the contact or a bolt, each group a list of names."""
    bodies, contact = list(data["bodies"]), data["contact"]
    group = {name: {name} for name in bodies}
    joins = [(contact["slave"].get("body"), contact["master"].get("body"))]
    joins += [tuple(str(bolt.get(end, "")).partition(".")[0] for end in ("head", "nut"))
              for bolt in data.get("bolts", {}).values() if isinstance(bolt, dict)]
    for a, b in joins:
        if isinstance(a, str) and isinstance(b, str) and a in group and b in group and group[a] is not group[b]:
            merged = group[a] | group[b]
            for name in merged:
                group[name] = merged
    groups = []
    for name in bodies:
        if group[name] not in groups:
            groups.append(group[name])
    return [[name for name in bodies if name in members] for members in groups]


def _check_support(data, problems):
    """Every group of bodies (joined by the contact or bolts) is held against rigid-body motion: one
    of its bodies has a fixed selection, or [[motions]] prescribe each translation of the group.
    Necessary, not sufficient (a support of one component leaves the others free): run before any
    mesh is built, it gives the earlier message; :mod:`pipelines.support` checks every rigid mode
    once the selections are resolved to DOFs."""
    if data["contact"]["slave"].get("body") == data["contact"]["master"].get("body"):
        return  # _check_contact says so: the bodies are not joined as the scene means them to be
    translations = ("ux", "uy", "uz")[:data["scene"]["dimension"]]
    motions = [str(entry.get("dof", "")).split(".") for entry in data.get("motions", [])
               if isinstance(entry, dict)] if isinstance(data.get("motions", []), list) else []
    for members in held_groups(data):
        if any(data["bodies"][name].get("fixed") for name in members):
            continue
        driven = {dof[-1] for dof in motions if len(dof) == 3 and dof[0] in members}
        if set(translations) <= driven:
            continue
        names = " and ".join(f"'{name}'" for name in members)
        who = f"body {names} has" if len(members) == 1 else f"bodies {names} (joined by the contact or bolts) have"
        components = ", ".join(f'"{c}"' for c in translations)
        problems.append(f"{who} no support: no 'bodies.NAME.fixed' selection and no [[motions]] prescribing "
                        f"{', '.join(translations)}, so nothing holds them against rigid-body motion (their "
                        f"stiffness is singular); add a fixed selection, e.g. bodies.{members[-1]}.fixed = "
                        f"{{ nodes = {{ set = \"...\" }}, components = [{components}] }}")


def _check_procedure(data, problems):
    procedure = data.get("procedure", {})
    cof_cycles, wear_cycles = _cycles(procedure)
    if all(isinstance(n, int) and n == 0 for n in (cof_cycles, wear_cycles)):
        problems.append("'procedure.cof_cycles' and 'procedure.wear_cycles' are both 0 (or not given): the "
                        "run would end after the preload with no load cycle to judge; set cof_cycles (COF "
                        "stabilisation cycles) or wear_cycles (wear cycles) to at least 1")
    run_up = procedure.get("vibration_run_up", 0)
    if isinstance(run_up, int) and isinstance(cof_cycles, int) and run_up > cof_cycles:
        problems.append(f"'procedure.vibration_run_up' ({run_up}) must not exceed 'procedure.cof_cycles' "
                        f"({cof_cycles}): the vibration runs up within the COF phase")


def _cycles(procedure: dict) -> tuple:
    """The [procedure] table's cof_cycles and wear_cycles, the Procedure's defaults where not given."""
    return tuple(procedure.get(key, getattr(Procedure, key)) for key in ("cof_cycles", "wear_cycles"))


def idle_procedure(data) -> str | None:
    """Why a valid scene would run no load cycle: no COF cycles, and wear cycles without the
    effect "wear" that runs them (the run would end after the preload with nothing to judge);
    None when it runs one. Not part of :func:`pipelines.scene.schema.validate`: a model that is
    only built (the validation job's patch tests set 'scene.effects' = [] on a wear scene) is
    sound; :func:`pipelines.scene.load` asks it of every scene whose effects it did not set."""
    cof_cycles, wear_cycles = _cycles(data.get("procedure", {}))
    effects = _effects(data)
    if cof_cycles != 0 or not (isinstance(wear_cycles, int) and wear_cycles > 0) or effects is None or "wear" in effects:
        return None
    return (f"'procedure.cof_cycles' is 0 and the wear phase ('procedure.wear_cycles' = {wear_cycles}) runs only "
            f"with \"wear\" in 'scene.effects', which lists {effects or 'no effect'}: the run would end after the "
            "preload with no load cycle to judge; add \"wear\" to 'scene.effects', or set cof_cycles to at least 1")


def _effects(data) -> list | None:
    """The scene's effects, None when [scene] gives no list of them (the schema says so)."""
    scene = data.get("scene")
    effects = scene.get("effects") if isinstance(scene, dict) else None
    return effects if isinstance(effects, list) else None


def _check_mbs(data, problems):
    """The [mbs] table's values as the multibody model reads them (its files are read later)."""
    if "mbs" in data:
        problems += mbs_table_problems(data["mbs"])


#: Semantic checks and the tables each reads (run when the schema found those tables sound).
SEMANTIC_CHECKS = ((_check_effects, ("scene", "materials", "bodies", "coupling")),
                   (_check_bodies, ("scene", "materials", "bodies")),
                   (_check_contact, ("scene", "bodies", "contact")),
                   (_check_bolts, ("scene", "bodies", "bolts")),
                   (_check_patterns, ("materials", "bodies")),
                   (_check_support, ("scene", "bodies", "contact", "bolts")),
                   (_check_procedure, ("procedure",)),
                   (_check_mbs, ()))


# Plausibility: magnitudes that are valid but most likely a unit mistake. Each is a warning
# (the scene still runs), naming the key and the unit it was probably written in.
_METAL_DENSITY = 1.5e-9  # t/mm³: lighter than any structural metal (magnesium 1.7e-9)
_METAL_NAMES = ("steel", "iron", "alumin", "titan", "copper", "brass", "bronze", "metal", "nickel")
#: materials named so may be softer than 1 GPa (E of rubber ~5 MPa, PTFE ~500 MPa): no unit warning
_SOFT_NAMES = ("rubber", "elastomer", "polymer", "plastic", "gasket", "ptfe", "nylon", "epoxy", "foam", "silicone")


#: Engine speeds (rpm) outside this band are most likely written in another unit. The slowest
#: engines with bolted counterweights, large two-stroke marine diesels, run at 60-130 rpm at full
#: load, so below SLOWEST_ENGINE_RPM a speed is most likely in Hz (60 times too low: the default
#: medium-speed engine's 750 rpm is 12.5 Hz; a 1,800 rpm engine is 30 Hz) or rad/s (about 10
#: times too low); a 750 rpm engine in rad/s (78.5) lies among real marine engines' speeds and
#: cannot be told apart. Diesels with bolted counterweights run at up to about 5,000 rpm, petrol
#: car engines up to about 9,000, so above FASTEST_ENGINE_RPM a speed is most likely in degrees
#: per second (6 times too high) or has a digit too many.
SLOWEST_ENGINE_RPM = 30.0
FASTEST_ENGINE_RPM = 10000.0


def _speeds_text(speeds) -> str:
    values = sorted(float(v) for v in speeds)
    if len(values) > 3:
        return f"{len(values)} speeds from {values[0]:g} to {values[-1]:g} rpm are"
    return f"{listed([format(v, 'g') for v in values])} rpm {'is' if len(values) == 1 else 'are'}"


#: A sweep's speeds that all lie below 1/OTHER_UNIT_RATIO of the scene's own engine speed, or all
#: above OTHER_UNIT_RATIO times it, are most likely in another unit than that speed. Read as rpm,
#: speeds in rad/s are 60/2π ≈ 9.55 times too low and speeds in Hz 60 times: a sweep about a 750 rpm
#: engine written in rad/s (62.8-94.2) lies wholly below a fifth of 750 as long as its fastest speed
#: stays below 1.9 times the engine's, which a sweep about an operating speed does. Real speeds
#: wholly below a fifth of the engine's speed would all lie at or below its idle speed (engines with
#: bolted counterweights idle at about 20-40 % of their rated speed), where fretting margins are not
#: asked for. The other way round, a sweep wholly above five times the scene's speed means that
#: speed, at which a coupled scene is calibrated, is below idle: it is itself most likely in rad/s
#: or Hz (78.5 rad/s is 750 rpm), or the sweep is in °/s (6 times too high). A factor of 5 keeps a
#: wide sweep (a run-up from a fifth of the speed) unremarked. A unit is named only if, read in
#: it, the speeds' geometric middle lies within a factor of UNIT_MATCH of the scene's speed (the
#: middle of a sweep from half to twice an operating speed is that speed); speeds that no unit
#: brings near it (1-2 rpm beside 750 rpm) are judged on their own (SLOWEST_ENGINE_RPM …).
OTHER_UNIT_RATIO = 5.0
UNIT_MATCH = 2.0
#: rpm per unit of the units a speed is likely written in instead of rpm
_RPM_PER = {"rad/s": 30.0 / math.pi, "Hz": 60.0, "°/s": 1.0 / 6.0}


def engine_speed_warnings(speeds, named: str, reference_rpm: float | None = None,
                          reference_named: str = "[mbs] speed_rpm") -> list[str]:
    """Warnings about engine speeds (rpm) that are likely a unit mistake, at most one for those
    too slow and one for those too fast; ``named`` says where they were given ('[mbs] speed_rpm',
    '--speeds 5:20:5').

    Without a reference, too slow and too fast are outside :data:`SLOWEST_ENGINE_RPM` …
    :data:`FASTEST_ENGINE_RPM`. With ``reference_rpm``, the engine speed of the same scene
    (``reference_named``: its key), speeds that all lie further than :data:`OTHER_UNIT_RATIO` below
    or above it are said instead, in one warning naming both speeds and the likely unit."""
    speeds = [float(v) for v in speeds if finite(v) and v > 0]
    relative = _other_unit_than_reference(speeds, named, float(reference_rpm), reference_named) \
        if finite(reference_rpm) and reference_rpm > 0 and speeds else None
    side, found = (None, []) if relative is None else (relative[0], [relative[1]])
    slow = [v for v in speeds if v < SLOWEST_ENGINE_RPM]
    fast = [v for v in speeds if v > FASTEST_ENGINE_RPM]
    if slow and side != "below":
        v = min(slow)
        found.append(f"{named}: {_speeds_text(slow)} below {SLOWEST_ENGINE_RPM:g} rpm, slower than any engine "
                     f"runs: probably Hz or rad/s (rpm expected: {v:g} Hz is {60 * v:g} rpm, {v:g} rad/s is "
                     f"{30 * v / math.pi:.4g} rpm)")
    if fast and side != "above":
        v = max(fast)
        found.append(f"{named}: {_speeds_text(fast)} above {FASTEST_ENGINE_RPM:,.0f} rpm, faster than any engine "
                     f"with bolted counterweights runs: probably °/s or a digit too many (rpm expected: "
                     f"{v:g} °/s is {v / 6:.4g} rpm)")
    return found


def _runs(rpm) -> bool:
    """Whether every speed (rpm) is one an engine with bolted counterweights runs at."""
    return all(SLOWEST_ENGINE_RPM <= v <= FASTEST_ENGINE_RPM for v in rpm)


def _range(speeds, unit: str) -> str:
    """'62.8 to 94.2 rad/s is 599.7 to 899.5 rpm': the lowest and highest of speeds read in unit."""
    low, high = min(speeds), max(speeds)
    if low == high:
        return f"{low:g} {unit} is {low * _RPM_PER[unit]:.4g} rpm"
    return f"{low:g} to {high:g} {unit} is {low * _RPM_PER[unit]:.4g} to {high * _RPM_PER[unit]:.4g} rpm"


def _other_unit_than_reference(speeds, named: str, reference: float, reference_named: str):
    """('below' or 'above', the warning) for speeds that all lie further than OTHER_UNIT_RATIO
    from the reference speed; None if they do not, or if no unit makes engine speeds near it of them.
    Below, the speeds are in rad/s or Hz; above, in °/s, or the reference is in rad/s or Hz. Of
    the units that give engine speeds, the one said is that whose ratio of speeds to reference
    lies nearest (on a log scale) that of the speeds' geometric middle, if within UNIT_MATCH."""
    middle = math.exp(sum(math.log(v) for v in speeds) / len(speeds))
    if max(speeds) < reference / OTHER_UNIT_RATIO:
        side, suspects = "below", [(u, 1.0 / _RPM_PER[u]) for u in ("rad/s", "Hz")
                                   if _runs([v * _RPM_PER[u] for v in speeds])]
    elif min(speeds) > reference * OTHER_UNIT_RATIO:
        side, suspects = "above", [(u, 1.0 / _RPM_PER[u]) for u in ("°/s",) if _runs([v * _RPM_PER[u] for v in speeds])]
        suspects += [(u, _RPM_PER[u]) for u in ("rad/s", "Hz") if _runs([reference * _RPM_PER[u]])]
    else:
        return None
    mismatch = {unit: abs(math.log(middle / reference / ratio)) for unit, ratio in suspects}
    unit = min(mismatch, key=mismatch.get, default=None)
    if unit is None or mismatch[unit] > math.log(UNIT_MATCH):
        return None
    said = (f"{named}: {_speeds_text(speeds)} {'' if len(speeds) == 1 else 'all '}"
            f"{'below a fifth of' if side == 'below' else 'above five times'} the scene's engine speed "
            f"({reference_named} = {reference:g} rpm): ")
    if side == "below" or unit == "°/s":
        return side, said + f"probably {unit} (rpm expected: {_range(speeds, unit)}, about the scene's {reference:g} rpm)"
    return side, said + (f"probably {reference_named} is in {unit} (rpm expected: {_range([reference], unit)}; "
                         f"the sweep runs at {min(speeds):g}{'' if len(set(speeds)) == 1 else f' to {max(speeds):g}'} rpm)")


def _material_warnings(name, material) -> list[str]:
    found = []
    where = f"materials.{name}"
    modulus, density = material.get("youngs_modulus"), material.get("density")
    metal = (finite(density) and density >= _METAL_DENSITY) or any(m in name.lower() for m in _METAL_NAMES)
    soft = any(m in name.lower() for m in _SOFT_NAMES)
    if finite(modulus) and 0 < modulus < 1000.0 and metal:
        found.append(f"'{where}.youngs_modulus' = {modulus:g} MPa is below 1,000 MPa for a metal: probably GPa "
                     f"(MPa expected: {modulus:g} GPa is {1e3 * modulus:g} MPa)")
    elif finite(modulus) and 0 < modulus < 1000.0 and not soft:
        found.append(f"'{where}.youngs_modulus' = {modulus:g} MPa is below 1,000 MPa, softer than any metal or "
                     f"engineering solid of a bolted joint: looks like GPa (MPa expected: {modulus:g} GPa is "
                     f"{1e3 * modulus:g} MPa)")
    elif finite(modulus) and modulus > 1e7:
        found.append(f"'{where}.youngs_modulus' = {modulus:g} MPa is above any solid's: probably Pa "
                     f"(MPa expected: {modulus:g} Pa is {1e-6 * modulus:g} MPa)")
    for low, unit, scale in ((100.0, "kg/m³", 1e-12), (1e-3, "g/cm³", 1e-9), (1e-7, "kg/mm³", 1e-3)):
        if finite(density) and density > low:
            found.append(f"'{where}.density' = {density:g} t/mm³ is far heavier than any solid: probably {unit} "
                         f"(t/mm³ expected: {density:g} {unit} is {scale * density:g} t/mm³)")
            break
    return found


#: γ_crit, the reversible micro-slip before sliding, is 0.5-10 µm for metal contacts (the shipped
#: scenes 1 µm): above this (mm) it is most likely typed in µm
LARGEST_CRITICAL_SLIP_MM = 0.05
#: kn, the contact layer's penalty stiffness (N/mm³): the shipped scenes use 1e6-4e6 (1e5-1e7 is
#: the range of metal joints' interface stiffness per mm of overclosure); far outside this band it
#: is most likely in another unit, or would let the bodies sink into each other (below) or stiffen
#: the Newton iterations beyond use (above)
NORMAL_STIFFNESS_BAND = (1e2, 1e10)


def _normal_stiffness_warnings(stiffness) -> list[str]:
    low, high = NORMAL_STIFFNESS_BAND
    if not finite(stiffness) or low <= stiffness <= high or stiffness <= 0:
        return []
    said = f"'contact.normal_stiffness' = {stiffness:g} N/mm³ is "
    if stiffness < low:
        return [said + f"below {low:g} N/mm³, where metal joints' contact layers are 1e5 to 1e7 N/mm³ stiff (a "
                "pressure of 100 MPa would press them 1 mm or more into each other): check the unit (N/mm³ = "
                f"MPa/mm; 1 MPa/µm and 1 GPa/mm are 1000 N/mm³; {stiffness:g} MN/mm³ is {1e6 * stiffness:g} N/mm³)"]
    return [said + f"above {high:g} N/mm³, where metal joints' contact layers are 1e5 to 1e7 N/mm³ stiff: "
            f"probably N/m³ (N/mm³ expected: {stiffness:g} N/m³ is {1e-9 * stiffness:g} N/mm³)"]


#: keys that act only with an effect of 'scene.effects' (table, key); set to other than their
#: default without it, they are most likely meant to act
EFFECT_KEYS = {
    "cof_evolution": (("contact", "cof_rate"), ("procedure", "cof_during_wear"), ("procedure", "cof_jump")),
    "wear": (("contact", "wear_coefficients"), ("contact", "wear_form"), ("contact", "pressure_limit"),
             ("procedure", "wear_cycles"), ("procedure", "cycle_jump"), ("procedure", "jump_tolerance"),
             ("procedure", "max_cycle_jump"), ("procedure", "life_cycles"), ("procedure", "wear_cap")),
    "bolts": (("procedure", "clamp_loss_limit"), ("procedure", "loosening_window"),
              ("procedure", "loosening_window_cycles"), ("procedure", "stop_at_loosening")),
}
#: the defaults of the EFFECT_KEYS that are not fields of Procedure (contact.law.ContactLaw's, the wear cap's)
_EFFECT_KEY_DEFAULTS = {"cof_rate": 0.0, "wear_coefficients": [0.0, 0.0], "wear_form": "pressure",
                        "pressure_limit": 0.0, "wear_cap": math.inf}
_EFFECT_DOES = {"cof_evolution": "the COF stays at 'contact.cof_initial'",
                "wear": "no wear is computed and the wear phase does not run",
                "bolts": "without bolts there is no clamp force whose loss is loosening"}


def _inactive_effect_warnings(data: dict) -> list[str]:
    """Keys of an effect that 'scene.effects' does not list, set as if it did: they do nothing.
    Reads unvalidated tables safely."""
    effects = _effects(data)
    if effects is None:
        return []
    found = []
    for effect, keys in EFFECT_KEYS.items():
        if effect in effects:
            continue
        tables = {name: data.get(name) if isinstance(data.get(name), dict) else {} for name in ("contact", "procedure")}
        set_keys = [(table, key) for table, key in keys if key in tables[table]
                    and tables[table][key] != _EFFECT_KEY_DEFAULTS.get(key, getattr(Procedure, key, None))]
        contact = tables["contact"]
        if (effect == "cof_evolution" and finite(contact.get("cof_max")) and finite(contact.get("cof_initial"))
                and contact["cof_max"] > contact["cof_initial"]):
            set_keys.insert(0, ("contact", "cof_max"))
        if not set_keys:
            continue
        said = listed([f"'{table}.{key}' = {tables[table][key]!r}" for table, key in set_keys])
        found.append(f"{said} {'acts' if len(set_keys) == 1 else 'act'} only with the effect \"{effect}\", which "
                     f"'scene.effects' does not list ({effects or 'no effect'}): {_EFFECT_DOES[effect]}, and "
                     f"{'it does' if len(set_keys) == 1 else 'they do'} nothing; add \"{effect}\" to 'scene.effects', "
                     f"or remove {'it' if len(set_keys) == 1 else 'them'}")
    return found


#: a pretension that stretches its bolt by less than this (mm) is likely typed in kN
BOLT_STRETCH_MM = 2e-3


def plausibility(data: dict) -> list[str]:
    """Warnings about magnitudes that are likely unit mistakes (mm, N, MPa, t, s expected); each
    names its key and the unit it was probably written in. Reads unvalidated tables safely."""
    found: list[str] = []

    def table(name):
        return data.get(name) if isinstance(data.get(name), dict) else {}

    for name, material in table("materials").items():
        if isinstance(material, dict):
            found += _material_warnings(str(name), material)
    amplitude = table("coupling").get("wing_amplitude")
    if finite(amplitude) and amplitude > 10.0:
        found.append(f"'coupling.wing_amplitude' = {amplitude:g} mm is larger than 10 mm: probably µm "
                     f"(mm expected: {amplitude:g} µm is {1e-3 * amplitude:g} mm)")
    elif finite(amplitude) and 0 < amplitude < 1e-3:
        found.append(f"'coupling.wing_amplitude' = {amplitude:g} mm is below 1 µm: probably m "
                     f"(mm expected: {amplitude:g} m is {1e3 * amplitude:g} mm)")
    speed = table("mbs").get("speed_rpm")
    if finite(speed):
        found += engine_speed_warnings([speed], "[mbs] speed_rpm")
    slip = table("contact").get("critical_slip")
    if finite(slip) and slip > 1.0:
        found.append(f"'contact.critical_slip' = {slip:g} mm is larger than 1 mm: probably µm "
                     f"(mm expected: {slip:g} µm is {1e-3 * slip:g} mm)")
    elif finite(slip) and slip > LARGEST_CRITICAL_SLIP_MM:
        found.append(f"'contact.critical_slip' = {slip:g} mm is above {LARGEST_CRITICAL_SLIP_MM:g} mm, where γ_crit, "
                     f"a micro-slip, is typically 0.5 to 10 µm: probably µm (mm expected: {slip:g} µm is "
                     f"{1e-3 * slip:g} mm)")
    found += _normal_stiffness_warnings(table("contact").get("normal_stiffness"))
    found += _inactive_effect_warnings(data)
    for name, bolt in table("bolts").items():
        pretension = bolt.get("pretension") if isinstance(bolt, dict) else None
        stiffness = bolt.get("stiffness") if isinstance(bolt, dict) else None
        if finite(pretension) and 0 < pretension < 100.0:
            found.append(f"'bolts.{name}.pretension' = {pretension:g} N is below 100 N: probably kN "
                         f"(N expected: {pretension:g} kN is {1e3 * pretension:g} N)")
        elif finite(pretension) and finite(stiffness) and pretension > 0 and stiffness > 0 \
                and pretension / stiffness < BOLT_STRETCH_MM:
            # a preloaded bolt stretches by tens to hundreds of µm (the shipped joints 25-775 µm;
            # an M3 screw at 2 kN on 1e5 N/mm, 20 µm): 400 N on 8e5 N/mm is 400 kN typed in kN
            found.append(f"'bolts.{name}.pretension' = {pretension:g} N stretches the bolt ('stiffness' = "
                         f"{stiffness:g} N/mm) by {1e3 * pretension / stiffness:.2g} µm, where a preloaded bolt "
                         f"stretches by tens of µm or more: probably kN (N expected: {pretension:g} kN is "
                         f"{1e3 * pretension:g} N), or the stiffness is in N/m")
    loads = data.get("body_loads") if isinstance(data.get("body_loads"), list) else []
    for k, load in enumerate(entry for entry in loads if isinstance(entry, dict)):
        acceleration = load.get("acceleration")
        if isinstance(acceleration, list) and acceleration and all(finite(a) for a in acceleration):
            size = sum(a * a for a in acceleration) ** 0.5
            if 1.0 <= size <= 100.0:
                found.append(f"'body_loads[{k}].acceleration' has magnitude {size:g} mm/s²: probably m/s² "
                             f"(mm/s² expected: {size:g} m/s² is {1e3 * size:g} mm/s²)")
        spin = load.get("angular_velocity")
        if isinstance(spin, list) and spin and all(finite(w) for w in spin):
            size = sum(w * w for w in spin) ** 0.5
            if size > 1000.0:
                found.append(f"'body_loads[{k}].angular_velocity' has magnitude {size:g} rad/s: probably rpm "
                             f"(rad/s expected: {size:g} rpm is {size * 3.141592653589793 / 30:.4g} rad/s)")
    return found


#: a mesh read from a file smaller than this (mm) across while the scene places its body's
#: points and selections at least _SCENE_LENGTH (mm) from it is most likely in metres
_TINY_MESH = 1.0
_SCENE_LENGTH = 10.0


def _body_lengths(data: dict, body: str):
    """(key, point or (axis, coordinate)) of the lengths the scene gives for ``body``: reference-point
    positions and the boxes, rings and planes of its selections (mm). Reads unvalidated tables safely."""
    spec = data.get("bodies", {}).get(body, {})
    references = spec.get("reference_points", {}) if isinstance(spec.get("reference_points"), dict) else {}
    fixed = spec.get("fixed", [])
    selections = [(f"bodies.{body}.fixed", fixed.get("nodes"))] if isinstance(fixed, dict) else \
        [(f"bodies.{body}.fixed[{k}]", t.get("nodes")) for k, t in enumerate(fixed) if isinstance(t, dict)]
    for name, ref in references.items():
        if isinstance(ref, dict):
            yield f"bodies.{body}.reference_points.{name}.position", ref.get("position")
            selections.append((f"bodies.{body}.reference_points.{name}.nodes", ref.get("nodes")))
    contact = data.get("contact", {}) if isinstance(data.get("contact"), dict) else {}
    selections += [(f"contact.{role}", contact[role]) for role in ("slave", "master")
                   if isinstance(contact.get(role), dict) and contact[role].get("body") == body]
    for where, selection in selections:
        if not isinstance(selection, dict):
            continue
        boxes = [selection["box"]] if "box" in selection else selection.get("boxes", [])
        for k, box in enumerate(boxes if isinstance(boxes, list) else []):
            for corner in box if isinstance(box, list) else []:
                yield f"{where}.{'box' if 'box' in selection else f'boxes[{k}]'}", corner
        ring = selection.get("ring")
        if isinstance(ring, dict):
            yield f"{where}.ring.center", ring.get("center")
        if selection.get("axis") in ("x", "y", "z"):
            yield f"{where}.value", ("xyz".index(selection["axis"]), selection.get("value"))


def _distance_from_box(length, low, high) -> float | None:
    """Distance (mm) of a point, or of a plane (axis, coordinate), from the box low…high; None
    for anything else."""
    if isinstance(length, tuple):
        axis, value = length
        if not (finite(value) and math.isfinite(value)) or axis >= len(low):
            return None
        return max(low[axis] - value, 0.0, value - high[axis])
    if not (isinstance(length, list) and len(length) == len(low) and all(finite(c) for c in length)):
        return None
    distance = math.hypot(*(max(lo - c, 0.0, c - hi) for c, lo, hi in zip(length, low, high)))
    return distance if math.isfinite(distance) else None


#: a mean stress above this fraction of the body's Young's modulus (1 % strain) on a mesh under
#: :data:`_TINY_MESH` across is no elastic joint: most likely the mesh is in metres
_TINY_MESH_STRAIN = 0.01


def _body_loads(data: dict, body: str) -> list[tuple[str, float]]:
    """(key, N) of the forces the scene puts on ``body``: its [[loads]] and its bolts'
    pretensions (N, N per mm in 2D). Reads unvalidated tables safely."""
    found = []
    for k, load in enumerate(data.get("loads", []) if isinstance(data.get("loads"), list) else []):
        if (isinstance(load, dict) and str(load.get("dof", "")).split(".")[0] == body
                and finite(load.get("value"))):
            found.append((f"loads[{k}].value", abs(float(load["value"]))))
    bolts = data.get("bolts", {}) if isinstance(data.get("bolts"), dict) else {}
    for name, bolt in bolts.items():
        if (isinstance(bolt, dict) and finite(bolt.get("pretension"))
                and body in (str(bolt.get("head", "")).split(".")[0], str(bolt.get("nut", "")).split(".")[0])):
            found.append((f"bolts.{name}.pretension", abs(float(bolt["pretension"]))))
    return found


def _overloaded(data: dict, body: str, sizes: list[float]) -> str | None:
    """Why a tiny mesh's loads say it is in metres: the largest force on the body over its
    largest cross-section (3D: the product of the box's two largest sizes; 2D, per mm of
    thickness: its largest size) is above :data:`_TINY_MESH_STRAIN` of its Young's modulus."""
    spec = data.get("bodies", {}).get(body, {})
    material = data.get("materials", {}).get(spec.get("material"), {}) if isinstance(spec, dict) else {}
    young = material.get("youngs_modulus") if isinstance(material, dict) else None
    loads = _body_loads(data, body)
    ordered = sorted(sizes, reverse=True)
    section = ordered[0] if len(sizes) == 2 else ordered[0] * ordered[1]
    if not (loads and finite(young) and young > 0.0 and section > 0.0):
        return None
    key, force = max(loads, key=lambda entry: entry[1])
    stress = force / section
    if stress <= _TINY_MESH_STRAIN * young:
        return None
    unit = "N per mm" if len(sizes) == 2 else "N"
    return (f"'{key}' ({force:g} {unit}) on it is {stress:.3g} MPa over its largest section, "
            f"{100 * stress / young:.2g} % of its Young's modulus")


def mesh_unit_problem(data: dict, body: str, low, high, source: str) -> str | None:
    """A body's mesh file most likely written in metres: the mesh (box ``low``…``high``, mm) is
    less than :data:`_TINY_MESH` across while the scene places the body's reference points or
    selections :data:`_SCENE_LENGTH` or more from it, or loads it with more than a
    :data:`_TINY_MESH_STRAIN` strain's worth of stress over its section (a reference point on the
    body's own face is no evidence: QA, 2026-11-28, a 2D mesh in metres ran to 'stick' at 10 GPa);
    the sentence names the file (``source``), the mesh's size and the key. None when the sizes
    agree."""
    sizes = [float(hi - lo) for lo, hi in zip(low, high)]
    if not max(sizes) < _TINY_MESH:
        return None
    across = " × ".join(f"{s:.3g}" for s in sizes)
    advice = (f"the mesh is probably in metres (fretwork reads mm, so {max(sizes):.3g} m would be "
              f"{1e3 * max(sizes):.4g} mm); export it in mm or scale its coordinates by 1000")
    found = [(d, key) for key, length in _body_lengths(data, body)
             if (d := _distance_from_box(length, low, high)) is not None]
    if found and max(found)[0] >= _SCENE_LENGTH:
        distance, key = max(found)
        return (f"{source}: the mesh is {max(sizes):.3g} mm across ({across} mm), but '{key}' lies "
                f"{distance:.3g} mm from it: {advice}")
    overloaded = _overloaded(data, body, sizes)
    if overloaded is not None:
        return f"{source}: the mesh is {max(sizes):.3g} mm across ({across} mm), but {overloaded}: {advice}"
    return None
