"""FMU export of load histories: the exported FMU, run by FMPy, must replay the HDF5 histories.

Sample times are multiples of 1/64 s and the FMPy output grid is 1/256 s, both exact in binary
floating point, so the simulation lands on every sample time exactly and three points between.
"""

import os
import shutil
import stat
import time as clock
import zipfile

import h5py
import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

from pipelines.fmu.cli import add_export_fmu_parser, main_export
from pipelines.fmu.export import SourceOnlyFmuWarning, export_fmu
from pipelines.fmu.table import read_playback_table
from reduction.errors import InputError

OUTPUT_INTERVAL = 1.0 / 256.0


def write_results(path, time, signals, *, histories=True, time_units="s"):
    """Results file in the shared layout; signals: name -> (data, attrs)."""
    with h5py.File(path, "w") as results:
        results.attrs["fretwork_format"] = "fretwork-results"
        results.attrs["format_version"] = 1
        if not histories:
            return path
        group = results.create_group("histories")
        group.create_dataset("time", data=time).attrs["units"] = time_units
        for name, (data, attrs) in signals.items():
            dataset = group.create_dataset(name, data=data)
            for key, value in attrs.items():
                dataset.attrs[key] = value
    return path


@pytest.fixture(scope="module")
def history():
    """One revolution, 0.5 s, sampled at irregular multiples of 1/64 s, three signal kinds."""
    rng = np.random.default_rng(7)
    grid = np.arange(0, 33) / 64.0
    keep = np.sort(rng.choice(np.arange(1, 32), size=18, replace=False))
    time = np.concatenate([[grid[0]], grid[keep], [grid[-1]]])
    phase = 2 * np.pi * time / 0.5
    bolt_force = 12000.0 + 800.0 * np.sin(phase) + rng.normal(0, 30.0, time.size)
    interface_displacement = np.column_stack(
        [0.02 * np.sin(phase), 0.01 * np.cos(phase), 1e-4 * rng.normal(size=time.size)]
    )
    wing_acceleration = np.column_stack([3e3 * np.cos(2 * phase), -5e2 * np.sin(phase)])
    signals = {
        "bolt_force": (bolt_force, {"units": "N", "description": "Axial force in bolt 1"}),
        "interface_displacement": (
            interface_displacement,
            {"units": "mm", "description": "Relative slip of the interface", "components": ["x", "y", "z"]},
        ),
        "wing_acceleration": (wing_acceleration, {"units": "mm/s^2", "description": "Wing tip acceleration"}),
    }
    columns = {
        "bolt_force": bolt_force,
        "interface_displacement.x": interface_displacement[:, 0],
        "interface_displacement.y": interface_displacement[:, 1],
        "interface_displacement.z": interface_displacement[:, 2],
        "wing_acceleration[1]": wing_acceleration[:, 0],
        "wing_acceleration[2]": wing_acceleration[:, 1],
    }
    return time, signals, columns


@pytest.fixture(scope="module")
def results_file(tmp_path_factory, history):
    time, signals, _ = history
    return write_results(tmp_path_factory.mktemp("results") / "results.h5", time, signals)


@pytest.fixture(scope="module", params=[2, 3], ids=["fmi2", "fmi3"])
def exported(request, tmp_path_factory, results_file):
    path = tmp_path_factory.mktemp(f"fmi{request.param}") / "loads.fmu"
    return export_fmu(results_file, path, fmi_version=request.param), request.param


def assert_matches(result, expected_columns, expected_time_of):
    """Every output equals np.interp of its history at the mapped history time, to 1e-9 relative."""
    for name, values in expected_columns.items():
        expected = expected_time_of(result["time"], values)
        scale = np.max(np.abs(values))
        np.testing.assert_allclose(result[name], expected, rtol=1e-9, atol=1e-9 * scale, err_msg=name)


