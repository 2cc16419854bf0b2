"""An engineer's first hour (issue 18): the ten bad inputs of the tour, each run as the ``fretwork``
command in its own process, end with one message (exit 2, or 130 for Ctrl-C), no traceback and
no partial files.

Ctrl-C is sent as a terminal sends it: SIGINT to the command's whole process group (dask
workers included). Scenes are small and the long commands are stopped early.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import h5py
import pytest

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
CYLINDER = EXAMPLES / "cylinder_on_plane.toml"
ENV = {**os.environ, "MPLBACKEND": "Agg", "PYTHONWARNINGS": "default"}
TINY_MBS = '[mbs]\nn_modes = 2\neffects = ["gear_mesh"]\n[mbs.solver]\nrevolutions = 0.2\ntime_step = 2e-4\n'


def fretwork(*args, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "pipelines.cli.main", *map(str, args)], cwd=cwd, env=ENV,
                          capture_output=True, text=True, timeout=300, check=False)


def one_error(done: subprocess.CompletedProcess, *parts: str, code: int = 2) -> str:
    """The one message of a refused command (one line, or a list of a scene's problems each on a
    line '  - ...' below it), checked to contain ``parts``."""
    assert done.returncode == code, done.stderr
    first, *problems = done.stderr.splitlines()
    assert "Traceback" not in done.stderr and all(line.startswith("  - ") for line in problems), done.stderr
    assert first.startswith("fretwork: error: ") and all(part in done.stderr for part in parts), done.stderr
    return done.stderr.rstrip()


def files(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


class Background:
    """A ``fretwork`` command in its own process group, its stderr collected as it comes."""

    def __init__(self, *args, cwd: Path):
        self.process = subprocess.Popen([sys.executable, "-m", "pipelines.cli.main", *map(str, args)], cwd=cwd,
                                        env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                                        start_new_session=True)
        self.chunks: list[str] = []
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self):
        for chunk in iter(lambda: self.process.stderr.read(1), ""):
            self.chunks.append(chunk)

    @property
    def stderr(self) -> str:
        return "".join(self.chunks)

    def wait_for(self, text: str, timeout: float = 120.0) -> None:
        deadline = time.monotonic() + timeout
        while text not in self.stderr:
            assert self.process.poll() is None, f"ended before '{text}':\n{self.stderr}"
            assert time.monotonic() < deadline, f"no '{text}' within {timeout} s:\n{self.stderr}"
            time.sleep(0.05)

    def ctrl_c(self) -> tuple[int, str]:
        assert self.process.poll() is None, f"ended before the Ctrl-C:\n{self.stderr}"
        os.killpg(self.process.pid, signal.SIGINT)
        code = self.process.wait(timeout=120)
        self.reader.join(timeout=10)
        return code, self.stderr


@pytest.fixture(scope="module")
def place(tmp_path_factory) -> Path:
    """A scratch folder with the tour's scenes: a small counterweight, a bad one, a binary file."""
    folder = tmp_path_factory.mktemp("first-hour")
    text = ((EXAMPLES / "counterweight.toml").read_text()
            .replace("contact_size = 10.0", "contact_size = 20.0").replace("n_modes = 6", "n_modes = 4")
            .replace("revolutions = 12.0 ", "revolutions = 2.0").replace("cof_cycles = 400", "cof_cycles = 20")
            .replace("vibration_run_up = 300", "vibration_run_up = 15").replace("wear_cycles = 800", "wear_cycles = 5"))
    assert "cof_cycles = 20" in text and "vibration_run_up = 15" in text and "wear_cycles = 5" in text
    assert "revolutions = 2.0" in text
    (folder / "cw.toml").write_text(text)
    (folder / "unit_mistakes.toml").write_text(
        text.replace("wing_amplitude = 0.100", "wing_amplitude = 100.0")
        .replace("youngs_modulus = 210000.0", "youngs_modulus = 120.0"))
    (folder / "typo.toml").write_text(text.replace("poisson_ratio = 0.3", "poison_ratio = 0.3"))
    (folder / "no_mbs.toml").write_text(CYLINDER.read_text())
    (folder / "b.toml").write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\xd0\xff" * 20)
    (folder / "afile.txt").write_text("a file, not a folder")
    return folder


