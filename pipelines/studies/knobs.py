"""The fidelity knobs of a scene and how a study weighs them (see :mod:`pipelines.studies.accuracy`).

Knobs and their sweeps, the scene overrides of a setting, the run records and their errors
against the reference, the Pareto front, the recommendation, and the sweep itself: reference
and one-knob runs as one round of parallel cases, then the combinations one at a time.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np
from scipy.spatial import cKDTree

from contact import procedure
from pipelines import scene as scenes
from pipelines.build import make_mesh
from pipelines.parallel import map_cases
from reduction.errors import InputError


TOLERANCE = 0.02
COST = "cpu_time_s"
SCALAR_QUANTITIES = ("max_wear_depth_mm", "slip_area_fraction", "clamp_force_loss_fraction", "wing_amplitude_mm")
QUANTITIES = ("max_wear_depth_mm", "cof_map", "slip_area_fraction", "clamp_force_loss_fraction", "wing_amplitude_mm")
FLOORS = {"max_wear_depth_mm": 1e-6, "slip_area_fraction": 0.01, "clamp_force_loss_fraction": 0.01,
          "wing_amplitude_mm": 1e-6}


MULTIBODY_KNOBS = {
    "craig_bampton_modes": "multibody scenes only ([mbs] without [contact]); this is a contact scene",
    "mbs_time_step": "multibody scenes only ([mbs] without [contact]); this is a contact scene",
}


# Caps of the base run's cycle counts (the cycle jump is kept: raising it makes explicit
# wear unstable): a study runs the scene a dozen times.
# Combinations of coarsened knobs tried before settling on the single-knob runs.
MAX_COMBINED_RUNS = 3
CYCLE_CAPS = {False: {"wear_cycles": 20, "cof_cycles": 40}, True: {"wear_cycles": 4, "cof_cycles": 10}}


@dataclass(frozen=True)
class Knob:
    """One fidelity knob: its values (finest first) and how a value becomes scene overrides."""

    name: str
    meaning: str
    values: tuple
    finer_is_larger: bool

    def ordered(self, values) -> tuple:
        """``values`` sorted finest first, duplicates removed."""
        return tuple(sorted(set(values), reverse=self.finer_is_larger))


@dataclass
class Run:
    """One run of the scene at one setting (knob name → value)."""

    label: str
    settings: dict
    varied: tuple
    values: dict = field(default_factory=dict)
    verdict: str | None = None
    cof: np.ndarray | None = None
    coordinates: np.ndarray | None = None
    wall_time_s: float = math.nan
    cpu_time_s: float = math.nan
    failure: str | None = None


@dataclass
class Study:
    """Everything the study found; ``to_dict`` is the JSON form."""

    scene: str
    scene_path: str
    base_overrides: dict
    knobs: list
    not_applicable: dict
    reference: Run
    records: list
    recommendation: dict | None
    plot: str | None = None

    def to_dict(self) -> dict:
        return {
            "scene": self.scene, "scene_path": self.scene_path, "tolerance": TOLERANCE, "cost": COST,
            "base_overrides": self.base_overrides,
            "knobs": [{"name": k.name, "meaning": k.meaning, "values": list(k.values)} for k in self.knobs],
            "not_applicable": self.not_applicable,
            "reference": {"settings": self.reference.settings,
                          "values": {k: v for k, v in self.reference.values.items() if k != "cof_rise"},
                          "verdict": self.reference.verdict, "wall_time_s": self.reference.wall_time_s,
                          "cpu_time_s": self.reference.cpu_time_s},
            "records": self.records, "recommendation": self.recommendation, "plot": self.plot,
        }


def _contact_size_keys(data: dict) -> list[str]:
    return [f"bodies.{name}.mesh.contact_size" for name, body in data["bodies"].items()
            if "contact_size" in body.get("mesh", {})]


def _halvings(value, count, minimum):
    """value, value/2, value/4 ... (integers, at least ``minimum``, duplicates dropped)."""
    return tuple(dict.fromkeys(max(minimum, int(round(value / 2 ** k))) for k in range(count)))


def knobs_for(scene: scenes.Scene, quick: bool) -> tuple[list[Knob], dict]:
    """The knobs that apply to ``scene`` with their default sweeps, and those that do not (why).

    The sweeps start at the scene's own values; pass the scene with the study's base overrides.
    """
    data = scene.data
    proc, contact = data.get("procedure", {}), data["contact"]
    defaults = procedure.Procedure()
    count = 2 if quick else 3
    knobs, not_applicable = [], dict(MULTIBODY_KNOBS)
    sizes = [data["bodies"][key.split(".")[1]]["mesh"]["contact_size"] for key in _contact_size_keys(data)]
    if sizes:
        size = min(sizes)
        knobs.append(Knob("contact_size", "contact mesh size h, mm (both bodies)",
                          tuple(size * 2 ** k for k in range(count)), False))
    else:
        not_applicable["contact_size"] = "the meshes are files or have no contact_size"
    increments = proc.get("increments_per_cycle", defaults.increments_per_cycle)
    knobs.append(Knob("increments_per_cycle", "increments per load cycle",
                      _halvings(increments, count, 4), True))
    kn = contact["normal_stiffness"]
    knobs.append(Knob("normal_stiffness", "penalty stiffness kn, N/mm³",
                      (kn,) + tuple(kn / 10 ** k for k in range(1, count)) if quick else (10 * kn, kn, kn / 10),
                      True))
    gamma = contact["critical_slip"]
    knobs.append(Knob("critical_slip", "critical slip γ_crit, mm",
                      (gamma,) + tuple(gamma * 10 ** k for k in range(1, count)) if quick else
                      (gamma / 10, gamma, gamma * 10), False))
    wear_cycles = proc.get("wear_cycles", defaults.wear_cycles)
    jump = proc.get("cycle_jump", defaults.cycle_jump)
    if "wear" not in scene.effects or wear_cycles <= 0:
        not_applicable["cycle_jump"] = "the scene has no wear phase"
    elif jump == "auto":
        # the adaptive jump's own knob: the largest pressure change a block may cause (finer smaller)
        theta = proc.get("jump_tolerance", defaults.jump_tolerance)
        knobs.append(Knob("jump_tolerance", "adaptive cycle jump: largest pressure change per block / mean "
                          "pressure", tuple(dict.fromkeys(min(0.5, theta * 2 ** k) for k in range(-1, count - 1)))
                          if not quick else (theta, min(0.5, 2 * theta)), False))
        not_applicable["cycle_jump"] = "the scene's jump is adaptive (\"auto\"): its jump_tolerance is swept"
    else:
        equivalent = wear_cycles * jump
        knobs.append(Knob("cycle_jump", f"cycle-jump factor J (wear_cycles × J = {equivalent:g} kept)",
                          tuple(equivalent / n for n in _halvings(wear_cycles, count, 1)), False))
    cof_cycles = proc.get("cof_cycles", defaults.cof_cycles)
    if "cof_evolution" in scene.effects and cof_cycles > 0:
        knobs.append(Knob("cof_cycles", "COF-phase length, cycles", _halvings(cof_cycles, count, 1), True))
    else:
        not_applicable["cof_cycles"] = "the scene has no COF phase with COF evolution"
    return knobs, not_applicable


def _capped(proc: dict, key: str, quick: bool, default: int) -> int:
    return min(proc.get(key, default), CYCLE_CAPS[quick][key])


def run_up_within(scene: scenes.Scene, cof_cycles: int) -> dict:
    """A shortened COF phase keeps the vibration's run-up the same share of it (the run-up
    must lie within the COF phase)."""
    proc = scene.data.get("procedure", {})
    run_up, original = proc.get("vibration_run_up", 0), proc.get("cof_cycles", procedure.Procedure().cof_cycles)
    if run_up <= cof_cycles:
        return {}
    return {"procedure.vibration_run_up": int(round(run_up * cof_cycles / original))}


def base_overrides(scene: scenes.Scene, quick: bool) -> dict:
    """Overrides that shorten the scene's phases to the study's caps (none if already short)."""
    proc = scene.data.get("procedure", {})
    defaults = procedure.Procedure()
    out = {}
    for key in ("wear_cycles", "cof_cycles"):
        capped = _capped(proc, key, quick, getattr(defaults, key))
        if capped != proc.get(key, getattr(defaults, key)):
            out[f"procedure.{key}"] = capped
    if "procedure.cof_cycles" in out:
        out.update(run_up_within(scene, out["procedure.cof_cycles"]))
    return out


def setting_overrides(scene: scenes.Scene, settings: dict) -> dict:
    """Scene overrides that realise ``settings`` (knob name → value)."""
    out = {}
    for name, value in settings.items():
        if name == "contact_size":
            out.update({key: float(value) for key in _contact_size_keys(scene.data)})
        elif name in ("increments_per_cycle", "cof_cycles"):
            out[f"procedure.{name}"] = int(value)
            if name == "cof_cycles":
                out.update(run_up_within(scene, int(value)))
        elif name in ("normal_stiffness", "critical_slip"):
            out[f"contact.{name}"] = float(value)
        elif name == "jump_tolerance":
            out["procedure.jump_tolerance"] = float(value)
        elif name == "cycle_jump":
            proc = scene.data.get("procedure", {})
            equivalent = proc.get("wear_cycles", 0) * proc.get("cycle_jump", 1.0)
            wear_cycles = max(1, int(round(equivalent / value)))
            out["procedure.wear_cycles"] = wear_cycles
            out["procedure.cycle_jump"] = equivalent / wear_cycles
        else:
            raise InputError(f"unknown accuracy knob '{name}'")
    return out


def errors(run: Run, reference: Run) -> dict:
    """Error of each decision quantity of ``run`` against ``reference`` (see the module doc)."""
    out = {}
    for quantity in SCALAR_QUANTITIES:
        value, ref = run.values.get(quantity), reference.values.get(quantity)
        if ref is None or value is None:
            continue
        out[quantity] = abs(value - ref) / max(abs(ref), FLOORS[quantity])
    if reference.cof is not None and run.cof is not None:
        nearest = cKDTree(run.coordinates).query(reference.coordinates)[1]
        rms = float(np.sqrt(np.mean((run.cof[nearest] - reference.cof) ** 2)))
        out["cof_map"] = rms / max(reference.values["cof_rise"], 1e-12)
    return out


def _record(run: Run, reference: Run) -> dict:
    if run.failure:
        return {"label": run.label, "settings": run.settings, "varied": list(run.varied), "values": {},
                "errors": {}, "worst_error": math.inf, "verdict": None, "verdict_agrees": False,
                "within_tolerance": False, "wall_time_s": run.wall_time_s, "cpu_time_s": run.cpu_time_s,
                "failure": run.failure}
    errs = errors(run, reference)
    worst = max(errs.values(), default=0.0)
    agrees = run.verdict == reference.verdict
    values = {k: v for k, v in run.values.items() if k != "cof_rise" and v is not None}
    return {"label": run.label, "settings": run.settings, "varied": list(run.varied), "values": values,
            "errors": errs, "worst_error": worst, "verdict": run.verdict, "verdict_agrees": agrees,
            "within_tolerance": bool(agrees and worst <= TOLERANCE), "wall_time_s": run.wall_time_s,
            "cpu_time_s": run.cpu_time_s, "failure": None}


def recommend(records: list[dict], tolerance: float = TOLERANCE, cost: str = COST) -> dict | None:
    """The cheapest record (by ``cost``, s) whose worst error is within ``tolerance`` with the
    reference's verdict."""
    qualified = [r for r in records if r["failure"] is None and r["verdict_agrees"]
                 and r["worst_error"] <= tolerance]
    return min(qualified, key=lambda r: r[cost]) if qualified else None


