"""Benchmark: the scale bench's graded blocks against the uniform ones, 1,600 points (`make bench`).

The scale bench (test_bench_scale.py) runs flat-on-flat on blocks that coarsen in plane with
depth (:func:`reduction.mesh.generators.graded_flat_block`); the uniform blocks (n × n
elements through all 6 layers) are the reference. Both are solved on the sparse path over the
same history (:mod:`tests.bench.graded_physics`, one process each), and the last cycle's
contact results compared: the bodies' compliance differs by a few per mille in pressure and
about 1-2 % in shear (tests/reduction/test_graded_flat_block.py), so the fields may differ
by that much, not more. Measured (2 cores, load ~5): pressure 0.50 % of its peak pointwise
(0.20 % rms), shear 3.6 % of its peak at the worst point (a point at the stick-slip boundary
that changes state; 0.56 % rms), slip area 3.2 % (2.5 of 79.8 mm²), tangential force 1.0 %.
Writes results/bench/graded_physics.json.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.bench.graded_physics import compare

ROOT = Path(__file__).resolve().parents[2]
ENV = dict(os.environ, OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1", OMP_NUM_THREADS="1")
#: (figure, bound): twice the measured differences, relative to the uniform blocks' peaks
BOUNDS = {"pressure_max_rel": 0.01, "pressure_rms_rel": 0.005, "shear_max_rel": 0.07,
          "shear_rms_rel": 0.012, "slip_area_max_rel": 0.07, "tangential_force_max_rel": 0.02}


def _history(side: int, mesh: str, folder: Path) -> dict:
    out = folder / f"{mesh}_{side}.npz"
    done = subprocess.run([sys.executable, "-m", "tests.bench.graded_physics", str(side), mesh, str(out)],
                          check=False, cwd=ROOT, capture_output=True, text=True, env=ENV)
    assert done.returncode == 0, done.stderr[-3000:]
    with np.load(out) as data:
        return {name: data[name] for name in data.files}


@pytest.mark.bench
def test_graded_blocks_give_the_uniform_blocks_contact_results(tmp_path):
    figures = compare(_history(40, "graded", tmp_path), _history(40, "uniform", tmp_path))
    out = ROOT / "results" / "bench" / "graded_physics.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"load_average": os.getloadavg(), "points": 1600, **figures}, indent=2))
    print("\n" + "\n".join(f"{name}: {figures[name]:.3g} (bound {bound:g})" for name, bound in BOUNDS.items()))
    for name, bound in BOUNDS.items():
        assert figures[name] <= bound, f"graded and uniform blocks differ in {name}: {figures[name]:.3g}"
