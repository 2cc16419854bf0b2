"""Engine-speed sweep: the wing resonance sits at the Campbell crossing; failures do not stop it;
the CLI writes one HDF5 file and JSON."""

import argparse
import json
from dataclasses import replace

import h5py
import numpy as np
import pytest

import mbs.sweep as sweep_module
from pipelines.cli.mbs import add_sweep_parser
from mbs.model import SimulationError
from mbs.parameters import CrankThrowParams, ModelParams, SolverParams
from pipelines.jobs.sweep import check_resolution, parse_speeds, speed_sweep
from reduction.errors import InputError


def stiff_throw(factor=100.0):
    throw = CrankThrowParams()
    return replace(throw, bearing_stiffness=throw.bearing_stiffness * factor,
                   axial_stiffness=throw.axial_stiffness * factor,
                   pin_stiffness=tuple(np.asarray(throw.pin_stiffness) * factor))


def test_gear_mesh_resonance_peaks_at_the_campbell_crossing_within_one_step(tmp_path):
    params = ModelParams(n_modes=4, throw=stiff_throw(), effects=frozenset({"gear_mesh"}),
                         solver=SolverParams(revolutions=1.5, time_step=5e-5))
    step = 10.0
    result = speed_sweep(params, np.arange(620.0, 680.0 + 1, step), path=tmp_path / "sweep.h5")
    torsion_crossings = [c["speed_rpm"] for c in result.crossings if c["order"] == params.excitation.gear_teeth]
    nearest = min(torsion_crossings, key=lambda s: abs(s - result.peak_speed()))
    assert abs(result.peak_speed() - nearest) <= step
    peak = np.nanargmax(result.wing_amplitude[:, 0])
    assert result.wing_amplitude[peak, 0] > 2.0 * result.wing_amplitude[[0, -1], 0].max()
    assert result.resonance[peak] or result.resonance[max(peak - 1, 0)] or result.resonance[min(peak + 1, len(result.resonance) - 1)]
    assert result.dominant_orders[peak, 0] == pytest.approx(params.excitation.gear_teeth, rel=0.02)
    with h5py.File(tmp_path / "sweep.h5") as root:
        assert root.attrs["fretwork_format"] == "fretwork-sweep"
        assert root["sweep/wing_amplitude"].shape == (7, 2)
        assert root["sweep/wing_amplitude"].attrs["units"] == "mm"
        # 1.5 revolutions: a second half shorter than one engine cycle, so no speed's steadiness
        # can be judged, and the sweep says so for every speed
        assert np.isnan(root["sweep/unsettled_change"][:]).all()
    assert sorted(result.unsettled) == sorted(result.speeds_rpm.tolist())
    assert all("too short" in message for message in result.unsettled.values())


def test_a_failing_speed_is_reported_and_the_sweep_continues(monkeypatch):
    real_simulate = sweep_module.simulate

    def flaky(params, **kwargs):
        if params.speed_rpm == 700.0:
            raise SimulationError("time integration did not converge at 700.0 rpm")
        return real_simulate(params, **kwargs)

    monkeypatch.setattr(sweep_module, "simulate", flaky)
    params = ModelParams(n_modes=2, effects=frozenset({"gear_mesh"}), solver=SolverParams(revolutions=0.5, time_step=1e-4))
    result = speed_sweep(params, [700.0, 750.0], workers=0)  # in this process: the patch must apply
    assert list(result.failures) == [700.0]
    assert np.isnan(result.wing_amplitude[0]).all()
    assert np.isfinite(result.wing_amplitude[1]).all()


def test_speed_ranges_parse_with_end_included_and_bad_ones_are_named():
    assert parse_speeds("500:800:100").tolist() == [500.0, 600.0, 700.0, 800.0]
    assert parse_speeds("600,650").tolist() == [600.0, 650.0]
    with pytest.raises(InputError, match="speeds '800:500:10'"):
        parse_speeds("800:500:10")


