"""Plots of a results file, written as PNG files (matplotlib, no screen needed).

2D interfaces are drawn as profiles along the contact; 3D interfaces as maps over the two
in-plane coordinates with the largest extent. Cycle histories show the area fractions and,
where a clamp force exists, the clamp force versus cycles.

A field is drawn as a field only where the run resolves it. Newton stops once the kinematic
residual is within δ (``contact.solver.NewtonSettings.displacement_tolerance``, mm), so a stuck
joint's slip range, and the dissipation, wear, FDP and FFDP that slip drives, come out as
round-off of about δ (a slip range of 2e-11 mm, an FFDP of 6e-11 MPa²·mm) which a colour
scale would show as hot spots. Such a field is drawn as zero and said to be round-off.
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass
from pathlib import Path

import h5py
import matplotlib
import matplotlib.tri

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.ticker import ScalarFormatter  # noqa: E402

from contact.damage import fretting_damage  # noqa: E402
from contact.solver import NewtonSettings  # noqa: E402

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


#: what a field that is zero to within the run's resolution is said to be
ZERO_NAMES = {
    "slip_range": "no slip",
    "dissipation_in_cycle": "no frictional dissipation",
    "wear_depth": "no wear",
    "fdp": "no fretting damage",
    "ffdp": "no fretting fatigue damage",
}
#: relative spread below which a field is one value (the last digits of float64 arithmetic)
SAME_VALUE = 1e-12
#: characters per line of a stacked panel's y label; of a map's title (9 pt), per inch of figure
LABEL_WIDTH, TITLE_CHARACTERS_PER_INCH = 24, 14
#: characters per inch of figure of a figure's title (12 pt)
SUPTITLE_CHARACTERS_PER_INCH = 10


@dataclass(frozen=True)
class Field:
    """One field of one state as drawn: values in the units of FIELD_LABELS and ``round_off``,
    the largest magnitude the run does not resolve (0: every nonzero value is resolved)."""

    name: str
    values: np.ndarray
    round_off: float = 0.0

    @property
    def largest(self) -> float:
        return float(np.max(np.abs(self.values), initial=0.0))

    @property
    def is_zero(self) -> bool:
        return self.largest <= self.round_off

    @property
    def shown(self) -> np.ndarray:
        """The values drawn: zero where the field is round-off."""
        return np.zeros_like(self.values) if self.is_zero else self.values

    @property
    def is_uniform(self) -> bool:
        return self.is_zero or float(np.ptp(self.values)) <= SAME_VALUE * self.largest

    def note(self) -> str | None:
        """What a uniform field is, e.g. "no slip (max 2.2e-11 mm, round-off below 2.8e-10 mm)"."""
        if not self.is_uniform:
            return None
        if not self.is_zero:
            return f"{self.values[0]:.6g} everywhere"
        word = ZERO_NAMES.get(self.name, f"no {self.name.replace('_', ' ')}")
        if self.largest == 0.0:
            return f"{word} (0 everywhere)"
        unit = FIELD_LABELS[self.name].rsplit("[", 1)[1].rstrip("]")
        return f"{word} (max {self.largest:.2g} {unit}, round-off below {self.round_off:.2g} {unit})"


def round_off(state: dict[str, np.ndarray], dimension: int) -> dict[str, float]:
    """The largest magnitude of each slip-driven field of ``state`` that a converged run does
    not resolve, in the field's units.

    Newton resolves every displacement component to δ (mm), so a slip range (the norm over
    the dimension − 1 tangential components of the difference of two slips) to 2·√(dim−1)·δ,
    and the wear depth of two bodies to 2·δ. The dissipation of that slip at the state's
    largest shear τ_max is τ_max times it; FDP and FFDP are Ruiz's parameters of that slip
    range at each point's τ_max and σ_t (:func:`contact.damage.fretting_damage`). Pressure,
    shear and COF are the law's response to resolved displacements and are not listed: any
    nonzero value of theirs is drawn.
    """
    delta = NewtonSettings().displacement_tolerance
    slip = 2.0 * np.sqrt(dimension - 1) * delta
    shear = state.get("max_shear", state["shear"])
    fdp, ffdp = fretting_damage(shear, np.full_like(shear, slip),
                                state.get("surface_tangential_stress", np.zeros_like(shear)))
    return {"slip_range": slip, "wear_depth": 2.0 * delta, "dissipation_in_cycle": float(np.max(shear)) * slip,
            "fdp": float(np.max(fdp)), "ffdp": float(np.max(ffdp))}


def _fields(group, dimension: int, row: int | None = None) -> dict[str, Field]:
    """The drawn fields of the final state (``group`` = final) or of one recorded cycle
    (``group`` = cycles/fields, its ``row``): shear as |τ|, the wear of both bodies summed."""
    state = {}
    for name in (*FIELD_LABELS, "max_shear", "surface_tangential_stress"):
        if name in group:
            value = np.asarray(group[name][()] if row is None else group[name][row], dtype=float)
            if name == "shear":
                value = np.linalg.norm(value.reshape(value.shape[0], -1), axis=1)
            if name == "wear_depth":
                value = value.sum(axis=0)
            state[name] = value
    floors = round_off(state, dimension)
    return {name: Field(name, state[name], floors.get(name, 0.0)) for name in FIELD_LABELS if name in state}


def _title(inches: float, *lines: str) -> str:
    """A map's title wrapped to a figure ``inches`` wide."""
    return "\n".join(textwrap.fill(line, int(TITLE_CHARACTERS_PER_INCH * inches)) for line in lines if line)


