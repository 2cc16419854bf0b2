"""Benchmark of issue 14 (`make bench`): contact solves from 100 to 10,000 points, one table.

Every case runs twice in the same session, each run in its own process (its peak memory is
its own) with the shipped linear solver ("auto": on flat-on-flat, the path
:func:`contact.sparse.choose_path` picks: the dense contact compliance W below its measured
threshold, with preconditioned GMRES on large closed sets and an exact LU on small ones; the
sparse bodies of :mod:`contact.sparse`, no dense W, from it) and with the dense reference
("dense": the exact LU of the dense bordered system in every Newton iteration); their final
pressure, shear and COF fields must agree to 1e-8 relative (the loosening counterweight: its
fields at the end of the COF phase, and its clamp force against the real cycles within 2 %, see
LOOSENING_TOLERANCE) and their verdicts must be the same. Where the shipped choice
is the dense W, the sparse path runs too (row "sparse"): the crossover is measured in the
same run. Rows whose estimated set-up memory exceeds FRETWORK_BENCH_MEMORY_GB
(default 8, the share of a shared 2-core, 24 GB machine) or whose dense run would take hours
are reported as not run, with the reason. Times are CPU seconds of the process (single-
threaded BLAS: on a shared machine they measure the work, not the neighbours' load); the
load average is printed with the table (flat-on-flat set-up: CPU s too; the counterweight
and cylinder rows' set-up is wall time). per_increment_ms is the mean over the last cycle,
max_increment_ms (flat-on-flat) the most expensive increment of the history: on the sparse
path the one that factorises the preconditioner, which set-up does not include. Writes
results/bench/scale.json.

Flat-on-flat bodies: the graded blocks (:func:`tests.bench.bench_report.run`'s default,
:func:`reduction.mesh.generators.graded_flat_block`: the contact spacing at the contact face
and in the two layers under it, then 3:1 coarsening in plane with depth), an engineer's
contact mesh instead of n × n elements through the whole depth; every solver of a row runs on
the same meshes. Their contact results agree with the uniform blocks' to a few per cent at
1,600 points (test_bench_graded_physics.py).

Targets: flat-on-flat 10,000 points: set-up ≤ 60 s, ≤ 1 s per increment, ≤ 6 GB; the
counterweight at 2.5 mm, full shipped procedure: ≤ 10 min wall, ≤ 4 GB; the 2D
cylinder-on-plane scene ≤ 2 ms per increment.

Measured on the graded blocks (2 shared cores, load 3-5; CPU s): 10,000 points, sparse path:
set-up 50 s, 2.96 s per increment, 5.3 GB peak (the uniform blocks: 72 s, 3.9 s, 6.96 GB):
set-up and memory within target, the increment 3x over. One increment is ~15 solves with the
two sparse factors (the float32 preconditioner of K + Gᵀ·B₀·G, 261M entries, ~0.17 s; the
float64 K_aa of W·λ, 139M entries, ~0.18 s), each streaming ~2 GB of factor: memory bound. The
factors are those of the fine contact zone (a 100 × 100 face, a few fine layers deep, both
bodies coupled through it), which the graded far body does not shrink; starting the 3:1
transitions at the face would cut them to 97M and 52M entries (symbolic analysis).
"""

import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from tests.bench.scene_run import FIELDS  # the fields scene_run --fields saves

