"""Accuracy versus time: what each fidelity knob of a scene costs and what it changes.

For every knob that applies to the scene (contact mesh size, increments per cycle, penalty
stiffness kn, critical slip γ_crit, cycle-jump factor J, COF-phase length) the scene is run at
a few settings, one knob at a time, against a reference that takes the finest swept setting
of every knob. Each run is compared with the reference on the quantities an engineer decides
on: max wear depth (mm), the stabilised COF map, slip area fraction, clamp-force loss and the
verdict. Then the knobs are combined: for every knob the coarsest setting that kept all
quantities within the tolerance on its own. Coarsening errors can add up, so when the
combination misses the tolerance, the knob whose own error was largest goes one level finer
and the combination runs again (at most three combinations). The recommended setting
is the cheapest run whose quantities all stay within the tolerance of the reference (2 %) with
the same verdict.

Error measures (all dimensionless, 0.02 = 2 %):
- scalar quantities: |value − reference| / max(|reference|, floor). The floors (1 nm of wear,
  1 % of the contact area, 1 % of the clamp force) keep differences that are noise of a
  vanishing reference from dominating;
- COF map: RMS over the reference's contact points of μ − μ_ref, each run point taken at the
  nearest reference point when the meshes differ, divided by the COF's possible rise
  μ_max − μ_0 (the map is about how far μ has evolved);
- verdict: agrees or not; a run with another verdict never qualifies.

The cycle-jump knob keeps the equivalent cycles constant: wear_cycles × J is fixed.
Craig–Bampton modes and the multibody time step belong to the multibody model: a scene with an
[mbs] table and no [contact] is studied on those two knobs, its decision quantity the wing
amplitude (largest |wing torsion| of any counterweight over the second half of the run, mm);
contact scenes list them as not applicable, and multibody scenes the contact knobs.

Each run records its wall time and the CPU time of this process (build and condensation plus
the procedure, or the simulation, s). The cost that ranks runs (Pareto front,
recommendation) is the CPU time: on a shared machine the wall time of one setting varied 5x
between two identical runs, the CPU time far less. Runs use one BLAS thread (threadpoolctl, when
installed): the contact-space systems are small and dense, and two OpenBLAS threads on a loaded
2-core machine spin against each other (a 2.6 s run took 27 s of CPU), which made the costs
depend on the neighbours instead of the settings.

The reference and the one-knob runs do not depend on each other: they run as one round of
parallel cases (pipelines.parallel: an embedded local cluster, or ``scheduler``; workers=0
runs them in this process). The combinations follow one at a time, each depending on the last.
Every run is the same computation wherever it runs, so the records do not depend on where.
"""

from __future__ import annotations

import json
import math
import sys
import time
import tomllib
from contextlib import nullcontext
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np
from scipy.spatial import cKDTree

try:
    from threadpoolctl import threadpool_limits
except ImportError:  # the same answers, costs measured with the default BLAS threads
    threadpool_limits = None

from contact import procedure
from contact.solver import ContactSolver, ConvergenceError
from contact.structure import ContactSpace
from pipelines import scene as scenes
from pipelines.build import build, make_mesh
from pipelines.parallel import add_cluster_arguments, map_cases
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
    if "wear" in scene.effects and wear_cycles > 0:
        jump = proc.get("cycle_jump", defaults.cycle_jump)
        equivalent = wear_cycles * jump
        knobs.append(Knob("cycle_jump", f"cycle-jump factor J (wear_cycles × J = {equivalent:g} kept)",
                          tuple(equivalent / n for n in _halvings(wear_cycles, count, 1)), False))
    else:
        not_applicable["cycle_jump"] = "the scene has no wear phase"
    cof_cycles = proc.get("cof_cycles", defaults.cof_cycles)
    if "cof_evolution" in scene.effects and cof_cycles > 0:
        knobs.append(Knob("cof_cycles", "COF-phase length, cycles", _halvings(cof_cycles, count, 1), True))
    else:
        not_applicable["cof_cycles"] = "the scene has no COF phase with COF evolution"
    return knobs, not_applicable


