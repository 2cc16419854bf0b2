"""The same scene gives the same bits, in separate processes, whatever the BLAS thread count
and whichever sparse solver condenses the bodies (issue 13).

Each run is a ``fretwork run`` in its own process, as an engineer's two runs would be. Every
dataset and attribute of ``results.h5`` must be bit-equal, and so must the file itself.
"""

import os
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from reduction.factorization import SOLVER_VARIABLE, solver_available


def _run(scene, out, threads: int, solver: str = "auto") -> None:
    env = {**os.environ, "MPLBACKEND": "Agg", "OMP_NUM_THREADS": str(threads),
           "OPENBLAS_NUM_THREADS": str(threads), "MKL_NUM_THREADS": str(threads),
           SOLVER_VARIABLE: solver}
    done = subprocess.run([sys.executable, "-m", "pipelines.cli.main", "run", str(scene), "--out", str(out),
                           "--quiet", "--no-cache"], env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


def _contents(path) -> dict:
    """Every dataset and attribute of an HDF5 file, by name."""
    out = {}
    with h5py.File(path, "r") as file:
        out.update({f"/@{key}": value for key, value in file.attrs.items()})

        def visit(name, item):
            if isinstance(item, h5py.Dataset):
                out[name] = item[()]
            out.update({f"{name}@{key}": value for key, value in item.attrs.items()})
        file.visititems(visit)
    return out


def assert_bit_equal(first, second) -> None:
    a, b = _contents(first), _contents(second)
    assert a.keys() == b.keys()
    for name, value in a.items():
        value, other = np.asarray(value), np.asarray(b[name])
        floating = value.dtype.kind == "f"
        assert value.shape == other.shape and np.array_equal(value, other, equal_nan=floating), \
            f"{name} differs: largest difference {np.max(np.abs(value - other)) if floating else '-'}"
    assert first.read_bytes() == second.read_bytes(), "same contents, yet the files differ"


@pytest.fixture
def scene(coarse_cylinder, tmp_path):
    """The coarse cylinder with a few wear cycles, so that round-off has time to grow."""
    path = tmp_path / "determinism.toml"
    path.write_text(coarse_cylinder.read_text().replace("wear_cycles = 2 ", "wear_cycles = 4 "))
    return path


def test_one_and_two_blas_threads_give_the_same_bits(scene, tmp_path):
    _run(scene, tmp_path / "one", threads=1)
    _run(scene, tmp_path / "two", threads=2)
    assert_bit_equal(tmp_path / "one" / "results.h5", tmp_path / "two" / "results.h5")


@pytest.mark.parametrize("solver", ["pardiso", "cholmod", "splu"])
def test_each_sparse_solver_is_deterministic(scene, tmp_path, solver):
    if not solver_available(solver):
        pytest.skip(f"{solver} is not installed here")
    _run(scene, tmp_path / "one", threads=1, solver=solver)
    _run(scene, tmp_path / "two", threads=2, solver=solver)
    assert_bit_equal(tmp_path / "one" / "results.h5", tmp_path / "two" / "results.h5")


EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_a_coupled_scene_gives_the_same_bits_with_one_and_two_threads(tmp_path):
    """The whole chain, multibody run and inertia patterns included (the per-step limits alone
    left 37 datasets of the counterweight different): a coarse extreme counterweight."""
    scene = tmp_path / "cw.toml"
    scene.write_text(f"""[scene]
base = "{EXAMPLES / 'counterweight_extreme.toml'}"
name = "cw_coarse"
[bodies.counterweight.mesh]
contact_size = 20.0
[bodies.web.mesh]
contact_size = 20.0
[mbs]
n_modes = 4
[mbs.solver]
revolutions = 2.0
[procedure]
cof_cycles = 6
vibration_run_up = 3
wear_cycles = 4
""")
    _run(scene, tmp_path / "one", threads=1)
    _run(scene, tmp_path / "two", threads=2)
    assert_bit_equal(tmp_path / "one" / "results.h5", tmp_path / "two" / "results.h5")


def test_the_results_file_does_not_depend_on_how_long_the_run_took(scene, tmp_path, monkeypatch):
    """When rows are written changes where HDF5 puts the chunks, so it must not follow the clock.
    A run on a machine so slow that every call to the clock is an hour later gives the same bytes.
    (The writer once flushed every 10 s of wall time: runs of more than 10 s differed in bytes.)"""
    import time

    from pipelines import scene as scenes
    from pipelines.jobs.run import run_scene

    run_scene(scenes.load(scene), tmp_path / "quick", progress=False, plots=False)
    hours = iter(range(10**9))
    monkeypatch.setattr(time, "monotonic", lambda: 3600.0 * next(hours))
    run_scene(scenes.load(scene), tmp_path / "slow", progress=False, plots=False)
    assert_bit_equal(tmp_path / "quick" / "results.h5", tmp_path / "slow" / "results.h5")