ROOT = Path(__file__).resolve().parents[2]
MEMORY_GB = float(os.environ.get("FRETWORK_BENCH_MEMORY_GB", "8"))
#: dense set-up memory of flat-on-flat, measured at 3,600 points (issue 14; graded blocks:
#: 10.2 GB peak, the uniform ones 11.5 GB), growing as n²
FLAT_GB_AT_3600 = 10.2
#: flat-on-flat cases whose auto choice is the dense W also run the sparse path
ALSO_SPARSE = "sparse"
DENSE_HOURS = "the dense LU of ~4,900 rows in every Newton iteration would take hours"
#: run only the cases whose label contains one of these (comma separated, a comma before three
#: digits belongs to a number: "flat-on-flat 1,600"); all by default
ONLY = [c for c in re.split(r",(?!\d{3}\b)", os.environ.get("FRETWORK_BENCH_CASES", "")) if c]
ENV = dict(os.environ, OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1", OMP_NUM_THREADS="1")


def _flat(side: int, solver: str, folder: Path) -> dict:
    fields = folder / f"flat_{side}_{solver}.npz"
    done = subprocess.run([sys.executable, "-m", "tests.bench.bench_report", str(side), solver, str(fields)],
                          cwd=ROOT, capture_output=True, text=True, env=ENV)
    assert done.returncode == 0, done.stderr[-3000:]
    out = json.loads(done.stdout.strip().splitlines()[-1])
    path = "sparse" if out["solver"] == "sparse" else "dense W"
    return {"points": out["points"], "setup_s": out["setup_cpu_s"], "per_increment_ms": 1e3 * out["increment_mean_cpu_s"],
            "newton": out["newton_mean"], "peak_mb": out["peak_rss_mb"], "fields": fields, "path": path,
            "krylov": out["linear"]["krylov_iterations"], "factorisations": out["linear"]["factorisations"],
            "max_increment_ms": 1e3 * out["history_max_cpu_s"], "history_s": out["history_cpu_s"]}


def _scene(scene: str, size, solver: str, folder: Path) -> dict:
    fields = folder / f"{scene}_{size}_{solver}.npz"
    command = [sys.executable, str(ROOT / "tests" / "bench" / "scene_run.py"), scene,
               "--linear", solver, "--fields", str(fields)]
    if size is not None:
        command += ["--size", str(size)]
    started = time.perf_counter()
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, env=ENV)
    assert done.returncode == 0, done.stderr[-3000:]
    out = json.loads(done.stdout.strip().splitlines()[-1])
    return {"points": out["points"], "setup_s": out["setup_s"], "verdict": out["verdict"],
            "per_increment_ms": 1e3 * out["procedure_cpu_per_increment_s"], "increments": out["increments"],
            "wall_s": time.perf_counter() - started, "peak_mb": out["peak_rss_mb"], "fields": fields}


def _difference(a: Path, b: Path, prefix: str = "") -> float:
    """Largest difference of the pressure, shear and COF fields (final, or with ``prefix``
    "first_phase_" at the end of the COF phase), relative to ``b``'s largest of each."""
    with np.load(a) as x, np.load(b) as y:
        return max(float(np.max(np.abs(x[prefix + k] - y[prefix + k])))
                   / max(float(np.max(np.abs(y[prefix + k]))), 1e-300) for k in FIELDS)


def _clamp_force_difference(a: Path, b: Path) -> float:
    """Largest difference of ``a``'s clamp force from ``b``'s at the same real cycles (``a``'s
    interpolated at ``b``'s cycles, over the span both ran), relative to ``b``'s."""
    with np.load(a) as x, np.load(b) as y:
        cycles, force = y["equivalent_cycles"], y["clamp_force_N"]
        both = cycles <= x["equivalent_cycles"][-1]
        other = np.interp(cycles[both], x["equivalent_cycles"], x["clamp_force_N"])
        return float(np.max(np.abs(other - force[both]) / np.abs(force[both])))


#: agreement of the two solvers on a loosening counterweight. Explicit wear on a sliding,
#: unloading joint amplifies the differences of where two Newton iterations stop inside their
#: tolerance (1e-10 mm): ~1e-7 after 130 wear blocks (the procedure of 2026-11-24), and over
#: the shipped 3,000 blocks at 10 mm the shipped GMRES and the exact LU part from block 478 on
#: (1e-6 in the clamp force), differ by 0.1-0.7 % from block ~1,300 and end with final fields
#: that differ by O(1) at the edge points: the code before and after the pool change of
#: 2026-11-27 (fourth session) alike. So such a run is compared on its fields at the end of
#: the COF phase (3e-9 at 10 mm; to Newton's floor, FLAT_TOLERANCE below), and judged on its
#: verdict and on its clamp force against the real cycles, within LOOSENING_CLAMP_FORCE of
#: the exact LU's: at 10 mm the code before the pool change 1.5e-2, after it 4.7e-3 (final
#: losses 16.8 and 16.4 % against 16.4 %), a sensitivity of the loosening joint, not of a solver.
LOOSENING_TOLERANCE = "loosening"
LOOSENING_CLAMP_FORCE = 0.02
#: flat-on-flat (1,600 points): pressures agree to 1e-13 whatever the path, shears and COFs to
#: 3-5e-8 (the shipped dense-W GMRES and the sparse path alike, against the dense LU, in the
#: same run). That is Newton's own floor: its 1e-10 mm kinematic tolerance times the stick
#: stiffness μ·p/γ_crit (2e4 N/mm³ at 100 MPa) is 2e-6 MPa, 5e-8 of the 40 MPa peak shear;
#: closer agreement would need a tighter Newton tolerance, not another linear solver. On the
#: graded blocks (load 3-5 on 2 cores): the sparse path against the dense LU 4.1e-9 (1,600
#: points) and 6.2e-9 (3,600), the shipped dense-W GMRES at 1,600 points 1.2e-8, all in shear
#: (pressures 5e-12 to 8e-15, COFs 2-3e-9): under the floor, but not with a margin to 1e-8
#: (the uniform blocks gave 3-5e-8 for the same pairs), so 1e-8 would fail by chance.
FLAT_TOLERANCE = 1e-7
CASES = [  # (label, runner, arguments, reason not to run the dense reference, tolerance)
    ("flat-on-flat 1,600", _flat, (40,), None, FLAT_TOLERANCE),
    ("flat-on-flat 3,600", _flat, (60,), None, FLAT_TOLERANCE),
    ("flat-on-flat 10,000", _flat, (100,), None, FLAT_TOLERANCE),
    ("CW extreme 10 mm", _scene, ("counterweight_extreme", 10.0), None, LOOSENING_TOLERANCE),
    ("CW extreme 5 mm", _scene, ("counterweight_extreme", 5.0), None, LOOSENING_TOLERANCE),
    ("CW extreme 2.5 mm", _scene, ("counterweight_extreme", 2.5), DENSE_HOURS, LOOSENING_TOLERANCE),
    ("2D cylinder-on-plane", _scene, ("cylinder_on_plane", None), None, 1e-8),
]