def test_validate_fmu_reports_no_problems(exported):
    path, fmi_version = exported
    assert validate_fmu(str(path)) == []
    assert read_model_description(str(path)).fmiVersion.startswith(str(fmi_version))


def test_fmu_holds_binary_sources_and_table(exported):
    path, fmi_version = exported
    names = zipfile.ZipFile(path).namelist()
    binary = "binaries/linux64/loads.so" if fmi_version == 2 else "binaries/x86_64-linux/loads.so"
    assert binary in names
    assert "resources/histories.bin" in names
    assert f"sources/fmi{fmi_version}_player.c" in names and "sources/player.c" in names


def test_outputs_carry_units_and_descriptions(exported):
    path, _ = exported
    description = read_model_description(str(path))
    outputs = {v.name: v for v in description.modelVariables if v.causality == "output"}
    assert list(outputs) == [
        "bolt_force",
        "interface_displacement.x",
        "interface_displacement.y",
        "interface_displacement.z",
        "wing_acceleration[1]",
        "wing_acceleration[2]",
    ]
    assert outputs["bolt_force"].unit == "N"
    assert outputs["bolt_force"].description == "Axial force in bolt 1"
    assert outputs["interface_displacement.y"].unit == "mm"
    assert outputs["interface_displacement.y"].description == "Relative slip of the interface (component y)"
    assert outputs["wing_acceleration[2]"].unit == "mm/s^2"
    millimetre = next(u for u in description.unitDefinitions if u.name == "mm")
    assert millimetre.baseUnit.m == 1 and millimetre.baseUnit.factor == pytest.approx(1e-3)


def test_playback_equals_samples_and_linear_interpolation(exported, history):
    path, _ = exported
    time, _, columns = history
    result = simulate_fmu(str(path), stop_time=time[-1], output_interval=OUTPUT_INTERVAL)
    at_samples = np.isin(result["time"], time)
    assert at_samples.sum() == time.size
    for name, values in columns.items():
        np.testing.assert_allclose(result[name][at_samples], values, rtol=1e-9,
                                   atol=1e-9 * np.abs(values).max(), err_msg=name)
    assert_matches(result, columns, lambda t, values: np.interp(t, time, values))


def test_offset_holds_first_and_last_sample_outside_history(exported, history):
    path, _ = exported
    time, _, columns = history
    offset = 0.25
    result = simulate_fmu(
        str(path), stop_time=1.0, output_interval=OUTPUT_INTERVAL, start_values={"time_offset": offset}
    )
    assert_matches(result, columns, lambda t, values: np.interp(t - offset, time, values))
    first, last = result["time"] < offset, result["time"] > offset + time[-1]
    assert first.any() and last.any()
    np.testing.assert_array_equal(result["bolt_force"][first], columns["bolt_force"][0])
    np.testing.assert_array_equal(result["bolt_force"][last], columns["bolt_force"][-1])


def test_periodic_repetition_with_offset(exported, history):
    path, _ = exported
    time, _, columns = history
    span, offset = time[-1] - time[0], 0.1
    result = simulate_fmu(
        str(path), stop_time=2.3, output_interval=OUTPUT_INTERVAL,
        start_values={"periodic": True, "time_offset": offset},
    )
    assert_matches(result, columns, lambda t, values: np.interp(np.mod(t - offset, span), time, values))


def test_period_longer_than_span_bridges_back_to_first_sample(exported, history):
    path, _ = exported
    time, _, columns = history
    period = time[-1] + 0.125
    result = simulate_fmu(
        str(path), stop_time=2.0, output_interval=OUTPUT_INTERVAL,
        start_values={"periodic": True, "period": period},
    )
    closed_time = np.append(time, period)
    assert_matches(
        result, columns,
        lambda t, values: np.interp(np.mod(t, period), closed_time, np.append(values, values[0])),
    )


def test_period_shorter_than_span_is_refused(exported):
    path, _ = exported
    with pytest.raises(Exception, match="ExitInitializationMode"):
        simulate_fmu(str(path), stop_time=1.0, start_values={"periodic": True, "period": 0.25})