def _capped(proc: dict, key: str, quick: bool, default: int) -> int:
    return min(proc.get(key, default), CYCLE_CAPS[quick][key])


def base_overrides(scene: scenes.Scene, quick: bool) -> dict:
    """Overrides that shorten the scene's phases to the study's caps (none if already short)."""
    proc = scene.data.get("procedure", {})
    defaults = procedure.Procedure()
    out = {}
    for key in ("wear_cycles", "cof_cycles"):
        capped = _capped(proc, key, quick, getattr(defaults, key))
        if capped != proc.get(key, getattr(defaults, key)):
            out[f"procedure.{key}"] = capped
    return out


def setting_overrides(scene: scenes.Scene, settings: dict) -> dict:
    """Scene overrides that realise ``settings`` (knob name → value)."""
    out = {}
    for name, value in settings.items():
        if name == "contact_size":
            out.update({key: float(value) for key in _contact_size_keys(scene.data)})
        elif name in ("increments_per_cycle", "cof_cycles"):
            out[f"procedure.{name}"] = int(value)
        elif name in ("normal_stiffness", "critical_slip"):
            out[f"contact.{name}"] = float(value)
        elif name == "cycle_jump":
            proc = scene.data.get("procedure", {})
            equivalent = proc.get("wear_cycles", 0) * proc.get("cycle_jump", 1.0)
            wear_cycles = max(1, int(round(equivalent / value)))
            out["procedure.wear_cycles"] = wear_cycles
            out["procedure.cycle_jump"] = equivalent / wear_cycles
        else:
            raise InputError(f"unknown accuracy knob '{name}'")
    return out


def run_setting(scene_path: Path, overrides: dict, label: str, settings: dict, varied: tuple) -> Run:
    """Build and run the scene with ``overrides``; a non-converging run is recorded, not raised."""
    scene = scenes.load(scene_path, overrides)
    record = Run(label, dict(settings), varied)
    clock, cpu = time.perf_counter(), time.process_time()
    try:
        with threadpool_limits(limits=1, user_api="blas") if threadpool_limits else nullcontext():
            model = build(scene)
            solver = ContactSolver(ContactSpace(model.assembly.structure), model.law, model.settings)
            result = procedure.run(solver, model.initial_state(), model.program, model.procedure,
                                   cof_evolution="cof_evolution" in scene.effects, wear="wear" in scene.effects)
    except ConvergenceError as error:
        record.wall_time_s = time.perf_counter() - clock
        record.cpu_time_s = time.process_time() - cpu
        record.failure = str(error)
        return record
    record.wall_time_s = time.perf_counter() - clock
    record.cpu_time_s = time.process_time() - cpu
    record.values = {q: result.figures.get(q) for q in SCALAR_QUANTITIES}
    record.verdict = result.verdict
    if "cof_evolution" in scene.effects:
        cof_phase = [c for c in result.cycles if c.phase == "cof"]
        record.cof = (cof_phase[-1].cof if cof_phase else result.state.cof).copy()
    record.coordinates = model.assembly.pairing.slave.coordinates
    contact = scene.data["contact"]
    record.values["cof_rise"] = contact["cof_max"] - contact["cof_initial"]
    return record


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


