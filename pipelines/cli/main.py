"""The ``fretwork`` command line.

Every message on stderr is one line starting ``fretwork: error:`` (bad input, exit status 2; a
simulation that stopped, exit 1), ``fretwork: warning:`` (a likely unit mistake in the scene),
``fretwork: note:`` or ``fretwork: interrupted`` (Ctrl-C, exit 130); never a traceback. Every
command that writes files checks and locks its ``--out`` folder before any work
(:func:`pipelines.output.locks.claim`).
"""

from __future__ import annotations

import argparse
import os
import re
import signal
import sys
import threading
import warnings
from contextlib import contextmanager, nullcontext
from pathlib import Path

import numpy as np

from pipelines import interrupts
from pipelines.cli import json_text
from reduction.errors import InputError, listed


def _cache(args):
    """The stage cache folder of the command (None: --no-cache), checked: a file or a folder that
    cannot be written is an InputError before any stage runs."""
    from pipelines.stages import check_directory, default_directory

    if getattr(args, "no_cache", False):
        return None
    directory = args.cache or str(default_directory())
    check_directory(directory)
    return directory


def _add_cache_arguments(parser) -> None:
    parser.add_argument("--cache", default=None, metavar="DIR",
                        help="stage cache (default: $FRETWORK_CACHE or ./.fretwork-cache)")
    parser.add_argument("--no-cache", action="store_true", help="compute every stage, keep nothing")


def cmd_run(args) -> int:
    from pipelines import scene
    from pipelines.jobs.run import run_scene
    from pipelines.stages import StageCache

    loaded = scene.load(args.scene)
    outcome = run_scene(loaded, args.out, progress=not args.quiet, resume=args.resume,
                        cache=StageCache(_cache(args)))
    if args.json:
        print(json_text(outcome.summary))
    else:
        print(_human_summary(outcome))
    return 0


def cmd_report(args) -> int:
    from pipelines.output.report import write_report

    print(write_report(args.results_dir, args.out))
    return 0


#: Area fractions are sums of point areas over the nominal area: a whole area can sum to 1 + 2e-16.
_ROUNDING = 1e-9


def _widened(*fractions) -> str:
    """The note that explains area fractions above 100 %: they refer to the contact area closed
    after the preload, and wear, or a contact patch that moves as the bodies slide, can bring
    points beyond it into contact."""
    if max((f for f in fractions if f is not None), default=0.0) <= 1.0 + _ROUNDING:
        return ""
    return (" (above 100 %: points beyond the area closed after the preload came into contact, as wear "
            "widened the contact or the contact patch moved)")


def _short_of_life(s: dict) -> str | None:
    """A line when a run that neither shook down nor loosened ended short of its life_cycles
    (its wear_cycles budget ran out first): its verdict covers that much running time only."""
    life = s.get("life_cycles")
    if life is None or s.get("shakedown_at_cycles") is not None or s["verdict"] == "loosening":
        return None
    if s["equivalent_cycles"] >= (1.0 - 1e-9) * life:
        return None
    return (f"  NOTE: the run ended at its wear_cycles budget after {s['equivalent_cycles']:.3g} real cycles, "
            f"{s['equivalent_cycles'] / life:.1%} of its life_cycles ({life:.3g}): the verdict covers that running "
            "time only (raise wear_cycles, or the jump, to reach the life)")


def _clamp_still_falling(s: dict) -> str | None:
    """A line when a joint not judged loosening was still losing clamp force visibly at the end
    (:func:`contact.verdict.clamp_still_falling`): its verdict holds for the running time run."""
    lost = s.get("clamp_loss_recent_fraction")
    if lost is None:
        return None
    from contact.verdict import clamp_loss_pace

    pace = clamp_loss_pace(s.get("clamp_loss_rate_ratio"))
    return (f"  NOTE: the clamp force was still falling at the end: {lost:.2%} of it lost over the last "
            f"{s['clamp_loss_recent_cycles']:.3g} real cycles, {pace}; the joint has not settled, and whether it "
            "levels off or loosens needs a longer run (raise wear_cycles or life_cycles)")


def loss_percent(fraction: float) -> str:
    """A loss fraction in percent with two significant digits when small (5.2e-5 -> '0.0052'),
    two decimals otherwise (0.0319 -> '3.19'): a small loss is not rounded up or to nothing."""
    percent = 100 * fraction
    decimals = 2 if abs(percent) >= 0.1 or percent == 0 else 1 - int(np.floor(np.log10(abs(percent))))
    return f"{percent:.{decimals}f}"


def _damage_maximum(name: str, value: float, units: str, location) -> str:
    """'FDP max 3.2 MPa·mm at [x, y, z] mm', each maximum at its own location; no location where
    the maximum is 0 (no point holds it more than another)."""
    text = f"{name} max {value:.4g} {units}"
    if value and location is not None:
        text += f" at {np.round(location, 2).tolist()} mm"
    return text


def _not_settled(s: dict) -> str | None:
    """A line when a run that did not loosen ended before its contact became stationary: what to
    raise to see where it settles (QA: the user joint with steel's rates ended 'damage (not yet
    stationary)' after 90 real cycles, its COF phase cut short, and nothing said what to do)."""
    if s.get("stationary", True) or s["verdict"] == "loosening":
        return None
    if s["verdict"] == "damage" and (s.get("stick_area_fraction") or 0.0) <= _ROUNDING:
        return None  # gross slip: the whole contact slides for good, nothing to settle
    return ("  NOTE: the contact was still changing when the run ended (not yet stationary): the verdict covers "
            "the running time run; raise procedure.cof_cycles (the COF phase) or wear_cycles / life_cycles "
            "(the wear phase) to see where it settles")


