"""Benchmark: parallel efficiency of a 16-case amplitude study on the embedded LocalCluster.

Sixteen wing amplitudes (100–400 µm) of the counterweight scene, each a complete contact run
(40 COF cycles, 20 wear cycles, no stage cache), as dask tasks on one and on two workers;
prints the wall times, the speed-up and the efficiency (speed-up / workers). make bench only.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

from pipelines.parallel import map_cases
from pipelines import scene as scenes
from pipelines.jobs.limit import run_amplitude
from pipelines.studies.knobs import run_up_within

SCENE = Path(__file__).resolve().parents[2] / "examples" / "counterweight.toml"
OVERRIDES = {"procedure.cof_cycles": 40, "procedure.wear_cycles": 20,
             **run_up_within(scenes.load(SCENE), 40)}


def study(workers: int):
    cases = [(float(a), {"scene_path": str(SCENE), "overrides": OVERRIDES, "amplitude_mm": float(a),
                         "cache_dir": None}) for a in np.linspace(0.1, 0.4, 16)]
    clock = time.perf_counter()
    outcomes = map_cases(run_amplitude, cases, workers=workers, label=f"{workers} worker(s)", progress=False)
    return time.perf_counter() - clock, outcomes


@pytest.mark.bench
def test_parallel_efficiency_of_a_16_case_amplitude_study():
    one, first = study(1)
    two, second = study(2)
    assert all(o.error is None for o in first + second)
    assert [o.value.verdict for o in first] == [o.value.verdict for o in second]
    speed_up = one / two
    print(f"\n16-case amplitude study: 1 worker {one:.1f} s, 2 workers {two:.1f} s, "
          f"speed-up {speed_up:.2f}, efficiency {speed_up / 2:.0%}")
    print("verdicts:", {f"{1e3 * o.key:.0f} µm": o.value.verdict for o in first})
