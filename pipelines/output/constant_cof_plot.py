"""The plot of the constant-COF comparison (``fretwork study constant-cof``): the maximum shear
traction of the last COF cycle, evolving COF against constant μ = μ_max, over the contact.

3D interface: a map of each model on the contact's plane (the two axes along which the contact
points spread most) on one square-root colour scale for both (the shear peaks at the contact's
edges would leave the rest of the maps in one colour on a linear one), a third map of their
difference (variable − constant, a linear diverging scale centred on 0: red where the evolving
COF carries more shear, blue where the constant one does), and under them both models along the
dashed line through the first two probes (gaps where it crosses a hole). The facets of the
contact surface are triangulated, so a bolt hole stays a hole. 2D interface (plane strain): both
models along the contact, the difference below. The probes are marked and named (P1, P2, ...) in
every panel. Units: mm, MPa."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import matplotlib.tri

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import PowerNorm, TwoSlopeNorm  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402

from pipelines.output.plots import PATH_POINTS, _plane_axes, _title  # noqa: E402

SHEAR_LABEL = "max shear traction in the cycle [MPa]"
DIFFERENCE_LABEL = "variable − constant [MPa]"
#: Filled-contour levels of the maps.
LEVELS = 24


def plot_constant_cof(comparison, path: str | Path) -> Path:
    """Draw ``comparison`` (:class:`pipelines.studies.constant_cof.Comparison`) to ``path`` (PNG)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    variable, constant = comparison.models
    title = (f"{comparison.scene_name}: max shear traction in the last COF cycle (cycle {variable.cycle}), "
             f"evolving COF (μ {comparison.cof_initial:g} → {comparison.cof_max:g}) vs constant μ = "
             f"{comparison.cof_max:g}")
    figure = (_maps if comparison.dimension == 3 else _profiles)(comparison, title)
    figure.savefig(path, dpi=130)
    plt.close(figure)
    return path


def _difference(comparison) -> np.ndarray:
    variable, constant = comparison.models
    return variable.max_shear - constant.max_shear


def _triangulation(coordinates: np.ndarray, facets: np.ndarray, a: int, b: int) -> matplotlib.tri.Triangulation:
    """Triangles of the contact surface's facets on the plane (a, b): a triangle's corners are
    its first three nodes, a quadrilateral's its first four (quadratic facets' mid-side nodes
    follow their corners)."""
    corners = facets[:, :3] if facets.shape[1] in (3, 6) else np.concatenate([facets[:, [0, 1, 2]],
                                                                              facets[:, [0, 2, 3]]])
    return matplotlib.tri.Triangulation(coordinates[:, a], coordinates[:, b], corners)


def _probe_at(ax, x: float, name: str) -> None:
    """A probe on a profile: a dotted vertical line at ``x``, named at its top."""
    ax.axvline(x, color="0.3", lw=0.8, ls=":")
    ax.annotate(name, (x, 1.0), xycoords=("data", "axes fraction"), xytext=(2, -10),
                textcoords="offset points", fontsize=8)


def _mark_probes(ax, comparison, a: int, b: int | None = None) -> None:
    """Each probe's contact point marked and named: a cross on a map, a dotted line on a profile."""
    for probe in comparison.probes:
        x = probe.position_mm[a]
        if b is None:
            _probe_at(ax, x, probe.name)
            continue
        y = probe.position_mm[b]
        ax.plot(x, y, marker="X", ms=8, mfc="white", mec="black", mew=1.0)
        ax.annotate(probe.name, (x, y), xytext=(4, 4), textcoords="offset points", fontsize=8, fontweight="bold",
                    bbox={"boxstyle": "round,pad=0.15", "facecolor": "white", "edgecolor": "none", "alpha": 0.8})


def _levels(low: float, high: float) -> np.ndarray:
    """About :data:`LEVELS` contour levels at round values from ``low`` to at least ``high``."""
    return MaxNLocator(LEVELS, steps=[1, 2, 2.5, 5, 10]).tick_values(low, high if high > low else low + 1.0)


def _diverging(values: np.ndarray) -> TwoSlopeNorm:
    """A scale centred on 0, symmetric, so that equal colours mean equal differences either way."""
    reach = float(_levels(0.0, float(np.max(np.abs(values))))[-1])
    return TwoSlopeNorm(vcenter=0.0, vmin=-reach, vmax=reach)