def _human_summary(outcome) -> str:
    s = outcome.summary
    lines = [f"scene {s['scene']}: verdict {s['verdict'].upper()}"
             f"{'' if s['stationary'] else ' (not yet stationary)'} after {s['cycles_run']} cycles",
             f"  in the last cycle: stick {s['stick_area_fraction']:.1%}, at the friction limit (slip) "
             f"{s['slip_area_fraction']:.1%}, of it at μ_max (damaged) {s['damaged_area_fraction']:.1%} "
             f"of the area closed by the preload"
             + _widened(s['slip_area_fraction'] + s['stick_area_fraction'], s['damaged_area_fraction'],
                        s['cof_evolved_area_fraction']),
             f"  still sliding (the verdict's measure) {s.get('active_slip_area_fraction', s['slip_area_fraction']):.1%}, "
             f"COF evolved on {s['cof_evolved_area_fraction']:.1%}"
             + _widened(s.get('active_slip_area_fraction'), s['cof_evolved_area_fraction']),
             f"  max wear depth {s['max_wear_depth_mm'] * 1000:.2f} µm, dissipated {s['dissipated_energy_mJ']:.4g} mJ "
             f"in the simulated cycles" + ("" if s["equivalent_cycles"] == s["cycles_run"] else
                                           " (not multiplied by the cycle jump, unlike the wear)")]
    if "wing_amplitude_mm" in s:
        lines.insert(1, f"  wing amplitude {1e3 * s['wing_amplitude_mm']:.0f} µm at {s['engine_speed_rpm']:.0f} rpm, "
                        f"one load cycle = {s['load_cycle'].replace('_', ' ')} ({s['load_cycle_frequency_hz']:.0f} Hz)")
    if s.get("bolt_force_initial_N") is not None:
        lines.append(f"  clamp force {s['bolt_force_initial_N'] / 1e3:.4g} kN -> {s['bolt_force_final_N'] / 1e3:.4g} kN "
                     f"({loss_percent(s['clamp_force_loss_fraction'])} % loss)")
    if s.get("equivalent_engine_hours") is not None:
        when = [f"{what} after {s[key + '_cycles']:.3g} cycles ({s[key + '_engine_hours']:.3g} h)"
                for what, key in (("shakedown", "shakedown_at"), ("loosening evident", "loosening_evident_at"))
                if s.get(key + "_engine_hours") is not None]
        lines.append(f"  the run stands for {s['equivalent_cycles']:.3g} real load cycles, "
                     f"{s['equivalent_engine_hours']:.3g} engine hours at {s['engine_speed_rpm']:.0f} rpm"
                     + (f"; {', '.join(when)}" if when else ""))
    short = _short_of_life(s)
    for note in (short, _clamp_still_falling(s), None if short else _not_settled(s)):
        if note:
            lines.append(note)
    if s.get("min_stick_margin") is not None:
        lines.append(f"  smallest stick margin of stuck points: {s['min_stick_margin']:.3f} (1 − max |τ|/p / μ_max: "
                     "against the COF sliding can raise a point to, not against its present COF)")
    if s.get("fdp_max_MPa_mm") is not None:
        lines.append("  fretting damage: " + _damage_maximum("FDP", s["fdp_max_MPa_mm"], "MPa·mm", s.get("fdp_max_location_mm"))
                     + ", " + _damage_maximum("FFDP", s["ffdp_max_MPa2_mm"], "MPa²·mm", s.get("ffdp_max_location_mm")))
    from pipelines.output.report import meaning

    lines.insert(1, f"  {s['verdict']}: {meaning(s)}")
    if s.get("contact_solver") is not None:
        lines.append(f"  contact solver: {s['contact_solver']}; {s['linear_solver']}")
    if outcome.stage_times:
        times = outcome.stage_times
        phases = ", ".join(f"{k.removesuffix('_phase_s')} {v:.1f} s" for k, v in times.items() if k.endswith("_phase_s"))
        lines.append("  time: " + ", ".join(
            f"{name.removesuffix('_s').replace('_', ' ')} {value:.1f} s" + (f" ({phases})" if name == "procedure_s" and phases else "")
            for name, value in times.items() if not name.endswith("_phase_s")))
    if s.get("multibody_warning"):
        lines.append(f"  WARNING: {s['multibody_warning']}")
    lines.append(f"  results: {outcome.results_path}")
    if outcome.plots:
        lines.append(f"  plots:   {Path(outcome.plots[0]).parent}")
    return "\n".join(lines)


def cmd_validate(args) -> int:
    from pipelines.jobs.validate import run_validation

    records = run_validation(quick=args.quick, out_dir=Path(args.out), progress=not args.json)
    if args.json:
        print(json_text(records))
    else:
        for r in records:
            mark = "PASS" if r["passed"] else "FAIL"
            print(f"{mark}  {r['case']:<28} {r['quantity']:<34} value {r['value']:.6g}  "
                  f"reference {r['reference']:.6g}  error {r['rel_error']:.2e} (tol {r['tolerance']:g})")
    return 0 if all(r["passed"] for r in records) else 1


def cmd_demo(args) -> int:
    from pipelines.jobs.demo import describe, run_demo

    result = run_demo(args.out, cache_dir=_cache(args), workers=args.workers, progress=not args.quiet)
    print(json_text({"summary": result.summary, "stage_times_s": result.stage_times, "files": result.files})
          if args.json else describe(result))
    return 0


