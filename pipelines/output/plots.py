"""Plots of a results file, written as PNG files (matplotlib, no screen needed).

2D interfaces are drawn as profiles along the contact; 3D interfaces as maps over the two
in-plane coordinates with the largest extent. Cycle histories show the area fractions and,
where a clamp force exists, the clamp force versus cycles.
"""

from __future__ import annotations

from pathlib import Path

import h5py
import matplotlib
import matplotlib.tri

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.ticker import ScalarFormatter
from mpl_toolkits.axes_grid1 import make_axes_locatable

#: Values below this magnitude (in the field's own units: mm, MPa, mJ/mm²) are round-off of a
#: field that is zero (a stuck run's dissipation is ±1e-15, not a pattern worth a colour scale).
ROUND_OFF = 1e-12
PATH_POINTS = 400

FIELD_LABELS = {
    "pressure": "contact pressure p [MPa]",
    "shear": "shear traction |τ| [MPa]",
    "cof": "COF μ [-]",
    "max_utilised_cof": "max utilised COF |τ|/p [-]",
    "slip_range": "slip range in cycle [mm]",
    "dissipation_in_cycle": "frictional dissipation in cycle [mJ/mm²]",
    "wear_depth": "wear depth (both bodies) [mm]",
    "fdp": "fretting damage parameter FDP = τ·δ [MPa·mm]",
    "ffdp": "fretting fatigue parameter FFDP = σ_t·τ·δ [MPa²·mm]",
}

#: the status of the cycle's last increment ("at the friction limit": |τ| = μ·p, which a point
#: reaches with a tiny irreversible slip, and a stuck joint shows on much of its area), and
#: what still slid over the cycle, the verdict's measure (:func:`contact.verdict.active_slip_area_fraction`)
AREA_LABELS = {
    "stick_area_fraction": "stick (below the friction limit)",
    "slip_area_fraction": "at the friction limit",
    "active_slip_area_fraction": "sliding in the cycle (verdict)",
    "damaged_area_fraction": "at the friction limit with μ = μ_max (damaged)",
    "worn_area_fraction": "worn",
    "cof_evolved_area_fraction": "COF evolved",
}


def _field(group, name):
    value = group[name][()]
    if name == "shear":
        value = np.linalg.norm(np.atleast_2d(value.T).T.reshape(value.shape[0], -1), axis=1)
    if name == "wear_depth":
        value = value.sum(axis=0)
    value = np.asarray(value, dtype=float)
    return np.where(np.abs(value) < ROUND_OFF, 0.0, value)


def _plane_axes(coordinates: np.ndarray) -> tuple[int, int]:
    spans = np.ptp(coordinates, axis=0)
    first, second = np.argsort(spans)[::-1][:2]
    return int(min(first, second)), int(max(first, second))


def _path_plot(mesh, final, names, a, b, title, out_dir) -> Path:
    """Fields along the straight line through the middle of the interface's ``b`` extent (the
    paper's Figs. 9 and 12), interpolated linearly over the contact facets at PATH_POINTS points;
    gaps where the line crosses a hole or leaves the contact."""
    middle = 0.5 * (mesh.y.min() + mesh.y.max())
    x = np.linspace(mesh.x.min(), mesh.x.max(), PATH_POINTS)
    shown = [n for n in ("pressure", "slip_range", "cof", "wear_depth", "fdp") if n in names]
    fig, axes = plt.subplots(len(shown), 1, figsize=(7, 1.9 * len(shown)), sharex=True)
    for ax, name in zip(np.atleast_1d(axes), shown):
        values = matplotlib.tri.LinearTriInterpolator(mesh, _field(final, name))(x, np.full_like(x, middle))
        ax.plot(x, np.ma.filled(values.astype(float), np.nan), "-", lw=1.2)
        ax.set_ylabel(FIELD_LABELS[name], fontsize=7)
        ax.grid(alpha=0.3)
    np.atleast_1d(axes)[-1].set_xlabel(f"{'xyz'[a]} [mm] along {'xyz'[b]} = {middle + 0.0:.4g} mm "
                                       f"(the middle of the contact's {'xyz'[b]} extent)")
    fig.suptitle(f"{title}: fields along the line {'xyz'[b]} = {middle + 0.0:.3g} mm through the middle")
    return _save(fig, out_dir / "path.png")