def _maps(comparison, title: str):
    """Three maps side by side, under them both models along the line through the probes."""
    coordinates = comparison.coordinates
    a, b = _plane_axes(coordinates)
    mesh = _triangulation(coordinates, comparison.facets, a, b)
    width, height = np.ptp(coordinates[:, a]), np.ptp(coordinates[:, b])
    stacked = width > 1.6 * height  # a long contact: the maps one above the other, full width
    if stacked:
        panel = float(np.clip(10.0 * height / width, 1.2, 6.0))  # a map is about 10 in wide
        layout, size, heights = [["variable"], ["constant"], ["difference"], ["line"]], (12.0, 3 * panel + 6.0), \
            (panel + 0.7, panel + 0.7, panel + 0.7, 2.6)
    else:
        panel = float(np.clip(3.8 * height / width, 1.2, 6.0))  # a map is 3.5 to 3.8 in wide
        layout, size, heights = [["variable", "constant", "difference"], ["line"] * 3], (13.5, panel + 4.8), \
            (panel + 1.3, 2.6)
    figure, axes = plt.subplot_mosaic(layout, figsize=size, height_ratios=heights, layout="constrained")
    maps = [axes["variable"], axes["constant"], axes["difference"]]
    top = max(float(np.max(m.max_shear)) for m in comparison.models)
    shear_scale = PowerNorm(0.5, 0.0, float(_levels(0.0, top)[-1]))
    shear_levels = shear_scale.inverse(np.linspace(0.0, 1.0, LEVELS + 1))
    for ax, model in zip(maps, comparison.models):
        shear = ax.tricontourf(mesh, model.max_shear, levels=shear_levels, cmap="viridis", norm=shear_scale)
        ax.set_title(f"{model.name} (slip area {model.figures['slip_area_fraction']:.0%})", fontsize=9)
    difference = _difference(comparison)
    scale = _diverging(difference)
    change = maps[2].tricontourf(mesh, difference, levels=_levels(scale.vmin, scale.vmax), cmap="RdBu_r", norm=scale)
    maps[2].set_title("difference: variable − constant", fontsize=9)
    side = "right" if stacked else "bottom"
    bar = figure.colorbar(shear, ax=maps[:2], location=side, fraction=0.05, aspect=30 if stacked else 40)
    bar.set_ticks(_levels(0.0, shear_scale.vmax)[::2] if top > 0 else [0.0])
    bar.set_label(SHEAR_LABEL + "\n(square-root colour scale)" if stacked else SHEAR_LABEL + " (square-root colour scale)")
    bar = figure.colorbar(change, ax=maps[2], location=side, fraction=0.05, aspect=15 if stacked else 20)
    ticks = MaxNLocator(6, symmetric=True).tick_values(scale.vmin, scale.vmax)
    bar.set_ticks(ticks[(ticks >= scale.vmin) & (ticks <= scale.vmax)])
    bar.set_label(DIFFERENCE_LABEL)
    start, direction, length = _probe_line(comparison, a, b)
    ends = start + np.outer([0.0, length], direction)
    for ax in maps:
        ax.plot(ends[:, 0], ends[:, 1], color="white", lw=0.9, ls="--")
        _mark_probes(ax, comparison, a, b)
        ax.set_aspect("equal")
        ax.set_xlabel(f"{'xyz'[a]} [mm]")
        ax.set_ylabel(f"{'xyz'[b]} [mm]")
    _line_panel(axes["line"], comparison, mesh, (a, b), (start, direction, length))
    figure.suptitle(_title(figure.get_figwidth(), title), fontsize=10)
    return figure


