"""BLAS threads of a pinned process (reduction/threads.py): started with two threads asked for,
every BLAS runs one thread inside a library step after pin_process, also once modules were
imported after the pinning (the process is then pinned again, once: its record follows them)."""

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

PROBE = """
import json, sys
from threadpoolctl import threadpool_info
from reduction import threads
threads.pin_process()
before = len(sys.modules)
import sklearn_stand_in  # noqa: F401  (a module loaded after the pinning)
assert len(sys.modules) > before
with threads.single_threaded_blas():
    inside = [entry["num_threads"] for entry in threadpool_info() if entry["user_api"] == "blas"]
print(json.dumps({"inside": inside, "pinned": threads._pinned[0] == len(sys.modules)}))
"""


def test_pinned_process_runs_one_blas_thread_also_after_new_imports(tmp_path):
    (tmp_path / "sklearn_stand_in.py").write_text("import scipy.optimize  # more extension modules\n")
    env = dict(os.environ, OPENBLAS_NUM_THREADS="2", MKL_NUM_THREADS="2", OMP_NUM_THREADS="2",
               PYTHONPATH=os.pathsep.join([str(ROOT), str(tmp_path)]))
    done = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    out = json.loads(done.stdout.strip().splitlines()[-1])
    assert out["inside"] and set(out["inside"]) == {1}
    assert out["pinned"]  # re-pinned once for the new modules, then nothing more to do


LIBRARY_PROBE = """
import json
from threadpoolctl import threadpool_info
from reduction import threads
import pipelines.jobs.run as run_job


def blas():
    return sorted({entry["num_threads"] for entry in threadpool_info() if entry["user_api"] == "blas"})


seen = {"before": blas()}


class Seen(Exception):
    pass


def fake_build(scene, **kwargs):  # what run_scene's steps run under
    seen["inside run_scene"] = blas()
    raise Seen


run_job.build = fake_build
try:
    run_job.run_scene(type("S", (), {"data": {}, "name": "probe"})(), "unused", progress=False)
except Seen:
    pass
seen["after run_scene"] = blas()


@threads.one_blas_thread
def job(inner):
    seen.setdefault("nested", []).append(blas())
    if inner:
        job(False)  # a job calling another: the inner one's exit keeps the outer's pinning
        seen["outer after inner"] = blas()


job(True)
seen["all left"] = blas()
print(json.dumps(seen))
"""


def test_a_library_caller_runs_jobs_on_one_blas_thread_and_gets_its_settings_back():
    """A program that imports fretwork and calls run_scene (or any job) without pinning its
    process: inside, every BLAS runs one thread, as under the command line, also after a job
    called inside another has ended; then the caller's two threads come back."""
    env = dict(os.environ, OPENBLAS_NUM_THREADS="2", MKL_NUM_THREADS="2", OMP_NUM_THREADS="2",
               PYTHONPATH=str(ROOT))
    done = subprocess.run([sys.executable, "-c", LIBRARY_PROBE], env=env, capture_output=True, text=True,
                          check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    seen = json.loads(done.stdout.strip().splitlines()[-1])
    assert seen["before"] == [2]
    assert seen["inside run_scene"] == [1]
    assert seen["after run_scene"] == [2]
    assert seen["nested"] == [[1], [1]]
    assert seen["outer after inner"] == [1]
    assert seen["all left"] == [2]
