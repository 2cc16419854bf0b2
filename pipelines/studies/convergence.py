"""Mesh convergence of a scene: its verdict and figures at several contact element sizes.

Each level runs the whole scene with every body mesh's ``contact_size`` set to one size (mm):
verdict, stick / sliding / worn areas, maximum wear depth, clamp-force loss, minimum stick
margin, the real cycles after which loosening was evident (a loosening joint's design figure)
and, when asked, the wing-amplitude limit. With ``stop_at_loosening`` every level ends once its
loosening is evident, whatever the scene says: a verdict check of a scene that runs on to its
life horizon (the extreme counterweight) then costs the run-up to the verdict, not the
horizon. Where three or more levels halve the size and a figure converges monotonically,
Richardson extrapolation estimates its limit h → 0 and the observed order. A scene is converged at a size when its verdict equals that of the next
finer level and its limit is within ``limit_tolerance`` of the finest level's.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import h5py
import numpy as np

from reduction.errors import InputError
from reduction.threads import one_blas_thread

FIGURES = ("stick_area_fraction", "active_slip_area_fraction", "cof_evolved_area_fraction",
           "worn_area_fraction", "max_wear_depth_mm", "clamp_force_loss_fraction", "min_stick_margin",
           "equivalent_cycles", "loosening_evident_at_cycles")


@dataclass
class Level:
    """One element size (mm) and what the scene gave there; limit_mm None when not searched."""

    size_mm: float
    verdict: str
    figures: dict
    limit_mm: float | None = None
    monotone: bool | None = None
    points: int | None = None
    wall_time_s: float | None = None
    extra: dict = field(default_factory=dict)


def size_overrides(data: dict, size_mm: float) -> dict:
    """Dotted overrides that set every body mesh's ``contact_size`` (mm) to ``size_mm``."""
    overrides = {f"bodies.{name}.mesh.contact_size": float(size_mm)
                 for name, body in data.get("bodies", {}).items()
                 if isinstance(body.get("mesh"), dict) and "contact_size" in body["mesh"]}
    if not overrides:
        raise InputError("no body mesh of the scene has a contact_size to refine: a mesh read from a file is "
                         "fixed, so a convergence study needs generated meshes (bodies.NAME.mesh.generator with "
                         "contact_size), or run the scene once per mesh file you made at each size")
    return overrides


def richardson(sizes, values) -> dict | None:
    """Richardson estimate of the h → 0 value from the three finest levels.

    sizes: element sizes (mm), any order; values: the figure at each. Needs a constant
    refinement ratio r > 1 and monotone convergence (differences of one sign, shrinking).
    Returns {"estimate", "order", "error_finest"} or None where the sequence does not allow it;
    two finest levels that agree exactly give their value with no order (None: it is undefined).
    """
    pairs = sorted((s, v) for s, v in zip(sizes, values) if v is not None and math.isfinite(v))
    if len(pairs) < 3:
        return None
    (h1, f1), (h2, f2), (h3, f3) = pairs[:3]  # finest first
    ratio = h2 / h1
    if not (ratio > 1.0 and math.isclose(h3 / h2, ratio, rel_tol=1e-6)):
        return None
    near, far = f2 - f1, f3 - f2
    if near == 0.0:
        return {"estimate": f1, "order": None, "error_finest": 0.0}
    if far == 0.0 or near * far < 0.0 or abs(near) >= abs(far):
        return None  # oscillating or not yet converging: no estimate
    order = math.log(abs(far) / abs(near)) / math.log(ratio)
    estimate = f1 - near / (ratio ** order - 1.0)
    return {"estimate": estimate, "order": order, "error_finest": f1 - estimate}


def converged_size(levels: list[Level], limit_tolerance: float = 0.05) -> float | None:
    """The coarsest size whose verdict equals every finer level's and whose limit is within
    ``limit_tolerance`` (relative) of the finest level's; None if no level qualifies (the finest
    level has no finer one to agree with). A size that agrees with the next finer level but not
    with the finest is not converged: stick at 4 and 2 mm and loosening at 1 mm converge nowhere."""
    ordered = sorted(levels, key=lambda level: level.size_mm, reverse=True)  # coarse first
    finest = ordered[-1]
    for index, level in enumerate(ordered[:-1]):
        if any(finer.verdict != level.verdict for finer in ordered[index + 1:]):
            continue
        if finest.limit_mm is not None or level.limit_mm is not None:
            if level.limit_mm is None or finest.limit_mm is None:
                continue
            if abs(level.limit_mm - finest.limit_mm) > limit_tolerance * finest.limit_mm:
                continue
        return level.size_mm
    return None


