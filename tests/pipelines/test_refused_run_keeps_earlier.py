"""A refused input loses nothing: an earlier run's outputs survive, byte for byte, a scene
refused as the run builds it or after its preload, and an option refused as the job starts;
--resume says before building anything that there is no checkpoint, or that it is damaged; a
run whose surfaces slide apart mid-run ends (exit 1, ending ``separated``), not an input error."""

import json
import os
from pathlib import Path

import h5py
import pytest

import pipelines.jobs.run as run_job
from pipelines.cli.main import OUTPUTS, main
from pipelines.output.locks import EARLIER_NAME, claim

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _contents(folder: Path) -> dict:
    """Every file below ``folder`` but the manifest and its bytes."""
    return {str(path.relative_to(folder)): path.read_bytes() for path in sorted(folder.rglob("*"))
            if path.is_file() and path.name != ".fretwork-outputs"}


def _variant(scene: Path, name: str, old: str, new: str) -> Path:
    text = scene.read_text()
    assert old in text
    path = scene.with_name(name)
    path.write_text(text.replace(old, new))
    return path


def test_a_finished_run_survives_scenes_refused_at_build_and_after_the_preload(coarse_cylinder, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", str(coarse_cylinder), "--out", str(out), "--quiet"]) == 0
    before = _contents(out)
    assert {"results.h5", "plots/cycles.png", "interface_final.vtu"} <= set(before)
    refused = {
        "a motion on a DOF the reference point does not have": _variant(
            coarse_cylinder, "dof.toml", 'dof = "cylinder.rp.ux"', 'dof = "cylinder.rp.uz"'),
        "a contact selection that finds no facet": _variant(
            coarse_cylinder, "box.toml", "box = [[-2.6, -0.01], [2.6, 0.3]]", "box = [[-2.6, 5.0], [2.6, 6.0]]"),
        "no load pressing the cylinder on the plane": _variant(
            coarse_cylinder, "loads.toml", "value = -1066.0", "value = 0.0"),
    }
    for why, scene in refused.items():
        capsys.readouterr()
        assert main(["run", str(scene), "--out", str(out), "--quiet"]) == 2, why
        err = capsys.readouterr().err
        assert "removed" not in err and err.startswith("fretwork: error: "), why
        assert _contents(out) == before, why
        assert not (out / EARLIER_NAME).exists()
    assert "nothing presses the contact surfaces together after the preload" in err
    assert main(["run", str(coarse_cylinder), "--out", str(out), "--quiet"]) == 0  # the folder is still a run's
    assert f"removed {len(os.listdir(out)) - 1} output(s) of an earlier run" in capsys.readouterr().err


def test_a_refused_cluster_option_keeps_the_earlier_limit_runs(tmp_path, capsys):
    out = tmp_path / "limit"
    with claim(out, outputs=OUTPUTS["limit"]):  # an earlier search
        (out / "runs" / "amplitude_0100.00um").mkdir(parents=True)
        (out / "runs" / "amplitude_0100.00um" / "results.h5").write_bytes(b"h5")
        (out / "limit.json").write_text("{}")
    before = _contents(out)
    assert main(["limit", str(EXAMPLES / "counterweight.toml"), "--amplitude", "100:200", "--workers", "-1",
                 "--out", str(out), "--quiet"]) == 2
    assert "--workers -1" in capsys.readouterr().err
    assert _contents(out) == before


def test_earlier_outputs_go_once_the_command_wrote_its_own_and_come_back_if_it_wrote_none(tmp_path):
    with claim(tmp_path, outputs=("plots", "results.h5")):
        (tmp_path / "plots").mkdir()
        (tmp_path / "plots" / "old.png").write_bytes(b"old")
        (tmp_path / "results.h5").write_bytes(b"old")
    notes = []
    with pytest.raises(RuntimeError), claim(tmp_path, outputs=("plots", "results.h5"), note=notes.append):
        assert not (tmp_path / "results.h5").exists()  # set aside while the command runs
        raise RuntimeError("failed before writing anything")
    assert _contents(tmp_path) == {"plots/old.png": b"old", "results.h5": b"old"} and not notes
    with pytest.raises(KeyboardInterrupt), claim(tmp_path, outputs=("plots", "results.h5"), note=notes.append):
        (tmp_path / "results.h5.part").write_bytes(b"half")  # removed as half-written
        raise KeyboardInterrupt
    assert _contents(tmp_path) == {"plots/old.png": b"old", "results.h5": b"old"} and not notes
    with pytest.raises(RuntimeError), claim(tmp_path, outputs=("plots", "results.h5"), note=notes.append):
        (tmp_path / "plots").mkdir()
        (tmp_path / "plots" / "new.png").write_bytes(b"new")
        raise RuntimeError("failed after writing")
    assert _contents(tmp_path) == {"plots/new.png": b"new"}  # no old plot beside a new one
    assert notes == [f"removed 2 output(s) of an earlier run from {tmp_path}: plots, results.h5"]


def _killed_after_setting_aside(folder: Path, name: str, written: str | None = None) -> None:
    """An earlier run's output ``name`` set aside by a command then killed (SIGKILL: no clean-up),
    after it had written its own output ``written``, if given."""
    with claim(folder, outputs=(name,), note=lambda _: None):
        (folder / name).write_bytes(b"old")
    (folder / EARLIER_NAME).mkdir()
    (folder / name).rename(folder / EARLIER_NAME / name)
    if written is not None:
        with h5py.File(folder / written, "w") as file:
            file.attrs["fretwork_format"] = "fretwork-results"


def test_outputs_set_aside_by_a_killed_command_come_back_unless_it_wrote_its_own(tmp_path):
    _killed_after_setting_aside(tmp_path, "results.h5")
    with claim(tmp_path, outputs=("results.h5", "checkpoint.h5"), clear=False):  # e.g. --resume
        assert (tmp_path / "results.h5").read_bytes() == b"old" and not (tmp_path / EARLIER_NAME).exists()
    (tmp_path / "results.h5").unlink()
    _killed_after_setting_aside(tmp_path, "results.h5", written="checkpoint.h5")
    with claim(tmp_path, outputs=("results.h5", "checkpoint.h5"), clear=False, note=lambda _: None):
        pass
    assert list(_contents(tmp_path)) == ["checkpoint.h5"]


@pytest.fixture
def never_built(monkeypatch):
    def build(*args, **kwargs):
        raise AssertionError("built the model before checking the checkpoint")
    monkeypatch.setattr(run_job, "build", build)


def test_resume_without_a_checkpoint_says_so_before_building(coarse_cylinder, tmp_path, capsys, never_built):
    assert main(["run", str(coarse_cylinder), "--out", str(tmp_path / "none"), "--resume", "--quiet"]) == 2
    assert f"nothing to resume: {tmp_path / 'none' / 'checkpoint.h5'} does not exist" in capsys.readouterr().err
    (tmp_path / "done").mkdir()
    with h5py.File(tmp_path / "done" / "results.h5", "w") as file:
        file.attrs["fretwork_format"] = "fretwork-results"
    assert main(["run", str(coarse_cylinder), "--out", str(tmp_path / "done"), "--resume", "--quiet"]) == 2
    assert "results.h5 is complete: there is nothing to resume" in capsys.readouterr().err


def _checkpoint(path: Path) -> bytes:
    with h5py.File(path, "w") as file:
        file.attrs["fretwork_format"] = "fretwork-results"
        state = file.create_group("checkpoint")
        state.attrs["scalars"] = json.dumps({"cycle_number": 3})
        state.create_group("state").create_dataset("cof", data=[0.5] * 5000)
    return path.read_bytes()


@pytest.mark.parametrize("damage, said", [
    (lambda whole: b"", "empty: 0 bytes"),
    (lambda whole: whole[:300], "truncated or unreadable: HDF5 cannot open its 300 bytes"),
    (lambda whole: whole[:len(whole) // 2], "truncated or unreadable")])
def test_a_damaged_checkpoint_is_said_damaged_and_a_new_run_replaces_it(coarse_cylinder, tmp_path, capsys,
                                                                       never_built, damage, said):
    path = tmp_path / "checkpoint.h5"
    path.write_bytes(damage(_checkpoint(path)))
    os.utime(path, ns=(1, 1))  # changed since any manifest recorded it
    assert main(["run", str(coarse_cylinder), "--out", str(tmp_path), "--resume", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"{path} is damaged ({said}" in err and "did not write" not in err
    assert "run again without --resume to start the run afresh (that replaces the damaged checkpoint)" in err
    with claim(tmp_path, outputs=OUTPUTS["run"], note=lambda _: None):  # the run again, without --resume
        assert not path.exists()
        path.write_bytes(b"the new run's")
    assert path.read_bytes() == b"the new run's"


def test_surfaces_that_slide_apart_mid_run_end_it_with_its_results_so_far(coarse_cylinder, tmp_path, capsys):
    """The vibration runs up over 10 cycles to a 10 mm stroke: the cylinder leaves the plane's
    ±3.2 mm master surface in a late cycle; the cycles before it are in results.h5 and drawn."""
    scene = _variant(coarse_cylinder, "apart.toml", "value = 0.107 ", "value = 10.0 ")
    scene = _variant(scene, "apart.toml", "cof_cycles = 0", "cof_cycles = 10\nvibration_run_up = 10")
    out = tmp_path / "out"
    assert main(["run", str(scene), "--out", str(out), "--quiet", "--json"]) == 1
    captured = capsys.readouterr()
    printed = json.loads(captured.out)
    assert printed["verdict"] is None and printed["ending"] == "separated"
    assert "the contact surfaces no longer face each other" in printed["error"]
    assert "marked 'separated'" in captured.err and "check the contact selections" not in captured.err
    with h5py.File(out / "results.h5", "r") as file:
        assert file.attrs["ending"] == "separated" and file.attrs["complete"]
        assert len(file["cycles/cycle"]) >= 3 and "summary" not in file
    assert (out / "plots" / "cycles.png").is_file()
    assert not (out / "checkpoint.h5").exists() and not (out / "results.h5.part").exists()
