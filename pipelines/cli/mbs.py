"""Command-line parts of the multibody model.

`fretwork sweep SCENE.toml --speeds 500:800:10 [--json] [--scheduler tcp://HOST:PORT] [--workers N]`:
engine-speed sweep, the speeds as parallel dask cases (add_sweep_parser / run_sweep; sweep_summary
draws and reports a sweep, for `sweep --margins` too).
`fretwork mbs SCENE.toml [--out DIR] [--json] [--interface-histories FILE [--counterweight N]]`: one
run at the scene's speed with HDF5 histories, spectra, Campbell diagram and plots, and optionally
one CW's interface histories (mbs.histories_file; .h5 or .csv) for a scene's
'coupling.histories' (add_run_parser / run_single). The lead's CLI registers them
and calls args.handler(args). Summaries go to stdout (JSON with --json), progress bars to stderr.
"""

from __future__ import annotations

import os
import sys
import tomllib
from pathlib import Path

import numpy as np

from mbs.histories import SETTLED_CHANGE, unsettled_message
from mbs.model import SimulationError
from mbs.parameters import ModelParams
from mbs.plots import plot_campbell, plot_sweep
from mbs.run import run_model
from mbs.sweep import SweepResult
from pipelines.cli import json_text
from pipelines.jobs.sweep import check_resolution, output_paths, parse_speeds, speed_sweep, sweep_paths
from pipelines.parallel import add_cluster_arguments
from pipelines.scene.checks import engine_speed_warnings
from reduction.errors import InputError

RUN_FILE = "run.h5"  # what mbs.run.run_model writes in its folder


def model_params(path) -> ModelParams:
    """The multibody model of a scene file: a coupled scene's [mbs] table with the multibody
    effects of its 'scene.effects', else the [mbs] table alone; a scene without [mbs] is refused,
    and a file with more than [mbs] must be a valid scene as a whole."""
    from mbs.scene import load_model_params
    from pipelines import scene as scenes
    from pipelines.coupling import multibody_params

    tables = scenes.tables(path)
    if not isinstance(tables.get("mbs"), dict):
        raise InputError(f"{path} has no [mbs] table: it does not describe a multibody model "
                         "(an empty [mbs] table runs the default generic engine)")
    if set(tables) == {"mbs"}:
        return load_model_params(path)
    scene = scenes.load(path)
    return multibody_params(scene) if "coupling" in scene.data else load_model_params(path)


def coupled_resolution(scene, speeds=()) -> list[str]:
    """The multibody time step of a scene whose contact run its multibody model drives (a
    [coupling] table that names no interface-histories file) checked against the excitation
    (:func:`pipelines.jobs.sweep.check_resolution`) at the scene's speed and ``speeds`` (rpm),
    before any work: a step that cannot sample it is refused (InputError), the warnings of a coarse
    one are returned. `run`, `limit`, `demo` and the studies check their scene with it, as `mbs`
    and `sweep` check theirs; [] for a scene without a multibody model."""
    from pipelines.coupling import histories_path, multibody_params

    if "coupling" not in scene.data or histories_path(scene) is not None:
        return []
    params = multibody_params(scene)
    return check_resolution(params, [params.speed_rpm, *speeds])


def _counterweight(args, params: ModelParams) -> int:
    """The CW whose interface histories `fretwork mbs` writes (checked when they are asked for)."""
    counterweight = args.counterweight
    if counterweight is None:
        try:
            table = tomllib.loads(Path(args.scene).read_text()).get("coupling", {})
        except (OSError, tomllib.TOMLDecodeError):
            table = {}
        counterweight = table.get("counterweight", 1) if isinstance(table, dict) else 1
    if not isinstance(counterweight, int) or not 1 <= counterweight <= params.n_counterweights:
        raise InputError(f"--counterweight is {counterweight!r}, but the multibody model has "
                         f"{params.n_counterweights} counterweights (1 … {params.n_counterweights})")
    if args.interface_histories and Path(args.interface_histories).suffix.lower() not in (".h5", ".hdf5", ".csv"):
        raise InputError(f"--interface-histories {args.interface_histories}: the file must end in .h5, .hdf5 or .csv")
    return counterweight


def scene_calibration(path) -> tuple[str, float | None, int]:
    """What the plots need of a scene file to name it and to calibrate the multibody amplitudes
    as its coupling does: its name (the file's stem when it states none), its stated wing
    amplitude (mm; None when it states none, is not coupled, or reads its interface histories from
    a file instead of the multibody run) and its coupled CW (1 = first)."""
    from pipelines import scene as scenes

    tables = scenes.tables(path)
    name = tables.get("scene", {}).get("name") if isinstance(tables.get("scene"), dict) else None
    coupling = tables.get("coupling") if isinstance(tables.get("coupling"), dict) else {}
    stated = None if coupling.get("histories") else coupling.get("wing_amplitude")
    counterweight = coupling.get("counterweight", 1)
    return (name or Path(path).stem, float(stated) if isinstance(stated, (int, float)) else None,
            counterweight if isinstance(counterweight, int) else 1)


