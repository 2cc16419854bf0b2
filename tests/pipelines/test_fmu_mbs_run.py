"""The FMU of ``fretwork mbs``'s run.h5 plays the steady part of the run, where the project measures
the wing amplitude (:func:`mbs.histories.steady_part`), not its start-up ring-down; ``--whole``
plays every sample. ``export-fmu`` takes the output folder of ``fretwork mbs`` (its run.h5) and of
a coupled ``fretwork run`` (its results.h5) for the file."""

import h5py
import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

from mbs.histories import steady_part
from pipelines.cli.main import main
from pipelines.fmu.export import export_fmu
from pipelines.fmu.table import read_playback_table
from reduction.errors import InputError

N_SAMPLES = 401
STEP = 2.5e-4


def ring_down():
    """(time s, wing torsion mm) of a start-up: a 200 Hz swing decaying to a steady 1 µm, the
    first half's swing 100 times the second's."""
    time = np.arange(N_SAMPLES) * STEP
    torsion = (1e-3 + 0.1 * np.exp(-time / 0.005)) * np.sin(2 * np.pi * 200.0 * time)
    return time, torsion


def write_mbs_run(path):
    """A run.h5 as ``fretwork mbs`` writes it (mbs.results.write_run: /histories and /model)."""
    time, torsion = ring_down()
    with h5py.File(path, "w") as results:
        results.attrs.update(fretwork_format="fretwork-results", format_version=1)
        group = results.create_group("histories")
        group.create_dataset("time", data=time).attrs["units"] = "s"
        group.create_dataset("cw1_wing_torsion", data=torsion).attrs["units"] = "mm"
        group.create_dataset("crank_angle", data=78.5 * time).attrs["units"] = "rad"
        results.create_group("model").attrs["torsion_mode"] = 0
    return path


@pytest.fixture
def mbs_folder(tmp_path):
    folder = tmp_path / "mbs"
    folder.mkdir()
    write_mbs_run(folder / "run.h5")
    return folder


def test_the_table_is_the_steady_part_the_wing_amplitude_is_measured_on(mbs_folder):
    time, torsion = ring_down()
    steady = steady_part(N_SAMPLES)
    table = read_playback_table(mbs_folder / "run.h5", ["cw1_wing_torsion"])
    assert np.array_equal(table.time, time[steady]) and np.array_equal(table.values[:, 0], torsion[steady])
    whole = read_playback_table(mbs_folder / "run.h5", ["cw1_wing_torsion"], whole=True)
    assert np.array_equal(whole.time, time) and np.array_equal(whole.values[:, 0], torsion)


def test_the_fmu_starts_at_the_steady_part_and_loops_it(mbs_folder, tmp_path):
    time, torsion = ring_down()
    steady = steady_part(N_SAMPLES)
    fmu = export_fmu(mbs_folder / "run.h5", tmp_path / "wing.fmu")
    model = read_model_description(str(fmu))
    assert float(model.defaultExperiment.startTime) == time[steady][0]
    assert "steady second half" in model.description and f"{time[steady][0]:.6g} s" in model.description
    assert "start-up transient" in model.description and "--whole" in model.description
    # looped over three periods from t = 0, the wing never swings beyond its steady swing
    span = time[-1] - time[steady][0]
    played = simulate_fmu(str(fmu), start_time=0.0, stop_time=3 * span, output_interval=STEP,
                          start_values={"periodic": True})
    steady_swing = np.abs(torsion[steady]).max()
    assert np.abs(played["cw1_wing_torsion"]).max() <= steady_swing * (1 + 1e-12)
    assert np.abs(torsion).max() > 50 * steady_swing  # the transient it leaves out


def test_whole_plays_the_start_up_too_and_says_so(mbs_folder, tmp_path, capsys):
    time, torsion = ring_down()
    fmu = tmp_path / "whole.fmu"
    assert main(["export-fmu", str(mbs_folder / "run.h5"), "--whole", "-o", str(fmu)]) == 0
    model = read_model_description(str(fmu))
    assert float(model.defaultExperiment.startTime) == 0.0
    assert "whole multibody run" in model.description and "start-up transient" in model.description
    table = read_playback_table(mbs_folder / "run.h5", whole=True)
    assert table.time.size == N_SAMPLES


def test_help_documents_whole(capsys):
    with pytest.raises(SystemExit):
        main(["export-fmu", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "--whole" in text and "steady" in text and "run.h5" in text


def test_the_mbs_output_folder_stands_for_its_run_h5(mbs_folder, tmp_path, capsys):
    fmu = tmp_path / "folder.fmu"
    assert main(["export-fmu", str(mbs_folder), "-o", str(fmu)]) == 0
    assert read_playback_table(mbs_folder).time.size == N_SAMPLES - steady_part(N_SAMPLES).start
    assert read_model_description(str(fmu)).description == read_model_description(
        str(export_fmu(mbs_folder / "run.h5", tmp_path / "file.fmu"))).description


def test_a_coupled_run_folder_stands_for_its_results_h5(tmp_path):
    folder = tmp_path / "run"
    folder.mkdir()
    write_mbs_run(folder / "results.h5")
    with h5py.File(folder / "results.h5", "a") as results:
        del results["model"]  # a coupled run's results: its histories are the steady part already
        results["histories"].attrs["counterweight"] = 1
    assert read_playback_table(folder).time.size == N_SAMPLES
    with pytest.raises(InputError, match="holds only the steady part"):
        read_playback_table(folder, whole=True)


def test_a_folder_without_results_says_what_it_looks_for(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    assert main(["export-fmu", str(tmp_path / "empty"), "-o", str(tmp_path / "x.fmu")]) == 2
    message = capsys.readouterr().err
    assert "does not exist" not in message
    assert "holds no results file" in message and "results.h5" in message and "run.h5" in message


def test_a_folder_with_both_files_asks_which(mbs_folder, capsys, tmp_path):
    write_mbs_run(mbs_folder / "results.h5")
    with pytest.raises(InputError, match="both"):
        read_playback_table(mbs_folder)
