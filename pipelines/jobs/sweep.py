"""``fretwork sweep``: the multibody model at every engine speed of a range, as parallel cases.

Each speed is an independent case (:func:`mbs.sweep.run_speed`) on dask
(:func:`pipelines.parallel.map_cases`: an embedded local cluster by default, an existing one with
``scheduler``, in this process with ``workers=0``). The CW (and flexible-throw) reduction is done
once on the client and sent to every worker once: re-reducing on each worker cost more (see
tests/bench/test_bench_distributed.py). Units: rpm, Hz, mm.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from mbs.model import reduce_bodies
from mbs.parameters import ModelParams
from mbs.sweep import SweepResult, collect_sweep, run_speed, write_sweep
from pipelines.parallel import map_cases
from reduction.errors import InputError

SWEEP_FILE = "sweep.h5"


def sweep_paths(out) -> tuple[Path, Path]:
    """The sweep's output folder and file for ``--out``: a folder holds ``sweep.h5`` and the plots;
    the older form, a file name ending in .h5, still names the file (the plots go beside it)."""
    out = Path(out)
    if out.suffix in (".h5", ".hdf5"):
        return out.parent, out
    return out, out / SWEEP_FILE


def parse_speeds(text: str) -> np.ndarray:
    """'500:800:10' -> 500, 510, ..., 800 rpm (end included); '600,650,700' -> a list."""
    try:
        if ":" in text:
            start, stop, step = (float(v) for v in text.split(":"))
            if step <= 0 or stop < start:
                raise ValueError
            return np.arange(start, stop + 0.5 * step, step)
        return np.asarray([float(v) for v in text.split(",")])
    except ValueError:
        raise InputError(f"speeds {text!r}: use START:STOP:STEP with STEP > 0 and STOP >= START, "
                         "or a comma-separated list (rpm)") from None


def speed_sweep(model_params: ModelParams, speeds, *, path=None, progress: bool = False,
                scheduler: str | None = None, workers: int | None = None) -> SweepResult:
    """Run model_params at every engine speed in ``speeds`` (rpm) and collect the sweep.

    path: optional HDF5 file for the whole sweep (group /sweep, Campbell in /campbell), written
    here, by the client. progress: a bar over the finished speeds on stderr.
    scheduler, workers: where the speeds run (:func:`pipelines.parallel.map_cases`): None, None is
    an embedded local cluster with one worker per core; workers=0 runs them in this process.
    """
    speeds = np.asarray(speeds, dtype=float)
    if speeds.ndim != 1 or speeds.size == 0 or np.any(speeds <= 0):
        raise InputError("sweep speeds must be a non-empty list of positive engine speeds (rpm)")
    model_params.validate()
    reduced, reduced_throw = reduce_bodies(model_params)
    cases = [(float(speed), {"params": replace(model_params, speed_rpm=float(speed))}) for speed in speeds]
    outcomes = map_cases(run_speed, cases, scheduler=scheduler, workers=workers, label="sweep", progress=progress,
                         shared={"reduced": reduced, "reduced_throw": reduced_throw})
    result = collect_sweep(model_params, speeds, [o.error if o.value is None else o.value for o in outcomes], reduced)
    if path is not None:
        write_sweep(path, result)
    return result
