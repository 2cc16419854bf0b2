"""Benchmark: condensed interface versus the full sparse model, 3D flat-on-flat (`make bench`).

For about 400, 1,600 and 3,600 contact points the same cyclic partial-slip history (normal
load, then tangential motion ±5 µm with COF evolution) is solved by the condensed contact-space
solver and by Newton on the full uncondensed model. Each run has its own process, so the
peak resident memory is that run's. Prints a table and writes results/bench/contact.json.
Targets (issue 2): condensed ≥ 10× faster per increment than full at 1,600 points with
identical results (< 1e-6); ≤ 0.15 s per increment and ≤ 8 Newton iterations at 1,600
points; ≤ 1 s per increment at 3,600 points.
"""

import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from tests.bench.bench_report import format_table, relative_difference

ROOT = Path(__file__).resolve().parents[2]
SIDES = [int(s) for s in os.environ.get("FRETWORK_BENCH_SIDES", "20,40,60").split(",")]
# BLAS/MKL threads per run. One by default: on a shared 2-core machine two spinning threads
# per process made a 1,200² product 25x slower; both solvers get the same.
THREADS = os.environ.get("FRETWORK_BENCH_THREADS", "1")
# The full model at 3,600 points (~130k DOFs, a sparse LU per Newton iteration) takes tens of
# minutes on a shared machine; FRETWORK_BENCH_FULL_SIDES limits the sizes it is run for.
FULL_SIDES = [int(s) for s in os.environ.get("FRETWORK_BENCH_FULL_SIDES", ",".join(map(str, SIDES))).split(",")]


def _run(side: int, solver: str, folder: Path) -> tuple[dict, dict]:
    fields_path = folder / f"{solver}_{side}.npz"
    env = dict(os.environ, OPENBLAS_NUM_THREADS=THREADS, MKL_NUM_THREADS=THREADS, OMP_NUM_THREADS=THREADS)
    done = subprocess.run([sys.executable, "-m", "tests.bench.bench_report", str(side), solver, str(fields_path)],
                          cwd=ROOT, capture_output=True, text=True, env=env)
    assert done.returncode == 0, f"{solver} run with {side}² points failed:\n{done.stderr[-3000:]}"
    summary = json.loads(done.stdout.strip().splitlines()[-1])
    with np.load(fields_path) as data:
        fields = {name: data[name] for name in data.files}
    return summary, fields


def _save(rows: list[dict], started: float) -> None:
    """Write the table so far: a long study that dies late still leaves its figures."""
    meta = {"machine": platform.processor() or platform.machine(), "cpus": os.cpu_count(),
            "load_average": os.getloadavg(), "wall_time_s": time.time() - started,
            "blas_threads": THREADS,
            "case": "tests.bench.bench_report.flat_on_flat(points_per_side); figures over its last full cycle"}
    out = ROOT / "results" / "bench" / "contact.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"meta": meta, "rows": rows}, indent=2))


@pytest.mark.bench
def test_condensed_versus_full_sparse_model_flat_on_flat(tmp_path):
    rows, started = [], time.time()
    for side in SIDES:
        condensed, condensed_fields = _run(side, "condensed", tmp_path)
        rows.append(condensed)
        _save(rows, started)
        if side not in FULL_SIDES:
            continue
        full, full_fields = _run(side, "full", tmp_path)
        difference = relative_difference(full_fields, condensed_fields)
        speedup = full["increment_mean_s"] / condensed["increment_mean_s"]
        speedup_cpu = full["increment_mean_cpu_s"] / condensed["increment_mean_cpu_s"]
        condensed.update(rel_diff=difference, speedup=speedup, speedup_cpu=speedup_cpu)
        full.update(rel_diff=difference, speedup=1.0, speedup_cpu=1.0)
        rows.append(full)
        _save(rows, started)
    print("\n" + format_table(rows))

    for row in rows:
        assert row.get("rel_diff", 0.0) < 1e-6, f"{row['points']} points: condensed and full differ by {row['rel_diff']:.2e}"
        if row["solver"] == "condensed":
            assert row["newton_max"] <= 8, f"{row['points']} points: {row['newton_max']} Newton iterations"
    at_1600 = [r for r in rows if r["solver"] == "condensed" and r["points"] == 1600]
    if at_1600:
        # CPU time: with single-threaded runs it measures the work, not the neighbours' load.
        assert at_1600[0].get("speedup_cpu", np.inf) >= 10.0, \
            f"condensed only {at_1600[0]['speedup_cpu']:.1f}x faster (CPU time) at 1,600 points"
