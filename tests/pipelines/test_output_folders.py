"""Output folders: checked before any work, locked while in use, cleared of an earlier run's outputs;
one message format for every command; negative option values; plausibility warnings."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pipelines.cli.main import attach_negative_values, main
from pipelines.output.locks import LOCK_NAME, MANIFEST_NAME, check_folder, claim
from pipelines.scene.checks import plausibility
from reduction.errors import InputError

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
CYLINDER = EXAMPLES / "cylinder_on_plane.toml"


def _dead_pid() -> int:
    process = subprocess.Popen([sys.executable, "-c", "pass"])
    process.wait()
    return process.pid


def test_a_claim_creates_locks_and_releases_the_folder(tmp_path):
    out = tmp_path / "new" / "out"
    with claim(out) as folder:
        assert folder == out and (out / LOCK_NAME).read_text().split() == [str(os.getpid())]
    assert out.is_dir() and not (out / LOCK_NAME).exists()


def test_a_folder_in_use_is_refused_and_its_lock_kept(tmp_path):
    (tmp_path / LOCK_NAME).write_text(f"{os.getpid()}\n")  # this process: alive
    with pytest.raises(InputError, match=r"--out .* is in use by another fretwork command \(pid \d+\)"), \
            claim(tmp_path):
        pass
    assert (tmp_path / LOCK_NAME).exists()


def test_the_stale_lock_of_a_dead_process_is_taken_over(tmp_path):
    (tmp_path / LOCK_NAME).write_text(f"{_dead_pid()}\n")
    with claim(tmp_path):
        pass
    assert not (tmp_path / LOCK_NAME).exists()


def test_outputs_of_an_earlier_run_are_removed_after_the_input_is_checked(tmp_path):
    (tmp_path / "mine.txt").write_text("the user's")
    with claim(tmp_path, outputs=("plots", "results.h5")):  # the earlier run
        (tmp_path / "plots").mkdir()
        (tmp_path / "plots" / "old.png").write_bytes(b"png")
        (tmp_path / "results.h5").write_bytes(b"h5")
    assert _recorded_names(tmp_path) == ["plots/old.png", "results.h5"]
    notes = []

    def refuse():
        raise InputError("bad scene")

    with pytest.raises(InputError), claim(tmp_path, outputs=("plots", "results.h5"), ready=refuse, note=notes.append):
        pass
    assert (tmp_path / "results.h5").exists() and not notes  # refused input: nothing lost
    with claim(tmp_path, outputs=("plots", "results.h5"), note=notes.append):
        pass
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.txt"]
    assert notes == [f"removed 2 output(s) of an earlier run from {tmp_path}: plots, results.h5"]


def _recorded_names(folder):
    return [line.split(" ", 2)[2] for line in (folder / MANIFEST_NAME).read_text().splitlines()
            if not line.startswith("#")]


def test_a_recorded_output_the_user_wrote_over_is_not_removed(tmp_path):
    with claim(tmp_path, outputs=("results.h5",)):
        (tmp_path / "results.h5").write_bytes(b"fretwork's")
    (tmp_path / "results.h5").write_bytes(b"the user's own")
    with pytest.raises(InputError, match="did not write, where this command writes its outputs: results.h5;"), \
            claim(tmp_path, outputs=("results.h5",)):
        pass
    assert (tmp_path / "results.h5").read_bytes() == b"the user's own"


def _hdf5(path, **attrs):
    import h5py

    with h5py.File(path, "w") as file:
        file.attrs.update(attrs)


def test_files_fretwork_did_not_write_are_never_removed(tmp_path):
    """A user's file in a folder fretwork writes (plots/), an HDF5 file of another program named
    as fretwork's results: refused, naming them, and nothing is removed."""
    (tmp_path / "plots").mkdir()
    (tmp_path / "plots" / "notes.txt").write_text("mine")
    _hdf5(tmp_path / "results.h5", creator="my own code")
    with pytest.raises(InputError) as refused, claim(tmp_path, outputs=("plots", "results.h5")):
        pass
    assert str(refused.value) == (
        f"--out {tmp_path} holds files that fretwork did not write, where this command writes its outputs: "
        "plots/notes.txt, results.h5; they are left alone: give another --out, or move or remove them yourself")
    assert (tmp_path / "plots" / "notes.txt").read_text() == "mine" and (tmp_path / "results.h5").exists()
    assert not (tmp_path / LOCK_NAME).exists() and not (tmp_path / MANIFEST_NAME).exists()