def cmd_limit(args) -> int:
    from pipelines.jobs.limit import (coupled_scene, describe_limit, find_limit, format_um, parse_range_um, plot_limit,
                                      write_limit)

    low, high = parse_range_um(args.amplitude)
    if args.tolerance <= 0:
        raise InputError("--tolerance must be positive (µm)")
    name = coupled_scene(args.scene).name
    out = Path(args.out)
    result = find_limit(args.scene, low, high, tolerance_mm=1e-3 * args.tolerance, grid=args.grid,
                        cache_dir=_cache(args), out_dir=out / "runs", scheduler=args.scheduler,
                        workers=args.workers, progress=not args.quiet)
    plot = plot_limit(result, out / "limit.png", name)
    summary = dict(result.to_json(), plot=str(plot), file=str(write_limit(result, out / "limit.json")))
    if args.json:
        print(json_text(summary))
    else:
        for run in summary["runs"]:
            print(f"  {format_um(1e-3 * run['amplitude_um'], result.tolerance_mm):>8} µm: "
                  f"{run['verdict'] or 'FAILED ' + str(run['error'])}"
                  + (f", clamp-force loss {100 * run['clamp_force_loss_fraction']:.2f} %, damaged area "
                     f"{100 * (run['damaged_area_fraction'] or 0.0):.1f} %{_widened(run['damaged_area_fraction'])}"
                     if run.get("clamp_force_loss_fraction") is not None else "")
                  + (f" ({run['note']})" if run.get("note") else ""))
        print(f"{name}: {describe_limit(result)} (tolerance {args.tolerance:g} µm)")
        if not result.monotone:
            for change in result.changes:
                print(f"  {change.verdict_below} at {format_um(change.below_mm, result.tolerance_mm)} µm -> "
                      f"{change.verdict_above} at {format_um(change.above_mm, result.tolerance_mm)} µm")
        print(f"  plot: {plot}")
    return 0


def cmd_sweep(args) -> int:
    """`fretwork sweep`: the multibody speed sweep; with --margins also the amplitude limit and the margins."""
    if not args.margins:
        if args.margins_only:
            _warn(f"{listed(args.margins_only)} {'is' if len(args.margins_only) == 1 else 'are'} for --margins "
                  "only: ignored (the sweep runs without the amplitude limit and the margins)")
        return args.multibody_handler(args)
    from pipelines.jobs.sweep import parse_speeds, sweep_paths
    from pipelines.jobs.limit import format_um, parse_range_um
    from pipelines.jobs.margins import describe_margins, margin_basis, margin_sweep, plot_margins
    from pipelines import scene as scenes
    from pipelines.cli.mbs import crossing_lines, model_params, sweep_summary, sweep_warnings

    speeds = parse_speeds(args.speeds)
    params = model_params(args.scene)
    for message in sweep_warnings(params, speeds, args.speeds):
        _warn(message)
    low, high = parse_range_um(args.amplitude)
    scene = scenes.load(args.scene)
    folder, out = sweep_paths(args.out)
    limit_runs = folder / "limit_runs"
    result, sweep = margin_sweep(args.scene, speeds, amplitude_range_mm=(low, high),
                                 tolerance_mm=1e-3 * args.tolerance, cache_dir=_cache(args), sweep_path=out,
                                 out_dir=limit_runs, scheduler=args.scheduler, workers=args.workers,
                                 progress=not getattr(args, "quiet", False))
    plots = Path(args.plots) if args.plots else folder
    # the multibody sweep as plain `sweep` reports it (uncalibrated amplitudes, mm, every CW), its
    # plot with the margins' calibration
    swept = sweep_summary(sweep, out, plots, calibration=_margins_calibration(scene, params.speed_rpm, result))
    plot = plot_margins(result, plots / "margins.png", f"{scene.name}: fretting safety margin")
    summary = dict(result.to_json(), margins=describe_margins(result), file=str(out), plot=str(plot),
                   limit_plot=str(limit_runs / "limit.png"), limit_file=str(limit_runs / "limit.json"), sweep=swept)
    if args.json:
        print(json_text(summary))
    else:
        print(f"{'rpm':>8} {f'CW{result.counterweight} µm':>9} {'margin':>8}")
        flags = {"unsafe": "  < 1: UNSAFE", "at the limit": "  at the limit (within the tolerance)", "safe": "",
                 "not judged": "  not judged: the multibody run failed"}
        for k, (speed, amplitude, margin) in enumerate(zip(result.speeds_rpm, result.wing_amplitude_mm, result.margin)):
            print(f"{speed:8.1f} {1e3 * amplitude:9.1f} {margin:8.2f}{flags[result.state(k)]}")
        divided = format_um(result.limit.margin_limit_mm, result.limit.tolerance_mm)
        print(f"margins divide {divided} µm: {margin_basis(result)}; "
              f"calibration factor {result.calibration:.4g} (the scene's stated wing amplitude / the multibody "
              f"wing amplitude at its own speed: every speed's multibody amplitude is multiplied by it)")
        print(describe_margins(result))
        for line in crossing_lines(sweep):
            print(line)
        print(f"results: {out}, plots: {plot}, {summary['limit_plot']}, {', '.join(swept['plots'].values())}")
    return 0


def _margins_calibration(scene, speed_rpm: float, result) -> tuple[float | None, str]:
    """The factor the margins multiplied the sweep's multibody amplitudes by and where it comes
    from, for :func:`pipelines.cli.mbs.sweep_summary`; None when the scene states no wing
    amplitude: its multibody amplitudes are then its own (:func:`pipelines.jobs.margins.calibration_factor`)."""
    from pipelines.cli.mbs import UNCALIBRATED
    from pipelines.jobs.limit import format_um

    stated = scene.data["coupling"].get("wing_amplitude")
    if stated is None:
        return None, UNCALIBRATED
    return result.calibration, (f"calibration = the scene's stated {format_um(stated)} µm / "
                                f"CW{result.counterweight}'s multibody amplitude at the scene's "
                                f"{speed_rpm:g} rpm (as the margins use it)")


def cmd_reduce(args) -> int:
    from reduction.report import accuracy_report_for_mesh, plot_error_vs_modes

    report = accuracy_report_for_mesh(args.mesh, args.youngs_modulus, args.poisson_ratio, args.density,
                                      args.modes, args.interface_sets, clamp_sets=tuple(args.clamp_sets or ()))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    plot = plot_error_vs_modes(report, out / "reduction_error_vs_modes.png")
    if args.json:
        print(json_text({"summary": report.summary(), "records": report.to_records(), "plot": str(plot)}))
    else:
        for key, value in report.summary().items():
            print(f"  {key}: {value}")
        print(f"  plot: {plot}")
    return 0