def pareto_front(records: list[dict], cost: str = COST) -> list[dict]:
    """Records no other record beats in both cost (s) and worst error, cheapest first."""
    finished = sorted((r for r in records if r["failure"] is None),
                      key=lambda r: (r[cost], r["worst_error"]))
    front, best = [], math.inf
    for record in finished:
        if record["worst_error"] < best:
            front.append(record)
            best = record["worst_error"]
    return front


def _label(knobs: list[Knob], settings: dict, reference: dict) -> str:
    changed = [f"{k.name}={settings[k.name]:g}" for k in knobs if settings[k.name] != reference[k.name]]
    return ", ".join(changed) or "reference"


def _step_back(knobs: list[Knob], records: list[dict], combined: dict, varied: tuple) -> dict:
    """``combined`` with the knob whose coarsening erred most on its own one level finer."""
    own = {r["varied"][0]: r["worst_error"] for r in records if len(r["varied"]) == 1
           and r["varied"][0] in varied and r["settings"][r["varied"][0]] == combined[r["varied"][0]]}
    worst = max(varied, key=lambda name: own.get(name, 0.0))
    values = next(k.values for k in knobs if k.name == worst)
    return {**combined, worst: values[values.index(combined[worst]) - 1]}


def _combined(knobs: list[Knob], records: list[dict], reference: dict) -> dict:
    """Per knob the coarsest value that was within tolerance on its own (else the reference's)."""
    settings = dict(reference)
    for knob in knobs:
        passing = [r["settings"][knob.name] for r in records
                   if r["varied"] == [knob.name] and r["within_tolerance"]]
        if passing:
            settings[knob.name] = knob.ordered(passing)[-1]
    return settings


