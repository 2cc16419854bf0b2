"""Whether a scene's supports hold each group of bodies against rigid-body motion.

Checked once the meshes, the fixed selections, the reference points and the [[motions]] are
resolved to DOFs, before any body is condensed. A group is the bodies joined by the contact or
bolts (:func:`pipelines.scene.checks.held_groups`); with its contact tied it moves as one rigid
body, and it is held when its fixed DOFs and the DOFs whose motion is prescribed stop every
rigid mode (:mod:`contact.rigid_modes`). Loads hold nothing. The TOML check
(:func:`pipelines.scene.checks._check_support`) catches a group with no support at all before
any mesh is built; this one catches a group held in some directions only, which the contact
solver would meet as a singular stiffness ("Newton did not converge").
"""

from __future__ import annotations

import numpy as np

from contact.assembly import Body, component_names
from contact.rigid_modes import (Frame, describe, free_motions, holding_components, locked_rotation_rows,
                                 point_rows, rotation_rows)
from pipelines.scene import Scene
from pipelines.scene.checks import held_groups
from reduction.errors import InputError


def check_support(scene: Scene, bodies: list[Body], motions: dict) -> None:
    """Raise :class:`InputError` naming each group of bodies whose supports leave a rigid
    motion free, the motions in words and how to hold them.

    motions: pattern name → [(body, reference point, component, value)] as
    :func:`contact.assembly.assemble` takes them (every DOF they name is prescribed).
    """
    driven = {}
    for entries in motions.values():
        for body, point, component, _ in entries:
            driven.setdefault((body, point), set()).add(component)
    by_name = {body.name: body for body in bodies}
    problems = [_group_problem(scene, [by_name[name] for name in members], driven)
                for members in held_groups(scene.data)]
    problems = [problem for problem in problems if problem]
    if problems:
        raise InputError("\n".join(problems))


def _group_problem(scene: Scene, group: list[Body], driven: dict) -> str | None:
    frame = Frame.around(np.vstack([body.elastic.coordinates for body in group]))
    rows = np.vstack([_held_rows(frame, body, driven) for body in group])
    free = free_motions(rows, frame.n_modes)
    if free.shape[0] == 0:
        return None
    names = " and ".join(f"'{body.name}'" for body in group)
    who = (f"body {names} is" if len(group) == 1
           else f"bodies {names} (joined by the contact or bolts, the contact taken as tied) are")
    fixed = next((body.name for body in group if scene.data["bodies"][body.name].get("fixed")), None)
    where = (f"bodies.{fixed}.fixed" if fixed else f"a fixed selection, e.g. bodies.{group[-1].name}.fixed")
    translations, rotations = holding_components(free, frame.dim)
    quoted = ", ".join(f'"{c}"' for c in translations)
    at_points = ", ".join(f'"{c}"' for c in translations + rotations)
    return (f"{who} not held against rigid-body motion: the fixed selections and the prescribed "
            f"[[motions]] leave free {describe(free, frame)}, so the stiffness is singular and the "
            f"contact solver would not converge; add {quoted} to the components of {where}, or "
            f"prescribe {at_points} of a reference point ([[motions]], value 0 to hold it in place"
            f"{'; a rotation needs a reference point with rotations = true' if rotations else ''}); "
            "a [[loads]] entry holds nothing")


def _held_rows(frame: Frame, body: Body, driven: dict) -> np.ndarray:
    """Rows of the rigid modes at the DOFs of ``body`` held by its supports and prescribed
    motions, and of the constraints of its couplings without rotations."""
    dim, coordinates = frame.dim, body.elastic.coordinates
    flat = np.empty(body.elastic.n_dofs, dtype=int)  # DOF → node·dim + component
    flat[body.elastic.node_dofs.ravel()] = np.arange(body.elastic.node_dofs.size)
    node, component = np.divmod(flat[body.held_dofs()], dim)
    rows = [point_rows(frame, coordinates[node], component)]
    for name, reference in body.reference_points.items():
        labels = component_names(dim, reference.rotations)
        held = np.array([labels.index(c) for c in driven.get((body.name, name), ()) if c in labels], dtype=int)
        translations, rotations = held[held < dim], held[held >= dim] - dim
        if reference.rotations:
            position = np.tile(reference.position, (translations.size, 1))
            rows += [point_rows(frame, position, translations), rotation_rows(frame, rotations)]
        else:
            # the coupled nodes move with the reference translation: they cannot turn, and a
            # prescribed translation holds them all
            nodes = coordinates[np.unique(reference.nodes)]
            position = np.tile(nodes.mean(axis=0), (translations.size, 1))
            rows += [locked_rotation_rows(frame, nodes), point_rows(frame, position, translations)]
    return np.vstack(rows)