def _point(text: str) -> list[float]:
    try:
        point = [float(v) for v in text.split(",")]
    except ValueError:
        raise InputError(f"--probe {text!r}: give the point as x,y[,z] in mm, e.g. --probe -65,0,0") from None
    if not all(np.isfinite(point)):
        raise InputError(f"--probe {text!r}: the coordinates must be finite numbers of mm, e.g. --probe -65,0,0")
    return point


def cmd_study(args) -> int:
    """`fretwork study constant-cof`: both models' max shear at the probes; the plot and the HDF5 file in --out."""
    from pipelines.cli.accuracy import set_overrides
    from pipelines.output.constant_cof_plot import plot_constant_cof
    from pipelines.studies.constant_cof import constant_cof_comparison, write_comparison

    probes = {f"P{k + 1}": _point(p) for k, p in enumerate(args.probe)}
    comparison = constant_cof_comparison(args.scene, probes, set_overrides(args.set))
    out = Path(args.out)
    summary = {"scene": comparison.scene_name, "records": comparison.records(),
               "plot": str(plot_constant_cof(comparison, out / "constant_cof.png")),
               "file": str(write_comparison(comparison, out / "constant_cof.h5"))}
    if args.json:
        print(json_text(summary))
    else:
        for r in summary["records"]:
            print(f"{r['model']:<20} {r['probe']} at {np.round(r['position_mm'], 2)} mm "
                  f"({r['distance_mm']:.2g} mm from the probe): "
                  f"max shear {r['max_shear_MPa']:.2f} MPa (slip area {r['slip_area_fraction']:.0%})")
        print(f"  plot: {summary['plot']}")
        print(f"  data: {summary['file']}")
    return 0


def _percent(value) -> str:
    return "-" if value is None else f"{100 * value:.1f}"


def _sizes(text: str) -> list[float]:
    try:
        sizes = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise InputError(f"--sizes {text!r}: use element sizes in mm separated by commas, e.g. 10,5,2.5") from None
    if len(set(sizes)) < 2 or min(sizes) <= 0:
        raise InputError(f"--sizes {text!r}: needs at least two different positive element sizes (mm)")
    return sizes


def cmd_convergence(args) -> int:
    """`fretwork study convergence`: a table per size, the converged size, Richardson estimates."""
    from pipelines.jobs.limit import coupled_scene, parse_range_um
    from pipelines.studies.convergence import convergence_study, plot_convergence, plot_histories

    sizes = _sizes(args.sizes)
    limit_range = None
    if args.amplitude:
        limit_range = parse_range_um(args.amplitude)
        coupled_scene(args.scene)
    out = Path(args.out)
    study = convergence_study(args.scene, sizes, out, cache_dir=_cache(args), limit_range_mm=limit_range,
                              tolerance_mm=1e-3 * args.tolerance, grid=args.grid, scheduler=args.scheduler,
                              workers=args.workers, progress=not args.quiet,
                              stop_at_loosening=args.stop_at_loosening)
    study["plot"] = str(plot_convergence(study, out / "convergence.png"))
    histories = plot_histories(study, out / "convergence_cycles.png")
    study["history_plot"] = None if histories is None else str(histories)
    (out / "convergence.json").write_text(json_text(study))
    if args.json:
        print(json_text(study))
        return 0
    levels = sorted(study["levels"], key=lambda level: -level["size_mm"])  # coarse first
    print(f"{'size mm':>8} {'points':>7} {'verdict':>10} {'stick %':>8} {'sliding %':>9} {'worn %':>7} "
          f"{'max wear µm':>11} {'clamp loss %':>12} {'margin':>7} {'limit µm':>9}")
    for level in levels:
        f = level["figures"]
        print(f"{level['size_mm']:>8g} {level['points']:>7} {level['verdict']:>10} {_percent(f['stick_area_fraction']):>8} "
              f"{_percent(f['active_slip_area_fraction']):>9} {_percent(f['worn_area_fraction']):>7} "
              f"{1e3 * (f['max_wear_depth_mm'] or 0.0):>11.2f} {_percent(f['clamp_force_loss_fraction']):>12} "
              f"{'-' if f['min_stick_margin'] is None else format(f['min_stick_margin'], '.3f'):>7} "
              f"{'-' if level['limit_mm'] is None else format(1e3 * level['limit_mm'], '.1f'):>9}")
    if study.get("common_cycles"):
        print(f"at equal running time, {study['common_cycles']:.4g} real cycles (the shortest run that did not "
              "shake down):")
        for level in levels:
            f = level["extra"]["at_common_cycles"]
            print(f"{level['size_mm']:>8g} {'':>7} {'':>10} {_percent(f['stick_area_fraction']):>8} "
                  f"{_percent(f['active_slip_area_fraction']):>9} {_percent(f['worn_area_fraction']):>7} "
                  f"{1e3 * (f['max_wear_depth_mm'] or 0.0):>11.2f} {_percent(f['clamp_force_loss_fraction']):>12}")
    for level in levels:
        evident = level["figures"].get("loosening_evident_at_cycles")
        if evident is not None:
            print(f"{level['size_mm']:>8g} mm: loosening evident after {evident:.4g} real cycles"
                  + (" (the run stopped there)" if study["stop_at_loosening"] else ""))
    converged = study["converged_size_mm"]
    print("converged at " + (f"{converged:g} mm (its verdict equals every finer level's)" if converged else
                             "no size: the verdict changes down to the finest level run"))
    for name, found in ((n, f) for n, f in study["extrapolated"].items() if f["order"] is not None):
        print(f"  {name}: Richardson estimate {found['estimate']:.4g} (observed order {found['order']:.2f})")
    print(f"  plot: {study['plot']}" + (f", over the run: {study['history_plot']}" if study["history_plot"] else ""))
    return 0