def test_files_that_say_they_are_fretwork_s_are_removed_without_a_manifest(tmp_path):
    """A results file whose root attribute says "fretwork-..." and a page of `fretwork report`
    are fretwork's even when no manifest lists them (a folder of an older fretwork)."""
    _hdf5(tmp_path / "results.h5", fretwork_format="fretwork-results")
    (tmp_path / "report.html").write_text("<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
                                          "<title>fretwork report: out</title></head></html>")
    with claim(tmp_path, outputs=("results.h5", "report.html"), note=lambda _: None):
        pass
    assert list(tmp_path.iterdir()) == []


def test_a_results_file_half_written_when_its_run_was_killed_is_fretwork_s(tmp_path):
    """A run killed (SIGKILL) in the middle of a write leaves a results.h5.part that HDF5 cannot
    open: its --resume takes it over (it was refused as not fretwork's, once in a CI pass); an
    unreadable HDF5 file under an output's own name is still refused."""
    damaged = b"\x89HDF\r\n\x1a\n" + bytes(range(256)) * 8
    (tmp_path / "results.h5.part").write_bytes(damaged)
    with claim(tmp_path, outputs=("results.h5", "results.h5.part"), clear=False):  # --resume
        pass
    assert (tmp_path / "results.h5.part").exists()
    (tmp_path / "results.h5").write_bytes(damaged)
    with pytest.raises(InputError, match="fretwork did not write, where this command writes its outputs: "
                                         "results.h5;"), claim(tmp_path, outputs=("results.h5", "results.h5.part")):
        pass


def test_the_command_that_ran_in_the_users_folder(tmp_path, capsys, monkeypatch):
    """`cd d; fretwork run SCENE --out .` with the user's plots/mine.txt in d: refused, kept."""
    (tmp_path / "plots").mkdir()
    (tmp_path / "plots" / "mine.txt").write_text("keep")
    monkeypatch.chdir(tmp_path)
    assert main(["run", str(CYLINDER), "--out", ".", "--quiet"]) == 2
    assert "plots/mine.txt" in capsys.readouterr().err
    assert (tmp_path / "plots" / "mine.txt").read_text() == "keep"


def test_a_resumed_or_rewritten_output_is_kept_and_recorded(tmp_path):
    with claim(tmp_path, outputs=("results.h5", "checkpoint.h5")):
        (tmp_path / "checkpoint.h5").write_bytes(b"state")
    with claim(tmp_path, outputs=("results.h5", "checkpoint.h5"), clear=False):  # --resume
        assert (tmp_path / "checkpoint.h5").exists()
        (tmp_path / "results.h5").write_bytes(b"done")
    assert _recorded_names(tmp_path) == ["checkpoint.h5", "results.h5"]


@pytest.mark.parametrize("out", ["/", "/usr", "/usr/x", "/etc", "/bin", "/lib", "/var", "/boot", "/root", "~",
                                 "/proc/x", "/sys", "/dev/x"])
def test_system_folders_are_refused(out):
    with pytest.raises(InputError, match=rf"^--out {out}: \S+ (is a system folder|holds other folders)"):
        check_folder(out)


def test_an_empty_out_is_refused(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["run", str(CYLINDER), "--out", "", "--quiet"]) == 2
    assert capsys.readouterr().err == ("fretwork: error: --out is empty: give a folder for the results (it is "
                                       "created if missing), e.g. --out results\n")
    assert list(tmp_path.iterdir()) == []


def test_a_refused_mode_count_keeps_the_earlier_plot(tmp_path, capsys):
    """`fretwork reduce` writes its one plot anew: a mode count the mesh refuses loses nothing."""
    mesh = EXAMPLES / "user_joint" / "cw.inp"
    out = tmp_path / "o"
    assert main(["reduce", str(mesh), "--modes", "4", "--out", str(out)]) == 0
    plot = (out / "reduction_error_vs_modes.png").read_bytes()
    for modes in ("-3", "100000"):
        assert main(["reduce", str(mesh), "--modes", modes, "--out", str(out)]) == 2
        assert (out / "reduction_error_vs_modes.png").read_bytes() == plot
    err = capsys.readouterr().err
    assert "removed" not in err and "normal modes" in err


@pytest.mark.parametrize("sizes, message", [
    ("0.2,10", "--sizes: 10 mm does not suit body 'cylinder'"),
    ("10,10", "--sizes '10,10': needs at least two different positive element sizes (mm)"),
    ("0.2,-1", "needs at least two different positive element sizes")])
