"""Newton's work per increment along a run, by phase and by window of cycles (docs/performance.md).

``python tests/bench/iteration_probe.py SCENE [--window 50] [scene_run options]`` runs
``examples/SCENE.toml`` as ``tests/bench/scene_run.py`` does (the same options: ``--size``,
``--cycles``, ``--set KEY=VALUE``, ...) and prints, for the preload and for every window of
cycles of each phase, the increments, the CPU ms per increment and, per increment, the Newton
iterations, the residual passes (the predictors' and the line search's included), the Krylov
iterations and the cutbacks. It showed that the counterweight's run-up went without the
cyclic predictors (4.4-4.9 Newton iterations per increment at 10 mm, against 2.0 once its
steps were known by their place in the cycle).
"""

from __future__ import annotations

import argparse
import collections
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "bench"))

import contact.linear as linear  # noqa: E402
import contact.procedure as procedure  # noqa: E402
import contact.solver as solver  # noqa: E402
import scene_run  # noqa: E402


def counting(window: int) -> dict:
    """Wrap the procedure's step, the residual, the increment and the linear solve to count
    per (phase, first cycle of the window); returns the counters."""
    counts: dict = collections.defaultdict(collections.Counter)
    current: dict = {"key": None}
    step, residual, increment = procedure._Run.step, solver.ContactSolver._residual, solver.ContactSolver.increment
    solve = linear.NewtonLinearSolver.solve

    def counted_step(run, amplitudes, effects, phase, cycle, t, position=None):
        current["key"] = key = (phase, (cycle - 1) // window * window + 1 if cycle else 0)
        start = time.process_time()
        status = step(run, amplitudes, effects, phase, cycle, t, position)
        counts[key]["cpu"] += time.process_time() - start
        counts[key]["increments"] += 1
        return status

    def counted_residual(contact_solver, *args, **kwargs):
        counts[current["key"]]["residuals"] += 1
        return residual(contact_solver, *args, **kwargs)

    def counted_increment(contact_solver, *args, **kwargs):
        out = increment(contact_solver, *args, **kwargs)
        counts[current["key"]]["newton"] += out[3].iterations
        counts[current["key"]]["cutbacks"] += out[3].cutbacks
        return out

    def counted_solve(linear_solver, *args, **kwargs):
        before = linear_solver.counters.krylov_iterations
        out = solve(linear_solver, *args, **kwargs)
        counts[current["key"]]["krylov"] += linear_solver.counters.krylov_iterations - before
        return out

    procedure._Run.step = counted_step
    solver.ContactSolver._residual = counted_residual
    solver.ContactSolver.increment = counted_increment
    linear.NewtonLinearSolver.solve = counted_solve
    return counts


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(add_help=False)
    parser.add_argument("--window", type=int, default=50, help="cycles per row")
    args, rest = parser.parse_known_args(argv)
    counts = counting(args.window)
    scene_run.main(rest)  # prints its JSON line
    print(f"{'phase':8s} {'cycles':>11s} {'increments':>10s} {'ms/inc':>7s} {'Newton':>7s} "
          f"{'residuals':>9s} {'Krylov':>7s} {'cutbacks':>8s}")
    order = {"preload": 0, "cof": 1, "wear": 2}
    for (phase, first), c in sorted(counts.items(), key=lambda item: (order.get(item[0][0], 3), item[0][1])):
        n = max(c["increments"], 1)
        cycles = "—" if phase == "preload" else f"{first}–{first + args.window - 1}"
        print(f"{phase:8s} {cycles:>11s} {c['increments']:10d} {1e3 * c['cpu'] / n:7.2f} {c['newton'] / n:7.2f} "
              f"{c['residuals'] / n:9.2f} {c['krylov'] / n:7.2f} {c['cutbacks']:8d}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
