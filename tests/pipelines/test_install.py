"""A non-editable install works from any directory: the scenes the commands need ship in the wheel.

The wheel is built from this checkout and installed without its dependencies into a fresh venv
that borrows them from the test environment (a .pth line to its site-packages, whose own .pth
files, the editable install among them, are not processed). The commands then run from a
directory that holds no fretwork sources.
"""

import os
import subprocess
import sys
import sysconfig
import venv
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _run(args, cwd):
    """Run ``args`` in ``cwd`` with this environment less PYTHONPATH (which could reach the checkout)."""
    environment = {key: value for key, value in os.environ.items() if key != "PYTHONPATH"}
    return subprocess.run(args, cwd=cwd, capture_output=True, text=True, timeout=1800,
                          env=dict(environment, MPLBACKEND="Agg"))


@pytest.mark.slow
def test_wheel_installed_elsewhere_runs_validate_and_demo(tmp_path):
    wheels = tmp_path / "wheels"
    built = _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet", "-w", str(wheels), str(ROOT)], tmp_path)
    assert built.returncode == 0, built.stderr
    environment = tmp_path / "venv"
    venv.create(environment, with_pip=False)
    python = environment / "bin" / "python"
    site = Path(_run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                     tmp_path).stdout.strip())
    (site / "test_dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    wheel = next(wheels.glob("fretwork-*.whl"))
    installed = _run([sys.executable, "-m", "pip", "--python", str(python), "install", "--no-deps", "--quiet",
                      str(wheel)], tmp_path)
    assert installed.returncode == 0, installed.stderr
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    fretwork = environment / "bin" / "fretwork"
    where = _run([str(python), "-c", "import pipelines; print(pipelines.__file__)"], elsewhere)
    assert str(environment) in where.stdout, "the test must exercise the installed copy, not the checkout"
    demo = _run([str(fretwork), "demo", "--help"], elsewhere)
    assert demo.returncode == 0 and "counterweight" in demo.stdout, demo.stderr
    validate = _run([str(fretwork), "validate", "--quick", "--json", "--out", str(tmp_path / "validation")], elsewhere)
    assert validate.returncode == 0, validate.stderr[-2000:]
    assert '"passed": false' not in validate.stdout