def test_1_a_binary_file_as_the_scene(place):
    one_error(fretwork("run", "b.toml", "--out", "o1", cwd=place), "scene file b.toml is not a text file")
    assert not (place / "o1").exists()


def test_2_output_folders_that_cannot_be_written(place):
    one_error(fretwork("run", CYLINDER, "--out", "afile.txt/out", cwd=place), "--out afile.txt/out lies below the file")
    one_error(fretwork("sweep", "cw.toml", "--speeds", "700", "--out", "/proc/x", cwd=place),
              "--out /proc/x: /proc is a system folder")
    one_error(fretwork("mbs", "cw.toml", "--out", "afile.txt", cwd=place), "--out afile.txt is a file")


def test_3_a_folder_in_use_and_6_ctrl_c_during_a_limit_search_with_dask_workers(place):
    # 2,000 amplitudes: the search must still run when the check below has taken its time on a busy
    # machine (beside two CPU-bound processes the check took long enough for 60 to finish)
    search = Background("limit", "cw.toml", "--amplitude", "100:400", "--grid", "2000", "--workers", "2",
                        "--out", "limit", "--cache", "cache", cwd=place)
    search.wait_for("limit: round 1")
    assert (place / "limit" / ".fretwork.lock").read_text().split() == [str(search.process.pid)]
    one_error(fretwork("run", CYLINDER, "--out", "limit", cwd=place),
              f"--out limit is in use by another fretwork command (pid {search.process.pid})")
    code, stderr = search.ctrl_c()
    assert code == 130, stderr
    assert stderr.rstrip().endswith("\nfretwork: interrupted") and stderr.count("fretwork:") == 1, stderr
    assert "Traceback" not in stderr and "leaked" not in stderr, stderr
    left = files(place / "limit") if (place / "limit").exists() else []
    assert not [name for name in left if name.endswith((".part", ".tmp", ".lock", "checkpoint.h5"))], left


def test_4_a_rerun_clears_the_outputs_of_the_earlier_run_and_nothing_else(place):
    (place / "mbs.toml").write_text(TINY_MBS)
    done = fretwork("mbs", "mbs.toml", "--out", "o4", "--json", cwd=place)  # the earlier run
    assert done.returncode == 0 and "note:" not in done.stderr, done.stderr
    written = ["campbell.png", "run.h5", "wing_spectrum.png", "wing_time_history.png"]
    assert files(place / "o4") == [".fretwork-outputs", *written]
    (place / "o4" / "notes.txt").write_text("the user's")
    done = fretwork("mbs", "mbs.toml", "--out", "o4", "--json", cwd=place)
    assert done.returncode == 0, done.stderr
    notes = [line for line in done.stderr.splitlines() if line.startswith("fretwork: note:")]
    assert notes == [f"fretwork: note: removed 4 output(s) of an earlier run from o4: {', '.join(written)}"]
    assert files(place / "o4") == [".fretwork-outputs", *sorted(written + ["notes.txt"])]
    (place / "o4" / "run.h5").write_text("the user's own run.h5")  # not fretwork's: never removed
    one_error(fretwork("mbs", "mbs.toml", "--out", "o4", cwd=place),
              "--out o4 holds files that fretwork did not write, where this command writes its outputs: run.h5; "
              "they are left alone: give another --out, or move or remove them yourself")
    assert (place / "o4" / "run.h5").read_text() == "the user's own run.h5"


