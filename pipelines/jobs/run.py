"""Run a scene end to end: build, condense, solve the procedure, write results and plots."""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from tqdm import tqdm

from contact import procedure
from contact.procedure import RunStopped
from contact.sliding import SlidingSolver
from contact.solver import ConvergenceError
from contact.verdict import Ending
from pipelines.build import Model, build
from pipelines.output.checkpoint import check_resumable
from pipelines.output.damage import DamageObserver
from pipelines.output.paraview import (
    write_final_vtu,
    write_increment_series,
    write_interface_series,
    write_master_final_vtu,
)
from pipelines.output.plots import plot_results
from pipelines.output.results import ResultsWriter
from pipelines.scene import Scene
from pipelines.stages import StageCache
from reduction.errors import InputError
from reduction.threads import one_blas_thread


class ProgressBar:
    """tqdm bar over the load cycles of all phases, with the current slip and stick areas; it
    also times each phase (``phase_times``, s)."""

    def __init__(self, total_cycles: int, enabled: bool, label: str, done: int = 0):
        self.bar = tqdm(total=total_cycles, initial=done, unit="cycle", disable=not enabled, desc=label,
                        dynamic_ncols=True, leave=True)
        self.phase_times: dict[str, float] = {}
        self._current: tuple[str, float] | None = None
        self._loosening_said = False

    def _stop_clock(self):
        if self._current is not None:
            name, start = self._current
            self.phase_times[name] = self.phase_times.get(name, 0.0) + time.perf_counter() - start
            self._current = None

    def phase(self, name, n_cycles):
        self._stop_clock()
        self._current = (name, time.perf_counter())
        self.bar.set_description(f"{name}")

    def increment(self, record):
        pass

    def cycle(self, summary):
        # what slid in the cycle, and what sits at the friction limit (it need not move: in
        # normal operation a third of the pads sits at the limit of μ₀ and sticks), of the area
        figures = summary.figures
        shown = {"sliding": f"{100 * figures['active_slip_area_fraction']:.0f}%",
                 "at_limit": f"{100 * figures['slip_area_fraction']:.0f}%"}
        if summary.clamp_force is not None:
            shown["clamp"] = f"{1e-3 * summary.clamp_force:.1f}kN"
        self.bar.set_postfix(shown, refresh=False)
        if summary.loosening_evident_at is not None and not self._loosening_said:
            # a long run that goes on to its life horizon: its verdict is known from here on
            self._loosening_said = True
            if not self.bar.disable:
                self.bar.write(f"loosening evident after {summary.loosening_evident_at:.3g} real cycles: the "
                               "verdict is loosening unless the joint shakes down later (Ctrl-C stops the run; "
                               "--resume goes on from its last checkpoint)", file=sys.stderr)
        self.bar.update(1)

    def close(self, reason: str | None = None, *, done: bool = False):
        """Close the bar, saying ``reason`` (why the run ended); ``done``: the run answered its
        question and the bar ends full (a run that shakes down early needs no more cycles)."""
        self._stop_clock()
        if reason is not None and not self.bar.disable:
            if done:
                self.bar.total = self.bar.n
            self.bar.set_postfix_str(reason, refresh=False)
            self.bar.refresh()
        self.bar.close()


#: Why a run ended, as its progress bar says it.
ENDINGS = {Ending.COMPLETED: "all cycles run", Ending.SHAKEDOWN: "stuck: shaken down, no more cycles needed",
           Ending.LOOSENING: "stopped: loosening evident", Ending.SLID_OFF: "stopped: the joint slides off",
           Ending.WEAR_RUNAWAY: "stopped: runaway wear",
           Ending.SEPARATED: "stopped: the contact surfaces slid or wore apart",
           Ending.DIVERGED: "stopped: an increment did not converge"}
#: Runs that end early but answer the question: their results file is complete, marked with the ending.
EARLY_ENDINGS = (Ending.SLID_OFF, Ending.WEAR_RUNAWAY, Ending.SEPARATED)


@dataclass
class Outcome:
    """What a run produced: the summary for --json, the files, and stage times (s)."""

    summary: dict
    results_path: Path
    plots: list
    stage_times: dict = field(default_factory=dict)


def contact_solver(model: Model) -> str:
    """Which contact path ran and why, e.g. "sparse (2,704 points ≥ 2,500)"."""
    return f"{model.contact_path} ({model.contact_path_reason})"


def _linear_solver(solver):
    """The Newton linear solver of a contact solver (a sliding solver's current one)."""
    return solver.solver.linear if isinstance(solver, SlidingSolver) else solver.linear


def _say(progress: bool, label: str, stage: str) -> None:
    """One line on stderr as a set-up stage starts (before the progress bar exists), if progress is shown."""
    if progress:
        print(f"{label}: {stage} ...", file=sys.stderr, flush=True)