def _probe_line(comparison, a: int, b: int) -> tuple[np.ndarray, np.ndarray, float]:
    """The line through the first two probes' contact points (through the first along the
    contact's longer axis when there is one probe, or both are read at one point) within the
    contact points' bounding box: its start (a, b) mm, unit direction and length (mm)."""
    plane = comparison.coordinates[:, [a, b]]
    first = np.asarray(comparison.probes[0].position_mm)[[a, b]]
    along = np.asarray(comparison.probes[1].position_mm)[[a, b]] - first if len(comparison.probes) > 1 else 0.0
    if np.linalg.norm(along) == 0.0:
        along = np.array([1.0, 0.0]) if np.ptp(plane[:, 0]) >= np.ptp(plane[:, 1]) else np.array([0.0, 1.0])
    direction = along / np.linalg.norm(along)
    low, high = -np.inf, np.inf  # the line within the contact's bounding box (slabs)
    for axis in (0, 1):
        if direction[axis] != 0.0:
            ends = sorted((np.array([plane[:, axis].min(), plane[:, axis].max()]) - first[axis]) / direction[axis])
            low, high = max(low, ends[0]), min(high, ends[1])
    return first + low * direction, direction, high - low


def _line_panel(ax, comparison, mesh, axes: tuple, line: tuple) -> None:
    """Both models' max shear along ``line`` (start, direction, length), interpolated linearly on
    the contact's facets (gaps where the line crosses a hole); the probes near it marked. A line
    along a coordinate axis is drawn against that coordinate, any other against the distance."""
    start, direction, length = line
    distance = np.linspace(0.0, length, PATH_POINTS)
    points = start + np.outer(distance, direction)
    start, direction = np.round(start, 6) + 0.0, np.round(direction, 6) + 0.0  # no "-0" in the labels
    a, b = axes
    along = np.flatnonzero(np.abs(direction) == 1.0)
    origin, sense = 0.0, 1.0  # the abscissa of a point at distance d is origin + sense * d
    if along.size:
        k = int(along[0])
        origin, sense = start[k], direction[k]
        ax.set_xlabel(f"{'xyz'[axes[k]]} [mm] along the dashed line, {'xyz'[axes[1 - k]]} = {start[1 - k]:.4g} mm")
    else:
        angle = np.degrees(np.arctan2(direction[1], direction[0]))
        ax.set_xlabel(f"distance along the dashed line [mm], from ({'xyz'[a]}, {'xyz'[b]}) = ({start[0]:.4g}, "
                      f"{start[1]:.4g}) mm along direction ({direction[0]:.3g}, {direction[1]:.3g}), "
                      f"{angle:.1f}° from the {'xyz'[a]} axis")
    for model, style in zip(comparison.models, ("-", "--")):
        values = matplotlib.tri.LinearTriInterpolator(mesh, model.max_shear)(points[:, 0], points[:, 1])
        ax.plot(origin + sense * distance, np.ma.filled(values.astype(float), np.nan), style, lw=1.4, label=model.name)
    normal = np.array([-direction[1], direction[0]])
    for probe in comparison.probes:
        offset = np.asarray(probe.position_mm)[[a, b]] - start
        if abs(offset @ normal) <= 0.02 * length:
            _probe_at(ax, origin + sense * (offset @ direction), probe.name)
    ax.set_xlim(*sorted((origin, origin + sense * length)))
    ax.set_ylim(bottom=0.0)
    ax.set_ylabel(SHEAR_LABEL)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)


def _profiles(comparison, title: str):
    """Both models along the contact (the axis along which its points spread), the difference below."""
    a = int(np.argmax(np.ptp(comparison.coordinates, axis=0)))
    order = np.argsort(comparison.coordinates[:, a])
    x = comparison.coordinates[order, a]
    figure, (top, bottom) = plt.subplots(2, 1, figsize=(8.0, 5.6), sharex=True, height_ratios=(2, 1),
                                         layout="constrained")
    for model, style in zip(comparison.models, ("-", "--")):
        top.plot(x, model.max_shear[order], style, lw=1.4,
                 label=f"{model.name} (slip area {model.figures['slip_area_fraction']:.0%})")
    top.set_ylabel(SHEAR_LABEL)
    top.set_ylim(bottom=0.0)
    top.legend(fontsize=8)
    bottom.plot(x, _difference(comparison)[order], "-", color="tab:red", lw=1.2)
    bottom.axhline(0.0, color="0.5", lw=0.8)
    bottom.set_ylabel(DIFFERENCE_LABEL)
    bottom.set_xlabel(f"position along the contact {'xyz'[a]} [mm]")
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
        _mark_probes(ax, comparison, a)
    figure.suptitle(_title(figure.get_figwidth(), title), fontsize=10)
    return figure
