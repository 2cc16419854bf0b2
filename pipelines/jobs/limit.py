"""Amplitude limit of a coupled scene: the lowest wing amplitude whose verdict is not ``stick``.

Each amplitude is one complete contact run (preload, COF phase, wear phase) of the scene with
its wing vibration scaled (:func:`pipelines.coupling.coupled_program`; nothing is re-condensed).
A run in which the joint cannot carry the load at all (tangential equilibrium lost: the CW
slides off) counts as ``loosening``, and so does a wear phase whose wear runs away (the wear
increment does not shrink with the step: the interface slides by itself); both are noted.

The search does not assume that a larger amplitude never gives a safer verdict: it scans a
grid of amplitudes over the range, then refines every change of verdict to the tolerance
(:mod:`pipelines.jobs.scan`), each round running :data:`AMPLITUDES_PER_ROUND` amplitudes
whatever the workers (the amplitudes run, and so the bracket found, are the scene's, not the
machine's).
The limit is the lowest amplitude found not stuck; every change of verdict is listed, and a
verdict that returns to ``stick`` above the limit is reported as non-monotone. Runs are
independent cases (:func:`pipelines.parallel.map_cases`) and each is cached (stage
``contact_run``), so a repeated or extended search only runs new amplitudes.

Amplitudes in mm internally; the command line takes µm, as engineers quote wing amplitudes.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from contact.verdict import Ending
from contact.solver import ConvergenceError
from pipelines.output.jsonfile import json_text
from reduction.errors import InputError
from reduction.threads import one_blas_thread

SAFE = "stick"
NOT_CONVERGED = "not_converged"  # a run whose Newton failed even after its cutbacks: not shown to stick
FIGURES = ("clamp_force_loss_fraction", "damaged_area_fraction", "slip_area_fraction", "cof_evolved_area_fraction",
           "worn_area_fraction", "max_wear_depth_mm", "bolt_force_initial_N", "bolt_force_final_N",
           "min_stick_margin", "cycles_run", "equivalent_cycles")


@dataclass(frozen=True)
class AmplitudeRun:
    """One contact run: wing amplitude (mm), its verdict, the figures of its summary, or an error."""

    amplitude_mm: float
    verdict: str | None
    figures: dict
    error: str | None = None

    @property
    def safe(self) -> bool:
        return self.verdict == SAFE


@dataclass
class LimitResult:
    """limit_mm: the lowest amplitude found not stuck (None: stuck over the whole range);
    bracket_mm: (largest stuck amplitude below it or None, limit_mm); range_mm: the range
    searched; changes: every change of verdict (:class:`pipelines.jobs.scan.Change`);
    monotone: False when a verdict returns to stick above the limit."""

    limit_mm: float | None
    bracket_mm: tuple
    tolerance_mm: float
    runs: list = field(default_factory=list)
    range_mm: tuple = (None, None)
    changes: list = field(default_factory=list)
    monotone: bool = True

    @property
    def margin_limit_mm(self) -> float | None:
        """What margins divide (mm): the largest amplitude shown to stick, the lower end of the
        bracket, so that a margin of at least 1 means the wing vibrates no more than an amplitude
        that stuck. Where every amplitude of the range stuck, the range's top (the margins are then
        lower bounds); where none did, the range's bottom, the limit (the margins are then upper
        bounds: no amplitude was shown to stick). See :attr:`margin_bound`."""
        if self.limit_mm is None:
            return self.range_mm[1]
        return self.limit_mm if self.bracket_mm[0] is None else self.bracket_mm[0]

    @property
    def margin_bound(self) -> str:
        """How the margins stand to the true ones: "stuck" (divided by an amplitude that stuck),
        "lower bound" (all of the range stuck) or "upper bound" (none of it did)."""
        if self.limit_mm is None:
            return "lower bound"
        return "upper bound" if self.bracket_mm[0] is None else "stuck"

    @property
    def speed_rpm(self) -> float | None:
        """The engine speed the search ran at (rpm), as its runs' summaries state it; None when
        no run states it."""
        speeds = {r.figures["engine_speed_rpm"] for r in self.runs if r.figures.get("engine_speed_rpm") is not None}
        return float(min(speeds)) if speeds else None

    def to_json(self) -> dict:
        runs = sorted(self.runs, key=lambda r: r.amplitude_mm)
        return {
            "limit_um": _um(self.limit_mm),
            "limit_mm": None if self.limit_mm is None else float(self.limit_mm),
            "bracket_um": [_um(a) for a in self.bracket_mm],
            "margin_amplitude_um": _um(self.margin_limit_mm),
            "margin_bound": self.margin_bound,
            "tolerance_um": float(1e3 * self.tolerance_mm),
            "range_um": [_um(a) for a in self.range_mm],
            "speed_rpm": self.speed_rpm,
            "monotone": self.monotone,
            "changes": [{"below_um": _um(c.below_mm), "above_um": _um(c.above_mm),
                         "verdict_below": c.verdict_below, "verdict_above": c.verdict_above} for c in self.changes],
            "runs": [{"amplitude_um": float(1e3 * r.amplitude_mm), "verdict": r.verdict, "error": r.error,
                      "note": r.figures.get("note"),
                      **{k: r.figures.get(k) for k in FIGURES}} for r in runs],
        }


def _um(amplitude_mm: float | None) -> float | None:
    return None if amplitude_mm is None else float(1e3 * amplitude_mm)


#: The top of an amplitude range below which it was probably typed in mm: the wing amplitudes a
#: joint is rated against are tens to hundreds of µm, and the scene's own wing_amplitude is
#: flagged below 1 µm too (:func:`pipelines.scene.checks.plausibility`).
SMALLEST_RANGE_TOP_UM = 1.0


def parse_range_um(text: str) -> tuple[float, float]:
    """'100:400' (µm) → (0.1, 0.4) mm. A range that tops below :data:`SMALLEST_RANGE_TOP_UM` is
    refused as a likely mm-for-µm mistake: every run of such a range is stuck, and the search would
    report a limit above a range nobody meant."""
    try:
        low, high = (float(v) for v in text.split(":"))
    except ValueError:
        raise InputError(f"--amplitude {text!r}: use LOW:HIGH in µm, e.g. 100:400") from None
    if not (math.isfinite(low) and math.isfinite(high)):
        raise InputError(f"--amplitude {text!r}: LOW and HIGH must be finite numbers (µm)")
    if not 0 < low < high:
        raise InputError(f"--amplitude {text!r}: needs 0 < LOW < HIGH (µm)")
    if high < SMALLEST_RANGE_TOP_UM:
        raise InputError(f"--amplitude {text!r} tops at {high:g} µm, below {SMALLEST_RANGE_TOP_UM:g} µm: probably "
                         f"mm (µm expected: {low:g}:{high:g} mm is --amplitude {1e3 * low:g}:{1e3 * high:g})")
    return 1e-3 * low, 1e-3 * high


def check_search(low_mm: float, high_mm: float, tolerance_mm: float, grid: int = 7) -> None:
    """The search's range (mm), tolerance (mm) and grid, every problem in one InputError.

    A tolerance as wide as the range is refused: the search could only say that the limit lies
    somewhere in the range, which the range already says."""
    problems = []
    if not (math.isfinite(low_mm) and math.isfinite(high_mm)):
        problems.append("the amplitude range must be finite")
    elif not 0 < low_mm < high_mm:
        problems.append("the amplitude range needs 0 < low < high")
    if not math.isfinite(tolerance_mm) or tolerance_mm <= 0:
        problems.append("the limit tolerance must be a finite positive number")
    elif 0 < low_mm < high_mm and tolerance_mm >= (1 - 1e-9) * (high_mm - low_mm):  # µm → mm rounds
        width = high_mm - low_mm
        problems.append(f"the limit tolerance, {format_um(tolerance_mm)} µm, is not narrower than the amplitude "
                        f"range {format_um(low_mm, width)}:{format_um(high_mm, width)} µm "
                        f"({format_um(width, width)} µm wide): give a tolerance below the range's width")
    if grid < 2:
        problems.append("the amplitude grid needs at least 2 amplitudes")
    if problems:
        raise InputError("; ".join(problems))


def format_um(amplitude_mm: float, tolerance_mm: float | None = None) -> str:
    """An amplitude (mm) in µm, without the unit, with the digits that tell it apart: at least
    one decimal, two significant digits below 1 µm, and the tolerance's decimals when given."""
    um = 1e3 * amplitude_mm
    decimals = 1
    if 0 < abs(um) < 1:
        decimals = max(decimals, 1 - math.floor(math.log10(abs(um))))
    if tolerance_mm:
        decimals = max(decimals, -math.floor(math.log10(1e3 * tolerance_mm)))
    return f"{um:.{decimals}f}"


