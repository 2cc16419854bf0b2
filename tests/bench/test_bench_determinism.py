"""Benchmark: what determinism costs (`make bench`).

Each scene is run in its own process twice, side by side in the same session: as shipped
(BLAS on one thread in every numerical step, :mod:`reduction.threads`) and with those limits
switched off and two BLAS threads, the machine's default before issue 13. Prints wall and CPU time of each,
their ratio, the load average, and writes results/bench/determinism.json. The ratio is what
bit-identical results cost (below 1: they save time).
"""

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCENES = os.environ.get("FRETWORK_BENCH_DETERMINISM_SCENES",
                        "cylinder_on_plane,counterweight").split(",")
UNPINNED = ("import contextlib, sys, reduction.threads as t; t.single_threaded_blas = contextlib.nullcontext; "
            "t.pin_process = lambda: None; "
            "import contact.solver as s; "
            "s.blas_threads = lambda limit: contextlib.nullcontext(); "
            "from pipelines.cli.main import main; sys.exit(main(sys.argv[1:]))")


def _run(scene: str, out: Path, pinned: bool) -> dict:
    env = {**os.environ, "MPLBACKEND": "Agg", "OMP_NUM_THREADS": "2", "OPENBLAS_NUM_THREADS": "2",
           "MKL_NUM_THREADS": "2"}
    args = ["run", str(ROOT / "examples" / f"{scene}.toml"), "--out", str(out), "--quiet", "--no-cache"]
    command = [sys.executable, "-m", "pipelines.cli.main", *args] if pinned else [sys.executable, "-c", UNPINNED, *args]
    started, cpu = time.perf_counter(), os.times()
    done = subprocess.run(command, env=env, cwd=ROOT, capture_output=True, text=True)
    after = os.times()
    assert done.returncode == 0, done.stderr[-2000:]
    return {"wall_s": time.perf_counter() - started,
            "cpu_s": (after.children_user - cpu.children_user) + (after.children_system - cpu.children_system)}


@pytest.mark.bench
def test_cost_of_determinism(tmp_path):
    rows = []
    for scene in SCENES:
        load = os.getloadavg()
        pinned = _run(scene, tmp_path / f"{scene}_pinned", pinned=True)
        free = _run(scene, tmp_path / f"{scene}_free", pinned=False)
        rows.append({"scene": scene, "pinned": pinned, "two_threads": free, "load_average": load,
                     "wall_ratio": pinned["wall_s"] / free["wall_s"], "cpu_ratio": pinned["cpu_s"] / free["cpu_s"]})
    print("\nscene                 pinned wall/CPU s   2 threads wall/CPU s   ratio wall/CPU   load average")
    for r in rows:
        print(f"{r['scene']:<20} {r['pinned']['wall_s']:8.1f} {r['pinned']['cpu_s']:7.1f}   "
              f"{r['two_threads']['wall_s']:10.1f} {r['two_threads']['cpu_s']:7.1f}   "
              f"{r['wall_ratio']:8.2f} {r['cpu_ratio']:6.2f}   {' '.join(f'{x:.2f}' for x in r['load_average'])}")
    out = ROOT / "results" / "bench" / "determinism.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(rows, indent=2))