def test_resource_location_with_spaces_and_percent(exported, history, tmp_path):
    """FMI 2.0 passes the resources folder as a percent-encoded file URI."""
    path, _ = exported
    time, _, columns = history
    unzipdir = extract(str(path), unzipdir=str(tmp_path / "dir with space %20"))
    result = simulate_fmu(unzipdir, stop_time=time[-1], output_interval=OUTPUT_INTERVAL)
    assert_matches(result, columns, lambda t, values: np.interp(t, time, values))


def test_selected_signals_only_in_given_order(results_file, tmp_path):
    path = export_fmu(results_file, tmp_path / "two.fmu", signals=["wing_acceleration", "bolt_force"], fmi_version=3)
    outputs = [v.name for v in read_model_description(str(path)).modelVariables if v.causality == "output"]
    assert outputs == ["wing_acceleration[1]", "wing_acceleration[2]", "bolt_force"]


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_source_only_fmu_without_compiler(results_file, tmp_path, fmi_version):
    with pytest.warns(SourceOnlyFmuWarning, match="no C compiler found"):
        path = export_fmu(results_file, tmp_path / "src.fmu", fmi_version=fmi_version, compiler="no-such-cc")
    names = zipfile.ZipFile(path).namelist()
    assert not any(name.startswith("binaries/") for name in names)
    assert f"sources/fmi{fmi_version}_player.c" in names
    assert validate_fmu(str(path)) == []