def coupled_scene(scene_path, overrides: dict | None = None):
    """The scene of a limit search; a scene without [coupling] has no wing amplitude to vary."""
    from pipelines import scene as scenes

    scene = scenes.load(scene_path, overrides or None)
    if "coupling" not in scene.data:
        raise InputError(f"{scene_path}: the amplitude limit needs a coupled scene (a [coupling] table whose "
                         "wing amplitude the search varies)")
    return scene


class BuiltModels:
    """The condensed model of each scene a limit search has built, kept for its next amplitudes.

    One instance belongs to one search (:func:`find_limit` creates it and hands it to every
    case): a process that runs several amplitudes of the search builds the model once. The model
    holds factorisations that cannot be pickled, so it is not a stage of the stage cache."""

    def __init__(self):
        self._models = {}

    def __getstate__(self):  # sent to a worker empty: a worker builds its own copy once per round
        return {"_models": {}}

    def model(self, scene, cache):
        from pipelines.build import build
        from pipelines.stages import stage_key

        key = stage_key("contact_model", scene.data)
        if key not in self._models:
            self._models = {key: build(scene, cache=cache)}
        return self._models[key]


#: Runs that stop on a failed increment and still answer the search: the joint is not stuck.
#: Amplitudes each refining round of the search runs, split among the intervals still to narrow:
#: the same on every machine, so that the amplitudes run, and so the bracket and the margins,
#: do not depend on the number of workers (QA: the user joint's bracket was 218.8–228.1 µm run
#: serially and 225.0–233.3 µm on two workers, its margins 3.88 and 3.99 at 600 rpm). Two keep
#: the default two-core machine busy with one interval to narrow.
AMPLITUDES_PER_ROUND = 2

