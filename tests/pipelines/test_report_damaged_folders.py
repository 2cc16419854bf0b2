"""`fretwork report` on folders QA damaged or interrupted: each is said in one line naming the
file and what happened to it (exit status 2), never h5py's own text or a page without a verdict."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

from pipelines.cli.main import main


def _part(folder: Path, cycles: int, checkpoint: bool | str = True) -> None:
    """What a run killed after ``cycles`` cycles leaves: results.h5.part (as the results writer
    fills it) and its checkpoint (a readable one, or a damaged one with checkpoint='damaged')."""
    folder.mkdir(parents=True, exist_ok=True)
    with h5py.File(folder / "results.h5.part", "w") as file:
        file.attrs.update(fretwork_format="fretwork-results", format_version=1, scene_name="double_beam",
                          scene_toml="", complete=False)
        file.create_dataset("cycles/cycle", data=np.arange(1, cycles + 1))
    if checkpoint == "damaged":
        (folder / "checkpoint.h5").write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(100))
    elif checkpoint:
        with h5py.File(folder / "checkpoint.h5", "w") as file:
            file.attrs["fretwork_format"] = "fretwork-checkpoint"


def error_of(capsys, folder: Path, tmp_path: Path) -> str:
    assert main(["report", str(folder), "--out", str(tmp_path / "page.html")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("fretwork: error: ") and len(err.strip().splitlines()) == 1, err
    assert "Unable to" not in err and "synchronously" not in err, err  # h5py's words
    assert not (tmp_path / "page.html").exists()
    return err


def test_an_interrupted_run_is_said_to_be_resumable_after_its_cycles(tmp_path, capsys):
    _part(tmp_path / "intr", 150)
    err = error_of(capsys, tmp_path / "intr", tmp_path)
    assert "interrupted after 150 cycles" in err and "before it finished a cycle" not in err
    assert f"fretwork run SCENE --out {tmp_path / 'intr'} --resume" in err


def test_an_interrupted_run_with_a_damaged_checkpoint_is_to_be_run_again(tmp_path, capsys):
    _part(tmp_path / "intr", 150, checkpoint="damaged")
    err = error_of(capsys, tmp_path / "intr", tmp_path)
    assert "interrupted after 150 cycles" in err and "checkpoint.h5 is damaged" in err and "--resume" not in err


def test_a_run_stopped_before_its_first_cycle_is_not_called_resumable(tmp_path, capsys):
    _part(tmp_path / "early", 0, checkpoint=False)
    err = error_of(capsys, tmp_path / "early", tmp_path)
    assert "before it finished a cycle" in err and "--resume" not in err


@pytest.fixture
def run_folder(tmp_path) -> Path:
    """A contact run's folder: results.h5 (a small valid file, 50 kB) and its plots/."""
    folder = tmp_path / "run"
    (folder / "plots").mkdir(parents=True)
    with h5py.File(folder / "results.h5", "w") as file:
        file.attrs.update(fretwork_format="fretwork-results", format_version=1, scene_name="cw")
        file.create_dataset("cycles/cycle", data=np.arange(6000))
    for name in ("cycles.png", "fields.png"):
        (folder / "plots" / name).write_bytes(b"\x89PNG\r\n\x1a\n")
    return folder


def test_a_truncated_results_file_is_named_damaged(run_folder, tmp_path, capsys):
    path = run_folder / "results.h5"
    path.write_bytes(path.read_bytes()[:2000])
    err = error_of(capsys, run_folder, tmp_path)
    assert f"{path} is damaged" in err and "2,000 bytes" in err and "truncated" in err


def test_a_folder_in_place_of_the_results_file_is_named(run_folder, tmp_path, capsys):
    (run_folder / "results.h5").unlink()
    (run_folder / "results.h5").mkdir()
    err = error_of(capsys, run_folder, tmp_path)
    assert f"{run_folder / 'results.h5'} is a folder, not a results file" in err


def test_plots_without_their_results_file_are_no_result(run_folder, tmp_path, capsys):
    (run_folder / "results.h5").unlink()
    err = error_of(capsys, run_folder, tmp_path)
    assert f"results.h5 is missing in {run_folder}" in err


def test_a_job_folder_with_one_run_missing_its_results_says_so_at_the_top(run_folder, tmp_path):
    from pipelines.output.report import write_report

    job = tmp_path / "job"
    shutil.copytree(run_folder, job / "kept")
    shutil.copytree(run_folder / "plots", job / "lost" / "plots")
    page = write_report(job).read_text()
    assert page.index("MISSING: results.h5 is missing in") < page.index("<h2>")


def test_a_truncated_multibody_run_is_named_damaged(tmp_path, capsys):
    folder = tmp_path / "mbs"
    folder.mkdir()
    with h5py.File(folder / "run.h5", "w") as file:
        file.attrs.update(fretwork_format="fretwork-results", format_version=1)
        file.create_group("model").attrs["parameters_json"] = json.dumps({"speed_rpm": 750.0})
        file.create_dataset("histories/cw1_wing_torsion", data=np.zeros(20000))
    (folder / "wing_time_history.png").write_bytes(b"\x89PNG\r\n\x1a\n")
    (folder / "run.h5").write_bytes((folder / "run.h5").read_bytes()[:5000])
    err = error_of(capsys, folder, tmp_path)
    assert f"{folder / 'run.h5'} is damaged" in err
    (folder / "run.h5").unlink()  # plots of a multibody run, its file gone
    assert f"run.h5 is missing in {folder}" in error_of(capsys, folder, tmp_path)
