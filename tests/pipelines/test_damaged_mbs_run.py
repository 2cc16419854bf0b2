"""A damaged run.h5 of `fretwork mbs` (QA: a signal cut short, a NaN sample, /histories/time
removed) is refused by every reader, `fretwork report` and `fretwork export-fmu`, with the same
one-line error naming the file and the dataset, exit 2, nothing written. Before, report failed
with an internal error on the short signal and wrote a page for the other two; export-fmu missed
a NaN in the start-up half it does not play, and in a signal not selected."""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
import pytest

from mbs.results import read_histories
from pipelines.cli.main import main
from reduction.errors import InputError

SPEED_RPM = 750.0
N_SAMPLES = 4801


def write_mbs_run(path: Path) -> Path:
    """A run.h5 in the layout of mbs.results.write_run: 12 revolutions at 750 rpm, a steady 30th-order
    wing torsion of 75 and 43 µm on two CWs, CW1's frame acceleration."""
    time = np.linspace(0.0, 12 * 60.0 / SPEED_RPM, N_SAMPLES)
    crank = 2 * np.pi * SPEED_RPM / 60.0 * time
    with h5py.File(path, "w") as file:
        file.attrs.update(fretwork_format="fretwork-results", format_version=1)
        model = file.create_group("model")
        model.attrs.update(parameters_json=json.dumps({"speed_rpm": SPEED_RPM, "n_modes": 4, "solver": {
            "revolutions": 12.0, "time_step": 2e-4}}), torsion_mode=1, real_time_factor=0.24)
        model.create_dataset("eigenfrequencies", data=[500.0, 673.54, 1236.5])
        histories = file.create_group("histories")
        histories.create_dataset("time", data=time).attrs["units"] = "s"
        histories.create_dataset("crank_angle", data=crank).attrs["units"] = "rad"
        for c, amplitude in ((1, 0.075), (2, 0.043)):
            histories.create_dataset(f"cw{c}_wing_torsion", data=amplitude * np.sin(30 * crank)).attrs["units"] = "mm"
        centripetal = np.full_like(time, -(SPEED_RPM * np.pi / 30) ** 2 * 230.0)  # mm/s², 230 mm from the axis
        acceleration = np.column_stack([np.zeros_like(time), centripetal, np.zeros_like(time)])
        histories.create_dataset("cw1_frame_acceleration", data=acceleration).attrs.update(
            units="mm/s^2", components=["x", "y", "z"])
    return path


def _short(histories):
    data = histories["cw1_wing_torsion"][:10]
    del histories["cw1_wing_torsion"]
    histories.create_dataset("cw1_wing_torsion", data=data)


def _set(name, index, value):
    def damage(histories):
        histories[name][index] = value
    return damage


def _no_time(histories):
    del histories["time"]


def _short_time(histories):
    time = histories["time"][:4000]
    del histories["time"]
    histories.create_dataset("time", data=time)


#: QA's damage, and where the message must say it is
DAMAGE = {
    "a signal cut short": (_short, "signal 'cw1_wing_torsion' has shape (10,); expected (4801,)"),
    "NaN in the steady half": (_set("cw1_wing_torsion", 3600, np.nan),
                               "signal 'cw1_wing_torsion' has a NaN or infinite value at sample 3600 (t = 0.72 s)"),
    "NaN in the start-up half": (_set("cw2_wing_torsion", 100, np.nan),
                                 "signal 'cw2_wing_torsion' has a NaN or infinite value at sample 100 (t = 0.02 s)"),
    "inf in a vector signal": (_set("cw1_frame_acceleration", (4000, 2), np.inf),
                               "signal 'cw1_frame_acceleration' has a NaN or infinite value at sample 4000 "
                               "(t = 0.8 s), component 2"),
    "time removed": (_no_time, "/histories/time is missing"),
    "time cut short": (_short_time, "signal 'crank_angle' has shape (4801,); expected (4000,)"),
}


@pytest.fixture
def mbs_folder(tmp_path) -> Path:
    folder = tmp_path / "mbs"
    folder.mkdir()
    write_mbs_run(folder / "run.h5")
    return folder


def _error(capsys, argv, written: Path) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("fretwork: error: ") and len(err.strip().splitlines()) == 1, err
    assert "internal error" not in err
    assert not written.exists()
    return err.strip().removeprefix("fretwork: error: ")


def test_the_undamaged_run_is_reported_and_exported(mbs_folder, tmp_path, capsys):
    """The file the damage is done to is read by every reader (so a refusal below is the damage's)."""
    assert main(["report", str(mbs_folder), "--out", str(tmp_path / "page.html")]) == 0
    assert "CW1 75 µm, CW2 43 µm" in (tmp_path / "page.html").read_text()
    assert main(["export-fmu", str(mbs_folder), "--out", str(tmp_path / "loads.fmu")]) == 0
    assert (tmp_path / "loads.fmu").is_file()
    assert set(read_histories(mbs_folder / "run.h5")) == {"time", "crank_angle", "cw1_wing_torsion",
                                                          "cw2_wing_torsion", "cw1_frame_acceleration"}


@pytest.mark.parametrize("case", list(DAMAGE), ids=list(DAMAGE))
def test_every_reader_refuses_a_damaged_run_naming_file_and_dataset(case, mbs_folder, tmp_path, capsys):
    damage, said = DAMAGE[case]
    path = mbs_folder / "run.h5"
    with h5py.File(path, "a") as file:
        damage(file["histories"])
    expected = f"results file {path}: {said}"
    report = _error(capsys, ["report", str(mbs_folder), "--out", str(tmp_path / "page.html")], tmp_path / "page.html")
    fmu = _error(capsys, ["export-fmu", str(mbs_folder), "--out", str(tmp_path / "loads.fmu")], tmp_path / "loads.fmu")
    # one signal selected: the file is damaged all the same
    selected = _error(capsys, ["export-fmu", str(path), "--signals", "crank_angle", "--whole", "--out",
                               str(tmp_path / "one.fmu")], tmp_path / "one.fmu")
    with pytest.raises(InputError) as refused:
        read_histories(path)
    assert report.startswith(expected), report
    assert report == fmu == selected == str(refused.value)  # one check, one sentence


def test_an_unreadable_file_is_an_input_error_of_the_reader(tmp_path):
    path = tmp_path / "run.h5"
    path.write_bytes(b"not an HDF5 file")
    with pytest.raises(InputError, match=f"results file {path} is not a readable HDF5 file"):
        read_histories(path)


def test_a_run_without_the_signals_the_report_reads_is_refused_naming_them(mbs_folder, tmp_path, capsys):
    """The page reads the crank angle and the wing torsions: a run.h5 without them was an internal
    error (KeyError)."""
    path = mbs_folder / "run.h5"
    with h5py.File(path, "a") as file:
        del file["histories/crank_angle"]
    report = _error(capsys, ["report", str(mbs_folder), "--out", str(tmp_path / "page.html")], tmp_path / "page.html")
    assert report == f"results file {path}: /histories/crank_angle is missing"
