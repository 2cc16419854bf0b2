"""The main job, end to end on the shipped default counterweight scene (``make demo``).

1. multibody: reduce the CW (Craig–Bampton) and simulate the crank throw at the scene's speed;
2. contact model: mesh, assemble and condense the CW–web joint with its inertia patterns;
3. COF and wear phases of the scene at its wing amplitude (normal operation): the verdict;
4. amplitude limit: the lowest wing amplitude that does not end stuck (coarse tolerance);
5. speed sweep of the multibody model and the fretting safety margin at every speed: the largest
   amplitude shown to stick (the lower end of the limit's bracket) / the wing amplitude there.

The demo runs a shorter procedure than the shipped scene (``DEMO_OVERRIDES``: 60 COF cycles,
30 wear cycles; the vibration's run-up kept the same share of the COF phase) so that it
finishes in a few minutes on a 2-core machine; stages whose inputs are unchanged are read from
the stage cache on a second run.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pipelines import examples
from pipelines.output.jsonfile import json_text
from reduction.threads import one_blas_thread

DEFAULT_SCENE = examples.scene_path("counterweight")
DEMO_OVERRIDES = {
    "procedure.cof_cycles": 60,
    "procedure.wear_cycles": 30,
}
DEMO_SPEEDS_RPM = np.arange(600.0, 901.0, 50.0)
DEMO_AMPLITUDE_RANGE_MM = (0.1, 0.4)
DEMO_TOLERANCE_MM = 0.025


@dataclass
class DemoResult:
    summary: dict
    stage_times: dict = field(default_factory=dict)
    files: dict = field(default_factory=dict)


def _overrides(scene_path, overrides) -> dict:
    """The demo's scene overrides; a shortened COF phase keeps the scene's run-up share of it."""
    from pipelines import scene as scenes
    from pipelines.studies.knobs import run_up_within

    out = dict(DEMO_OVERRIDES if overrides is None else overrides)
    if "procedure.cof_cycles" in out and "procedure.vibration_run_up" not in out:
        out.update(run_up_within(scenes.load(scene_path), out["procedure.cof_cycles"]))
    return out


@one_blas_thread
def run_demo(out_dir, *, scene_path=DEFAULT_SCENE, overrides=None, speeds_rpm=DEMO_SPEEDS_RPM,
             amplitude_range_mm=DEMO_AMPLITUDE_RANGE_MM, tolerance_mm=DEMO_TOLERANCE_MM, cache_dir=None,
             workers=None, progress=True) -> DemoResult:
    """Run the five stages (module doc) into ``out_dir``; returns the summary and stage times (s)."""
    from pipelines.jobs.sweep import speed_sweep
    from pipelines import scene as scenes
    from pipelines.coupling import multibody_params
    from pipelines.jobs.limit import find_limit, plot_limit, write_limit
    from pipelines.jobs.margins import margins_of, plot_margins, write_margins
    from pipelines.jobs.run import run_scene
    from pipelines.stages import StageCache

    out_dir = Path(out_dir)
    overrides = _overrides(scene_path, overrides)
    scene = scenes.load(scene_path, overrides)
    cache = StageCache(cache_dir)
    outcome = run_scene(scene, out_dir / "operating", progress=progress, cache=cache)
    names = {"multibody_s": "multibody_s", "build_and_condense_s": "contact_model_s",
             "contact_space_s": "contact_space_s", "cof_phase_s": "cof_phase_s", "wear_phase_s": "wear_phase_s",
             "outputs_s": "contact_outputs_s"}
    times = {ours: outcome.stage_times[theirs] for theirs, ours in names.items() if theirs in outcome.stage_times}

    clock = time.perf_counter()
    limit = find_limit(scene_path, *amplitude_range_mm, tolerance_mm=tolerance_mm,
                       overrides=dict(overrides, **{"mbs.speed_rpm": float(max(speeds_rpm))}),
                       cache_dir=cache_dir, out_dir=out_dir / "limit", workers=workers, progress=progress)
    times["amplitude_limit_s"] = time.perf_counter() - clock
    limit_plot = plot_limit(limit, out_dir / "limit" / "limit.png", scene.name)
    write_limit(limit, out_dir / "limit" / "limit.json")

    clock = time.perf_counter()
    sweep_path = out_dir / "sweep.h5"
    sweep = speed_sweep(multibody_params(scene), speeds_rpm, path=sweep_path, progress=progress, workers=workers)
    margins = margins_of(scene, sweep, limit, cache)
    write_margins(sweep_path, margins)
    margin_plot = plot_margins(margins, out_dir / "margins.png", f"{scene.name}: fretting safety margin")
    times["speed_sweep_s"] = time.perf_counter() - clock

    summary = _summary(scene.name, outcome.summary, limit, margins, times)
    files = {"results": str(outcome.results_path), "plots": str(out_dir / "operating" / "plots"),
             "limit_plot": str(limit_plot), "margins_plot": str(margin_plot), "sweep": str(sweep_path)}
    (out_dir / "summary.json").write_text(json_text({"summary": summary, "stage_times_s": times, "files": files}))
    from pipelines.output.report import write_report

    files["report"] = str(write_report(out_dir))
    return DemoResult(summary, times, files)


def _summary(name: str, s: dict, limit, margins, times: dict) -> dict:
    """The demo's summary: the operating run (``s``, its run summary), the amplitude limit,
    the margins over the speed sweep and the total wall time (s). The margins, the operating
    point's too, divide the largest amplitude shown to stick (``margin_amplitude_um``; a bound
    when the search's range stuck throughout or nowhere: ``margin_bound``)."""
    from pipelines.jobs.margins import describe_margins, margin_basis

    point = _operating_point(s, limit, margins)
    return {
        "scene": name,
        "engine_speed_rpm": s["engine_speed_rpm"],
        "wing_amplitude_um": 1e3 * s["wing_amplitude_mm"],
        "verdict": s["verdict"],
        "cof_evolved_area_fraction": s["cof_evolved_area_fraction"],
        "bolt_force_initial_N": s.get("bolt_force_initial_N"),
        "bolt_force_final_N": s.get("bolt_force_final_N"),
        "clamp_force_loss_fraction": s.get("clamp_force_loss_fraction"),
        # what the margins divide first: the amplitude limit is the lowest amplitude found not stuck
        "margin_amplitude_um": 1e3 * limit.margin_limit_mm,
        "margin_basis": margin_basis(margins),
        "amplitude_limit_um": None if limit.limit_mm is None else 1e3 * limit.limit_mm,
        "margin_at_operating_point": float(point.margin[0]),
        "operating_point": point.shown_state(0),
        **{k: v for k, v in margins.to_json().items()
           if k in ("bracket_um", "margin_bound", "smallest_margin", "smallest_margin_speed_rpm",
                    "unsafe_speeds", "at_limit_speeds", "warnings", "counterweight", "crossings_between_speeds_rpm",
                    "larger_swings")},
        **({"multibody_warning": s["multibody_warning"]} if s.get("multibody_warning") else {}),
        "margins": describe_margins(margins),
        "wall_time_s": sum(times.values()),
    }