def _save(fig, target: Path) -> Path:
    fig.tight_layout()
    fig.savefig(target, dpi=130)
    plt.close(fig)
    return target


def _map(mesh, value, name, a, b, title, target) -> Path:
    """A filled contour map, the colour bar as tall as the map; a field that is zero (or constant)
    everywhere is drawn in one colour and said so."""
    width, height = np.ptp(mesh.x), np.ptp(mesh.y)
    fig, ax = plt.subplots(figsize=(6.5, float(np.clip(5.5 * height / width, 2.0, 7.0)) + 1.0))
    constant = np.ptp(value) <= ROUND_OFF
    if constant:
        mappable = ax.tripcolor(mesh, value, cmap="viridis", vmin=value[0] - 1.0, vmax=value[0] + 1.0)
        title += f" ({value[0]:g} everywhere)"
    else:
        mappable = ax.tricontourf(mesh, value, levels=24, cmap="viridis")
    ax.set_aspect("equal")
    bar_axes = make_axes_locatable(ax).append_axes("right", size="4%", pad=0.1)
    fig.colorbar(mappable, cax=bar_axes, label=FIELD_LABELS[name], ticks=[value[0]] if constant else None)
    ax.set_xlabel(f"{'xyz'[a]} [mm]")
    ax.set_ylabel(f"{'xyz'[b]} [mm]")
    ax.set_title(title, fontsize=9)
    return _save(fig, target)