STOPPED = {Ending.SLID_OFF: "the CW slides off: tangential equilibrium lost",
           Ending.WEAR_RUNAWAY: "runaway wear: the wear phase slid by itself at the scene's cycle jump",
           Ending.SEPARATED: "the CW's contact surfaces slid or wore apart"}


def run_amplitude(scene_path: str, overrides: dict, amplitude_mm: float, cache_dir: str | None,
                  out_dir: str | None = None, models: BuiltModels | None = None) -> AmplitudeRun:
    """One contact run of the scene at a wing amplitude (mm); a case of the limit search.

    models: the search's built models (built here when None). A run that stops because the CW
    slid off, its wear ran away or its surfaces came apart counts as ``loosening``
    (:data:`STOPPED`); any other failed
    run is an error."""
    import tempfile
    from contextlib import nullcontext

    from contact.procedure import RunStopped
    from pipelines.coupling import coupled_program
    from pipelines.jobs.run import run_model
    from pipelines.jobs.scan import decimal_mm
    from pipelines.stages import StageCache

    scene = coupled_scene(scene_path, overrides)
    cache = StageCache(cache_dir)
    models = models or BuiltModels()

    def compute() -> AmplitudeRun:
        model = coupled_program(models.model(scene, cache), amplitude_mm)
        folder = nullcontext(Path(out_dir) / f"amplitude_{1e3 * amplitude_mm:07.2f}um") if out_dir \
            else tempfile.TemporaryDirectory()
        try:
            with folder as where:
                outcome = run_model(model, Path(where), progress=False, plots=False)
        except RunStopped as stopped:
            if stopped.ending in STOPPED:
                return AmplitudeRun(amplitude_mm, "loosening", {"note": STOPPED[stopped.ending]})
            # Not shown to stick: the scan counts it as a change of verdict like any other and
            # lists it, so that one hard amplitude does not end the search for the others.
            return AmplitudeRun(amplitude_mm, NOT_CONVERGED, {"note": f"Newton did not converge: {stopped}"})
        summary = {k: v for k, v in outcome.summary.items() if isinstance(v, (int, float, str, type(None)))}
        return AmplitudeRun(amplitude_mm, outcome.summary["verdict"], summary)

    inputs = {"scene": scene.data, "amplitude_mm": decimal_mm(amplitude_mm)}
    return cache.get("contact_run", inputs, compute)