def extrapolations(levels: list[Level]) -> dict:
    """Richardson estimates of every figure (and the limit) that the levels allow."""
    sizes = [level.size_mm for level in levels]
    out = {}
    for name in FIGURES:
        found = richardson(sizes, [level.figures.get(name) for level in levels])
        if found is not None:
            out[name] = found
    found = richardson(sizes, [level.limit_mm for level in levels])
    if found is not None:
        out["limit_mm"] = found
    return out


def check_levels(scene_path, sizes_mm) -> None:
    """Every level's scene and generated meshes, before any level runs: a size that the scene's
    mesh generators refuse (a beam's hole block must be a whole number of elements) is said at
    once, naming the size, not after the other levels have run for hours. Generating the meshes
    is cheap (the counterweight's two bodies at 2.5 mm: 0.35 s)."""
    from pipelines import scene as scenes
    from pipelines.build import make_mesh

    base = scenes.load(scene_path)
    for size in sizes_mm:
        scene = scenes.load(scene_path, size_overrides(base.data, size))
        for name, body in scene.data["bodies"].items():
            spec = body.get("mesh", {})
            if "generator" not in spec:
                continue
            try:
                make_mesh(spec, f"bodies.{name}.mesh", None)
            except InputError as error:
                raise InputError(f"--sizes: {size:g} mm does not suit body {name!r}: {error}") from None


def run_level(scene_path: str, size_mm: float, out_dir: str, cache_dir: str | None,
              limit_range_mm: tuple | None = None, tolerance_mm: float = 0.01, grid: int = 7,
              stop_at_loosening: bool = False) -> Level:
    """One level of the study: the scene at ``size_mm``, and its amplitude limit when asked;
    ``stop_at_loosening``: the level's runs end once loosening is evident."""
    import time

    from pipelines import scene as scenes
    from pipelines.jobs.run import run_scene
    from pipelines.stages import StageCache

    base = scenes.load(scene_path)
    overrides = size_overrides(base.data, size_mm)
    if stop_at_loosening:
        overrides["procedure.stop_at_loosening"] = True
    clock = time.perf_counter()
    outcome = run_scene(scenes.load(scene_path, overrides), Path(out_dir) / f"size_{size_mm:g}mm",
                        progress=False, plots=False, cache=StageCache(cache_dir))
    summary = outcome.summary
    with h5py.File(outcome.results_path, "r") as results:
        points = int(results["points/area"].shape[0])
    level = Level(size_mm, summary["verdict"], {k: summary.get(k) for k in FIGURES}, points=points,
                  wall_time_s=time.perf_counter() - clock, extra={"results": str(outcome.results_path)})
    if limit_range_mm is not None:
        from pipelines.jobs.limit import find_limit

        limit = find_limit(scene_path, *limit_range_mm, tolerance_mm=tolerance_mm, grid=grid, overrides=overrides,
                           cache_dir=cache_dir, workers=0, progress=False)
        level.limit_mm, level.monotone = limit.limit_mm, limit.monotone
        level.extra["limit_bracket_mm"] = list(limit.bracket_mm)
        level.extra["limit_runs"] = limit.to_json()["runs"]
    return level


@one_blas_thread
def convergence_study(scene_path, sizes_mm, out_dir, *, cache_dir=None, limit_range_mm=None,
                      tolerance_mm: float = 0.01, grid: int = 7, scheduler=None, workers=None,
                      progress: bool = True, stop_at_loosening: bool = False) -> dict:
    """The scene at every size (levels run side by side as cases), with Richardson estimates
    and the converged size; a dict ready for JSON. stop_at_loosening: every run ends once its
    loosening is evident (see :func:`run_level`)."""
    from pipelines.parallel import map_cases

    sizes = sorted({float(s) for s in sizes_mm}, reverse=True)
    check_levels(scene_path, sizes)
    cases = [(size, {"scene_path": str(scene_path), "size_mm": size, "out_dir": str(out_dir),
                     "cache_dir": None if cache_dir is None else str(cache_dir),
                     "limit_range_mm": limit_range_mm, "tolerance_mm": tolerance_mm, "grid": grid,
                     "stop_at_loosening": stop_at_loosening})
             for size in sizes]
    outcomes = map_cases(run_level, cases, scheduler=scheduler, workers=workers, label="convergence",
                         progress=progress)
    failed = [f"{o.key:g} mm: {o.error}" for o in outcomes if o.error is not None]
    if failed:
        raise InputError("the convergence study could not run every level: " + "; ".join(failed))
    levels = [o.value for o in outcomes]
    horizon = common_horizon(levels)
    return {"scene": str(scene_path), "levels": [asdict(level) for level in levels],
            "extrapolated": extrapolations(levels), "converged_size_mm": converged_size(levels),
            "verdicts_agree": len({level.verdict for level in levels}) == 1, "common_cycles": horizon,
            "stop_at_loosening": stop_at_loosening}


