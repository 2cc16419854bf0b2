"""``fretwork sweep``: the multibody model at every engine speed of a range, as parallel cases.

Each speed is an independent case (:func:`mbs.sweep.run_speed`) on dask
(:func:`pipelines.parallel.map_cases`: an embedded local cluster by default, an existing one with
``scheduler``, in this process with ``workers=0``). The CW (and flexible-throw) reduction is done
once on the client and sent to every worker once: re-reducing on each worker cost more (see
tests/bench/test_bench_distributed.py). Units: rpm, Hz, mm.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from mbs.excitation import excitation_orders
from mbs.model import reduce_bodies
from mbs.parameters import ModelParams
from mbs.sweep import SweepResult, collect_sweep, run_speed, write_sweep
from pipelines.parallel import map_cases
from reduction.errors import InputError, listed
from reduction.threads import one_blas_thread

SWEEP_FILE = "sweep.h5"


def output_paths(out, name: str) -> tuple[Path, Path]:
    """A multibody command's output folder and results file for ``--out``: a folder holds the file
    ``name`` and the plots; a name ending in .h5 or .hdf5 (the sweep's older form) names the
    file, and the plots go beside it."""
    out = Path(out)
    if out.suffix in (".h5", ".hdf5"):
        return out.parent, out
    return out, out / name


def sweep_paths(out) -> tuple[Path, Path]:
    """The sweep's output folder and file for ``--out`` (:func:`output_paths` of ``sweep.h5``)."""
    return output_paths(out, SWEEP_FILE)


#: The most speeds a sweep runs: each is a multibody run of seconds to minutes.
MAX_SPEEDS = 1000


def parse_speeds(text: str) -> np.ndarray:
    """'500:800:10' -> 500, 510, ..., 800 rpm (end included); '600,650,700' -> a list. At most
    :data:`MAX_SPEEDS` speeds, counted before the list is made (a tiny step would not fit memory)."""
    try:
        if ":" in text:
            start, stop, step = (float(v) for v in text.split(":"))
            if not (step > 0 and stop >= start):  # NaN too
                raise ValueError
        else:
            speeds = np.asarray([float(v) for v in text.split(",")])
    except ValueError:
        raise InputError(f"speeds {text!r}: use START:STOP:STEP with STEP > 0 and STOP >= START, "
                         "or a comma-separated list (rpm)") from None
    if ":" in text:
        finite = np.isfinite([start, stop, step]).all()
        with np.errstate(over="ignore"):
            count = np.floor((stop - start) / step + 0.5) + 1.0 if finite else 0.0
        if count > MAX_SPEEDS:
            smallest = (stop - start) / (MAX_SPEEDS - 1)
            digits = 10.0 ** (np.floor(np.log10(smallest)) - 2)  # three significant digits, rounded up
            amount = f"{count:,.0f}" if count < 1e12 else f"about {count:.2g}" if np.isfinite(count) else "countless"
            raise InputError(f"speeds {text!r}: {amount} speeds at a step of {step:g} rpm, more than the "
                             f"{MAX_SPEEDS:,} a sweep runs (each is a multibody run): give a step of at least "
                             f"{np.ceil(smallest / digits) * digits:.3g} rpm")
        speeds = np.arange(start, stop + 0.5 * step, step) if finite else np.asarray([start, stop, step])
    wrong = [f"{v:g}" for v in speeds if not (np.isfinite(v) and v > 0.0)]
    if wrong:
        raise InputError(f"speeds {text!r}: engine speeds must be positive and finite (rpm), got {', '.join(wrong)}")
    if speeds.size > MAX_SPEEDS:
        raise InputError(f"speeds {text!r}: {speeds.size:,} speeds, more than the {MAX_SPEEDS:,} a sweep runs "
                         "(each is a multibody run)")
    return speeds


#: Time steps per period of the highest excitation order. Below SAMPLED_STEPS (Nyquist) the
#: excitation is not represented at all, and exudyn may cut its steps to converge, leaving the
#: histories without the fixed sample rate their spectra need (75000 rpm at 5e-5 s: 0.5 steps per
#: gear-mesh period). Below ACCURATE_STEPS the wing amplitude is off by more than about 3 %: near
#: a resonance the amplitude follows the integrator's frequency error, not only its period error
#: (2π/n)²/12. Measured at 750 rpm against 5e-5 s (53 steps; QA, 2026-11-28): 2e-4 s (13 steps)
#: read CW1 17 % and CW2 44 % low, 1e-4 s (27 steps) 3 % and 10 % low; the README's 975 rpm case
#: reads 3 % low at 5e-5 s (41 steps). 30, not 40: the defaults (48 teeth, 5e-5 s, 750 rpm) give 33.
SAMPLED_STEPS = 2.0
ACCURATE_STEPS = 30.0


@dataclass(frozen=True)
class Resolution:
    """How the multibody time step samples the highest excitation order at one speed."""

    speed_rpm: float
    order: float
    source: str  # "gear mesh" or "gas torque"
    frequency_hz: float
    steps_per_period: float
    time_step_s: float

    def advice(self) -> str:
        """The way out: a time step that resolves the order at this speed, or a lower speed."""
        needed = 1.0 / (ACCURATE_STEPS * self.frequency_hz)
        highest = 60.0 / (ACCURATE_STEPS * self.order * self.time_step_s)
        return (f"set [mbs.solver] time_step to at most {needed:.2g} s ({ACCURATE_STEPS:g} steps per period), or "
                f"keep to speeds up to {highest:.0f} rpm at {self.time_step_s:g} s")


def excitation_resolution(model_params: ModelParams, speeds) -> list[Resolution]:
    """The resolution of the highest excitation order at every speed (rpm); [] without excitation."""
    orders = excitation_orders(model_params.excitation, model_params.effects)
    if orders.size == 0:
        return []
    order = float(orders.max())
    gear = "gear_mesh" in model_params.effects and order == float(model_params.excitation.gear_teeth)
    step = model_params.solver.time_step
    found = []
    for speed in np.asarray(speeds, dtype=float):
        frequency = order * speed / 60.0
        found.append(Resolution(float(speed), order, "gear mesh" if gear else "gas torque", frequency,
                                1.0 / (frequency * step), step))
    return found


def check_resolution(model_params: ModelParams, speeds) -> list[str]:
    """Refuse (InputError) the speeds whose highest excitation order the time step does not
    sample (:data:`SAMPLED_STEPS`), before any run; return a warning for those it samples with
    fewer than :data:`ACCURATE_STEPS` steps per period."""
    resolutions = excitation_resolution(model_params, speeds)
    unsampled = [r for r in resolutions if r.steps_per_period < SAMPLED_STEPS]
    coarse = [r for r in resolutions if SAMPLED_STEPS <= r.steps_per_period < ACCURATE_STEPS]
    if unsampled:
        worst = max(unsampled, key=lambda r: r.speed_rpm)
        raise InputError(f"at {_speeds(unsampled)} rpm the multibody time step {worst.time_step_s:g} s cannot "
                         f"follow the {worst.source} (engine order {worst.order:g}): at {worst.speed_rpm:g} rpm it "
                         f"is {worst.frequency_hz:.0f} Hz, {worst.steps_per_period:.2g} steps per period, fewer "
                         f"than the {SAMPLED_STEPS:g} that sample it at all: {worst.advice()} "
                         f"(is {worst.speed_rpm:g} rpm the engine speed you meant?)")
    if not coarse:
        return []
    worst = max(coarse, key=lambda r: r.speed_rpm)
    return [f"at {_speeds(coarse)} rpm the multibody time step {worst.time_step_s:g} s follows the {worst.source} "
            f"(engine order {worst.order:g}) with fewer than {ACCURATE_STEPS:g} steps per period "
            f"({worst.steps_per_period:.2g} at {worst.speed_rpm:g} rpm, {worst.frequency_hz:.0f} Hz): its response "
            f"there is not accurate; {worst.advice()}"]


def _speeds(resolutions) -> str:
    return listed([f"{r.speed_rpm:g}" for r in resolutions])


@one_blas_thread
def speed_sweep(model_params: ModelParams, speeds, *, path=None, progress: bool = False,
                scheduler: str | None = None, workers: int | None = None) -> SweepResult:
    """Run model_params at every engine speed in ``speeds`` (rpm) and collect the sweep.

    path: optional HDF5 file for the whole sweep (group /sweep, Campbell in /campbell), written
    here, by the client. progress: a bar over the finished speeds on stderr.
    scheduler, workers: where the speeds run (:func:`pipelines.parallel.map_cases`): None, None is
    an embedded local cluster with one worker per core; workers=0 runs them in this process.
    Speeds whose excitation the time step does not sample are refused before any run
    (:func:`check_resolution`; its warnings are the caller's to say).
    """
    speeds = np.asarray(speeds, dtype=float)
    if speeds.ndim != 1 or speeds.size == 0 or np.any(speeds <= 0):
        raise InputError("sweep speeds must be a non-empty list of positive engine speeds (rpm)")
    model_params.validate()
    check_resolution(model_params, speeds)
    reduced, reduced_throw = reduce_bodies(model_params)
    cases = [(float(speed), {"params": replace(model_params, speed_rpm=float(speed))}) for speed in speeds]
    outcomes = map_cases(run_speed, cases, scheduler=scheduler, workers=workers, label="sweep", progress=progress,
                         shared={"reduced": reduced, "reduced_throw": reduced_throw})
    result = collect_sweep(model_params, speeds, [o.error if o.value is None else o.value for o in outcomes], reduced)
    if path is not None:
        write_sweep(path, result)
    return result