def _plane_axes(coordinates: np.ndarray) -> tuple[int, int]:
    spans = np.ptp(coordinates, axis=0)
    first, second = np.argsort(spans)[::-1][:2]
    return int(min(first, second)), int(max(first, second))


def _stacked(count: int):
    """A figure of ``count`` panels over one x axis; constrained layout keeps the suptitle, the
    wrapped y labels and the x label clear of each other."""
    fig, axes = plt.subplots(count, 1, figsize=(7, 0.9 + 1.9 * count), sharex=True, layout="constrained")
    return fig, np.atleast_1d(axes)


def _panel(ax, field: Field, x: np.ndarray, y: np.ndarray, **style) -> None:
    """One stacked panel: the field's profile, its label wrapped to the panel's height, and a
    field that is zero said so in the panel."""
    ax.plot(x, y, "-", **style)
    ax.set_ylabel(textwrap.fill(FIELD_LABELS[field.name], LABEL_WIDTH), fontsize=8)
    ax.grid(alpha=0.3)
    if field.is_zero:
        ax.text(0.5, 0.5, field.note(), transform=ax.transAxes, ha="center", va="center", fontsize=8,
                bbox={"facecolor": "white", "edgecolor": "0.7", "alpha": 0.9})


def _path_plot(mesh, fields, a, b, title, out_dir, state: Drawn) -> Path:
    """Fields along the straight line through the middle of the interface's ``b`` extent (the
    paper's Figs. 9 and 12), interpolated linearly over the contact facets at PATH_POINTS points;
    gaps where the line crosses a hole or leaves the contact."""
    middle = 0.5 * (mesh.y.min() + mesh.y.max())
    x = np.linspace(mesh.x.min(), mesh.x.max(), PATH_POINTS)
    shown = [fields[n] for n in ("pressure", "slip_range", "cof", "wear_depth", "fdp") if n in fields]
    fig, axes = _stacked(len(shown))
    for ax, field in zip(axes, shown):
        values = matplotlib.tri.LinearTriInterpolator(mesh, field.shown)(x, np.full_like(x, middle))
        _panel(ax, field, x, np.ma.filled(values.astype(float), np.nan), lw=1.2)
    fig.align_ylabels(axes)
    axes[-1].set_xlabel(f"{'xyz'[a]} [mm] along {'xyz'[b]} = {middle + 0.0:.4g} mm "
                        f"(the middle of the contact's {'xyz'[b]} extent)")
    _suptitle(fig, f"{title}: fields along the line {'xyz'[b]} = {middle + 0.0:.3g} mm through the middle"
                   f"{state.when}", state.stop)
    return _save(fig, out_dir / "path.png")


