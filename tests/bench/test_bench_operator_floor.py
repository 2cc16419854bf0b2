"""Benchmark: per-increment cost of the condensed solver against one pass over its condensed
operator W (the memory-bandwidth floor), `make bench`.

The condensed solver works on the dense contact compliance W (3 n_points rows in 3D); every
residual needs W·λ, so one increment can never cost less than one pass over W (reading
8·(3 n)² bytes). The ratio "increment / one pass" says how far the solver is from that floor.
Case: tests.bench.bench_report.flat_on_flat (the flat-on-flat benchmark of
tests/bench/test_bench_contact.py), 400 and 1,600 contact points (3,600 with
FRETWORK_BENCH_FLOOR_SIDES=20,40,60: 11.5 GB), increments of its last full cycle; one W pass
is a dense W @ x (numpy, median of repeats). BLAS on one thread, like the contact benchmark.
Prints a table and writes results/bench/operator_floor.json.
"""

import json
import os
import platform
import time
from pathlib import Path

import numpy as np
import pytest

from tests.bench.bench_report import drive, flat_on_flat

ROOT = Path(__file__).resolve().parents[2]
SIDES = [int(s) for s in os.environ.get("FRETWORK_BENCH_FLOOR_SIDES", "20,40").split(",")]
PASS_REPEATS = 30
COLUMNS = ("points", "rows", "W_MB", "pass_ms", "pass_cpu_ms", "GB_per_s", "increment_ms", "increment_cpu_ms",
           "newton_mean", "increment_per_pass", "increment_per_pass_cpu")


def one_pass_time(operator: np.ndarray) -> tuple[float, float]:
    """Median wall time and mean CPU time (s) of operator @ x for a random x, after a warm-up."""
    x = np.random.default_rng(0).standard_normal(operator.shape[1])
    operator @ x
    walls, cpu_start = [], time.process_time()
    for _ in range(PASS_REPEATS):
        start = time.perf_counter()
        operator @ x
        walls.append(time.perf_counter() - start)
    return float(np.median(walls)), (time.process_time() - cpu_start) / PASS_REPEATS


def measure(points_per_side: int) -> dict:
    from contact.assembly import assemble
    from contact.solver import ContactSolver
    from contact.structure import ContactSpace

    case = flat_on_flat(points_per_side)
    start = time.perf_counter()
    structure = assemble(case.bodies, case.slave, case.master, loads=case.loads, motions=case.motions).structure
    solver = ContactSolver(ContactSpace(structure), case.law)
    record, _ = drive(solver, case.initial_state(solver.n_points), case, label="condensed",
                      points=solver.n_points, dofs=structure.n_dofs, setup_time=time.perf_counter() - start)
    summary = record.summary(case.cycle)
    operator = solver.space.W
    pass_wall, pass_cpu = one_pass_time(operator)
    return {"points": solver.n_points, "rows": operator.shape[0], "W_MB": operator.nbytes / 1e6,
            "pass_ms": 1e3 * pass_wall, "pass_cpu_ms": 1e3 * pass_cpu, "GB_per_s": operator.nbytes / pass_wall / 1e9,
            "increment_ms": 1e3 * summary["increment_mean_s"], "increment_cpu_ms": 1e3 * summary["increment_mean_cpu_s"],
            "newton_mean": summary["newton_mean"],
            "increment_per_pass": summary["increment_mean_s"] / pass_wall,
            "increment_per_pass_cpu": summary["increment_mean_cpu_s"] / pass_cpu}


def format_rows(rows: list[dict]) -> str:
    width = {c: max(len(c), 9) for c in COLUMNS}
    lines = [" ".join(f"{c:>{width[c]}}" for c in COLUMNS)]
    for row in rows:
        lines.append(" ".join(f"{row[c]:>{width[c]}.4g}" if isinstance(row[c], float) else f"{row[c]!s:>{width[c]}}"
                              for c in COLUMNS))
    return "\n".join(lines)


@pytest.mark.bench
def test_increment_cost_against_one_pass_over_the_condensed_operator():
    threadpoolctl = pytest.importorskip("threadpoolctl")
    started = time.time()
    with threadpoolctl.threadpool_limits(limits=1, user_api="blas"):
        rows = [measure(side) for side in SIDES]
    meta = {"machine": platform.processor() or platform.machine(), "cpus": os.cpu_count(),
            "load_average": os.getloadavg(), "wall_time_s": time.time() - started, "blas_threads": 1,
            "case": "tests.bench.bench_report.flat_on_flat(points_per_side); increments of its last full cycle"}
    out = ROOT / "results" / "bench" / "operator_floor.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"meta": meta, "rows": rows}, indent=2))
    print("\n" + format_rows(rows))

    for row in rows:
        # An increment evaluates at least one residual, i.e. one full W·λ pass.
        assert row["increment_per_pass_cpu"] > 1.0, f"{row['points']} points: faster than one pass over W?"