def figures_at_cycles(results_path, cycles: float) -> dict:
    """The figures (:data:`FIGURES`) of a run's last cycle at or before ``cycles`` real cycles,
    from its results.h5; a run that shook down earlier keeps its last figures (a stuck joint
    stays as it is). The clamp-force loss is relative to the clamp force the run's own loss
    refers to; loosening counts as evident there if the run found it so by then (None if not)."""
    with h5py.File(results_path, "r") as results:
        final = json.loads(results["summary"].attrs["figures"])
        table = results["cycles"]
        real = table["equivalent_cycles"][()]
        row = max(int(np.searchsorted(real, cycles * (1.0 + 1e-12), side="right")) - 1, 0)
        stored = {name: table["figures"][name][()] for name in table["figures"]}
    out = {name: float(stored[name][row]) if name in stored else final.get(name) for name in FIGURES}
    out["equivalent_cycles"] = float(real[row])
    evident = final.get("loosening_evident_at_cycles")
    out["loosening_evident_at_cycles"] = evident if evident is not None and evident <= real[row] else None
    loss = final.get("clamp_force_loss_fraction")
    clamp = stored.get("clamp_force_N")
    if loss is not None and clamp is not None and loss < 1.0:
        initial = float(clamp[-1]) / (1.0 - loss)
        out["clamp_force_loss_fraction"] = 1.0 - float(clamp[row]) / initial
    if "min_stick_margin" in stored and not np.isfinite(stored["min_stick_margin"][row]):
        out["min_stick_margin"] = None
    return out


def common_horizon(levels: list[Level]) -> float | None:
    """Compare the levels at equal engine running time: the fewest real cycles any level's
    run reached without shaking down (a wear budget of blocks ends at fewer real cycles on a
    finer mesh, whose adaptive jump is smaller). Adds each level's figures there to
    ``extra["at_common_cycles"]``; None (nothing added) when the runs already end together or
    shook down."""
    ends = {}
    for level in levels:
        path = level.extra.get("results")
        if path is None:
            return None
        with h5py.File(path, "r") as results:
            ending = str(results.attrs.get("ending", "completed"))
        if ending != "shakedown":
            ends[level.size_mm] = level.figures.get("equivalent_cycles") or 0.0
    if len(ends) < 2 or max(ends.values()) <= min(ends.values()) * (1.0 + 1e-6):
        return None
    horizon = min(ends.values())
    for level in levels:
        level.extra["at_common_cycles"] = figures_at_cycles(level.extra["results"], horizon)
    return horizon


