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

import time
import tomllib
from contextlib import nullcontext
from pathlib import Path
from typing import Callable

from contact import procedure
from contact.solver import ConvergenceError
from pipelines import scene as scenes
from pipelines.build import build
from pipelines.studies.knobs import (CONTACT_KNOBS, Run, SCALAR_QUANTITIES, Study, _apply_sweeps,
                                     _check_contact_sizes, _is_multibody,
                                     _multibody_overrides, _sweep,
                                     base_overrides, knobs_for,
                                     multibody_knobs, setting_overrides)
from reduction.threads import one_blas_thread


try:
    from threadpoolctl import threadpool_limits
except ImportError:  # the same answers, costs measured with the default BLAS threads
    threadpool_limits = None


def run_setting(scene_path: Path, overrides: dict, label: str, settings: dict, varied: tuple) -> Run:
    """Build and run the scene with ``overrides``; a non-converging run is recorded, not raised."""
    scene = scenes.load(scene_path, overrides)
    record = Run(label, dict(settings), varied)
    clock, cpu = time.perf_counter(), time.process_time()
    try:
        with threadpool_limits(limits=1, user_api="blas") if threadpool_limits else nullcontext():
            model = build(scene)
            solver = model.solver()  # as `fretwork run` runs the scene (finite sliding where it asks)
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


@one_blas_thread
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


__all__ = ["accuracy_study", "multibody_study", "run_setting", "run_multibody_setting"]


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


@one_blas_thread
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