def test_refused_sizes_keep_the_earlier_study(tmp_path, capsys, sizes, message):
    out = tmp_path / "study"
    with claim(out, outputs=("size_*mm", "convergence.png")):  # an earlier study's outputs
        (out / "size_1mm").mkdir()
        (out / "size_1mm" / "results.h5").write_bytes(b"h5")
        (out / "convergence.png").write_bytes(b"png")
    capsys.readouterr()
    assert main(["study", "convergence", str(CYLINDER), "--sizes", sizes, "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert message in err and "removed" not in err
    assert (out / "size_1mm" / "results.h5").exists() and (out / "convergence.png").exists()


def test_the_stopped_hint_offers_resume_only_from_a_checkpoint(tmp_path):
    from types import SimpleNamespace

    from contact.solver import ConvergenceError
    from pipelines.cli.main import _stopped_hint

    error = ConvergenceError("Newton did not converge")
    run = SimpleNamespace(command="run", out=str(tmp_path))
    assert _stopped_hint(run, error) == (f"; partial results stay in {tmp_path}: after changing the scene, "
                                         "run again")
    (tmp_path / "checkpoint.h5").write_bytes(b"state")
    assert _stopped_hint(run, error).endswith("run again (or --resume from its last checkpoint)")
    assert "--resume" not in _stopped_hint(SimpleNamespace(command="limit", out=str(tmp_path)), error)


def test_a_run_that_stops_before_its_first_checkpoint_does_not_offer_resume(coarse_cylinder, tmp_path, capsys):
    pull = tmp_path / "pull.toml"  # pulled off the plane under force control in the preload
    pull.write_text(coarse_cylinder.read_text().replace("value = -1066.0", "value = 1066.0"))
    assert main(["run", str(pull), "--out", str(tmp_path / "out"), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "partial results stay in" in err and "--resume" not in err


def test_area_fractions_that_sum_to_one_in_rounding_are_not_above_100_percent():
    from pipelines.cli.main import _widened

    assert _widened(1.0000000000000002, None) == ""  # stick + slip of a run where nothing opened
    assert _widened(1.001).startswith(" (above 100 %")


def test_a_refused_command_leaves_no_folder_behind(tmp_path):
    with pytest.raises(InputError), claim(tmp_path / "a" / "b"):
        raise InputError("bad scene")
    assert list(tmp_path.iterdir()) == []


def test_an_interrupted_command_leaves_no_half_written_files(tmp_path):
    (tmp_path / "mine").mkdir()  # the user's, older than the command: kept
    (tmp_path / "download.part").write_bytes(b"the user's")
    old = (tmp_path / "download.part").stat().st_mtime_ns - 10**9
    for path in (tmp_path / "download.part", tmp_path / "mine"):
        os.utime(path, ns=(old, old))
    with pytest.raises(KeyboardInterrupt), claim(tmp_path) as folder:
        (folder / "runs" / "a").mkdir(parents=True)
        (folder / "runs" / "a" / "results.h5.part").write_bytes(b"part")
        (folder / "runs" / "b").mkdir()
        (folder / "runs" / "b" / "results.h5").write_bytes(b"whole")
        raise KeyboardInterrupt
    assert sorted(str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*")) == [
        "download.part", "mine", "runs", "runs/b", "runs/b/results.h5"]


@pytest.mark.parametrize("command", [
    ["run", str(CYLINDER)], ["limit", str(EXAMPLES / "counterweight.toml"), "--amplitude", "100:200"],
    ["mbs", str(EXAMPLES / "counterweight.toml")], ["sweep", str(EXAMPLES / "counterweight.toml"), "--speeds", "700"],
    ["reduce", "mesh.inp", "--modes", "2"]])
def test_every_command_refuses_an_output_folder_that_is_a_file(tmp_path, capsys, command):
    afile = tmp_path / "afile.txt"
    afile.write_text("not a folder")
    assert main([*command, "--out", str(afile / "out")]) == 2
    error = capsys.readouterr().err
    assert error == f"fretwork: error: --out {afile / 'out'} lies below the file {afile}: give a folder (it is created if missing)\n"
    assert sorted(tmp_path.iterdir()) == [afile]


def test_export_fmu_refuses_an_output_in_a_system_folder(tmp_path, capsys):
    assert main(["export-fmu", str(tmp_path / "results.h5"), "-o", "/proc/x/loads.fmu"]) == 2
    assert capsys.readouterr().err == ("fretwork: error: -o /proc/x: /proc is a system folder, not a place for "
                                       "results; give a folder of your own\n")


def test_usage_errors_have_the_one_format(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["limit", str(CYLINDER)])
    assert stop.value.code == 2
    assert capsys.readouterr().err == ("fretwork: error: the following arguments are required: --amplitude "
                                       "(see fretwork limit --help)\n")


def test_version(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0 and capsys.readouterr().out.startswith("fretwork ")


def test_negative_values_are_attached_to_their_options():
    options = {"--probe", "--amplitude", "--out"}
    assert attach_negative_values(["study", "x.toml", "--probe", "-65,0,0", "--probe", "1,2", "--json"], options) == [
        "study", "x.toml", "--probe=-65,0,0", "--probe", "1,2", "--json"]
    assert attach_negative_values(["--amplitude", "-.5:3", "--out", "-dir"], options) == [
        "--amplitude=-.5:3", "--out", "-dir"]


def test_a_negative_probe_reaches_the_command(tmp_path, capsys):
    assert main(["study", "constant-cof", str(tmp_path / "none.toml"), "--probe", "-65,0,0"]) == 2
    assert capsys.readouterr().err == f"fretwork: error: scene file {tmp_path / 'none.toml'} does not exist\n"
    assert main(["study", "constant-cof", str(CYLINDER), "--probe", "-65,a"]) == 2
    assert capsys.readouterr().err == ("fretwork: error: --probe '-65,a': give the point as x,y[,z] in mm, "
                                       "e.g. --probe -65,0,0\n")


def test_plausibility_names_the_key_and_the_likely_unit():
    data = {"materials": {"steel": {"youngs_modulus": 210.0, "density": 7850.0},
                          "ti64": {"youngs_modulus": 120000.0, "density": 4.43},
                          "rubber": {"youngs_modulus": 5.0, "density": 1.1e-9}},
            "coupling": {"wing_amplitude": 100.0}, "contact": {"critical_slip": 20.0},
            "bolts": {"m42": {"pretension": 44.0}}, "body_loads": [{"acceleration": [0.0, -9.81, 0.0]}, {"angular_velocity": [0.0, 0.0, 1500.0]}]}
    assert plausibility(data) == [
        ("'materials.steel.youngs_modulus' = 210 MPa is below 1,000 MPa for a metal: probably GPa "
         "(MPa expected: 210 GPa is 210000 MPa)"),
        ("'materials.steel.density' = 7850 t/mm³ is far heavier than any solid: probably kg/m³ "
         "(t/mm³ expected: 7850 kg/m³ is 7.85e-09 t/mm³)"),
        ("'materials.ti64.density' = 4.43 t/mm³ is far heavier than any solid: probably g/cm³ "
         "(t/mm³ expected: 4.43 g/cm³ is 4.43e-09 t/mm³)"),
        "'coupling.wing_amplitude' = 100 mm is larger than 10 mm: probably µm (mm expected: 100 µm is 0.1 mm)",
        "'contact.critical_slip' = 20 mm is larger than 1 mm: probably µm (mm expected: 20 µm is 0.02 mm)",
        "'bolts.m42.pretension' = 44 N is below 100 N: probably kN (N expected: 44 kN is 44000 N)",
        ("'body_loads[0].acceleration' has magnitude 9.81 mm/s²: probably m/s² "
         "(mm/s² expected: 9.81 m/s² is 9810 mm/s²)"),
        ("'body_loads[1].angular_velocity' has magnitude 1500 rad/s: probably rpm "
         "(rad/s expected: 1500 rpm is 157.1 rad/s)")]
    assert plausibility({"coupling": {"wing_amplitude": 1e-4}}) == [
        "'coupling.wing_amplitude' = 0.0001 mm is below 1 µm: probably m (mm expected: 0.0001 m is 0.1 mm)"]


@pytest.mark.parametrize("name", sorted(p.stem for p in EXAMPLES.glob("*.toml")))
def test_the_shipped_scenes_raise_no_plausibility_warning(name):
    import tomllib

    assert plausibility(tomllib.loads((EXAMPLES / f"{name}.toml").read_text())) == []


def test_margins_below_one_are_unsafe_and_those_within_the_tolerance_at_the_limit():
    """Bracket (0.24 stuck, 0.25 not), tolerance 0.01 mm: the margins divide 0.24 mm, the largest
    amplitude shown to stick. 0.1 mm: 2.4, safe; 0.235 mm: 1.02 but within the tolerance of the
    bracket, at the limit; 0.245 mm, inside the bracket, not shown to stick: 0.98, unsafe; 0.3 mm
    unsafe."""
    from pipelines.jobs.limit import LimitResult
    from pipelines.jobs.margins import MarginResult, describe_margins

    limit = LimitResult(0.25, (0.24, 0.25), 0.01, range_mm=(0.1, 0.4))
    amplitude = np.array([0.1, 0.235, 0.245, 0.3])
    result = MarginResult(np.array([600.0, 750.0, 800.0, 900.0]), amplitude, 1.0, limit,
                          limit.margin_limit_mm / amplitude, 900.0)
    assert limit.margin_limit_mm == 0.24
    summary = result.to_json()
    assert summary["unsafe_speeds"] == [800.0, 900.0] and summary["at_limit_speeds"] == [750.0, 800.0]
    assert summary["margin_amplitude_um"] == pytest.approx(240.0) and summary["limit_um"] == pytest.approx(250.0)
    assert [result.state(k) for k in range(4)] == ["safe", "at the limit", "unsafe", "unsafe"]
    assert describe_margins(result) == ("UNSAFE at 800, 900 rpm: the wing vibration exceeds 240.0 µm, the largest "
                                        "amplitude shown to stick (margin below 1); at the limit at 750 rpm (within "
                                        "the limit's tolerance of its bracket); safe at the others; the margins "
                                        "judge CW1 ([coupling] counterweight = 1)")


def test_a_run_that_ends_early_ends_its_progress_bar_full_with_the_reason(capsys):
    from contact.verdict import Ending
    from pipelines.jobs.run import ENDINGS, ProgressBar

    bar = ProgressBar(100, True, "scene")
    for _ in range(12):
        bar.bar.update(1)
    bar.close(ENDINGS[Ending.SHAKEDOWN], done=True)
    assert (bar.bar.n, bar.bar.total) == (12, 12)
    last = capsys.readouterr().err.replace("\r", "\n").splitlines()[-1]
    assert "100%" in last and "12/12" in last and "stuck: shaken down, no more cycles needed" in last
    stopped = ProgressBar(100, True, "scene")
    stopped.bar.update(3)
    stopped.close(ENDINGS[Ending.SLID_OFF])
    last = capsys.readouterr().err.replace("\r", "\n").splitlines()[-1]
    assert "3/100" in last and "stopped: the joint slides off" in last


def test_a_long_run_says_once_when_loosening_became_evident(capsys):
    """A run that goes on to its horizon says when its verdict became known (on stderr, beside
    the bar: --json output stays clean), and shows the clamp force as it goes."""
    from types import SimpleNamespace

    from pipelines.jobs.run import ProgressBar

    bar = ProgressBar(10, True, "scene")
    figures = {"active_slip_area_fraction": 0.8, "slip_area_fraction": 0.9}
    for evident, clamp in ((None, 879.3e3), (6.9e5, 872.1e3), (6.9e5, 871.0e3)):
        bar.cycle(SimpleNamespace(figures=figures, clamp_force=clamp, loosening_evident_at=evident))
    bar.close()
    said = capsys.readouterr()
    assert said.out == ""
    assert said.err.count("loosening evident after 6.9e+05 real cycles") == 1
    assert "clamp=871.0kN" in said.err


def test_a_folder_without_write_permission_is_refused(tmp_path, monkeypatch):
    monkeypatch.setattr(os, "access", lambda path, mode: Path(path) != tmp_path)  # root may write anywhere
    with pytest.raises(InputError, match=rf"^--out {tmp_path}/out: {tmp_path} is not writable \(permission denied\)$"):
        check_folder(tmp_path / "out")


def test_the_sweep_still_takes_a_file_name_and_says_that_out_is_a_folder(tmp_path, capsys):
    assert main(["sweep", str(CYLINDER), "--speeds", "700", "--out", str(tmp_path / "old" / "sweep.h5")]) == 2
    assert capsys.readouterr().err.splitlines() == [
        (f"fretwork: note: --out {tmp_path}/old/sweep.h5 names a file: written, with the plots beside it "
         f"(--out is a folder for every command: --out {tmp_path}/old writes {tmp_path}/old/sweep.h5)"),
        (f"fretwork: error: {CYLINDER} has no [mbs] table: it does not describe a multibody model "
         "(an empty [mbs] table runs the default generic engine)")]
    assert list(tmp_path.iterdir()) == []
