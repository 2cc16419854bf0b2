"""``fretwork export-fmu IN -o OUT`` never removes a file it did not write: OUT must be an FMU file
name (.fmu), not the results file it reads, and an existing OUT is replaced only when it is an FMU
that fretwork wrote (its modelDescription.xml's generationTool and its playback table say so)."""

import zipfile

import h5py
import numpy as np
import pytest

from pipelines.cli.main import main
from pipelines.fmu.export import export_fmu, written_by_fretwork
from pipelines.output.locks import LOCK_NAME
from reduction.errors import InputError


def write_run(path):
    """A small results file in the shared layout: one signal over 20 samples."""
    time = np.arange(20) / 100.0
    with h5py.File(path, "w") as results:
        results.attrs["fretwork_format"] = "fretwork-results"
        group = results.create_group("histories")
        group.create_dataset("time", data=time).attrs["units"] = "s"
        group.create_dataset("bolt_force", data=1e4 + np.sin(time)).attrs["units"] = "N"
    return path


def refused(argv, capsys) -> str:
    """The one error line of a refused export-fmu (exit status 2)."""
    assert main(["export-fmu", *argv]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("fretwork: error: "), lines
    return lines[0]


def test_the_results_file_itself_is_refused_and_kept(tmp_path, capsys):
    run = write_run(tmp_path / "run.h5")
    before = run.read_bytes()
    message = refused([str(run), "-o", str(run)], capsys)
    assert str(run) in message and "the results file being exported" in message
    assert run.read_bytes() == before


def test_the_results_file_of_a_folder_is_refused_as_output(tmp_path, capsys):
    run = write_run(tmp_path / "run.h5")
    with h5py.File(run, "a") as results:
        results.create_group("model")  # the run.h5 of `fretwork mbs`
    before = run.read_bytes()
    message = refused([str(tmp_path), "-o", str(tmp_path / "run.h5")], capsys)
    assert "the results file being exported" in message
    assert run.read_bytes() == before


@pytest.mark.parametrize("name", ["scene.toml", "loads.zip", "loads"])
def test_a_name_without_the_fmu_suffix_is_refused(name, tmp_path, capsys):
    run = write_run(tmp_path / "run.h5")
    output = tmp_path / name
    message = refused([str(run), "-o", str(output)], capsys)
    assert str(output) in message and ".fmu" in message
    assert not output.exists()


@pytest.mark.parametrize("content", [b'[scene]\nname = "mine"\n', b"", b"PK\x03\x04 not a zip"])
def test_an_existing_file_that_is_not_fretworks_fmu_is_refused_and_kept(content, tmp_path, capsys):
    run = write_run(tmp_path / "run.h5")
    output = tmp_path / "loads.fmu"
    output.write_bytes(content)
    message = refused([str(run), "-o", str(output)], capsys)
    assert str(output) in message and "not an FMU that fretwork wrote" in message
    assert output.read_bytes() == content
    assert not (tmp_path / LOCK_NAME).exists()


def test_an_fmu_of_another_tool_is_refused_and_kept(tmp_path, capsys):
    run = write_run(tmp_path / "run.h5")
    output = tmp_path / "loads.fmu"
    export_fmu(run, output)
    with zipfile.ZipFile(output) as original, zipfile.ZipFile(tmp_path / "other.fmu", "w") as other:
        for item in original.infolist():
            data = original.read(item)
            if item.filename == "modelDescription.xml":
                data = data.replace(b'generationTool="fretwork"', b'generationTool="OtherTool"')
            other.writestr(item, data)
    before = (tmp_path / "other.fmu").read_bytes()
    assert not written_by_fretwork(tmp_path / "other.fmu")
    message = refused([str(run), "-o", str(tmp_path / "other.fmu")], capsys)
    assert "not an FMU that fretwork wrote" in message
    assert (tmp_path / "other.fmu").read_bytes() == before


def test_fretworks_own_fmu_is_replaced(tmp_path, capsys):
    run = write_run(tmp_path / "run.h5")
    output = tmp_path / "loads.fmu"
    assert main(["export-fmu", str(run), "-o", str(output)]) == 0
    assert written_by_fretwork(output)
    first = output.read_bytes()
    with h5py.File(run, "a") as results:
        results["histories/bolt_force"][...] *= 2.0
    assert main(["export-fmu", str(run), "-o", str(output)]) == 0
    assert "wrote" in capsys.readouterr().out
    assert output.read_bytes() != first and written_by_fretwork(output)
    assert not (tmp_path / LOCK_NAME).exists()


def test_the_library_refuses_as_the_command_does(tmp_path):
    run = write_run(tmp_path / "run.h5")
    (tmp_path / "notes.fmu").write_text("mine")
    with pytest.raises(InputError, match="not an FMU that fretwork wrote"):
        export_fmu(run, tmp_path / "notes.fmu")
    with pytest.raises(InputError, match="results file being exported"):
        export_fmu(run, run)
    assert (tmp_path / "notes.fmu").read_text() == "mine"