def accuracy_study(scene_path: str | Path, *, quick: bool = False, overrides: dict | None = None,
                   sweeps: dict | None = None, on_run: Callable[[dict], None] | None = None,
                   scheduler: str | None = None, workers: int | None = None) -> Study:
    """Sweep every applicable knob of the scene one at a time against the finest setting.

    overrides: scene overrides applied to every run ("procedure.cof_cycles": 10, ...), after the
    study's cycle caps (wear ≤ 20, COF ≤ 40 cycles; quick: ≤ 4 and ≤ 10, two values per knob).
    sweeps: knob name → values replacing its default sweep. on_run: called with each record.
    scheduler, workers: where the independent runs go (pipelines.parallel.map_cases).
    """
    scene_path = Path(scene_path)
    cluster = {"scheduler": scheduler, "workers": workers}
    if _is_multibody(scene_path):
        return multibody_study(scene_path, quick=quick, overrides=overrides, sweeps=sweeps, on_run=on_run,
                               **cluster)
    scene = scenes.load(scene_path)
    base = {**base_overrides(scene, quick), **(overrides or {})}
    scene = scenes.load(scene_path, base)
    knobs, not_applicable = knobs_for(scene, quick)
    knobs = _apply_sweeps(knobs, sweeps, scene.name)
    for knob in knobs:
        if knob.name == "contact_size":
            _check_contact_sizes(scene_path, scene, base, knob)

    def arguments(settings, varied, label):
        return {"scene_path": scene_path, "overrides": {**base, **setting_overrides(scene, settings)},
                "label": label, "settings": settings, "varied": varied}

    reference, records, recommendation = _sweep(knobs, run_setting, arguments, lambda s: setting_overrides(scene, s),
                                                on_run, cluster)
    return Study(scene.name, str(scene_path), base, knobs, not_applicable, reference, records, recommendation)


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


SHORT_NAMES = {"max_wear_depth_mm": "wear", "cof_map": "COF map", "slip_area_fraction": "slip area",
               "clamp_force_loss_fraction": "clamp loss", "wing_amplitude_mm": "wing amplitude"}