@one_blas_thread
def run_model(model: Model, out_dir: Path, *, progress: bool = True, plots: bool = True,
              resume: bool = False) -> Outcome:
    stage_times = {}
    _say(progress, model.scene.name, f"the contact operators ({contact_solver(model)} path)")
    clock = time.perf_counter()
    space = model.contact_space()
    solver = model.solver(space)
    stage_times["contact_space_s"] = time.perf_counter() - clock
    effects = model.scene.effects
    proc = model.procedure
    total = proc.cof_cycles + (proc.wear_cycles if "wear" in effects else 0)
    settings = model.scene.section("procedure")
    if resume:
        check_resumable(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    writer = ResultsWriter(out_dir / "results.h5", model, space, record_every=settings.get("record_every", 1),
                           resume=resume, field_output=settings.get("field_output"))
    if isinstance(solver, SlidingSolver):
        solver.listeners.append(writer.follow)
    observer = DamageObserver(writer, model, space)
    if isinstance(solver, SlidingSolver):
        solver.listeners.append(observer.follow)
    bar = ProgressBar(total, progress, model.scene.name,
                      done=writer.snapshot.cycle_number if writer.snapshot else 0)
    writer.progress = bar
    clock = time.perf_counter()
    try:
        result = procedure.run(solver, model.initial_state(), model.program, proc,
                               cof_evolution="cof_evolution" in effects, wear="wear" in effects,
                               observer=observer, checkpoint=writer.checkpoint,
                               checkpoint_every=settings.get("checkpoint_every", 10),
                               resume=writer.snapshot)
    except RunStopped as stopped:
        early = stopped.ending in EARLY_ENDINGS
        if early:
            path = writer.stop(stopped.ending, str(stopped))
        else:
            writer.abort()
        bar.close(ENDINGS[stopped.ending])
        if early and plots:  # what converged before the joint failed, the failure marked
            plot_results(path, out_dir / "plots")
        raise
    except (ConvergenceError, KeyboardInterrupt):
        writer.abort()
        bar.close()
        raise
    except InputError:  # refused before the cycles (the preload closed no contact): no output stays
        writer.discard()
        bar.close()
        raise
    bar.close(ENDINGS[result.ending], done=True)
    stage_times.update({f"{name}_phase_s": seconds for name, seconds in bar.phase_times.items()})
    stage_times["procedure_s"] = time.perf_counter() - clock
    clock = time.perf_counter()
    path = writer.finish(result)
    written = _write_outputs(path, out_dir, plots, writer.output_increments)
    stage_times["outputs_s"] = time.perf_counter() - clock
    return Outcome(_summary(model, solver, result, writer), path, written, stage_times)


def _write_outputs(path: Path, out_dir: Path, plots: bool, increments: bool) -> list:
    """Plots (when asked for) and the ParaView files of a finished results file; the plots written."""
    written = plot_results(path, out_dir / "plots") if plots else []
    write_interface_series(path, out_dir / "interface.xdmf")
    write_final_vtu(path, out_dir / "interface_final.vtu")
    write_master_final_vtu(path, out_dir / "interface_master_final.vtu")  # finite sliding only
    if increments:
        write_increment_series(path, out_dir / "interface_increments.xdmf")
    return written


def _summary(model: Model, solver, result, writer: ResultsWriter) -> dict:
    """The run summary: verdict and figures, the solver paths taken, the coupling's figures."""
    summary = {"scene": model.scene.name, "verdict": result.verdict, "stationary": result.stationary,
               **result.figures, "contact_solver": contact_solver(model),
               "linear_solver": _linear_solver(solver).description()}
    summary.update(solver.summary() if isinstance(solver, SlidingSolver) else
                   {"sliding": "small", "sliding_mode": "small", "pairing": model.assembly.pairing.method})
    if model.coupling is not None:
        summary.update(model.coupling.summary())
        summary.update(_engine_hours(summary))
    if writer.snapshot is not None:
        summary["resumed_from_cycle"] = writer.snapshot.cycle_number
    return summary


def _engine_hours(summary: dict) -> dict:
    """The run's real-cycle counts as hours of engine running (one load cycle lasts
    1/load_cycle_frequency_hz s): ``equivalent_engine_hours`` and, where the run says when,
    ``shakedown_at_engine_hours`` and ``loosening_evident_at_engine_hours``."""
    frequency = summary.get("load_cycle_frequency_hz")
    if not frequency:
        return {}
    return {key.replace("cycles", "engine_hours"): summary[key] / frequency / 3600.0
            for key in ("equivalent_cycles", "shakedown_at_cycles", "loosening_evident_at_cycles")
            if summary.get(key) is not None}


@one_blas_thread
def run_scene(scene: Scene, out_dir: str | Path, *, progress: bool = True, plots: bool = True,
              resume: bool = False, cache: StageCache | None = None) -> Outcome:
    """Build the scene's model and run it into ``out_dir``; see :func:`run_model`.

    resume: continue from ``out_dir/checkpoint.h5`` (written every ``checkpoint_every`` cycles),
    checked before anything is built: a missing or damaged checkpoint costs no meshing.
    cache: stage cache for the multibody stage of a coupled scene.
    """
    if resume:
        check_resumable(out_dir)
    times = {}
    multibody = None
    if "coupling" in scene.data:
        from pipelines.coupling import multibody_loading

        _say(progress, scene.name, "the multibody run (or its cached result)")
        clock = time.perf_counter()
        multibody = multibody_loading(scene, cache)
        times["multibody_s"] = time.perf_counter() - clock
    _say(progress, scene.name, "meshing, condensing the bodies and pairing the contact")
    clock = time.perf_counter()
    model = build(scene, cache=cache, multibody=multibody)
    times["build_and_condense_s"] = time.perf_counter() - clock
    outcome = run_model(model, Path(out_dir), progress=progress, plots=plots, resume=resume)
    outcome.stage_times = {**times, **outcome.stage_times}
    # the phase times are parts of procedure_s
    outcome.summary["wall_time_s"] = sum(v for k, v in outcome.stage_times.items() if not k.endswith("_phase_s"))
    return outcome