class Parser(argparse.ArgumentParser):
    """argparse with fretwork's one message format: a usage error is one line, exit status 2."""

    def error(self, message):
        command = self.prog.removeprefix("fretwork").strip()
        print(f"fretwork: error: {message} (see fretwork {command + ' ' if command else ''}--help)", file=sys.stderr)
        raise SystemExit(2)


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("fretwork")
    except PackageNotFoundError:  # run from a source tree that is not installed
        return "unknown (not installed)"


def build_parser() -> argparse.ArgumentParser:
    """The ``fretwork`` parser: one sub-command per job."""
    parser = Parser(prog="fretwork", description="Fretting safety of bolted joints under vibration.")
    parser.add_argument("--version", action="version", version=f"fretwork {_version()}")
    sub = parser.add_subparsers(dest="command", required=True)
    _add_run_parser(sub)
    _add_validate_and_demo_parsers(sub)
    report = sub.add_parser("report", help="one self-contained HTML page of a run's or a job's results folder")
    report.add_argument("results_dir", help="the --out folder of a run or a job")
    report.add_argument("--out", default=None, help="the HTML file (default RESULTS_DIR/report.html)")
    report.set_defaults(func=cmd_report)
    _add_limit_parser(sub)
    _add_reduce_parser(sub)
    _add_study_parsers(sub)
    from pipelines.cli.mbs import add_run_parser, add_sweep_parser
    from pipelines.fmu.cli import add_export_fmu_parser
    add_export_fmu_parser(sub)
    sweep = add_sweep_parser(sub)
    sweep.add_argument("--margins", action="store_true",
                       help="also find the amplitude limit of the coupled scene and report limit / amplitude per speed")
    sweep.add_argument("--amplitude", default="50:500", metavar="LOW:HIGH", action=_MarginsOnly,
                       help="with --margins: wing amplitude range of the limit search, µm (default %(default)s)")
    sweep.add_argument("--tolerance", type=float, default=10.0, action=_MarginsOnly,
                       help="with --margins: limit tolerance, µm")
    sweep.add_argument("--quiet", action="store_true", help="no progress bars")
    _add_cache_arguments(sweep)
    sweep.set_defaults(multibody_handler=sweep.get_default("handler"), handler=cmd_sweep, margins_only=[])
    add_run_parser(sub)
    return parser


class _MarginsOnly(argparse.Action):
    """An option of `sweep` that means something with --margins only: stored as usual, and its
    name kept in ``args.margins_only``, so that a sweep without --margins says it is ignored."""

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, self.const if self.nargs == 0 else values)
        given = getattr(namespace, "margins_only", [])
        namespace.margins_only = given if option_string in given else [*given, option_string]


def _add_run_parser(sub) -> None:
    run = sub.add_parser("run", help="run a scene file")
    run.add_argument("scene")
    run.add_argument("--out", required=True, help="output directory")
    run.add_argument("--json", action="store_true", help="print the global figures as JSON")
    run.add_argument("--quiet", action="store_true", help="no progress bar")
    run.add_argument("--resume", action="store_true",
                     help="continue an interrupted run from DIR/checkpoint.h5")
    _add_cache_arguments(run)
    run.set_defaults(func=cmd_run)


def _add_validate_and_demo_parsers(sub) -> None:
    validate = sub.add_parser("validate", help="validation against closed forms and reference models")
    validate.add_argument("--json", action="store_true")
    validate.add_argument("--quick", action="store_true", help="coarser settings (CI)")
    validate.add_argument("--out", default="results/validation", help="output folder (default: %(default)s)")
    validate.set_defaults(func=cmd_validate)
    demo = sub.add_parser("demo", help="run the main job on the built-in default scene",
                          description="The crankshaft-counterweight pipeline end to end on examples/counterweight.toml "
                                      "at a demo resolution: multibody run, contact model, COF and wear phases, "
                                      "amplitude limit, speed sweep to safety margins.")
    demo.add_argument("--out", default="results/demo", help="output folder (default: %(default)s)")
    demo.add_argument("--json", action="store_true")
    demo.add_argument("--quiet", action="store_true", help="no progress bars")
    demo.add_argument("--workers", type=int, default=None, help="worker processes for the limit and sweep cases")
    _add_cache_arguments(demo)
    demo.set_defaults(func=cmd_demo)


def _add_limit_parser(sub) -> None:
    limit = sub.add_parser("limit", help="lowest wing amplitude that does not end stuck (scan, then refine)",
                           description="Run the coupled scene's COF and wear phases on a grid of wing amplitudes "
                                       "over the range, then refine every change of verdict to the tolerance.")
    limit.add_argument("scene")
    limit.add_argument("--amplitude", required=True, metavar="LOW:HIGH", help="wing amplitude range, µm (e.g. 100:400)")
    _add_scan_arguments(limit, "results/limit")
    limit.set_defaults(func=cmd_limit)


def _add_scan_arguments(parser, out: str) -> None:
    """The limit scan's tolerance and grid, output, progress, cache and cluster options."""
    parser.add_argument("--tolerance", type=float, default=10.0, help="width of each refined change of verdict, "
                                                                      "µm (default 10)")
    parser.add_argument("--grid", type=int, default=7,
                        help="amplitudes of the first scan (default 7); their spacing is the scan's resolution")
    parser.add_argument("--out", default=out, help="output folder (default: %(default)s)")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--quiet", action="store_true")
    _add_cache_arguments(parser)
    from pipelines.parallel import add_cluster_arguments
    add_cluster_arguments(parser)