def test_cli_sweep_writes_hdf5_plots_and_json(tmp_path, capsys):
    scene = tmp_path / "scene.toml"
    scene.write_text('[mbs]\nn_modes = 2\neffects = ["gear_mesh"]\n[mbs.solver]\nrevolutions = 0.5\ntime_step = 1e-4\n')
    parser = argparse.ArgumentParser()
    add_sweep_parser(parser.add_subparsers())
    out = tmp_path / "out" / "sweep.h5"
    args = parser.parse_args(["sweep", str(scene), "--speeds", "700:750:50", "--out", str(out), "--json"])
    assert args.handler(args) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["speeds_rpm"] == [700.0, 750.0]
    assert out.exists() and (out.parent / "campbell.png").exists() and (out.parent / "sweep_wing_amplitude.png").exists()


def test_cli_reports_an_unknown_scene_key(tmp_path, capsys):
    scene = tmp_path / "scene.toml"
    scene.write_text("[mbs]\nspeed = 700\n")
    parser = argparse.ArgumentParser()
    add_sweep_parser(parser.add_subparsers())
    args = parser.parse_args(["sweep", str(scene), "--speeds", "700"])
    assert args.handler(args) == 2
    assert "unknown key(s) ['speed']" in capsys.readouterr().err


@pytest.mark.bench
def test_default_model_resonates_where_the_gear_order_crosses_the_coupled_torsion_mode(tmp_path):
    params = ModelParams(effects=frozenset({"gear_mesh"}), solver=SolverParams(revolutions=2.0, time_step=5e-5))
    step = 10.0
    result = speed_sweep(params, np.arange(460.0, 540.0 + 1, step), path=tmp_path / "sweep.h5")
    gear = [c for c in result.crossings if c["order"] == params.excitation.gear_teeth]
    nearest = min(gear, key=lambda c: abs(c["speed_rpm"] - result.peak_speed()))
    print(f"\npeak {result.peak_speed():.0f} rpm, crossing {nearest['speed_rpm']:.1f} rpm at {nearest['frequency_hz']:.1f} Hz; "
          f"amplitudes um {np.round(1e3 * result.wing_amplitude[:, 0], 3).tolist()}")
    assert abs(result.peak_speed() - nearest["speed_rpm"]) <= step


def _mbs_parser(tmp_path):
    """(parser of `fretwork mbs`, a small scene file: 600 rpm, 2 modes, one revolution)."""
    from pipelines.cli.mbs import add_run_parser

    scene = tmp_path / "scene.toml"
    scene.write_text('[mbs]\nspeed_rpm = 600\nn_modes = 2\n[mbs.solver]\nrevolutions = 1.0\ntime_step = 1e-4\n')
    parser = argparse.ArgumentParser()
    add_run_parser(parser.add_subparsers())
    return parser, scene


def test_cli_single_run_writes_histories_and_reports_json(tmp_path, capsys):
    parser, scene = _mbs_parser(tmp_path)
    args = parser.parse_args(["mbs", str(scene), "--out", str(tmp_path / "run"), "--json"])
    assert args.handler(args) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["speed_rpm"] == 600 and summary["cb_modes"] == 2
    with h5py.File(summary["file"]) as root:
        assert "cw1_wing_torsion" in root["histories"]


def test_a_speed_whose_excitation_the_time_step_cannot_sample_is_refused_before_any_run(tmp_path, monkeypatch,
                                                                                       capsys):
    """75000 rpm (750 meant) at 5e-5 s: 0.5 steps per gear-mesh period; exudyn cut its steps and the
    spectra refused the histories ("signal time step is not uniform"), naming neither cause nor speed."""
    import pipelines.jobs.sweep as jobs_sweep

    def refuse(*args, **kwargs):
        raise AssertionError("the sweep went on to reduce the bodies")

    monkeypatch.setattr(jobs_sweep, "reduce_bodies", refuse)
    scene = tmp_path / "scene.toml"
    scene.write_text('[mbs]\nn_modes = 2\neffects = ["gear_mesh"]\n[mbs.solver]\nrevolutions = 0.5\ntime_step = 5e-5\n')
    parser = argparse.ArgumentParser()
    add_sweep_parser(parser.add_subparsers())
    args = parser.parse_args(["sweep", str(scene), "--speeds", "750,75000", "--out", str(tmp_path / "out")])
    assert args.handler(args) == 2
    error = capsys.readouterr().err
    assert error.startswith("fretwork: error: at 75000 rpm the multibody time step 5e-05 s cannot follow the gear "
                            "mesh (engine order 48): at 75000 rpm it is 60000 Hz, 0.33 steps per period")
    assert "set [mbs.solver] time_step to at most 5.6e-07 s" in error and "speeds up to 833 rpm" in error