@one_blas_thread
def find_limit(scene_path, low_mm: float, high_mm: float, *, tolerance_mm: float = 0.01, grid: int = 7,
               overrides: dict | None = None, cache_dir=None, out_dir=None, scheduler: str | None = None,
               workers: int | None = None, progress: bool = True) -> LimitResult:
    """Scan ``grid`` amplitudes over [low_mm, high_mm] and refine every change of verdict (module doc)."""
    from pipelines.parallel import cluster, map_cases

    coupled_scene(scene_path, overrides)  # bad input is said before any run
    check_search(low_mm, high_mm, tolerance_mm, grid)
    search = (scene_path, low_mm, high_mm, tolerance_mm, grid, overrides, cache_dir, out_dir)
    if workers == 0:
        return _search(*search, {"scheduler": None, "workers": 0}, progress, map_cases)
    with cluster(scheduler, workers) as where:
        return _search(*search, where, progress, map_cases)


def _search(scene_path, low_mm, high_mm, tolerance_mm, grid, overrides, cache_dir, out_dir, where,
            progress, map_cases) -> LimitResult:
    from pipelines.jobs.scan import scan

    runs: dict[float, AmplitudeRun] = {}
    models = BuiltModels()
    rounds = itertools.count(1)

    def evaluate(amplitudes):
        label = f"limit: round {next(rounds)}"
        cases = [(float(a), {"scene_path": str(scene_path), "overrides": overrides or {}, "amplitude_mm": float(a),
                             "cache_dir": None if cache_dir is None else str(cache_dir),
                             "out_dir": None if out_dir is None else str(out_dir)}) for a in amplitudes]
        for outcome in map_cases(run_amplitude, cases, label=label, progress=progress, shared={"models": models},
                                 **where):
            runs[outcome.key] = outcome.value if outcome.error is None else \
                AmplitudeRun(outcome.key, None, {}, outcome.error)
        failed = [runs[a] for a in amplitudes if runs[a].verdict is None]
        if failed:  # not the input's fault (it was checked): a stopped simulation, exit status 1
            raise ConvergenceError("the limit search cannot continue: the run at " + "; ".join(
                f"{format_um(r.amplitude_mm, tolerance_mm)} µm failed ({r.error})" for r in failed))
        return {a: runs[a].verdict for a in amplitudes}

    found = scan(evaluate, low_mm, high_mm, tolerance_mm=tolerance_mm, grid=grid, parallel=AMPLITUDES_PER_ROUND)
    return LimitResult(found.limit_mm, (found.stuck_below_mm, found.limit_mm), tolerance_mm, list(runs.values()),
                       (low_mm, high_mm), found.changes, found.monotone)