def _add_reduce_parser(sub) -> None:
    reduce = sub.add_parser("reduce", help="accuracy of a Craig-Bampton reduction of a mesh")
    reduce.add_argument("mesh", help="mesh file (Abaqus .inp, Gmsh .msh, ...) with named node sets")
    reduce.add_argument("--modes", type=int, required=True, help="fixed-interface modes")
    reduce.add_argument("--youngs-modulus", type=float, default=206000.0, help="MPa")
    reduce.add_argument("--poisson-ratio", type=float, default=0.3)
    reduce.add_argument("--density", type=float, default=7.85e-9, help="t/mm³")
    reduce.add_argument("--interface-sets", nargs="*", help="node sets coupled as interfaces (default: all)")
    reduce.add_argument("--clamp-sets", nargs="*", help="node sets held fixed")
    reduce.add_argument("--out", default="results/reduce", help="output folder (default: %(default)s)")
    reduce.add_argument("--json", action="store_true")
    reduce.set_defaults(func=cmd_reduce)


def _add_study_parsers(sub) -> None:
    study = sub.add_parser("study", help="studies that compare several runs of a scene")
    kinds = study.add_subparsers(dest="study", required=True)
    constant = kinds.add_parser("constant-cof", help="variable vs constant COF (paper Fig. 8): max shear maps",
                                description="Run the scene's COF phase with the evolving COF and with a constant "
                                            "μ = μ_max; plot the last cycle's max shear traction of both over the "
                                            "contact and print it at the probes.")
    constant.add_argument("scene")
    constant.add_argument("--probe", action="append", default=[],
                          help="probe point 'x,y[,z]' in mm (repeat; paper's P1, P2)")
    constant.add_argument("--out", default="results/constant_cof",
                          help="folder of the plot constant_cof.png and the data constant_cof.h5 (default %(default)s)")
    constant.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                          help="override a scene value for both models (repeatable), e.g. procedure.cof_cycles=20")
    constant.add_argument("--json", action="store_true")
    constant.set_defaults(func=cmd_study)
    from pipelines.cli.accuracy import add_accuracy_parser
    add_accuracy_parser(kinds)
    convergence = kinds.add_parser("convergence", help="verdict and figures at several contact element sizes",
                                   description="Run the scene at every --sizes contact element size (mm) and, "
                                               "with --amplitude, search its amplitude limit at each.")
    convergence.add_argument("scene")
    convergence.add_argument("--sizes", required=True, metavar="S1,S2,...", help="element sizes, mm (e.g. 10,5,2.5)")
    convergence.add_argument("--amplitude", metavar="LOW:HIGH", help="also the amplitude limit on this range, µm")
    convergence.add_argument("--stop-at-loosening", action="store_true",
                             help="end every run once loosening is evident, whatever the scene's "
                                  "procedure.stop_at_loosening says (a verdict check of a scene that runs on to its "
                                  "life horizon; the figures then stand for the shortest run)")
    _add_scan_arguments(convergence, "results/convergence")
    convergence.set_defaults(func=cmd_convergence)


_NEGATIVE = re.compile(r"^-\.?\d")


def _valued_options(parser: argparse.ArgumentParser) -> set[str]:
    """The long options (of every sub-command) that take a value."""
    found = set()
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                found |= _valued_options(sub)
        elif action.nargs != 0:
            found.update(o for o in action.option_strings if o.startswith("--"))
    return found


def attach_negative_values(argv: list[str], options: set[str]) -> list[str]:
    """``--probe -65,0,0`` → ``--probe=-65,0,0``: argparse takes a value that starts with '-' and
    is not a plain number for an option, so negative coordinates and ranges are attached here."""
    out, tokens = [], iter(argv)
    for token in tokens:
        if token in options:
            value = next(tokens, None)
            if value is not None and _NEGATIVE.match(value):
                out.append(f"{token}={value}")
                continue
            out.append(token)
            if value is not None:
                out.append(value)
            continue
        out.append(token)
    return out


#: What each command writes into its --out folder, removed there before it runs again (with the
#: page `fretwork report` writes there by default: it would describe the earlier run).
OUTPUTS = {
    "run": ("results.h5", "results.h5.part", "checkpoint.h5", "checkpoint.h5.tmp", "plots", "interface.xdmf",
            "interface.h5", "interface_final.vtu", "interface_master_final.vtu", "interface_increments.xdmf",
            "interface_increments.h5", "report.html"),
    "limit": ("limit.png", "limit.json", "runs", "report.html"),
    "demo": ("operating", "limit", "sweep.h5", "margins.png", "summary.json", "report.html"),
    "sweep": ("sweep.h5", "sweep.h5.part", "sweep_wing_amplitude.png", "campbell.png", "margins.png", "limit_runs",
              "report.html"),
    "mbs": ("run.h5", "wing_time_history.png", "wing_spectrum.png", "wing_order_spectrum.png", "campbell.png",
            "report.html"),
    "study convergence": ("size_*mm", "convergence.png", "convergence.json", "report.html"),
    "study constant-cof": ("constant_cof.png", "constant_cof.h5", "report.html"),
    "study accuracy": ("accuracy_*.png", "accuracy_*.json", "report.html"),
    "validate": ("wear_gap_vs_geometry.png", "finite_sliding_scars.png"),
    "reduce": ("reduction_error_vs_modes.png",),
}
#: Commands whose one output is written anew under its name: it is not removed before they run,
#: so that an input refused only once the command runs (a mode count above what the mesh's
#: interior has, known after reading the mesh) loses nothing.
WRITTEN_ANEW = ("reduce",)


def _command(args) -> str:
    return f"study {args.study}" if args.command == "study" else args.command


def _warn(message: str) -> None:
    print(f"fretwork: warning: {message}", file=sys.stderr)