def _suptitle(fig, title: str, stop: str | None) -> None:
    """A figure's title; a run that stopped early says so on a line of its own, in red."""
    if stop is None:
        fig.suptitle(title)
        return
    width = int(SUPTITLE_CHARACTERS_PER_INCH * fig.get_size_inches()[0])
    fig.suptitle("\n".join(textwrap.fill(line, width) for line in (title, stop)), color="firebrick")


def _save(fig, target: Path) -> Path:
    fig.savefig(target, dpi=130)
    plt.close(fig)
    return target


def _map(mesh, field: Field, a, b, title, target, stop: str | None = None) -> Path:
    """A filled contour map with its colour bar under a wide map and beside a tall one, so that
    the bar's label fits along it; a uniform field is drawn in one colour and said so, and a run
    that stopped early (``stop``) says so too."""
    width, height = np.ptp(mesh.x), np.ptp(mesh.y)
    wide = height <= width
    if wide:  # 5.8 in of map across, under it its axis and the colour bar
        figsize = (6.5, float(np.clip(5.8 * height / width, 1.0, 7.0)) + 1.3)
    else:  # 4.3 to 7 in of map high, beside it its axis and the colour bar
        map_height = float(np.clip(4.3 * height / width, 4.3, 7.0))
        figsize = (max(4.0, map_height * width / height + 2.4), map_height + 0.9)
    title = _title(figsize[0], title, stop, field.note())
    fig, ax = plt.subplots(figsize=(figsize[0], figsize[1] + 0.2 * (title.count("\n") + 1)), layout="constrained")
    value = field.shown
    if field.is_uniform:
        mappable = ax.tripcolor(mesh, value, cmap="viridis", vmin=value[0] - 1.0, vmax=value[0] + 1.0,
                                edgecolors="none", antialiased=False)
    else:
        # levels spanning the values: with matplotlib's round-number levels a COF of
        # 0.6000000000000002 lay above the top level 0.6 and was left white where μ_max was reached;
        # a top level at the largest value itself left a plateau there (a patch at μ_max) white too
        levels = np.linspace(value.min(), value.max(), 25)
        levels[-1] = np.nextafter(levels[-1], np.inf)
        mappable = ax.tricontourf(mesh, value, levels=levels, cmap="viridis")
    ax.set_aspect("equal")
    ax.margins(0.0)
    bar = fig.colorbar(mappable, ax=ax, location="bottom" if wide else "right", fraction=0.05, pad=0.02,
                       aspect=60, ticks=[value[0]] if field.is_uniform else None)
    bar.set_label(FIELD_LABELS[field.name], fontsize=9)
    ax.set_xlabel(f"{'xyz'[a]} [mm]")
    ax.set_ylabel(f"{'xyz'[b]} [mm]")
    ax.set_title(title, fontsize=9, pad=12)  # clear of the top y tick label, half above the map's edge
    return _save(fig, target)


@dataclass(frozen=True)
class Drawn:
    """The state a results file's field plots show: ``/final`` (``row`` None), or, for a run that
    stopped early (slid off, runaway wear: no ``/final``), the last recorded cycle's row of
    ``/cycles/fields``, that of ``cycle``. ``stop``: how such a run ended, said on every figure."""

    group: h5py.Group
    row: int | None = None
    cycle: int | None = None
    stop: str | None = None

    def fields(self, dimension: int) -> dict[str, Field]:
        return _fields(self.group, dimension, self.row)

    @property
    def name(self) -> str:
        """The state's legend entry."""
        return "final" if self.row is None else f"end of cycle {self.cycle} (last recorded)"

    @property
    def when(self) -> str:
        """What a title adds to say which state it shows: nothing for the final one."""
        return "" if self.row is None else f", cycle {self.cycle} (the last recorded)"


def stop_note(file: h5py.File) -> str | None:
    """How a run that stopped early ended, e.g. "the run stopped in cycle 8: the joint slides
    off", from the file's ``ending``; None for a run that ended normally."""
    from contact.verdict import Ending
    from pipelines.jobs.run import EARLY_ENDINGS, ENDINGS

    ending = str(file.attrs.get("ending", ""))
    if ending not in {e.value for e in EARLY_ENDINGS}:
        return None
    cycles = file["cycles/cycle"][()] if "cycles/cycle" in file else np.zeros(0, int)
    failed = int(cycles[-1]) + 1 if cycles.size else 1  # /cycles holds every cycle that ended
    stopped, _, why = ENDINGS[Ending(ending)].partition(": ")  # "stopped: the joint slides off"
    return f"the run {stopped} in cycle {failed}: {why}"