def plot_limit(result: LimitResult, path: Path, title: str) -> Path:
    """Clamp-force loss and damaged area versus wing amplitude, verdicts marked, the bracket of
    the limit shaded (stuck at its lower end, not at its upper end). Each run is labelled with the
    real cycles it ran to: the runs end when their verdict is clear, at very different running
    times, so the curves do not compare amplitudes at equal cycles."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    everything = sorted((r for r in result.runs if r.verdict is not None), key=lambda r: r.amplitude_mm)
    runs = [r for r in everything if "note" not in r.figures]  # runs with figures
    failed_early = [r for r in everything if "note" in r.figures]  # slid off or wear ran away
    amplitude = np.array([1e3 * r.amplitude_mm for r in runs])
    loss = np.array([100 * (r.figures.get("clamp_force_loss_fraction") or 0.0) for r in runs])
    damaged = np.array([100 * (r.figures.get("damaged_area_fraction") or 0.0) for r in runs])
    colours = {"stick": "tab:green", "partial_slip": "tab:olive", "damage": "tab:orange", "loosening": "tab:red"}
    figure, axes = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True)
    low, high = result.bracket_mm
    for ax, values, label in ((axes[0], loss, "clamp-force loss (%)"), (axes[1], damaged, "damaged area (%)")):
        ax.plot(amplitude, values, color="0.6", zorder=1)
        for verdict, colour in colours.items():
            mask = np.array([r.verdict == verdict for r in runs])
            if mask.any():
                ax.scatter(amplitude[mask], values[mask], color=colour, label=verdict, zorder=2)
        if failed_early:
            ax.scatter([1e3 * r.amplitude_mm for r in failed_early], [ax.get_ylim()[1]] * len(failed_early),
                       marker="x", color="tab:red", label="slid off / runaway wear / not converged", zorder=2, clip_on=False)
        if low is not None and high is not None:
            ax.axvspan(1e3 * low, 1e3 * high, color="0.85", zorder=0,
                       label=f"limit bracket: stuck at {format_um(low, result.tolerance_mm)} µm, "
                             f"not at {format_um(high, result.tolerance_mm)} µm")
        elif result.limit_mm is not None:
            ax.axvline(1e3 * result.limit_mm, color="k", linestyle="--", linewidth=1)
        for change in result.changes if not result.monotone else ():
            if change.verdict_above == SAFE:  # back to stick above the limit
                ax.axvspan(1e3 * change.below_mm, 1e3 * change.above_mm, color="tab:purple", alpha=0.3)
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    for x, y, run in zip(amplitude, loss, runs):
        cycles = run.figures.get("equivalent_cycles")
        if cycles is not None:  # upright: neighbouring amplitudes of a refined bracket sit close
            mantissa, exponent = f"{cycles:.1e}".split("e")
            axes[0].annotate(f"{cycles:.0f}" if cycles < 1e4 else f"{mantissa}e{int(exponent)}", (x, y), xytext=(0, 6), textcoords="offset points",
                             ha="center", va="bottom", rotation=90, fontsize=7, color="0.25")
    bottom, top = axes[0].get_ylim()
    axes[0].set_ylim(bottom, top + 0.3 * (top - bottom))  # room for the cycle labels
    axes[0].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, fontsize=8)  # off the points
    speed = result.speed_rpm
    searched = f", searched at {speed:.0f} rpm" if speed is not None else ""
    axes[0].set_title(f"{title}{searched}: {describe_limit(result)}", fontsize=10)
    axes[1].set_xlabel("wing amplitude (µm)")
    figure.tight_layout(rect=(0, 0.05, 1, 1))
    figure.text(0.01, 0.01, "numbers over the points: the real load cycles each run reached. The runs end at very "
                "different running times,\nso the points are not at equal cycles: clamp-force loss and damaged area "
                "compare runs of different lengths.", fontsize=7.5, color="0.25", va="bottom")
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path


def describe_limit(result: LimitResult) -> str:
    """The limit in one line: where it lies, and whether the verdict is monotone."""
    low, high = result.range_mm

    def um(amplitude_mm):
        return format_um(amplitude_mm, result.tolerance_mm)

    if result.limit_mm is None:
        return f"stuck up to {um(high)} µm: the limit lies above the range"
    if result.bracket_mm[0] is None:
        return f"not stuck even at {um(low)} µm: the limit lies below the range"
    text = f"limit {um(result.limit_mm)} µm (not stuck; {um(result.bracket_mm[0])} µm is stuck)"
    return text if result.monotone else text + ", NOT MONOTONE: stuck again above it"


def write_limit(result: LimitResult, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json_text(result.to_json()))
    return path