def _check_contact_sizes(scene_path: Path, scene: scenes.Scene, base: dict, knob: Knob) -> None:
    """Generate the meshes of every swept contact size first: a size the mesh generator rejects
    stops the study before the first run, not after the reference."""
    for value in knob.values:
        sized = scenes.load(scene_path, {**base, **setting_overrides(scene, {"contact_size": value})})
        for name, body in sized.data["bodies"].items():
            try:
                make_mesh(body["mesh"], f"bodies.{name}.mesh", scene_path.parent)
            except InputError as error:
                raise InputError(f"contact_size {value:g} mm: {error}") from None


def _apply_sweeps(knobs: list[Knob], sweeps: dict | None, scene_name: str) -> list[Knob]:
    by_name = {k.name: k for k in knobs}
    for name, values in (sweeps or {}).items():
        if name not in by_name:
            raise InputError(f"knob '{name}' does not apply to scene {scene_name} "
                             f"(applicable: {', '.join(by_name)})")
        if not values:
            raise InputError(f"knob '{name}' needs at least one value")
        by_name[name] = replace(by_name[name], values=by_name[name].ordered(values))
    return [by_name[k.name] for k in knobs]


def _raising_input_errors(runner: Callable, **kwargs):
    """Call the runner (a dask task); bad input comes back as the InputError itself, to be raised
    by the client as before, not as a failed run."""
    try:
        return runner(**kwargs)
    except InputError as error:
        return error