def test_5_a_run_that_slides_off_leaves_a_complete_marked_results_file(place):
    scene = (CYLINDER.read_text().replace("contact_size = 0.05", "contact_size = 0.2")
             .replace("increments_per_cycle = 40", "increments_per_cycle = 8")
             .replace("[[motions]]", "[[loads]]").replace("value = 0.107 ", "value = 1000.0"))  # a force μp cannot carry
    (place / "slide.toml").write_text(scene)
    line = one_error(fretwork("run", "slide.toml", "--out", "o5", "--quiet", "--no-cache", cwd=place),
                     "tangential equilibrium is lost", code=1)
    assert line.endswith("the results file holds the cycles run so far, marked 'slid_off'")
    assert files(place / "o5") == [".fretwork-outputs", "results.h5"]
    with h5py.File(place / "o5" / "results.h5") as results:
        assert results.attrs["complete"] and results.attrs["ending"] == "slid_off"


def test_7_mbs_and_sweep_need_mbs_and_a_valid_scene(place):
    one_error(fretwork("mbs", "no_mbs.toml", "--out", "o7", cwd=place), "no_mbs.toml has no [mbs] table")
    one_error(fretwork("sweep", "typo.toml", "--speeds", "700", "--out", "o7", cwd=place),
              "unknown key 'materials.steel.poison_ratio' (did you mean 'poisson_ratio'?)")
    assert not (place / "o7").exists()


def test_8_a_folder_as_the_scene(place):
    one_error(fretwork("run", EXAMPLES, "--out", "o8", cwd=place), f"scene file {EXAMPLES} is a folder")
    assert not (place / "o8").exists()


def test_9_negative_numbers_in_options(place):
    one_error(fretwork("limit", "cw.toml", "--amplitude", "-100:300", "--out", "o9", cwd=place),
              "--amplitude '-100:300': needs 0 < LOW < HIGH (µm)")
    one_error(fretwork("study", "constant-cof", "none.toml", "--probe", "-65,0,0", cwd=place),
              "scene file none.toml does not exist")
    assert not (place / "o9").exists()


def test_10_unit_mistakes_are_said_before_any_work(place):
    # no stage cache: the multibody run (seconds) lies between the warnings and the contact
    # phases, whose absurd stiffness (120 MPa) would otherwise soon stop the run by itself
    run = Background("run", "unit_mistakes.toml", "--out", "o10", "--no-cache", cwd=place)
    run.wait_for("'coupling.wing_amplitude'")
    code, stderr = run.ctrl_c()
    assert code == 130, stderr
    lines = stderr.splitlines()
    assert lines[:2] == [
        ("fretwork: warning: 'materials.steel.youngs_modulus' = 120 MPa is below 1,000 MPa for a metal: probably GPa "
         "(MPa expected: 120 GPa is 120000 MPa)"),
        ("fretwork: warning: 'coupling.wing_amplitude' = 100 mm is larger than 10 mm: probably µm "
         "(mm expected: 100 µm is 0.1 mm)")]
    assert lines[-1] == "fretwork: interrupted" and "Traceback" not in stderr
    assert not [name for name in files(place / "o10") if name.endswith((".part", ".tmp", ".lock"))]


def test_6_ctrl_c_during_a_run_keeps_its_checkpoint_and_says_how_to_resume(place):
    scene = (CYLINDER.read_text().replace("contact_size = 0.05", "contact_size = 0.2")
             .replace("increments_per_cycle = 40", "increments_per_cycle = 8")
             .replace("wear_cap = 2.0e-4", "wear_cap = 2.0e-4\ncheckpoint_every = 1")
             .replace("wear_cycles = 20 ", "wear_cycles = 2000 "))  # still running when Ctrl-C comes
    (place / "long.toml").write_text(scene)
    run = Background("run", "long.toml", "--out", "o6", "--quiet", "--no-cache", cwd=place)
    deadline = time.monotonic() + 120
    while not (place / "o6" / "checkpoint.h5").exists():
        assert run.process.poll() is None and time.monotonic() < deadline, run.stderr
        time.sleep(0.05)
    code, stderr = run.ctrl_c()
    assert code == 130, stderr
    assert stderr == "fretwork: interrupted; continue with --resume (from o6/checkpoint.h5)\n"
    assert files(place / "o6") == [".fretwork-outputs", "checkpoint.h5"]
