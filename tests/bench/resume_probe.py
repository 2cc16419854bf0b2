"""What the dense Krylov path does in a resumed run (docs/performance.md: one preconditioner
per load step).

``python tests/bench/resume_probe.py SCENE OUT [--cache DIR] [--every 20]`` continues the run
in the folder OUT (a copy of an interrupted run's folder, with its ``checkpoint.h5``) as
``fretwork run SCENE --out OUT --resume --quiet`` does, and every ``--every`` seconds appends
one JSON line to ``OUT.probe``: wall and CPU seconds, the last finished cycle, solves, Krylov
iterations, solves that failed at ``max_iterations`` (each then rebuilt and solved again) and
rebuilds. Stop it with ``timeout``. Two copies of one checkpoint resumed side by side, each
with the checkout under test (run the script of that checkout: it imports its own modules),
compare two versions on the same blocks of a long run; the 2.3× of 2026-11-27 on the 2.5 mm
extreme's late wear blocks was measured so, from its block-1,150 checkpoint.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import contact.linear as linear  # noqa: E402
import contact.procedure as procedure  # noqa: E402
from pipelines.cli.main import main as fretwork  # noqa: E402


def instrument(counts: Counter, report) -> None:
    """Count solves, Krylov iterations, failures and rebuilds; call ``report`` after each solve."""
    solve, refactor, gmres = linear.NewtonLinearSolver.solve, linear.NewtonLinearSolver._refactor, linear._gmres

    def counted_solve(self, *args, **kwargs):
        counts["solves"] += 1
        result = solve(self, *args, **kwargs)
        report()
        return result

    def counted_refactor(self, *args, **kwargs):
        counts["rebuilds"] += 1
        return refactor(self, *args, **kwargs)

    def counted_gmres(*args, **kwargs):
        solution, iterations = gmres(*args, **kwargs)
        counts["krylov_iterations"] += iterations
        counts["failed"] += solution is None
        return solution, iterations

    linear.NewtonLinearSolver.solve = counted_solve
    linear.NewtonLinearSolver._refactor = counted_refactor
    linear._gmres = counted_gmres


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", type=Path)
    parser.add_argument("out", type=Path, help="the run's folder (with checkpoint.h5), continued in place")
    parser.add_argument("--cache", type=Path, default=None, help="stage cache (as fretwork run --cache)")
    parser.add_argument("--every", type=float, default=20.0, help="seconds between two lines of OUT.probe")
    args = parser.parse_args(argv)
    counts, started, last = Counter(), time.perf_counter(), [time.perf_counter()]
    log = args.out.with_name(args.out.name + ".probe")
    cycle = [None]
    phase_cycle = procedure._Run.cycle

    def remembered_cycle(self, *a, **k):
        result = phase_cycle(self, *a, **k)
        cycle[0] = self.cycle_number
        return result

    procedure._Run.cycle = remembered_cycle

    def report():
        if time.perf_counter() - last[0] < args.every:
            return
        last[0] = time.perf_counter()
        with log.open("a") as out:
            out.write(json.dumps({"wall_s": last[0] - started, "cpu_s": time.process_time(), "cycle": cycle[0],
                                  **counts}) + "\n")

    instrument(counts, report)
    command = ["run", str(args.scene), "--out", str(args.out), "--resume", "--quiet"]
    if args.cache is not None:
        command += ["--cache", str(args.cache)]
    return fretwork(command)


if __name__ == "__main__":
    raise SystemExit(main())