def plot_pareto(study: dict, path: str | Path) -> Path:
    """Worst decision-quantity error (%) versus cost (CPU time, s), one labelled point per run (PNG).

    ``study`` is :meth:`Study.to_dict` (or its JSON file read back); each label names the run's
    settings that differ from the reference and, in brackets, its worst quantity.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(10, 7))
    finished = [r for r in study["records"] if r["failure"] is None]
    front = {id(r) for r in pareto_front(finished)}
    notes = []  # combinations carry long labels: numbered on the plot, spelled out below it
    for record in finished:
        error = 100 * record["worst_error"]
        marker = "o" if record["verdict_agrees"] else "x"
        colour = "tab:green" if record["within_tolerance"] else "tab:red"
        ax.scatter(record[COST], error, marker=marker, color=colour, s=40 if id(record) in front else 20,
                   zorder=3)
        worst = max(record["errors"], key=record["errors"].get, default=None)
        label = record["label"]
        if label.startswith("combined"):
            notes.append(f"C{len(notes) + 1} = {label}")
            label = f"C{len(notes)}"
        label += f" [{SHORT_NAMES[worst]}]" if worst and record["worst_error"] > 0 else ""
        ax.annotate(label, (record[COST], error), fontsize=7, xytext=(4, 3 + 9 * (label[0] == "C") * len(notes)),
                    textcoords="offset points")
    line = sorted((r[COST], 100 * r["worst_error"]) for r in finished if id(r) in front)
    if line:
        ax.plot(*zip(*line), color="0.6", lw=1, zorder=2, label="Pareto front")
    rec = study["recommendation"]
    if rec:
        ax.scatter(rec[COST], 100 * rec["worst_error"], s=180, facecolors="none", edgecolors="k",
                   zorder=4, label="recommended")
    ax.axhline(100 * TOLERANCE, color="k", ls="--", lw=0.8, label=f"{100 * TOLERANCE:g} % tolerance")
    ax.set_xscale("log")
    ax.set_yscale("symlog", linthresh=0.1)
    ax.set_ylim(bottom=0.0, top=3 * max([100 * r["worst_error"] for r in finished] + [100 * TOLERANCE]))
    ax.set_xlabel("CPU time of the run (build and solve, one BLAS thread) [s]")
    ax.set_ylabel("worst decision-quantity error [%]  (x: verdict differs)")
    reference = study["reference"]["settings"]
    title = (f"accuracy vs time: {study['scene']}\nreference: "
             + ", ".join(f"{k}={v:g}" for k, v in reference.items()))
    if study["base_overrides"]:
        title += "\nall runs: " + ", ".join(f"{k}={v}" for k, v in study["base_overrides"].items())
    failed = [r["label"] for r in study["records"] if r["failure"]]
    if failed:
        title += f"\nnot converged: {'; '.join(failed)}"
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    ax.grid(True, which="both", alpha=0.3)
    if rec:
        notes.append(f"recommended: {rec['label']}")
    fig.text(0.01, 0.01, "\n".join(notes), fontsize=7, va="bottom")
    fig.tight_layout(rect=(0, 0.02 + 0.025 * len(notes), 1, 1))
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def table_lines(study: Study) -> list[str]:
    """The study as text: one line per run, then the recommendation."""
    names = [q for q in QUANTITIES if any(q in r["errors"] for r in study.records)]
    ref = study.reference
    lines = [f"scene {study.scene}: reference {ref.verdict or 'without verdict'}, CPU {ref.cpu_time_s:.1f} s "
             f"(wall {ref.wall_time_s:.1f} s); "
             + ", ".join(f"{q} {ref.values[q]:.6g}" for q in SCALAR_QUANTITIES if ref.values.get(q) is not None),
             f"  base overrides: {study.base_overrides or 'none'}",
             "  " + f"{'run':<44} {'CPU s':>7} {'wall s':>7} " + " ".join(f"{q[:14]:>14}" for q in names) + "  verdict"]
    for r in study.records:
        if r["failure"]:
            lines.append(f"  {r['label']:<44} {r['cpu_time_s']:>7.1f} {r['wall_time_s']:>7.1f}  did not converge")
            continue
        errs = " ".join(f"{100 * r['errors'][q]:>13.2f}%" if q in r["errors"] else f"{'-':>14}" for q in names)
        mark = "" if r["verdict_agrees"] else " (differs)"
        lines.append(f"  {r['label']:<44} {r['cpu_time_s']:>7.1f} {r['wall_time_s']:>7.1f} {errs}  "
                     f"{r['verdict'] or '-'}{mark}")
    for name, why in study.not_applicable.items():
        lines.append(f"  not applicable: {name}: {why}")
    rec = study.recommendation
    if rec:
        lines.append(f"  recommended (cheapest within {100 * TOLERANCE:g} %): {rec['label']} — "
                     f"CPU {rec['cpu_time_s']:.1f} s, {rec['speedup']:.1f}x cheaper than the reference, "
                     f"worst error {100 * rec['worst_error']:.2f} %; overrides {rec['overrides']}")
    else:
        lines.append(f"  no swept setting keeps every decision quantity within {100 * TOLERANCE:g} %")
    if study.plot:
        lines.append(f"  plot: {study.plot}")
    return lines


__all__ = ["Knob", "Run", "Study", "accuracy_study", "knobs_for", "setting_overrides", "run_setting", "errors",
           "recommend", "pareto_front", "plot_pareto", "table_lines", "TOLERANCE"]


def _parse_value(text: str, where: str):
    try:
        return tomllib.loads(f"value = {text}")["value"]
    except tomllib.TOMLDecodeError:
        raise InputError(f"{where}: '{text}' is not a TOML value (number, true/false, \"text\")") from None


def _parse_pairs(items: list[str], option: str) -> dict:
    pairs = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key or not value:
            raise InputError(f"{option} '{item}' must read NAME=VALUE")
        pairs[key.strip()] = value.strip()
    return pairs


def cmd_accuracy(args) -> int:
    """``fretwork study accuracy``: run the study, print the table (or JSON), write plot and JSON."""
    overrides = {key: _parse_value(value, f"--set {key}") for key, value in _parse_pairs(args.set, "--set").items()}
    sweeps = {key: [_parse_value(v, f"--knob {key}") for v in value.split(",")]
              for key, value in _parse_pairs(args.knob, "--knob").items()}
    for key, values in sweeps.items():
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0 for v in values):
            raise InputError(f"--knob {key}: values must be positive numbers, got {values}")

    def progress(record):
        state = "did not converge" if record["failure"] else f"worst error {100 * record['worst_error']:.2f} %"
        print(f"  {record['label']}: CPU {record['cpu_time_s']:.1f} s, wall {record['wall_time_s']:.1f} s, {state}",
              file=sys.stderr, flush=True)

    study = accuracy_study(args.scene, quick=args.quick, overrides=overrides, sweeps=sweeps, on_run=progress,
                           scheduler=args.scheduler, workers=args.workers)
    out = Path(args.out)
    study.plot = str(plot_pareto(study.to_dict(), out / f"accuracy_{study.scene}.png"))
    text = json.dumps(study.to_dict(), indent=2, default=float)
    (out / f"accuracy_{study.scene}.json").write_text(text)
    print(text if args.json else "\n".join(table_lines(study)))
    return 0


def add_accuracy_parser(kinds) -> None:
    """Register ``study accuracy`` under the ``study`` subcommand group."""
    parser = kinds.add_parser("accuracy", help="accuracy versus wall time of the fidelity knobs of a scene")
    parser.add_argument("scene")
    parser.add_argument("--json", action="store_true", help="print the study as JSON")
    parser.add_argument("--out", default="results/accuracy", help="directory of the Pareto plot and JSON")
    parser.add_argument("--quick", action="store_true", help="two values per knob, wear ≤ 4 and COF ≤ 10 cycles")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="scene override for every run, e.g. procedure.cof_cycles=10 (repeat)")
    parser.add_argument("--knob", action="append", default=[], metavar="NAME=V1,V2",
                        help="replace a knob's sweep, e.g. contact_size=3,4,6 (repeat)")
    add_cluster_arguments(parser)
    parser.set_defaults(func=cmd_accuracy)


CONTACT_KNOBS = ("contact_size", "increments_per_cycle", "normal_stiffness", "critical_slip", "cycle_jump",
                 "cof_cycles")


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


def run_multibody_setting(scene_path: Path, overrides: dict, label: str, settings: dict, varied: tuple) -> Run:
    """Simulate the multibody model with ``overrides``; the decision quantity is the largest wing
    amplitude (mm, :func:`mbs.histories.wing_amplitude`) of any counterweight."""
    from mbs.model import reduce_bodies, simulate
    from mbs.scene import model_params_from_mapping

    data = tomllib.loads(scene_path.read_text())
    scenes.apply_overrides(data, overrides)
    params = model_params_from_mapping(data.get("mbs", {}), where=f"{scene_path}: [mbs]", folder=scene_path.parent)
    record = Run(label, dict(settings), varied)
    clock, cpu = time.perf_counter(), time.process_time()
    with threadpool_limits(limits=1, user_api="blas") if threadpool_limits else nullcontext():
        reduced, reduced_throw = reduce_bodies(params)
        histories = simulate(params, reduced=reduced, reduced_throw=reduced_throw)
    record.wall_time_s = time.perf_counter() - clock
    record.cpu_time_s = time.process_time() - cpu
    record.values = {"wing_amplitude_mm": float(histories.wing_amplitude.max())}
    return record


def multibody_study(scene_path: Path, *, quick: bool = False, overrides: dict | None = None,
                    sweeps: dict | None = None, on_run: Callable[[dict], None] | None = None,
                    scheduler: str | None = None, workers: int | None = None) -> Study:
    """The accuracy study of a multibody scene ([mbs] table): CB modes and time step."""
    from mbs.scene import model_params_from_mapping

    data = tomllib.loads(scene_path.read_text())
    base = dict(overrides or {})
    scenes.apply_overrides(data, base)
    params = model_params_from_mapping(data.get("mbs", {}), where=f"{scene_path}: [mbs]", folder=scene_path.parent)
    name = data.get("scene", {}).get("name", scene_path.stem)
    knobs = _apply_sweeps(multibody_knobs(params, quick), sweeps, name)
    not_applicable = {knob: "contact scenes only; this scene has no contact interface" for knob in CONTACT_KNOBS}

    def arguments(settings, varied, label):
        return {"scene_path": scene_path, "overrides": {**base, **_multibody_overrides(settings)}, "label": label,
                "settings": settings, "varied": varied}

    reference, records, recommendation = _sweep(knobs, run_multibody_setting, arguments, _multibody_overrides, on_run,
                                                {"scheduler": scheduler, "workers": workers})
    return Study(name, str(scene_path), base, knobs, not_applicable, reference, records, recommendation)