def test_a_time_step_that_samples_the_excitation_coarsely_is_warned_about():
    params = ModelParams(n_modes=2, effects=frozenset({"gear_mesh"}), solver=SolverParams(time_step=1e-4))
    assert check_resolution(params, [200.0, 250.0]) == []  # 48 x 250/60 Hz = 200 Hz: 50 steps per period
    warning, = check_resolution(params, [200.0, 750.0, 3000.0])  # 750 rpm: 600 Hz, 17 steps per period
    assert warning.startswith("at 750 and 3000 rpm the multibody time step 0.0001 s follows the gear mesh (engine "
                              "order 48) with fewer than 30 steps per period (4.2 at 3000 rpm, 2400 Hz)")
    gas = ModelParams(n_modes=2, effects=frozenset({"gas_torque"}), solver=SolverParams(time_step=1e-4))
    assert "gas torque" in check_resolution(gas, [40000.0])[0]
    assert check_resolution(replace(params, effects=frozenset()), [75000.0]) == []  # nothing excites the model


def test_cli_single_run_reads_as_a_summary_with_units(tmp_path, capsys):
    parser, scene = _mbs_parser(tmp_path)
    as_json = parser.parse_args(["mbs", str(scene), "--out", str(tmp_path / "run"), "--json"])
    assert as_json.handler(as_json) == 0
    summary = json.loads(capsys.readouterr().out)
    args = parser.parse_args(["mbs", str(scene), "--out", str(tmp_path / "run")])
    assert args.handler(args) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "multibody run at 600 rpm: 1 revolutions, time step 0.0001 s, 2 Craig-Bampton modes per CW"
    amplitudes = [1e3 * a for a in summary["wing_amplitude_mm"]]
    assert lines[1] == ("  wing amplitude (half peak-to-peak over the second half of the run): "
                        f"CW1 {amplitudes[0]:.3g} µm, CW2 {amplitudes[1]:.3g} µm")
    assert lines[2] == "  second half: too short to tell whether it is steady"
    assert lines[3] == f"  CW torsion mode: {summary['torsion_mode_hz']:.1f} Hz"
    assert lines[5] == f"  results: {summary['file']}"
    assert not any("{" in line or "e-0" in line for line in lines)  # no raw dict, no unrounded floats


def test_a_refused_time_step_or_speed_loses_no_earlier_output(tmp_path, capsys):
    """The time step and the speeds are checked before the output folder is cleared: a refused
    input deleted the earlier run's outputs (QA, 2026-11-28: 'removed 5 output(s)', then the error)."""
    from pipelines.cli.main import main

    good = tmp_path / "good.toml"
    good.write_text('[mbs]\nn_modes = 2\neffects = ["gear_mesh"]\n[mbs.solver]\nrevolutions = 0.2\ntime_step = 5e-5\n')
    coarse = tmp_path / "coarse.toml"
    coarse.write_text(good.read_text().replace("time_step = 5e-5", "time_step = 2e-3"))  # 375 Hz: 1.3 steps
    out = tmp_path / "out"
    assert main(["mbs", str(good), "--out", str(out), "--json"]) == 0
    written = sorted(p.name for p in out.iterdir())
    capsys.readouterr()
    assert main(["mbs", str(coarse), "--out", str(out)]) == 2
    assert main(["sweep", str(good), "--speeds=-600,750", "--workers", "0", "--out", str(out)]) == 2
    errors = capsys.readouterr().err
    assert "cannot follow the gear mesh" in errors and "engine speeds must be positive and finite (rpm), got -600" in errors
    assert "removed" not in errors and sorted(p.name for p in out.iterdir()) == written