def _dense_does_not_fit(label: str, arguments: tuple) -> str | None:
    """Why the dense W of a flat-on-flat case is not run: its estimated set-up memory."""
    if label.startswith("flat"):
        estimate = FLAT_GB_AT_3600 * (arguments[0] ** 2 / 3600.0) ** 2
        if estimate > MEMORY_GB:
            return f"does not fit: dense set-up needs ~{estimate:.0f} GB (> {MEMORY_GB:g} GB)"
    return None


def _table(rows: list[dict]) -> str:
    columns = ("case", "solver", "path", "points", "setup_s", "per_increment_ms", "max_increment_ms",
               "increments", "wall_s", "peak_mb", "verdict", "ratio", "rel_diff", "clamp_force_diff", "note")
    lines = [" | ".join(columns)]
    for row in rows:
        lines.append(" | ".join(f"{row[c]:.4g}" if isinstance(row.get(c), float) else str(row.get(c, ""))
                                for c in columns))
    return "\n".join(lines)


@pytest.mark.bench
def test_contact_solves_from_100_to_10000_points(tmp_path):
    rows = []
    for label, runner, arguments, no_dense, tolerance in CASES:
        if ONLY and not any(part in label for part in ONLY):
            continue
        prefix = ""
        if tolerance == LOOSENING_TOLERANCE:  # the fields at the end of the COF phase
            prefix, tolerance = "first_phase_", FLAT_TOLERANCE
        auto = runner(*arguments, "auto", tmp_path)
        rows.append({"case": label, "solver": "auto", **auto})
        if auto.get("path") == "dense W":  # the crossover, measured in the same run
            sparse = runner(*arguments, ALSO_SPARSE, tmp_path)
            rows.append({"case": label, "solver": "sparse", **sparse,
                         "rel_diff": _difference(sparse["fields"], auto["fields"], prefix), "tolerance": tolerance})
        no_dense = no_dense or _dense_does_not_fit(label, arguments)
        if no_dense:
            rows.append({"case": label, "solver": "dense", "note": f"not run: {no_dense}"})
            continue
        dense = runner(*arguments, "dense", tmp_path)
        difference = _difference(auto["fields"], dense["fields"], prefix)
        ratio = auto["per_increment_ms"] / dense["per_increment_ms"]
        auto_row = next(r for r in rows if r["case"] == label and r["solver"] == "auto")
        auto_row.update(rel_diff=difference, ratio=ratio, tolerance=tolerance)
        if auto.get("path") == "dense W":
            rows[-1].update(rel_diff=_difference(sparse["fields"], dense["fields"], prefix),
                            ratio=sparse["per_increment_ms"] / dense["per_increment_ms"])
        rows.append({"case": label, "solver": "dense", **dense, "rel_diff": difference, "tolerance": tolerance})
        assert auto.get("verdict") == dense.get("verdict"), f"{label}: verdicts differ"
        if prefix:
            clamp = _clamp_force_difference(auto["fields"], dense["fields"])
            auto_row["clamp_force_diff"] = clamp
            assert clamp <= LOOSENING_CLAMP_FORCE, f"{label}: clamp forces differ by {clamp:.2e}"
    for row in rows:
        row.pop("fields", None)
    out = ROOT / "results" / "bench" / "scale.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"load_average": os.getloadavg(), "cpus": os.cpu_count(), "rows": rows}, indent=2))
    print(f"\nload average {os.getloadavg()}, {os.cpu_count()} CPUs; times are CPU s of one process\n"
          + _table(rows))
    for row in rows:
        assert row.get("rel_diff", 0.0) <= row.get("tolerance", 1e-8), \
            f"{row['case']}: auto and dense differ by {row['rel_diff']:.2e}"