def _check_input(args) -> None:
    """The command's scene and range options, checked before its output folder is touched;
    the scene's plausibility warnings (likely unit mistakes) are said here, once."""
    from pipelines import scene as scenes
    from pipelines.scene.checks import plausibility

    # `sweep` ignores --amplitude and --tolerance without --margins (cmd_sweep says so)
    if isinstance(getattr(args, "amplitude", None), str) and getattr(args, "margins", True):
        from pipelines.jobs.limit import check_search, parse_range_um
        _check_finite_search(args)
        low, high = parse_range_um(args.amplitude)
        if isinstance(getattr(args, "tolerance", None), (int, float)):
            check_search(low, high, 1e-3 * args.tolerance, getattr(args, "grid", 7))
    if isinstance(getattr(args, "speeds", None), str):
        from pipelines.jobs.sweep import parse_speeds
        parse_speeds(args.speeds)
    for probe in getattr(args, "probe", None) or ():  # `study constant-cof`
        _point(probe)
    if getattr(args, "plots", None) is not None:  # `sweep --plots`: its plots are written there after the work
        from pipelines.output.locks import check_folder
        check_folder(args.plots, "--plots")
    sizes = _sizes(args.sizes) if isinstance(getattr(args, "sizes", None), str) else None
    if hasattr(args, "cache") and getattr(args, "margins", True):  # `sweep` uses it with --margins only
        _cache(args)
    path = getattr(args, "scene", None)
    speeds = ()
    if args.command == "demo":  # the shipped scene, at the demo's speeds
        from pipelines.jobs.demo import DEFAULT_SCENE, DEMO_SPEEDS_RPM
        path, speeds = DEFAULT_SCENE, DEMO_SPEEDS_RPM
    if path is None:
        return
    # a multibody time step that cannot follow a speed's excitation is refused before any work
    if args.command in ("mbs", "sweep"):
        from pipelines.cli.mbs import model_params
        from pipelines.jobs.sweep import check_resolution, parse_speeds

        params = model_params(path)  # the whole scene is valid and has an [mbs] table
        speeds = list(parse_speeds(args.speeds)) if args.command == "sweep" else []
        if args.command == "mbs" or args.margins:  # `sweep --margins` searches the limit at the scene's speed
            speeds.append(params.speed_rpm)
        check_resolution(params, speeds)  # its warnings: said as the command runs
        data = scenes.tables(path)
    else:
        from pipelines.cli.mbs import coupled_resolution

        scene = scenes.load(path)
        for message in coupled_resolution(scene, speeds):
            _warn(message)
        data = scene.data
    if sizes is not None:
        from pipelines.studies.convergence import check_levels
        check_levels(path, sizes)  # every size suits the scene's mesh generators
    for message in plausibility(data):
        _warn(message)


def _check_finite_search(args) -> None:
    """--amplitude LOW:HIGH and --tolerance as finite numbers: a number is read by float(), which
    takes 'inf' and 'nan', and NaN passes every comparison of the range and tolerance checks (a
    search would run at 'nan µm')."""
    problems = []
    try:
        infinite = not all(np.isfinite([float(v) for v in args.amplitude.split(":")]))
    except ValueError:  # not numbers: parse_range_um says what the form is
        infinite = False
    if infinite:
        problems.append(f"--amplitude {args.amplitude!r}: LOW and HIGH must be finite numbers of µm, e.g. 100:400")
    tolerance = getattr(args, "tolerance", None)
    if isinstance(tolerance, (int, float)) and not np.isfinite(tolerance):
        problems.append(f"--tolerance {tolerance:g}: give the limit's tolerance as a finite width in µm, e.g. 10")
    if problems:
        raise InputError("; ".join(problems))


def _check_signals(args) -> None:
    """`export-fmu --signals`: at least one name (an empty word, or commas alone, name none)."""
    if args.signals is not None and not any(name.strip() for item in args.signals for name in item.split(",")):
        raise InputError(f"--signals {' '.join(args.signals)!r} names no signal: give the names of signals under "
                         "/histories of the results file (space or comma separated), or leave --signals out to "
                         "export them all")


def _output(args):
    """The claim on the command's output folder (nullcontext for a command that writes none)."""
    from pipelines.output.locks import PARTIAL, check_folder, claim

    if args.command == "export-fmu":
        _check_signals(args)
        check_folder(Path(args.output).parent, "-o")
        return nullcontext()
    if args.command == "report":  # --out is the HTML file (default: in the results folder)
        if args.out is not None:
            check_folder(Path(args.out).parent, "--out")
        elif Path(args.results_dir).is_dir():  # else write_report says what RESULTS_DIR should be
            check_folder(args.results_dir, "the results folder")
        return nullcontext()
    out = getattr(args, "out", None)
    if out is None:
        _check_input(args)
        return nullcontext()
    outputs = OUTPUTS.get(_command(args), ())
    clear = not getattr(args, "resume", False) and args.command not in WRITTEN_ANEW
    if args.command in ("sweep", "mbs"):
        from pipelines.cli.mbs import RUN_FILE
        from pipelines.jobs.sweep import SWEEP_FILE, output_paths

        name = SWEEP_FILE if args.command == "sweep" else RUN_FILE
        folder, path = output_paths(out, name)
        if folder != Path(out):
            print(f"fretwork: note: --out {out} names a file: written, with the plots beside it "
                  f"(--out is a folder for every command: --out {folder} writes {folder / name})",
                  file=sys.stderr)
            outputs = ()  # the folder holds more than this command's outputs: nothing else is removed
        out = folder
    # only `run` resumes: elsewhere a checkpoint of an interrupted run is a half-written output
    partial = PARTIAL if args.command == "run" else (*PARTIAL, "**/checkpoint.h5")
    return claim(out, outputs=outputs, clear=clear, ready=lambda: _check_input(args), partial=partial)


def _unexpected(error: BaseException) -> str:
    if isinstance(error, UnicodeDecodeError):
        return f"a file is not UTF-8 text ({error.reason} at byte {error.start})"
    if isinstance(error, OSError):
        where = f"{error.filename}: " if error.filename else ""
        return f"{where}{error.strerror or error}"
    return f"internal error ({type(error).__name__}: {error}); set FRETWORK_TRACEBACK=1 to see where"


