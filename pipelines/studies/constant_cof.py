"""Studies that run a scene several times and compare the answers.

``constant_cof_comparison``: the paper's Fig. 8 comparison. The COF phase is run once with
the evolving COF and once with a constant μ = μ_max; the maximum shear traction of the last
cycle is reported at probe points (the paper's P1 and P2 either side of the bolt hole), each
read at its nearest contact point. The records are returned, for the command line to print;
no file or plot is written.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from contact import procedure
from contact.solver import ContactSolver
from pipelines import scene as scenes
from pipelines.build import build
from reduction.errors import InputError


#: How far a probe may lie from the contact point it is read at, in local spacings of the contact
#: points (the distance from that point to its nearest neighbour: the element size there). Within
#: it, a probe given between points, or just off the patch's edge, is read at the nearest point.
PROBE_REACH = 2.0


@dataclass(frozen=True)
class ProbePoint:
    """A probe as given and the contact point it is read at: its index, coordinates and distance (mm)."""

    name: str
    given_mm: tuple
    index: int
    position_mm: tuple
    distance_mm: float


def wrong_dimension(probes: dict, dimension: int) -> list[str]:
    """A sentence for every probe whose number of coordinates is not the scene's dimension."""
    axes = "x,y,z" if dimension == 3 else "x,y"
    return [f"probe {name} ({','.join(f'{v:g}' for v in given)}) has {len(given)} coordinates, the scene is "
            f"{dimension}D: give {axes} in mm" for name, given in probes.items() if len(given) != dimension]


def probe_points(probes: dict, coordinates: np.ndarray) -> list[ProbePoint]:
    """Each probe {name: (x, y[, z]) mm} at its nearest contact point; every probe that has a
    different dimension from the contact points, or lies farther from its nearest point than
    :data:`PROBE_REACH` local spacings, is named in one InputError."""
    dimension = coordinates.shape[1]
    found, problems = [], wrong_dimension(probes, dimension)
    for name, given in probes.items():
        given = np.asarray(given, dtype=float)
        text = ",".join(f"{v:g}" for v in given)
        if given.shape != (dimension,):
            continue
        distances = np.linalg.norm(coordinates - given, axis=1)
        nearest = int(np.argmin(distances))
        others = np.delete(coordinates, nearest, axis=0)
        spacing = float(np.min(np.linalg.norm(others - coordinates[nearest], axis=1))) if len(others) else 0.0
        point = ProbePoint(name, tuple(given.tolist()), nearest, tuple(coordinates[nearest].tolist()),
                           float(distances[nearest]))
        if point.distance_mm > PROBE_REACH * spacing:
            problems.append(f"probe {name} ({text}) is {point.distance_mm:.4g} mm from the nearest contact point "
                            f"({','.join(f'{v:.4g}' for v in point.position_mm)}), farther than {PROBE_REACH:g} "
                            f"times the contact points' spacing there ({PROBE_REACH * spacing:.3g} mm): "
                            f"give a point on the contact surface (mm)")
        found.append(point)
    if problems:
        raise InputError("; ".join(problems))
    return found


def _last_cycle_max_shear(scene, model) -> tuple[np.ndarray, dict]:
    """The max shear (MPa) of every contact point in the last COF cycle, and the run's figures."""
    space = model.contact_space()
    solver = ContactSolver(space, model.law, model.settings)
    result = procedure.run(solver, model.initial_state(), model.program, model.procedure,
                           cof_evolution="cof_evolution" in scene.effects, wear=False)
    return result.cycles[-1].max_shear, {"verdict": result.verdict, **result.figures}


def constant_cof_comparison(scene_path: str | Path, probes: dict, overrides: dict | None = None) -> list[dict]:
    """Max shear (MPa) in the last COF cycle at ``probes`` {name: (x, y[, z]) mm}, both models.

    Each probe is read at its nearest contact point (:func:`probe_points`, checked before either
    run); a record gives the probe as given (probe_mm), the point used (position_mm) and their
    distance (distance_mm). Wear is switched off: the comparison is about the stabilised COF field.
    """
    if not probes:
        raise InputError("the comparison needs at least one probe point (--probe x,y[,z] in mm): the max shear "
                         "is reported at probes only")
    overrides = dict(overrides or {})
    base = scenes.load(scene_path, overrides)
    effects = [e for e in base.data["scene"]["effects"] if e != "wear"]
    if "cof_evolution" not in effects:
        raise InputError(f"{scene_path}: the comparison needs a scene with the 'cof_evolution' effect")
    wrong = wrong_dimension(probes, base.dimension)  # said before the model is built
    if wrong:
        raise InputError(f"{scene_path}: " + "; ".join(wrong))
    cof_max = base.data["contact"]["cof_max"]
    variable = scenes.load(scene_path, {**overrides, "scene.effects": effects})
    constant = scenes.load(scene_path, {**overrides, "scene.effects": [e for e in effects if e != "cof_evolution"],
                                        "contact.cof_initial": cof_max})
    model = build(variable)
    points = probe_points(probes, model.assembly.pairing.slave.coordinates)
    runs = {"variable COF": _last_cycle_max_shear(variable, model)}
    del model
    runs[f"constant COF {cof_max:g}"] = _last_cycle_max_shear(constant, build(constant))
    return [{"model": model_name, "probe": point.name, "probe_mm": list(point.given_mm),
             "position_mm": list(point.position_mm), "distance_mm": point.distance_mm,
             "max_shear_MPa": float(max_shear[point.index]), "slip_area_fraction": figures["slip_area_fraction"]}
            for model_name, (max_shear, figures) in runs.items() for point in points]