#: What a scene that states no wing amplitude does with the multibody amplitudes (a calibration note)
UNCALIBRATED = "a scene that states no wing amplitude uses these amplitudes as they are"


def sweep_calibration(result: SweepResult, scene_path, speed_rpm: float) -> tuple[float | None, str]:
    """The factor the scene's coupling multiplies the sweep's multibody amplitudes by, and a note
    saying where it comes from: its stated wing amplitude over the sweep's amplitude of its CW
    at its own speed ``speed_rpm``, when that speed is in the sweep; else None and how the scene
    calibrates (no stated amplitude: the multibody amplitudes are the scene's own)."""
    _, stated, counterweight = scene_calibration(scene_path)
    if stated is None:
        return None, UNCALIBRATED
    at = np.flatnonzero(np.isclose(result.speeds_rpm, speed_rpm))
    raw = result.wing_amplitude[at[0], counterweight - 1] if at.size and counterweight <= result.wing_amplitude.shape[1] \
        else np.nan
    if not np.isfinite(raw) or raw <= 0:
        return None, (f"the scene multiplies them by its stated {1e3 * stated:g} µm / CW{counterweight}'s amplitude at "
                      f"{speed_rpm:g} rpm, a speed not in this sweep")
    return float(stated / raw), (f"calibration = the scene's stated {1e3 * stated:g} µm / CW{counterweight}'s "
                                 f"{1e3 * raw:.3g} µm at {speed_rpm:g} rpm")


def add_sweep_parser(subparsers):
    """Add the `sweep` sub-command to an argparse subparsers object; returns the parser."""
    parser = subparsers.add_parser(
        "sweep", help="engine-speed sweep of the crankshaft-counterweight model",
        description="Run the multibody model at each engine speed; report wing torsion amplitude, "
                    "dominant frequencies and order/mode crossings; write one HDF5 file.")
    parser.add_argument("scene", help="scene TOML file (its [mbs] table sets the model)")
    parser.add_argument("--speeds", required=True, help="START:STOP:STEP or a comma list, rpm (e.g. 500:800:10)")
    parser.add_argument("--out", default="results/sweep",
                        help="output folder: sweep.h5 and the plots (default: %(default)s; a name ending .h5 is the file)")
    parser.add_argument("--plots", default=None,
                        help="folder for the PNG plots: wing amplitude over speed, Campbell diagram and, with "
                             "--margins, margins (default: the --out folder)")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON on stdout")
    add_cluster_arguments(parser)
    parser.set_defaults(handler=run_sweep)
    return parser


def _table(result, calibration: tuple[float | None, str] = (None, ""), counterweight: int = 1) -> str:
    """The sweep for a reader: the multibody model's raw wing amplitudes per speed (µm) and, when
    the scene calibrates them (:func:`sweep_calibration`), its coupled CW's (``counterweight``,
    1 = first) calibrated amplitude beside them, where that factor comes from said under the table."""
    factor, note = calibration
    if not 1 <= counterweight <= result.wing_amplitude.shape[1]:
        factor = None
    header = f"{'rpm':>8} {'CW1 raw µm':>11} {'CW2 raw µm':>11}"
    if factor is not None:
        header += f" {f'CW{counterweight} scene µm':>14}"
    lines = [header + f" {'f1 Hz':>9} {'f2 Hz':>9}  note"]
    for i, speed in enumerate(result.speeds_rpm):
        amplitude = 1e3 * result.wing_amplitude[i]
        f = result.dominant_frequencies[i]
        remark = "FAILED: " + result.failures[float(speed)] if float(speed) in result.failures else (
            "NOT STEADY (amplitude not to be trusted)" if float(speed) in (result.unsettled or {}) else
            "order/mode crossing" if result.resonance[i] else "")
        line = f"{speed:8.1f} {amplitude[0]:11.3f} {amplitude[1]:11.3f}"
        if factor is not None:
            line += f" {factor * amplitude[counterweight - 1]:14.1f}"
        lines.append(line + f" {f[0]:9.1f} {f[1]:9.1f}  {remark}")
    legend = ["raw: the multibody model's own wing torsion amplitude (half peak-to-peak), uncalibrated"]
    if factor is not None:
        legend.append(f"scene: raw × {factor:.4g}, the amplitude the scene's coupling applies ({note})")
    elif note:
        legend.append(f"calibration: {note}")
    return "\n".join(lines + legend + crossing_lines(result))


