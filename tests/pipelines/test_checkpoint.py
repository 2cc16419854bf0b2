"""A run killed with SIGKILL resumes from its last checkpoint and ends bit for bit equal: the
same datasets and attributes, the same file bytes; a checkpoint of another scene (its file or a
base it extends changed) is refused."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from pipelines import scene as scenes
from pipelines.cli.main import main
from pipelines.jobs.run import run_scene
from pipelines.output.results import ResultsWriter
from reduction.errors import InputError


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
    assert (interrupted / "results.h5").read_bytes() == (reference / "results.h5").read_bytes()
    assert main(["run", str(scene), "--out", str(interrupted), "--quiet", "--resume"]) == 2


def _long_cylinder(coarse_cylinder, folder: Path) -> Path:
    """The coarse cylinder, 14 wear cycles with a checkpoint every 3."""
    text = coarse_cylinder.read_text().replace("wear_cycles = 2 ", "wear_cycles = 14 ")
    scene = folder / "long.toml"
    scene.write_text(text.replace("wear_cap = 2.0e-4", "wear_cap = 2.0e-4\ncheckpoint_every = 3"))
    return scene


def _stopped_at(scene: Path, folder: Path, stop: int, monkeypatch, resume: bool = False) -> None:
    """Run ``scene`` into ``folder`` and interrupt it (Ctrl-C) right after the checkpoint of cycle ``stop``."""
    written = ResultsWriter.checkpoint
    monkeypatch.setattr(ResultsWriter, "checkpoint", lambda writer, snapshot: (
        written(writer, snapshot), _interrupt(snapshot.cycle_number == stop)))
    with pytest.raises(KeyboardInterrupt):
        run_scene(scenes.load(scene), folder, progress=False, plots=False, resume=resume)
    monkeypatch.setattr(ResultsWriter, "checkpoint", written)


def test_a_twice_resumed_file_is_the_uninterrupted_file(coarse_cylinder, tmp_path, monkeypatch):
    """Resumed twice, the results file has the uninterrupted run's bytes, so its size: not the
    space of each deleted /checkpoint more (it was 5.5 % bigger here, 27 % for a counterweight)."""
    scene = _long_cylinder(coarse_cylinder, tmp_path)
    reference = run_scene(scenes.load(scene), tmp_path / "reference", progress=False, plots=False).results_path
    folder = tmp_path / "resumed"
    _stopped_at(scene, folder, 3, monkeypatch)
    _stopped_at(scene, folder, 9, monkeypatch, resume=True)
    resumed = run_scene(scenes.load(scene), folder, progress=False, plots=False, resume=True).results_path
    assert resumed.stat().st_size == reference.stat().st_size
    assert resumed.read_bytes() == reference.read_bytes()


def test_the_last_cycle_of_the_cof_phase_is_a_checkpoint_to_resume_from(coarse_cylinder, tmp_path, monkeypatch):
    """3 COF and 4 wear cycles, a checkpoint every 3: the COF phase's last cycle writes one (it
    did not, so a run interrupted in the wear phase went back to the checkpoint before it; QA,
    2026-11-28), and the run resumed from it is the uninterrupted one to the byte."""
    text = (coarse_cylinder.read_text().replace("cof_cycles = 0", "cof_cycles = 3")
            .replace("wear_cycles = 2 ", "wear_cycles = 4 ")
            .replace("wear_cap = 2.0e-4", "wear_cap = 2.0e-4\ncheckpoint_every = 3"))
    assert "cof_cycles = 3" in text and "wear_cycles = 4 " in text
    scene = tmp_path / "phases.toml"
    scene.write_text(text)
    reference = run_scene(scenes.load(scene), tmp_path / "reference", progress=False, plots=False).results_path
    folder = tmp_path / "resumed"
    _stopped_at(scene, folder, 3, monkeypatch)  # the checkpoint of cycle 3, the COF phase's last
    resumed = run_scene(scenes.load(scene), folder, progress=False, plots=False, resume=True).results_path
    assert resumed.read_bytes() == reference.read_bytes()
    with h5py.File(resumed) as file:
        assert list(file["cycles/phase"][()]) == [1, 1, 1, 2, 2, 2, 2]


def test_a_changed_base_scene_refuses_the_checkpoint(coarse_cylinder, tmp_path, monkeypatch):
    """The checkpoint keeps the scene resolved: a value changed in the base file the scene extends
    is refused as a changed scene file is, naming the key; a comment added to it is not a change."""
    base = _long_cylinder(coarse_cylinder, tmp_path)
    scene = tmp_path / "derived" / "child.toml"
    scene.parent.mkdir()
    scene.write_text('[scene]\nbase = "../long.toml"\nname = "child"\n')
    reference = run_scene(scenes.load(scene), tmp_path / "reference", progress=False, plots=False).results_path
    folder = tmp_path / "resumed"
    _stopped_at(scene, folder, 3, monkeypatch)
    text = base.read_text()
    base.write_text(text.replace("cof_max = 0.56", "cof_max = 0.7"))
    with pytest.raises(InputError, match=r"belongs to a different scene \(contact\.cof_max changed"):
        run_scene(scenes.load(scene), folder, progress=False, plots=False, resume=True)
    base.write_text("# the same scene, commented\n" + text)
    resumed = run_scene(scenes.load(scene), folder, progress=False, plots=False, resume=True).results_path
    assert resumed.read_bytes() == reference.read_bytes()


EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_a_resumed_counterweight_takes_up_its_kept_preconditioners(tmp_path, monkeypatch):
    """The dense Krylov path (the counterweight at 10 mm: 158 points) keeps its
    preconditioners through a checkpoint, and a run stopped there forms them again from the
    checkpoint: it ends bit for bit as the uninterrupted run, in the COF and the wear phase."""
    scene = tmp_path / "cw.toml"
    scene.write_text(f"""[scene]
base = "{EXAMPLES / 'counterweight_extreme.toml'}"
name = "cw_resumed"
[procedure]
cof_cycles = 5
vibration_run_up = 2
wear_cycles = 5
checkpoint_every = 4
""")
    reference = run_scene(scenes.load(scene), tmp_path / "reference", progress=False, plots=False)
    assert "GMRES" in reference.summary["linear_solver"]
    for stop in (4, 8):  # in the COF phase, in the wear phase
        folder = tmp_path / f"stopped_at_{stop}"
        _stopped_at(scene, folder, stop, monkeypatch)
        with h5py.File(folder / "checkpoint.h5", "r") as file:
            assert file["checkpoint/linear/counts"].size > 1  # more than one preconditioner kept
        run_scene(scenes.load(scene), folder, progress=False, plots=False, resume=True)
        expected, resumed = _datasets(reference.results_path), _datasets(folder / "results.h5")
        assert expected.keys() == resumed.keys()
        for name, value in expected.items():
            floating = np.asarray(value).dtype.kind == "f"
            assert np.array_equal(value, resumed[name], equal_nan=floating), f"stopped at {stop}: {name}"
        assert (folder / "results.h5").read_bytes() == reference.results_path.read_bytes()


def _interrupt(now: bool) -> None:
    if now:
        raise KeyboardInterrupt