def drawn_state(file: h5py.File) -> Drawn | None:
    """The state to draw (:class:`Drawn`); None when a run stopped before its first recorded
    cycle ended: nothing converged beyond the preload has fields to draw."""
    stop = stop_note(file)
    if "final" in file:
        return Drawn(file["final"], stop=stop)
    recorded = file["cycles/fields/cycle"][()] if "cycles/fields/cycle" in file else np.zeros(0, int)
    if stop is None or not recorded.size:
        return None
    return Drawn(file["cycles/fields"], recorded.size - 1, int(recorded[-1]), stop)


def plot_results(path: str | Path, out_dir: str | Path) -> list[Path]:
    """Draw the standard figures of one results file; returns the PNG paths. A run that stopped
    early (slid off, runaway wear) is drawn up to its last converged cycle, each figure saying
    where and why it stopped; one that stopped before any cycle ended has none."""
    out_dir = Path(out_dir)
    with h5py.File(path, "r") as file:
        state = drawn_state(file)
        if state is None:
            return []
        out_dir.mkdir(parents=True, exist_ok=True)
        coordinates = file["points/coordinates"][()]
        title = file.attrs.get("scene_name", "")
        if coordinates.shape[1] == 2:
            written = [_line_fields(file, state, coordinates, title, out_dir)]
        else:
            written = _surface_maps(file, state, coordinates, title, out_dir)
        if "figures" in file["cycles"]:
            written.append(_cycles_plot(file["cycles"], title, out_dir, state.stop))
    return written


def _line_fields(file, state: Drawn, coordinates, title, out_dir) -> Path:
    """2D scenes: every field of the drawn state along the contact, pressure and shear of the
    first cycle too."""
    fields = state.fields(2)
    order = np.argsort(coordinates[:, 0])
    x = coordinates[order, 0]
    fig, axes = _stacked(len(fields))
    first = file["cycles/fields"]
    for ax, field in zip(axes, fields.values()):
        _panel(ax, field, x, field.shown[order], lw=1.4, label=state.name)
        if field.name in ("pressure", "shear") and field.name in first:
            initial = first[field.name][0]
            if field.name == "shear":
                initial = np.linalg.norm(initial.reshape(initial.shape[0], -1), axis=1)
            ax.plot(x, initial[order], "--", lw=1.0, label="first cycle")
            ax.legend(fontsize=7)
        if field.name == "wear_depth" and state.row is None and "master_wear_depth" in state.group:
            _master_profile(ax, file)
    fig.align_ylabels(axes)
    axes[-1].set_xlabel("position along the contact x [mm]")
    _suptitle(fig, f"{title}: interface fields{state.when}", state.stop)
    return _save(fig, out_dir / "fields.png")


def _master_profile(ax, file) -> None:
    """Finite sliding: the master's own wear depth along its own surface, beside the points'
    gap (the master's depth read at their current partners), which misses the scar they left."""
    x = file["master_surface/coordinates"][()][:, 0]
    order = np.argsort(x)
    ax.lines[0].set_label("final, at the points (both bodies)")
    ax.plot(x[order], file["final/master_wear_depth"][()][order], "--", lw=1.0,
            label="master's own surface (its depth alone)")
    ax.legend(fontsize=7)