@pytest.mark.parametrize("umask", [0o022, 0o002])
def test_the_fmu_has_the_mode_the_umask_gives_every_output(results_file, tmp_path, umask):
    previous = os.umask(umask)
    try:
        with pytest.warns(SourceOnlyFmuWarning):
            path = export_fmu(results_file, tmp_path / "loads.fmu", fmi_version=3, compiler="no-such-cc")
        (tmp_path / "beside.txt").write_text("an ordinary output")
    finally:
        os.umask(previous)
    assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~umask
    assert stat.S_IMODE(path.stat().st_mode) == stat.S_IMODE((tmp_path / "beside.txt").stat().st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["beside.txt", "loads.fmu"]  # no temporary left


def test_source_only_fmu_builds_with_fmpy(results_file, history, tmp_path):
    """The shipped sources alone rebuild a working FMU (FMPy's CMake build of the FMI 3.0 sources)."""
    if shutil.which("cmake") is None:
        pytest.skip("cmake not installed")
    from fmpy.build import build_platform_binary

    time, _, columns = history
    with pytest.warns(SourceOnlyFmuWarning):
        path = export_fmu(results_file, tmp_path / "src.fmu", fmi_version=3, compiler="no-such-cc")
    unzipdir = extract(str(path), unzipdir=str(tmp_path / "unzipped"))
    (tmp_path / "build").mkdir()
    build_platform_binary(unzipdir, build_dir=tmp_path / "build")
    result = simulate_fmu(unzipdir, stop_time=time[-1], output_interval=OUTPUT_INTERVAL)
    assert_matches(result, columns, lambda t, values: np.interp(t, time, values))


def _bad_time_values(time):
    return np.where(np.arange(time.size) == 5, time[3], time)


BAD_INPUTS = {
    "unknown signal": (
        dict(signals=["bolt_forces"]),
        lambda time, signals: (time, signals),
        "unknown signal.*'bolt_forces'.*available: bolt_force",
    ),
    "empty time": (
        {},
        lambda time, signals: (np.array([]), {"bolt_force": (np.array([]), {"units": "N"})}),
        "time is empty",
    ),
    "non-monotonic time": (
        {},
        lambda time, signals: (_bad_time_values(time), signals),
        "increase strictly.*sample 5",
    ),
    "repeated time": (
        {},
        lambda time, signals: (np.where(np.arange(time.size) == 4, time[3], time), signals),
        "increase strictly.*sample 4",
    ),
    "NaN in data": (
        {},
        lambda time, signals: (
            time,
            {**signals, "interface_displacement": (
                np.where(np.arange(time.size)[:, None] == 6, np.nan, signals["interface_displacement"][0]),
                signals["interface_displacement"][1],
            )},
        ),
        "signal 'interface_displacement' has a NaN.*sample 6",
    ),
    "signal length differs from time": (
        {},
        lambda time, signals: (time, {"bolt_force": (np.zeros(time.size - 1), {"units": "N"})}),
        "signal 'bolt_force' has shape",
    ),
    "time not in seconds": (
        dict(time_units="ms"),
        lambda time, signals: (time, signals),
        "time is in 'ms'",
    ),
    "no histories group": (
        dict(histories=False),
        lambda time, signals: (time, signals),
        "no /histories group",
    ),
}


@pytest.mark.parametrize("case", list(BAD_INPUTS), ids=list(BAD_INPUTS))
def test_bad_input_raises_and_leaves_no_file(case, history, tmp_path):
    options, make, message = BAD_INPUTS[case]
    options = dict(options)
    time, signals, _ = history
    bad_time, bad_signals = make(time, signals)
    write_results(
        tmp_path / "bad.h5", bad_time, bad_signals,
        histories=options.pop("histories", True), time_units=options.pop("time_units", "s"),
    )
    output = tmp_path / "out" / "loads.fmu"
    with pytest.raises(InputError, match=message):
        export_fmu(tmp_path / "bad.h5", output, **options)
    assert not output.exists()
    assert not output.parent.exists() or list(output.parent.iterdir()) == []


@pytest.mark.parametrize("cycle", ["wing_period", "revolution"])
def test_a_scaled_run_plays_its_histories_as_its_load_cycle_used_them(cycle, tmp_path):
    """A wing torsion of a 400 Hz and a 1200 Hz part, 0.1 s at 750 rpm (1.25 revolutions): the
    wing_period cycle keeps the mean and the scaled 400 Hz harmonic; the revolution cycle scales
    the whole signal about its mean over the last revolution (the last 0.08 s)."""
    time = np.arange(2000) * 5e-5
    torsion = 0.01 + 0.002 * np.sin(2 * np.pi * 400 * time) + 0.001 * np.sin(2 * np.pi * 1200 * time)
    path = write_results(tmp_path / "results.h5", time, {"cw1_wing_torsion": (torsion, {"units": "mm"})})
    with h5py.File(path, "a") as results:
        results["histories"].attrs.update(vibration_scale=50.0, load_cycle=cycle, counterweight=1, speed_rpm=750.0)
    table = read_playback_table(path)
    if cycle == "wing_period":
        expected = 0.01 + 50.0 * 0.002 * np.sin(2 * np.pi * 400 * time)
        stated = 50.0 * 0.002
    else:
        mean = torsion[time >= time[-1] - 0.08].mean()
        expected = mean + 50.0 * (torsion - mean)
        stated = 50.0 * 0.5 * np.ptp(torsion)
    # the wing frequency is the run's estimate (a refined spectral peak), 1e-10 off here
    np.testing.assert_allclose(table.values[:, 0], expected, rtol=0, atol=1e-6 * stated)
    assert table.scaling.wing_amplitude == pytest.approx(stated, rel=1e-6)


OTHER_KINDS = {
    "sweep": ({"fretwork_format": "fretwork-sweep"}, "a speed sweep of `fretwork sweep`", "`fretwork report`"),
    # a sweep written before sweeps had their own tag
    "older sweep": ({"fretwork_format": "fretwork-results"}, "a speed sweep of `fretwork sweep`",
                    "`fretwork report`"),
    "interface histories": ({"format": "fretwork-interface-histories", "format_version": 1},
                            "an interface-histories file", "[coupling] histories"),
}


@pytest.mark.parametrize("kind", list(OTHER_KINDS), ids=list(OTHER_KINDS))
def test_a_file_of_another_kind_is_refused_naming_it_and_its_reader(kind, tmp_path, capsys):
    attrs, what, reader = OTHER_KINDS[kind]
    with h5py.File(tmp_path / "other.h5", "w") as file:
        file.attrs.update(attrs)
        if "sweep" in kind:
            file.create_group("sweep").create_dataset("speed", data=[700.0, 750.0])
    assert main_export([str(tmp_path / "other.h5"), "-o", str(tmp_path / "loads.fmu")]) == 2
    message = capsys.readouterr().err
    assert f"other.h5 is {what}" in message and reader in message and "not a run's results" in message
    assert not (tmp_path / "loads.fmu").exists()


def test_output_path_that_is_a_folder_raises(results_file, tmp_path):
    with pytest.raises(InputError, match="is a folder"):
        export_fmu(results_file, tmp_path)


def test_missing_results_file_raises(tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        export_fmu(tmp_path / "missing.h5", tmp_path / "loads.fmu")
    assert not (tmp_path / "loads.fmu").exists()


def test_cli_writes_fmu_and_reports_bad_input(results_file, tmp_path, capsys):
    output = tmp_path / "cli.fmu"
    code = main_export(
        [str(results_file), "--signals", "bolt_force,wing_acceleration", "--fmi", "3", "-o", str(output)]
    )
    assert code == 0 and output.exists()
    assert "binary and sources" in capsys.readouterr().out
    code = main_export([str(results_file), "--signals", "nope", "-o", str(tmp_path / "bad.fmu")])
    assert code == 2
    assert "unknown signal" in capsys.readouterr().err
    assert not (tmp_path / "bad.fmu").exists()


def test_cli_parser_plugs_into_subcommands(results_file, tmp_path):
    import argparse

    parser = argparse.ArgumentParser(prog="fretwork")
    add_export_fmu_parser(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["export-fmu", str(results_file), "-o", str(tmp_path / "sub.fmu")])
    assert args.func(args) == 0
    assert validate_fmu(str(tmp_path / "sub.fmu")) == []


@pytest.mark.bench
@pytest.mark.parametrize("fmi_version", [2, 3])
def test_bench_export_10_signals_100k_samples(tmp_path, fmi_version):
    n_samples, n_signals = 100_000, 10
    time = np.arange(n_samples) * 1e-4
    rng = np.random.default_rng(1)
    signals = {
        f"signal_{j}": (
            np.sin(2 * np.pi * (j + 1) * time) + 1e-3 * rng.normal(size=n_samples),
            {"units": "mm", "description": f"Test signal {j}"},
        )
        for j in range(n_signals)
    }
    write_results(tmp_path / "big.h5", time, signals)
    start = clock.perf_counter()
    path = export_fmu(tmp_path / "big.h5", tmp_path / "big.fmu", fmi_version=fmi_version)
    seconds = clock.perf_counter() - start
    size = path.stat().st_size
    raw = (n_signals + 1) * n_samples * 8
    print(f"\nFMI {fmi_version}: export {n_signals} signals x {n_samples} samples in {seconds:.2f} s, "
          f"FMU {size / 1e6:.2f} MB (raw float64 table {raw / 1e6:.2f} MB)")
    assert seconds < 10.0
    assert size < 1.1 * raw
    assert validate_fmu(str(path)) == []
    start = clock.perf_counter()
    result = simulate_fmu(str(path), stop_time=time[-1], output_interval=time[-1] / 1000)
    print(f"FMI {fmi_version}: simulate 1000 communication steps over the full history in "
          f"{clock.perf_counter() - start:.2f} s")
    expected = np.interp(result["time"], time, signals["signal_3"][0])
    np.testing.assert_allclose(result["signal_3"], expected, rtol=1e-9, atol=1e-9 * np.abs(expected).max())
