"""How far each Krylov solve's tangent is from its preconditioner's (docs/performance.md).

``python tests/bench/tangent_probe.py [--size 2.5] [--cof 20] [--wear 10]`` runs
``examples/counterweight_extreme.toml`` at that contact size for that many COF cycles and wear
blocks and, for every solve that reuses a kept preconditioner, counts the closed points whose
tangent block (N/mm) differs from the preconditioner's by more than 1e-4, 1e-3, 1e-2 and 3e-2
of the largest entry. A low-rank (Woodbury) correction of the kept LU would cost three
triangular solves per such point. Prints the run's cost and counters, then the median, 90th
percentile and largest count per threshold.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "bench"))

import contact.linear as linear  # noqa: E402
import scene_run  # noqa: E402
from pipelines.jobs.run import run_model  # noqa: E402

THRESHOLDS = (1e-4, 1e-3, 1e-2, 3e-2)


def probe(rows: list, counters: list):
    """Wrap the pool's choice and the solver's construction to record both."""
    nearest, init = linear._Pool.nearest, linear.NewtonLinearSolver.__init__

    def probed_nearest(pool, blocks, closed_points):
        factor = nearest(pool, blocks, closed_points)
        if factor is not None:
            reference = np.zeros_like(blocks)
            reference[factor.points] = factor.blocks
            difference = np.abs(blocks[closed_points] - reference[closed_points]).max(axis=(1, 2))
            scale = np.abs(blocks[closed_points]).max()
            rows.append([closed_points.size] + [int(np.sum(difference > t * scale)) for t in THRESHOLDS])
        return factor

    def counted_init(solver, *args, **kwargs):
        init(solver, *args, **kwargs)
        counters.append(solver.counters)

    linear._Pool.nearest, linear.NewtonLinearSolver.__init__ = probed_nearest, counted_init


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    scene_run.short_extreme_arguments(parser, size=2.5)
    args = parser.parse_args(argv)
    model = scene_run.short_extreme(args)
    rows, counters = [], []
    probe(rows, counters)
    with tempfile.TemporaryDirectory() as out:
        start = time.process_time()
        outcome = run_model(model, Path(out), progress=False, plots=False)
        cpu = time.process_time() - start
    increments = outcome.summary["cycles_run"] * model.procedure.increments_per_cycle
    total = {key: sum(getattr(c, key) for c in counters)
             for key in ("solves", "krylov_iterations", "factorisations", "direct_solves")}
    print(json.dumps({"size": args.size, "points": model.assembly.structure.n_points,
                      "cpu_ms_per_cycle_increment": 1e3 * cpu / increments, **total,
                      "load_average": os.getloadavg()[0]}))
    table = np.array(rows)
    print(f"{len(table)} solves on a kept preconditioner, {np.median(table[:, 0]):.0f} closed points (median)")
    for k, threshold in enumerate(THRESHOLDS):
        count = table[:, k + 1]
        print(f"differing by more than {threshold:g} of the largest entry: median {np.median(count):.0f}, "
              f"90th percentile {np.percentile(count, 90):.0f}, largest {count.max()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