def crossing_lines(result: SweepResult) -> list[str]:
    """One line per order/mode crossing of the sweep."""
    return [f"crossing: order {crossing['order']:g} meets mode {crossing['mode'] + 1} at "
            f"{crossing['speed_rpm']:.1f} rpm ({crossing['frequency_hz']:.1f} Hz)" for crossing in result.crossings]


def sweep_warnings(params: ModelParams, speeds, written: str) -> list[str]:
    """The warnings of a sweep's speeds (``written``: as the user gave them): a likely unit
    mistake (on their own, and beside the scene's own engine speed ``params.speed_rpm``), and a time
    step too coarse for the gear mesh at the fastest of them."""
    return (engine_speed_warnings(speeds, f"--speeds {written}", reference_rpm=params.speed_rpm)
            + check_resolution(params, speeds))


def sweep_summary(result: SweepResult, path, plots, calibration: tuple[float | None, str]) -> dict:
    """Draw the sweep's plots into the folder ``plots`` (wing amplitude over speed with the
    crossings, Campbell diagram) and return its summary: the figures of ``--json``
    (:meth:`SweepResult.to_json`), the file ``path`` and the plots. `sweep` and `sweep --margins`
    both report a sweep with it. calibration: (factor or None, where it comes from) for the
    amplitude plot (:func:`sweep_calibration`)."""
    plots = Path(plots)
    factor, note = calibration
    crossing_speeds = [c["speed_rpm"] for c in result.crossings]
    drawn = {"wing_amplitude": plot_sweep(result.speeds_rpm, result.wing_amplitude, plots / "sweep_wing_amplitude.png",
                                          crossings_rpm=crossing_speeds, calibration=factor, calibration_note=note),
             "campbell": plot_campbell(result.campbell, plots / "campbell.png")}
    return dict(result.to_json(), file=str(path), plots={name: str(drawn[name]) for name in drawn})


def run_sweep(args) -> int:
    """Run the sweep described by parsed args; 0 if at least one speed converged, 1 if none, 2 on bad input."""
    folder, path = sweep_paths(args.out)
    try:
        params = model_params(args.scene)
        speeds = parse_speeds(args.speeds)
        for message in sweep_warnings(params, speeds, args.speeds):
            print(f"fretwork: warning: {message}", file=sys.stderr)
        result = speed_sweep(params, speeds, path=path, progress=not getattr(args, "quiet", False),
                             scheduler=args.scheduler,
                             workers=args.workers)
    except InputError as error:
        print(f"fretwork: error: {error}", file=sys.stderr)
        return 2
    calibration = sweep_calibration(result, args.scene, params.speed_rpm)
    summary = sweep_summary(result, path, Path(args.plots) if args.plots else folder, calibration=calibration)
    if args.json:
        print(json_text(summary))
    else:
        print(_table(result, calibration, scene_calibration(args.scene)[2]))
        print(f"results: {path}, plots: {', '.join(summary['plots'].values())}")
    for message in (result.unsettled or {}).values():
        print(f"fretwork: warning: {message}", file=sys.stderr)
    return 0 if np.isfinite(result.wing_amplitude).any() else 1


def add_run_parser(subparsers):
    """Add the `mbs` sub-command (one multibody run) to an argparse subparsers object."""
    parser = subparsers.add_parser(
        "mbs", help="one run of the crankshaft-counterweight model (histories, spectra, Campbell)",
        description="Simulate the scene's [mbs] model at its engine speed; write run.h5 (/histories) and PNGs.")
    parser.add_argument("scene", help="scene TOML file (its [mbs] table sets the model)")
    parser.add_argument("--out", default="results/mbs",
                        help=f"output folder: {RUN_FILE} and the plots (default: %(default)s; a name ending .h5 is the file)")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON on stdout")
    parser.add_argument("--interface-histories", default=None, metavar="FILE",
                        help="also write one CW's interface histories (.h5 or .csv, docs/histories_format.md), "
                             "the steady half of the run")
    parser.add_argument("--counterweight", type=int, default=None,
                        help="which CW's interface histories (1 = first; default: the scene's "
                             "'coupling.counterweight', else 1)")
    parser.set_defaults(handler=run_single)
    return parser