def _operating_point(s: dict, limit, margins):
    """The operating run as a one-speed :class:`MarginResult`, judged by the margins' own rules."""
    from pipelines.jobs.margins import MarginResult

    amplitude = np.array([s["wing_amplitude_mm"]], dtype=float)
    with np.errstate(divide="ignore"):
        margin = limit.margin_limit_mm / amplitude
    return MarginResult(np.array([s["engine_speed_rpm"]], dtype=float), amplitude, margins.calibration, limit,
                        margin, margins.limit_speed_rpm)


def describe(result: DemoResult) -> str:
    """A short human-readable account of the demo."""
    s, t = result.summary, result.stage_times
    lines = [f"fretwork demo: {s['scene']} at {s['engine_speed_rpm']:.0f} rpm, wing amplitude {s['wing_amplitude_um']:.0f} µm",
             f"  verdict: {s['verdict'].upper()} (COF evolved over {s['cof_evolved_area_fraction']:.0%} of the contact)"]
    if s["bolt_force_initial_N"] is not None:
        lines.append(f"  clamp force {s['bolt_force_initial_N'] / 1e3:.0f} kN -> {s['bolt_force_final_N'] / 1e3:.0f} kN "
                     f"({100 * s['clamp_force_loss_fraction']:.2f} % loss)")
    state = s["operating_point"]
    smallest = ("" if s["smallest_margin"] is None else
                f", smallest {s['smallest_margin']:.2f} at {s['smallest_margin_speed_rpm']:.0f} rpm")
    lines.append(f"  {s['margin_basis']}{': ' if s['margin_bound'] == 'stuck' else '; '}"
                 f"margin {s['margin_at_operating_point']:.2f} at the operating point "
                 f"({state if state == 'safe' else state.upper()}){smallest}")
    lines.append(f"  margins: {s['margins']}")
    if s.get("multibody_warning"):
        lines.append(f"  WARNING (operating run): {s['multibody_warning']}")
    lines.append("  time: " + ", ".join(f"{k.removesuffix('_s').replace('_', ' ')} {v:.1f} s" for k, v in t.items())
                 + f" (total {s['wall_time_s']:.0f} s)")
    for name, path in result.files.items():
        lines.append(f"  {name}: {path}")
    return "\n".join(lines)
