"""A run killed with SIGKILL resumes from its last checkpoint and ends bit for bit equal."""

import json
import os
import signal
import subprocess
import sys
import time

import h5py
import numpy as np

from pipelines.cli.main import main


def _datasets(path):
    out = {}
    with h5py.File(path, "r") as file:
        def visit(name, item):
            if isinstance(item, h5py.Dataset):
                out[name] = item[()]
        file.visititems(visit)
        out["verdict"] = file["summary"].attrs["verdict"]
    return out


def test_kill_and_resume_equals_uninterrupted_run(coarse_cylinder, tmp_path, capsys):
    text = coarse_cylinder.read_text().replace("wear_cycles = 2 ", "wear_cycles = 14 ")
    text = text.replace("wear_cap = 2.0e-4", "wear_cap = 2.0e-4\ncheckpoint_every = 3")
    scene = tmp_path / "long.toml"
    scene.write_text(text)

    reference = tmp_path / "reference"
    assert main(["run", str(scene), "--out", str(reference), "--quiet"]) == 0

    interrupted = tmp_path / "interrupted"
    process = subprocess.Popen([sys.executable, "-m", "pipelines.cli.main", "run", str(scene), "--out",
                                str(interrupted), "--quiet"], stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL, env={**os.environ, "MPLBACKEND": "Agg"})
    deadline = time.monotonic() + 120
    while not (interrupted / "checkpoint.h5").exists():
        assert process.poll() is None, "the run ended before its first checkpoint"
        assert time.monotonic() < deadline
        time.sleep(0.02)
    process.send_signal(signal.SIGKILL)
    process.wait()
    assert not (interrupted / "results.h5").exists()
    with h5py.File(interrupted / "checkpoint.h5", "r") as file:  # whole and readable
        assert file["checkpoint"].attrs["scalars"]
        columns = dict(file["increments/control"].attrs)  # its tables named as a finished file's
    with h5py.File(reference / "results.h5", "r") as file:
        assert columns == dict(file["increments/control"].attrs) and "dofs" in columns

    capsys.readouterr()
    assert main(["run", str(scene), "--out", str(interrupted), "--quiet", "--resume", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["resumed_from_cycle"] >= 3
    assert not (interrupted / "checkpoint.h5").exists()
    expected, resumed = _datasets(reference / "results.h5"), _datasets(interrupted / "results.h5")
    assert expected.keys() == resumed.keys()
    for name, value in expected.items():
        floating = np.asarray(value).dtype.kind == "f"
        assert np.array_equal(value, resumed[name], equal_nan=floating), name
    assert main(["run", str(scene), "--out", str(interrupted), "--quiet", "--resume"]) == 2