def plot_results(path: str | Path, out_dir: str | Path) -> list[Path]:
    """Draw the standard figures of one results file; returns the PNG paths."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    with h5py.File(path, "r") as file:
        coordinates = file["points/coordinates"][()]
        names = [n for n in FIELD_LABELS if n in file["final"]]
        title = file.attrs.get("scene_name", "")
        if coordinates.shape[1] == 2:
            written = [_line_fields(file, coordinates, names, title, out_dir)]
        else:
            written = _surface_maps(file, coordinates, names, title, out_dir)
        if "figures" in file["cycles"]:
            written.append(_cycles_plot(file["cycles"], title, out_dir))
    return written


def _line_fields(file, coordinates, names, title, out_dir) -> Path:
    """2D scenes: every final field along the contact, pressure and shear of the first cycle too."""
    final = file["final"]
    order = np.argsort(coordinates[:, 0])
    x = coordinates[order, 0]
    fig, axes = plt.subplots(len(names), 1, figsize=(7, 1.9 * len(names)), sharex=True)
    first = file["cycles/fields"]
    for ax, name in zip(np.atleast_1d(axes), names):
        ax.plot(x, _field(final, name)[order], "-", lw=1.4, label="final")
        if name in ("pressure", "shear") and name in first:
            initial = first[name][0]
            initial = np.linalg.norm(initial.reshape(initial.shape[0], -1), axis=1) if name == "shear" else initial
            ax.plot(x, initial[order], "--", lw=1.0, label="first cycle")
            ax.legend(fontsize=7)
        ax.set_ylabel(FIELD_LABELS[name], fontsize=7)
        ax.grid(alpha=0.3)
    np.atleast_1d(axes)[-1].set_xlabel("position along the contact x [mm]")
    fig.suptitle(f"{title}: interface fields")
    return _save(fig, out_dir / "fields.png")


def _surface_maps(file, coordinates, names, title, out_dir) -> list[Path]:
    """3D scenes: the path plot, a map per final field and the maps after the COF phase."""
    final = file["final"]
    a, b = _plane_axes(coordinates)
    facets = file["points/facets"][()] if "points/facets" in file else None
    # Triangles of the interface's own facets: holes (a bolt hole) stay holes.
    triangles = None if facets is None else (
        facets if facets.shape[1] == 3 else np.concatenate([facets[:, [0, 1, 2]], facets[:, [0, 2, 3]]]))
    mesh = matplotlib.tri.Triangulation(coordinates[:, a], coordinates[:, b], triangles)
    written = [_path_plot(mesh, final, names, a, b, title, out_dir)]
    for name in names:
        written.append(_map(mesh, _field(final, name), name, a, b, f"{title}: {name.replace('_', ' ')}",
                            out_dir / f"{name}_map.png"))
    # the stabilised state before the wear phase (the paper's Figs. 8, 15 and 16a-b)
    phase_of = dict(zip(file["cycles/cycle"][()], file["cycles/phase"][()]))
    recorded = file["cycles/fields/cycle"][()] if "cycles/fields/cycle" in file else np.zeros(0, int)
    cof_rows = [k for k, c in enumerate(recorded) if phase_of.get(c) == 1]
    if cof_rows and any(p == 2 for p in phase_of.values()):
        row, fields = cof_rows[-1], file["cycles/fields"]
        for name in ("cof", "slip_range", "max_utilised_cof", "dissipation_in_cycle"):
            written.append(_map(mesh, fields[name][row], name, a, b,
                                f"{title}: {name.replace('_', ' ')} after the COF phase (cycle {recorded[row]})",
                                out_dir / f"{name}_map_end_of_cof_phase.png"))
    return written


def _cycles_plot(cycles, title, out_dir) -> Path:
    """Area fractions (and the clamp force) over the real load cycles, the wear phase marked.

    The axis is the equivalent real cycles on a log scale: the COF phase counts one real
    cycle per simulated one, each wear block stands for as many as its (adaptive) jump, so
    150 COF cycles and millions of wear cycles share one readable axis, as on an S-N plot.
    """
    figures = cycles["figures"]
    phase = cycles["phase"][()]
    equivalent = cycles["equivalent_cycles"][()]
    clamp = figures.get("clamp_force_N")
    has_clamp = clamp is not None and np.any(np.isfinite(clamp[()]))
    fig, axes = plt.subplots(2 if has_clamp else 1, 1, figsize=(9, 5.2 if has_clamp else 3.2), sharex=True)
    axes = np.atleast_1d(axes)
    for key, name in AREA_LABELS.items():
        if key in figures:
            axes[0].plot(equivalent, figures[key][()], label=name)
    axes[0].set_ylabel("area / nominal area [-]")
    # above 1 where wear or a moving patch brings points beyond the preload's area into contact
    largest = max((np.nanmax(figures[key][()], initial=0.0) for key in AREA_LABELS if key in figures), default=1.0)
    axes[0].set_ylim(-0.03, 1.03 * max(1.0, largest))
    # beside the axes: the areas fill the whole plot over a run, and a legend inside hid them
    axes[0].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    axes[0].grid(alpha=0.3)
    if has_clamp:
        force = clamp[()] / 1000.0
        axes[1].plot(equivalent, force, color="k")
        axes[1].set_ylabel("clamp (bolt) force [kN]")
        # plain numbers, no "1e-5+8.98515e2" offset; a steady force gets a ±0.5 % window
        axes[1].yaxis.set_major_formatter(ScalarFormatter(useOffset=False))
        middle, spread = np.nanmean(force), np.nanmax(force) - np.nanmin(force)
        if spread < 1e-2 * abs(middle):
            axes[1].set_ylim(middle - 5e-3 * abs(middle), middle + 5e-3 * abs(middle))
        axes[1].grid(alpha=0.3)
    axes[-1].set_xscale("log")
    wear = np.flatnonzero(phase == 2)
    label = "equivalent real load cycles [-]"
    if wear.size and wear[0] > 0:
        start = equivalent[wear[0] - 1]
        for ax in axes:
            ax.axvline(start, color="grey", ls="--", lw=0.8)
        axes[0].text(start, 1.0, " wear phase", transform=axes[0].get_xaxis_transform(),
                     va="bottom", fontsize=7, color="grey")
        label += f"; wear phase after {start:,.0f}: {wear.size} blocks to {equivalent[-1]:.3g} cycles"
    elif wear.size:
        label += f"; wear phase throughout: {wear.size} blocks to {equivalent[-1]:.3g} cycles"
    axes[-1].set_xlabel(label)
    fig.suptitle(f"{title}: contact condition over cycles")
    return _save(fig, out_dir / "cycles.png")