def _stopped_hint(args, error) -> str:
    from pipelines.jobs.run import EARLY_ENDINGS

    ending = getattr(error, "ending", None)
    if ending in EARLY_ENDINGS:
        return f"; the results file holds the cycles run so far, marked '{ending.value}'"
    out = getattr(args, "out", None)
    if not out:
        return ""
    resumable = args.command == "run" and (Path(out) / "checkpoint.h5").is_file()
    return (f"; partial results stay in {out}: after changing the scene, run again"
            + (" (or --resume from its last checkpoint)" if resumable else ""))


def _interrupt(signum, frame):
    """Ctrl-C: interrupt the command once. Its clean-up (closing a cluster, removing half-written
    files) then runs to the end: a second Ctrl-C, or a library that raises the first one again
    once it has caught it, must not break it off with a traceback."""
    signal.signal(signal.SIGINT, lambda *_: None)
    interrupts.request()  # raised again at the next increment if this one is swallowed
    raise KeyboardInterrupt


def _unraisable(unraisable) -> None:
    """A Ctrl-C raised while Python ran a weak-reference callback or a destructor cannot
    propagate ("Exception ignored"): say nothing, :mod:`pipelines.interrupts` raises it again at
    the next increment. Anything else is reported as Python would."""
    if isinstance(unraisable.exc_value, KeyboardInterrupt):
        return
    sys.__unraisablehook__(unraisable)


def main(argv=None) -> int:
    """Run the ``fretwork`` command ``argv`` (default: the process's arguments); its exit status."""
    ours = threading.current_thread() is threading.main_thread() and \
        signal.getsignal(signal.SIGINT) is signal.default_int_handler
    if ours:
        signal.signal(signal.SIGINT, _interrupt)
        sys.unraisablehook = _unraisable
        # A Ctrl-C while dask's nannies stop their worker processes can end this process before
        # they release their multiprocessing semaphores; multiprocessing's resource tracker then
        # frees them and says so at exit ("resource_tracker: There appear to be 1 leaked
        # semaphore objects to clean up at shutdown"). Nothing is left behind, so the tracker,
        # which starts later with this process's warning options, is told to stay quiet.
        if "ignore:resource_tracker:UserWarning" not in sys.warnoptions:
            sys.warnoptions.append("ignore:resource_tracker:UserWarning")
    resumable = []
    try:
        return _main(argv, resumable)
    except KeyboardInterrupt:
        interrupts.clear()
        print("fretwork: interrupted" + "".join(f"; continue with --resume (from {path})" for path in resumable
                                                 if path.is_file()), file=sys.stderr)
        _forget_interrupt()
        return 130
    finally:
        if ours:
            signal.signal(signal.SIGINT, signal.default_int_handler)
            sys.unraisablehook = sys.__unraisablehook__


def _forget_interrupt() -> None:
    """Let the process end with status 130 after a handled Ctrl-C.

    A KeyboardInterrupt that went through code a C extension ran with PyRun_String (exudyn does)
    sets CPython's "unhandled KeyboardInterrupt" flag even when the interrupt is then caught, and
    the interpreter ends by killing itself with SIGINT instead of returning the status. Running
    an empty string the same way clears that flag."""
    import ctypes

    ctypes.pythonapi.PyRun_SimpleStringFlags(b"", None)


@contextmanager
def _scene_warnings_said():
    """A :class:`pipelines.scene.checks.SceneWarning` raised while a command runs (a scene that
    builds but most likely does not model what was meant) is said at once, before the run it
    precedes, as ``fretwork: warning: ...``; other warnings are shown as Python shows them."""
    from pipelines.scene.checks import SceneWarning

    with warnings.catch_warnings():  # restores showwarning on the way out
        shown = warnings.showwarning

        def show(message, category, filename, lineno, file=None, line=None):
            if issubclass(category, SceneWarning):
                _warn(str(message))
            else:
                shown(message, category, filename, lineno, file, line)
        warnings.showwarning = show
        yield


def _main(argv, resumable: list) -> int:
    """The command; ``resumable`` receives the checkpoint an interrupted run continues from."""
    parser = build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    args = parser.parse_args(attach_negative_values(argv, _valued_options(parser)))
    if args.command == "run":
        resumable.append(Path(args.out) / "checkpoint.h5")
    handler = getattr(args, "func", None) or args.handler
    from contact.solver import ConvergenceError
    from reduction.threads import pin_process

    pin_process()  # the same scene gives the same bits whatever the thread settings
    # Progress bars are drawn by this process alone: a thread lock, not tqdm's default
    # multiprocessing lock, whose semaphore a Ctrl-C could leave behind (a "leaked semaphore" warning).
    from tqdm import tqdm
    tqdm.set_lock(threading.RLock())

    try:
        with _output(args), _scene_warnings_said():
            return handler(args)
    except InputError as error:
        print(f"fretwork: error: {error}", file=sys.stderr)
        return 2
    except ConvergenceError as error:
        print(f"fretwork: error: the simulation stopped: {error}{_stopped_hint(args, error)}", file=sys.stderr)
        if getattr(args, "json", False) and args.command == "run":
            # a script reading --json gets how the run ended, not an empty output
            ending = getattr(error, "ending", None)
            print(json_text({"verdict": None, "ending": ending.value if ending is not None else "diverged",
                         "error": str(error), "out": str(args.out)}))
        return 1
    except (OSError, UnicodeDecodeError) as error:  # a file that cannot be read or written
        print(f"fretwork: error: {_unexpected(error)}", file=sys.stderr)
        return 2
    except Exception as error:
        if os.environ.get("FRETWORK_TRACEBACK"):
            raise
        if type(error).__name__ == "SimulationError" and type(error).__module__ == "mbs.model":
            # the multibody integration failed (a scene's coupled stage): not an internal error
            print(f"fretwork: error: the multibody run stopped: {error} (a value a warning above named, or "
                  "too coarse a [mbs.solver] time_step, is the usual cause)", file=sys.stderr)
            return 1
        print(f"fretwork: error: {_unexpected(error)}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
