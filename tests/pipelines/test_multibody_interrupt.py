"""Ctrl-C during the multibody stage (QA): exudyn swallows the KeyboardInterrupt that Python's
SIGINT handler raises inside its user functions (a ModelError, or a failed step retried), so
`fretwork mbs` ran on to its end, and `fretwork run` to a verdict or an 'internal error'. A real
SIGINT, sent while exudyn's solve runs, must end the command with 'fretwork: interrupted', exit
status 130, and leave no results file.

The command runs in its own process through a wrapper that says 'solving' on stderr as exudyn's
SolveDynamic starts, so that the Ctrl-C falls inside the solve, not before it.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
ENV = {**os.environ, "MPLBACKEND": "Agg"}
#: the command, with exudyn's SolveDynamic saying when it starts
WRAPPER = """
import sys, exudyn
solve = exudyn.MainSystem.SolveDynamic
def said(*args, **kwargs):
    print("solving", file=sys.stderr, flush=True)
    return solve(*args, **kwargs)
exudyn.MainSystem.SolveDynamic = said
from pipelines.cli.main import main
sys.exit(main(sys.argv[1:]))
"""
#: a multibody model whose solve takes about a minute: a Ctrl-C that is not honoured shows
LONG_MBS = '[mbs]\nn_modes = 2\neffects = ["gear_mesh"]\n[mbs.solver]\nrevolutions = 1500.0\ntime_step = 2e-4\n'


def interrupted_in_solve(args, cwd: Path) -> tuple[int, str, float]:
    """Run ``fretwork ARGS``, send SIGINT half a second into the first multibody solve; (exit
    status, stderr, seconds from the SIGINT to the end)."""
    process = subprocess.Popen([sys.executable, "-c", WRAPPER, *map(str, args)], cwd=cwd, env=ENV,
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, start_new_session=True)
    chunks: list[str] = []
    reader = threading.Thread(target=lambda: chunks.extend(iter(lambda: process.stderr.read(1), "")), daemon=True)
    reader.start()
    deadline = time.monotonic() + 240
    while "solving" not in "".join(chunks):
        assert process.poll() is None, "".join(chunks)
        assert time.monotonic() < deadline, "the multibody solve did not start:\n" + "".join(chunks)
        time.sleep(0.05)
    time.sleep(0.5)
    assert process.poll() is None
    sent = time.monotonic()
    os.kill(process.pid, signal.SIGINT)
    code = process.wait(timeout=120)
    reader.join(timeout=10)
    return code, "".join(chunks), time.monotonic() - sent


def assert_interrupted(code: int, stderr: str, seconds: float) -> None:
    lines = [line for line in stderr.splitlines() if line != "solving" and not line.startswith("fretwork: warning")]
    assert code == 130, stderr
    assert lines and lines[-1].startswith("fretwork: interrupted"), stderr
    assert "error" not in stderr and "Traceback" not in stderr, stderr
    assert seconds < 30, f"the solve ran on for {seconds:.0f} s after the Ctrl-C"


def test_ctrl_c_stops_fretwork_mbs_in_its_solve(tmp_path):
    (tmp_path / "long.toml").write_text(LONG_MBS)
    assert_interrupted(*interrupted_in_solve(["mbs", "long.toml", "--out", "out"], tmp_path))
    assert not (tmp_path / "out" / "run.h5").exists()


def test_ctrl_c_stops_the_multibody_stage_of_fretwork_run(tmp_path):
    text = ((EXAMPLES / "counterweight.toml").read_text()
            .replace("contact_size = 10.0", "contact_size = 20.0").replace("n_modes = 6", "n_modes = 4")
            .replace("revolutions = 12.0 ", "revolutions = 1500.0"))
    assert "revolutions = 1500.0" in text
    (tmp_path / "cw.toml").write_text(text)
    assert_interrupted(*interrupted_in_solve(["run", "cw.toml", "--out", "out", "--no-cache", "--quiet"], tmp_path))
    assert not list((tmp_path / "out").glob("results.h5*"))
