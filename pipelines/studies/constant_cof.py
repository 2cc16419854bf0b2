"""The constant-COF comparison of the paper's Fig. 8: evolving COF against a constant μ = μ_max.

:func:`constant_cof_comparison` runs the scene's COF phase twice, once with the evolving COF and
once with a constant μ = μ_max (``contact.cof_initial`` set to ``cof_max``, the
``cof_evolution`` effect removed), wear switched off in both: the comparison is about the
stabilised COF field. It returns a :class:`Comparison`: the contact points, each model's fields
of the last COF cycle (the maximum shear traction over the cycle above all) and the probe points
(the paper's P1 and P2 either side of the bolt hole), each read at its nearest contact point.
:func:`write_comparison` writes it as ``constant_cof.h5``; the plot is
:func:`pipelines.output.constant_cof_plot.plot_constant_cof`.

``constant_cof.h5`` (h5py; every dataset carries a ``units`` attribute):

    /                      attrs: fretwork_format="fretwork-constant-cof", format_version=1,
                           scene_name, dimension, cof_initial and cof_max (1: the evolving
                           model's μ0 and μ_max, the constant model's μ), models (the group
                           names in order: variable, constant)
    /points/               coordinates (n, dim) mm, area (n,) mm² (mm per unit thickness in 2D),
                           facets (m, k) point indices of the contact surface's facets (lines in
                           2D, quads/triangles in 3D): the contact points of both models
    /models/variable/      the evolving-COF model, attrs: name ("variable COF"), cof_evolution
                           (True), cycle (the last COF cycle, as numbered from 1), verdict,
                           figures (JSON: the run's global figures), scene_toml (the scene as run,
                           resolved; pipelines.scene.resolved_text); datasets of its last COF
                           cycle: max_shear (n,) MPa (the largest |τ| over the cycle),
                           max_utilised_cof (n,) 1 (the largest |τ|/p over the cycle), cof (n,) 1
                           (at the cycle's end), dissipation_in_cycle (n,) mJ/mm², status (n,)
                           (the worst over the cycle: 0 open, 1 stick, 2 slip, 3 slip at μ_max)
    /models/constant/      the same for the constant-COF model (name "constant COF <μ_max>",
                           cof_evolution False)
    /probes/               one row per probe: name (k,) text (P1, P2, ...), given (k, dim) mm (the
                           probe as given), position (k, dim) mm and index (k,) (the contact
                           point it is read at), distance (k,) mm (between the two), and
                           max_shear (k, 2) MPa, one column per model in the order of the root's
                           ``models`` attribute

The file is written as ``constant_cof.h5.part`` and renamed once complete.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

from contact import procedure
from pipelines import scene as scenes
from pipelines.build import build
from pipelines.coupling import multibody_loading
from pipelines.output.results import AREA_UNITS, FIELD_UNITS, STATUS_NAMES
from reduction.errors import InputError
from reduction.threads import one_blas_thread


#: The root attribute ``fretwork_format`` of the file: it says the file is fretwork's (an
#: output folder's earlier file is then removed, pipelines.output.locks).
FORMAT = "fretwork-constant-cof"
FORMAT_VERSION = 1
#: The per-point fields of each model written to the file.
MODEL_FIELDS = ("max_shear", "max_utilised_cof", "cof", "dissipation_in_cycle", "status")

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


@dataclass(frozen=True)
class ModelCycle:
    """One model's last COF cycle: its per-point fields (units as in the module's file layout)
    and the run's verdict and global figures."""

    key: str
    name: str
    cof_evolution: bool
    cycle: int
    max_shear: np.ndarray
    max_utilised_cof: np.ndarray
    cof: np.ndarray
    dissipation_in_cycle: np.ndarray
    status: np.ndarray
    verdict: str
    figures: dict
    scene_toml: str


@dataclass(frozen=True)
class Comparison:
    """Both models' last COF cycles on the same contact points, and the probes read there."""

    scene_name: str
    dimension: int
    cof_initial: float
    cof_max: float
    coordinates: np.ndarray
    area: np.ndarray
    facets: np.ndarray
    probes: tuple
    models: tuple

    def records(self) -> list[dict]:
        """One record per model and probe: the probe as given (probe_mm), the point it is read at
        (position_mm) and their distance (distance_mm), the max shear there (MPa) and the
        model's slip area in the last cycle."""
        return [{"model": model.name, "probe": point.name, "probe_mm": list(point.given_mm),
                 "position_mm": list(point.position_mm), "distance_mm": point.distance_mm,
                 "max_shear_MPa": float(model.max_shear[point.index]),
                 "slip_area_fraction": model.figures["slip_area_fraction"]}
                for model in self.models for point in self.probes]