def _surface_maps(file, state: Drawn, coordinates, title, out_dir) -> list[Path]:
    """3D scenes: the path plot, a map per field of the drawn state and the maps after the COF phase."""
    fields = state.fields(3)
    a, b = _plane_axes(coordinates)
    facets = file["points/facets"][()] if "points/facets" in file else None
    # Triangles of the interface's own facets: holes (a bolt hole) stay holes.
    triangles = None if facets is None else (
        facets if facets.shape[1] == 3 else np.concatenate([facets[:, [0, 1, 2]], facets[:, [0, 2, 3]]]))
    mesh = matplotlib.tri.Triangulation(coordinates[:, a], coordinates[:, b], triangles)
    written = [_path_plot(mesh, fields, a, b, title, out_dir, state)]
    for name, field in fields.items():
        written.append(_map(mesh, field, a, b, f"{title}: {name.replace('_', ' ')}{state.when}",
                            out_dir / f"{name}_map.png", state.stop))
    # the stabilised state before the wear phase (the paper's Figs. 8, 15 and 16a-b)
    phase_of = dict(zip(file["cycles/cycle"][()], file["cycles/phase"][()]))
    recorded = file["cycles/fields/cycle"][()] if "cycles/fields/cycle" in file else np.zeros(0, int)
    cof_rows = [k for k, c in enumerate(recorded) if phase_of.get(c) == 1]
    if cof_rows and any(p == 2 for p in phase_of.values()):
        row = cof_rows[-1]
        at_row = _fields(file["cycles/fields"], 3, row)
        for name in ("cof", "slip_range", "max_utilised_cof", "dissipation_in_cycle"):
            written.append(_map(mesh, at_row[name], a, b,
                                f"{title}: {name.replace('_', ' ')} after the COF phase (cycle {recorded[row]})",
                                out_dir / f"{name}_map_end_of_cof_phase.png", state.stop))
    return written


def _cycles_plot(cycles, title, out_dir, stop: str | None = None) -> Path:
    """Area fractions (and the clamp force) over the real load cycles, the wear phase marked,
    and the end of the last converged cycle of a run that stopped early (``stop``: how).

    The axis is the equivalent real cycles on a log scale: the COF phase counts one real
    cycle per simulated one, each wear block stands for as many as its (adaptive) jump, so
    150 COF cycles and millions of wear cycles share one readable axis, as on an S-N plot.
    """
    figures = cycles["figures"]
    phase = cycles["phase"][()]
    equivalent = cycles["equivalent_cycles"][()]
    clamp = figures.get("clamp_force_N")
    has_clamp = clamp is not None and np.any(np.isfinite(clamp[()]))
    fig, axes = plt.subplots(2 if has_clamp else 1, 1, figsize=(9, 5.2 if has_clamp else 3.2), sharex=True,
                             layout="constrained")
    axes = np.atleast_1d(axes)
    single = {"marker": "o"} if equivalent.size == 1 else {}  # a line through one point draws nothing
    for key, name in AREA_LABELS.items():
        if key in figures:
            axes[0].plot(equivalent, figures[key][()], label=name, **single)
    axes[0].set_ylabel("area / nominal area [-]")
    # above 1 where wear or a moving patch brings points beyond the preload's area into contact
    largest = max((np.nanmax(figures[key][()], initial=0.0) for key in AREA_LABELS if key in figures), default=1.0)
    axes[0].set_ylim(-0.03, 1.03 * max(1.0, largest))
    # beside the axes: the areas fill the whole plot over a run, and a legend inside hid them
    axes[0].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    axes[0].grid(alpha=0.3)
    if has_clamp:
        force = clamp[()] / 1000.0
        axes[1].plot(equivalent, force, color="k", **single)
        axes[1].set_ylabel("clamp (bolt) force [kN]")
        # plain numbers, no "1e-5+8.98515e2" offset; a steady force gets a ±0.5 % window
        axes[1].yaxis.set_major_formatter(ScalarFormatter(useOffset=False))
        low, high = np.nanmin(force), np.nanmax(force)
        middle = 0.5 * (low + high)
        if high - low < 5e-3 * abs(middle):  # the window holds every value (a 0.7 % loss fell below it)
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
    if stop is not None:
        for ax in axes:
            ax.axvline(equivalent[-1], color="firebrick", lw=1.0)
        axes[0].text(equivalent[-1], 1.0, "stopped ", transform=axes[0].get_xaxis_transform(),
                     ha="right", va="bottom", fontsize=7, color="firebrick")
    axes[-1].set_xlabel(label)
    _suptitle(fig, f"{title}: contact condition over cycles", stop)
    return _save(fig, out_dir / "cycles.png")