def run_single(args) -> int:
    """One run; 0 on success, 1 if the time integration failed, 2 on bad input."""
    folder, path = output_paths(args.out, RUN_FILE)
    try:
        params = model_params(args.scene)
        name, stated, coupled = scene_calibration(args.scene)
        counterweight = _counterweight(args, params)
        resolution_warnings = check_resolution(params, [params.speed_rpm])
        if path.name != RUN_FILE and (folder / RUN_FILE).exists():
            raise InputError(f"--out {args.out}: the run writes {folder / RUN_FILE} and then renames it, but that "
                             f"file exists: move it, or give --out another folder")
    except InputError as error:
        print(f"fretwork: error: {error}", file=sys.stderr)
        return 2
    for message in resolution_warnings:
        print(f"fretwork: warning: {message}", file=sys.stderr)
    try:  # the run is at the scene's speed: its stated wing amplitude calibrates the time-history plot
        outputs = run_model(params, folder, scene=name, stated_wing_amplitude_mm=stated, counterweight=coupled)
    except SimulationError as error:
        print(f"fretwork: error: the simulation stopped: {error}", file=sys.stderr)
        return 1
    if Path(outputs.results_file) != path:  # --out named the file (output_paths)
        os.replace(outputs.results_file, path)
    histories = outputs.histories
    interface = None
    if args.interface_histories:
        from mbs.histories_file import from_loading, write_interface_histories
        from mbs.loading import run_loading

        loading = run_loading(params, outputs.reduced, histories, counterweight)
        interface = str(write_interface_histories(args.interface_histories, from_loading(loading)))
        if Path(interface).suffix.lower() == ".csv" and loading.mode_shapes.size and params.counterweight.mesh_file is None:
            # a CSV holds no cells: read back, its mode shapes take their elements from the scene's
            # CW mesh, which here is not the multibody CW's generated block (QA, 2026-11-28)
            print(f"fretwork: note: {interface} holds the mode shapes on the multibody CW's generated mesh "
                  "without its cells: a scene reads them back only with that mesh as its CW; write .h5, "
                  "which keeps the cells, to drive another CW mesh", file=sys.stderr)
    summary = {
        "file": str(path),
        "plots": {name: str(plot) for name, plot in outputs.plots.items()},
        "speed_rpm": params.speed_rpm,
        "wing_amplitude_mm": histories.wing_amplitude.tolist(),
        "unsettled_change": histories.unsettled_change,
        "torsion_mode_hz": outputs.reduced.torsion_frequency,
        "real_time_factor": histories.real_time_factor,
        "time_step_s": params.solver.time_step,
        "cb_modes": params.n_modes,
    }
    if interface is not None:
        summary["interface_histories"] = interface
        summary["counterweight"] = counterweight
    print(json_text(summary) if args.json else describe_run(summary, params))
    message = unsettled_message(histories.unsettled_change, params.solver.revolutions, params.speed_rpm)
    if message is not None:
        print(f"fretwork: warning: {message}", file=sys.stderr)
    return 0


def describe_run(summary: dict, params: ModelParams) -> str:
    """The summary of `fretwork mbs` for a reader: wing amplitudes in µm, frequencies in Hz, the
    run's length and step, its files (the --json summary holds the same values unrounded)."""
    amplitudes = ", ".join(f"CW{k + 1} {_micrometres(a)}" for k, a in enumerate(summary["wing_amplitude_mm"]))
    change = summary["unsettled_change"]
    steadiness = ("too short to tell whether it is steady" if change is None else
                  f"{'steady' if change <= SETTLED_CHANGE else 'NOT STEADY'}, the wing amplitude changes by "
                  f"{100 * change:.1f} % between its first and last engine cycle (at most "
                  f"{100 * SETTLED_CHANGE:.0f} %)")
    lines = [f"multibody run at {summary['speed_rpm']:g} rpm: {params.solver.revolutions:g} revolutions, time step "
             f"{summary['time_step_s']:g} s, {summary['cb_modes']} Craig-Bampton modes per CW",
             f"  wing amplitude (half peak-to-peak over the second half of the run): {amplitudes}",
             f"  second half: {steadiness}",
             f"  CW torsion mode: {summary['torsion_mode_hz']:.1f} Hz",
             f"  run time: {summary['real_time_factor']:.3g} simulated s per wall-clock s",
             f"  results: {summary['file']}",
             f"  plots: {', '.join(summary['plots'].values())}"]
    if "interface_histories" in summary:
        lines.append(f"  interface histories of CW{summary['counterweight']}: {summary['interface_histories']}")
    return "\n".join(lines)


def _micrometres(amplitude_mm: float) -> str:
    """A wing amplitude (mm) in µm, three significant digits (the shipped CW's are below 1 µm)."""
    return f"{1e3 * amplitude_mm:.3g} µm"