def _last_cycle(key: str, name: str, scene, model) -> ModelCycle:
    """The last COF cycle of ``model`` run from its preload, wear off."""
    solver = model.solver()  # as `fretwork run` runs the scene (finite sliding where it asks)
    evolving = "cof_evolution" in scene.effects
    result = procedure.run(solver, model.initial_state(), model.program, model.procedure,
                           cof_evolution=evolving, wear=False)
    last = result.cycles[-1]
    return ModelCycle(key, name, evolving, last.cycle, last.max_shear, last.max_utilised_cof, last.cof,
                      last.dissipation_in_cycle, last.status, result.verdict, dict(result.figures),
                      scenes.resolved_text(scene))


@one_blas_thread
def constant_cof_comparison(scene_path: str | Path, probes: dict, overrides: dict | None = None) -> Comparison:
    """Both models' last COF cycle, the probes {name: (x, y[, z]) mm} read at their nearest
    contact points (:func:`probe_points`, checked before either run). ``overrides`` {dotted key:
    value} apply to both models."""
    if not probes:
        raise InputError("the comparison needs at least one probe point (--probe x,y[,z] in mm): the max shear "
                         "is reported at probes")
    overrides = dict(overrides or {})
    base = scenes.load(scene_path, overrides)
    effects = [e for e in base.data["scene"]["effects"] if e != "wear"]
    if "cof_evolution" not in effects:
        raise InputError(f"{scene_path}: the comparison needs a scene with the 'cof_evolution' effect")
    wrong = wrong_dimension(probes, base.dimension)  # said before the model is built
    wrong += [f"probe {name} ({','.join(f'{v:g}' for v in given)}) has a coordinate that is not a finite number: "
              "give it in mm" for name, given in probes.items() if not np.isfinite(np.asarray(given, dtype=float)).all()]
    if wrong:
        raise InputError(f"{scene_path}: " + "; ".join(wrong))
    cof_initial, cof_max = base.data["contact"]["cof_initial"], base.data["contact"]["cof_max"]
    variable = scenes.load(scene_path, {**overrides, "scene.effects": effects})
    constant = scenes.load(scene_path, {**overrides, "scene.effects": [e for e in effects if e != "cof_evolution"],
                                        "contact.cof_initial": cof_max})
    # one multibody run for both (a coupled scene): the COF is not one of its inputs
    multibody = multibody_loading(variable, None) if "coupling" in variable.data else None
    model = build(variable, multibody=multibody)
    pairing = model.assembly.pairing
    coordinates, area, facets = pairing.slave.coordinates.copy(), pairing.area.copy(), pairing.slave.facets.copy()
    points = probe_points(probes, coordinates)
    runs = [_last_cycle("variable", "variable COF", variable, model)]
    del model, pairing  # one model in memory at a time
    runs.append(_last_cycle("constant", f"constant COF {cof_max:g}", constant, build(constant, multibody=multibody)))
    return Comparison(base.name, base.dimension, float(cof_initial), float(cof_max), coordinates, area, facets,
                      tuple(points), tuple(runs))


def write_comparison(comparison: Comparison, path: str | Path) -> Path:
    """Write ``comparison`` to ``path`` (HDF5, the module's layout), through a ``.part`` file."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    part = path.with_name(path.name + ".part")
    with h5py.File(part, "w") as file:
        file.attrs.update(fretwork_format=FORMAT, format_version=FORMAT_VERSION, scene_name=comparison.scene_name,
                          dimension=comparison.dimension, cof_initial=comparison.cof_initial,
                          cof_max=comparison.cof_max, models=[model.key for model in comparison.models])
        points = file.create_group("points")
        for name, data, units in (("coordinates", comparison.coordinates, "mm"),
                                  ("area", comparison.area, AREA_UNITS),
                                  ("facets", comparison.facets, "index")):
            points.create_dataset(name, data=data).attrs["units"] = units
        for model in comparison.models:
            group = file.create_group(f"models/{model.key}")
            group.attrs.update(name=model.name, cof_evolution=model.cof_evolution, cycle=model.cycle,
                               verdict=model.verdict, figures=json.dumps(model.figures),
                               scene_toml=model.scene_toml)
            for name in MODEL_FIELDS:
                group.create_dataset(name, data=getattr(model, name)).attrs["units"] = FIELD_UNITS[name]
            group["status"].attrs["codes"] = STATUS_NAMES
        probes = file.create_group("probes")
        shown = comparison.probes
        rows = (("name", [p.name for p in shown], "text"), ("given", [p.given_mm for p in shown], "mm"),
                ("position", [p.position_mm for p in shown], "mm"), ("index", [p.index for p in shown], "index"),
                ("distance", [p.distance_mm for p in shown], "mm"),
                ("max_shear", [[model.max_shear[p.index] for model in comparison.models] for p in shown], "MPa"))
        for name, data, units in rows:
            probes.create_dataset(name, data=data).attrs["units"] = units
    os.replace(part, path)
    return path