def plot_convergence(study: dict, path: Path) -> Path:
    """Figures against element size (log axis, finest right), verdicts written at each level."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    levels = sorted(study["levels"], key=lambda level: level["size_mm"])
    sizes = [level["size_mm"] for level in levels]
    shown = [("stick_area_fraction", "stick area", 100), ("active_slip_area_fraction", "still sliding", 100),
             ("worn_area_fraction", "worn area", 100), ("clamp_force_loss_fraction", "clamp-force loss", 100)]
    found = [(level["size_mm"], 1e3 * level["limit_mm"]) for level in levels if level["limit_mm"] is not None]
    figure, axes = plt.subplots(2 if found else 1, 1, figsize=(7, 6 if found else 3.6), sharex=True, squeeze=False)
    areas = axes[0, 0]
    common = study.get("common_cycles")
    for name, label, scale in shown:
        values = [(level["extra"]["at_common_cycles"] if common else level["figures"]).get(name) for level in levels]
        if all(value is None for value in values):
            continue  # a figure no level has (the clamp force of a joint without bolts): no line at 0
        areas.plot(sizes, [np.nan if value is None else scale * value for value in values], marker="o", label=label)
    for level in levels:
        areas.annotate(level["verdict"], (level["size_mm"], 0), textcoords="offset points", xytext=(0, 4),
                       ha="center", fontsize=8)
    clamped = any(line.get_label() == "clamp-force loss" for line in areas.get_lines())
    areas.set_ylabel("% of nominal area" + ("\nor of clamp force" if clamped else ""))
    if common:
        areas.set_title(f"figures at {common:.3g} real cycles, the shortest run that did not shake down "
                        "(verdicts: whole runs)", fontsize=8)
    areas.legend(fontsize=8)
    if found:
        limits = axes[1, 0]
        limits.plot(*zip(*found), marker="s", color="k", label="amplitude limit (lowest not stuck)")
        brackets = [(level["size_mm"], level["extra"].get("limit_bracket_mm", [None])[0]) for level in levels
                    if level["limit_mm"] is not None]
        stuck = [(size, 1e3 * below) for size, below in brackets if below is not None]
        if stuck:
            limits.plot(*zip(*stuck), marker="v", linestyle="none", color="tab:green",
                        label="highest stuck below it")
        estimate = study["extrapolated"].get("limit_mm")
        if estimate:
            limits.axhline(1e3 * estimate["estimate"], color="0.5", linestyle="--", label="Richardson estimate")
        limits.set_ylabel("wing amplitude limit (µm)")
        limits.legend(fontsize=8)
    bottom = axes[-1, 0]
    bottom.set_xlabel("contact element size (mm)")
    bottom.set_xscale("log")
    bottom.set_xticks(sizes, [f"{size:g}" for size in sizes])
    bottom.minorticks_off()
    bottom.invert_xaxis()
    return _save(figure, axes[:, 0], f"mesh convergence: {Path(study['scene']).stem}", path)


def _save(figure, axes, title: str, path: Path) -> Path:
    """Grid the axes, title the figure, write it to ``path`` (PNG) and close it."""
    import matplotlib.pyplot as plt

    for ax in axes:
        ax.grid(True, alpha=0.3)
    figure.suptitle(title, fontsize=10)
    figure.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path


def plot_histories(study: dict, path: Path) -> Path | None:
    """Clamp force and stick area against real cycles, one line per level (each level's
    results.h5), loosening marked where it became evident: how the levels' histories converge,
    not only their end points. None when no level's results file is at hand."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    levels = sorted(study["levels"], key=lambda level: -level["size_mm"])  # coarse first
    histories = []
    for level in levels:
        results = level.get("extra", {}).get("results")
        if results is None or not Path(results).is_file():
            continue
        with h5py.File(results, "r") as file:
            table = file["cycles"]
            real = table["equivalent_cycles"][()]
            shown = real > 0.0  # a log axis of real cycles: the preload stands for none
            real = real[shown]
            clamp = table["figures/clamp_force_N"][()][shown]
            stick = table["figures/stick_area_fraction"][()][shown]
        if real.size == 0:
            continue
        histories.append((level, real, clamp, stick))
    if not histories:
        return None
    bolted = any(np.isfinite(clamp).any() for _, _, clamp, _ in histories)  # else no clamp-force panel
    if bolted:
        figure, (force, area) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    else:
        figure, area = plt.subplots(1, 1, figsize=(7, 3.6))
    for level, real, clamp, stick in histories:
        label = f"{level['size_mm']:g} mm ({level['points']:,} points): {level['verdict']}"
        if not bolted:
            area.plot(real, 100.0 * stick, label=label)
            continue
        line, = force.plot(real, 1e-3 * clamp, label=label)
        area.plot(real, 100.0 * stick, color=line.get_color())
        evident = level["figures"].get("loosening_evident_at_cycles")
        if evident is not None:
            row = min(int(np.searchsorted(real, evident * (1.0 - 1e-12))), real.size - 1)
            force.plot(real[row], 1e-3 * clamp[row], marker="v", color=line.get_color(), markersize=8)
    area.set_ylabel("stick area (% of nominal)")
    area.set_xlabel("real load cycles")
    area.set_xscale("log")
    title = f"mesh convergence over the run: {Path(study['scene']).stem}"
    if not bolted:
        area.legend(fontsize=8)
        return _save(figure, (area,), title, path)
    if any(level["figures"].get("loosening_evident_at_cycles") is not None for level, *_ in histories):
        force.plot([], [], marker="v", linestyle="none", color="0.3", label="loosening evident")
    force.set_ylabel("clamp force (kN)")
    force.legend(fontsize=8)
    return _save(figure, (force, area), title, path)