def _sweep(knobs: list[Knob], runner: Callable, arguments: Callable, overrides_of: Callable, on_run,
           cluster: dict) -> tuple[Run, list, dict | None]:
    """Reference, one-knob runs, combinations; the records and the recommendation.

    runner(**arguments(settings, varied, label)) makes one Run; cluster: map_cases' scheduler
    and workers.
    """
    reference_settings = {k.name: k.values[0] for k in knobs}

    def runs(settings_list):
        cases = []
        for settings, varied in settings_list:
            label = _label(knobs, settings, reference_settings)
            cases.append((label, {"runner": runner, **arguments(settings, varied, label)}))
        outcomes = map_cases(_raising_input_errors, cases, label="accuracy runs", progress=on_run is not None,
                             **cluster)
        for outcome in outcomes:
            if isinstance(outcome.value, InputError):
                raise outcome.value
            if outcome.error:
                raise RuntimeError(f"accuracy run {outcome.key}: {outcome.error}")
        return [outcome.value for outcome in outcomes]

    def run(settings, varied):
        return runs([(settings, varied)])[0]

    one_knob = [({**reference_settings, knob.name: value}, (knob.name,)) for knob in knobs for value in knob.values[1:]]
    reference, *singles = runs([(reference_settings, ()), *one_knob])
    if reference.failure:
        raise InputError(f"the reference run (finest setting of every knob) did not converge: "
                         f"{reference.failure}")
    records = [_record(reference, reference)]
    if on_run:
        on_run(records[-1])
    for single in singles:
        records.append(_record(single, reference))
        if on_run:
            on_run(records[-1])
    combined = _combined(knobs, records, reference_settings)
    for _ in range(MAX_COMBINED_RUNS):
        varied = tuple(k.name for k in knobs if combined[k.name] != reference_settings[k.name])
        if len(varied) < 2:
            break
        records.append(_record(run(combined, varied), reference))
        records[-1]["label"] = "combined: " + records[-1]["label"]
        if on_run:
            on_run(records[-1])
        if records[-1]["within_tolerance"]:
            break
        combined = _step_back(knobs, records, combined, varied)
    best = recommend(records)
    recommendation = None if best is None else {
        "label": best["label"], "settings": best["settings"],
        "overrides": overrides_of(best["settings"]), "wall_time_s": best["wall_time_s"],
        "cpu_time_s": best["cpu_time_s"], "worst_error": best["worst_error"],
        "speedup": reference.cpu_time_s / best["cpu_time_s"]}
    return reference, records, recommendation


CONTACT_KNOBS = ("contact_size", "increments_per_cycle", "normal_stiffness", "critical_slip", "cycle_jump",
                 "jump_tolerance", "cof_cycles")


def _is_multibody(path: Path) -> bool:
    """A multibody scene: an [mbs] table and no contact interface."""
    if not path.is_file():
        return False
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError:
        return False
    return "mbs" in data and "contact" not in data


def multibody_knobs(params, quick: bool) -> list[Knob]:
    """Craig–Bampton modes per counterweight and the integration time step (s), finest first."""
    modes, step = params.n_modes, params.solver.time_step
    return [Knob("craig_bampton_modes", "Craig–Bampton modes per counterweight",
                 (modes, max(1, modes // 2)) if quick else tuple(dict.fromkeys((2 * modes, modes, max(1, modes // 2)))),
                 True),
            Knob("mbs_time_step", "multibody time step, s", (step, 2 * step) if quick else (step / 2, step, 2 * step),
                 False)]


def _multibody_overrides(settings: dict) -> dict:
    return {("mbs.n_modes" if name == "craig_bampton_modes" else "mbs.solver.time_step"):
            (int(value) if name == "craig_bampton_modes" else float(value)) for name, value in settings.items()}
