"""Studies that run a scene several times and compare the answers.

``constant_cof_comparison``: the paper's Fig. 8 comparison. The COF phase is run once with
the evolving COF and once with a constant μ = μ_max; the maximum shear traction of the last
cycle is reported at probe points (the paper's P1 and P2 either side of the bolt hole).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from contact import procedure
from contact.solver import ContactSolver
from pipelines import scene as scenes
from pipelines.build import build
from reduction.errors import InputError


def _last_cycle_max_shear(scene) -> tuple[np.ndarray, np.ndarray, dict]:
    model = build(scene)
    space = model.contact_space()
    solver = ContactSolver(space, model.law, model.settings)
    result = procedure.run(solver, model.initial_state(), model.program, model.procedure,
                           cof_evolution="cof_evolution" in scene.effects, wear=False)
    last = result.cycles[-1]
    return model.assembly.pairing.slave.coordinates, last.max_shear, {
        "verdict": result.verdict, **result.figures}


def constant_cof_comparison(scene_path: str | Path, probes: dict, overrides: dict | None = None) -> list[dict]:
    """Max shear (MPa) in the last COF cycle at ``probes`` {name: (x, y[, z]) mm}, both models.

    Wear is switched off: the comparison is about the stabilised COF field.
    """
    overrides = dict(overrides or {})
    base = scenes.load(scene_path, overrides)
    effects = [e for e in base.data["scene"]["effects"] if e != "wear"]
    if "cof_evolution" not in effects:
        raise InputError(f"{scene_path}: the comparison needs a scene with the 'cof_evolution' effect")
    cof_max = base.data["contact"]["cof_max"]
    variable = scenes.load(scene_path, {**overrides, "scene.effects": effects})
    constant = scenes.load(scene_path, {**overrides, "scene.effects": [e for e in effects if e != "cof_evolution"],
                                        "contact.cof_initial": cof_max})
    records = []
    runs = {"variable COF": _last_cycle_max_shear(variable), f"constant COF {cof_max:g}": _last_cycle_max_shear(constant)}
    for model_name, (coordinates, max_shear, figures) in runs.items():
        for probe, position in probes.items():
            position = np.asarray(position, dtype=float)
            nearest = int(np.argmin(np.linalg.norm(coordinates[:, :position.size] - position, axis=1)))
            records.append({"model": model_name, "probe": probe,
                            "position_mm": coordinates[nearest].tolist(),
                            "max_shear_MPa": float(max_shear[nearest]),
                            "slip_area_fraction": figures["slip_area_fraction"]})
    return records
