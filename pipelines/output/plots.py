"""Plots of a results file, written as PNG files (matplotlib, no screen needed).

2D interfaces are drawn as profiles along the contact; 3D interfaces as maps over the two
in-plane coordinates with the largest extent, and a map of the contact status. Cycle histories
show the area fractions, the clamp force's loss and the deepest wear versus cycles, with the
shakedown and the loosening the verdict found.

Fields are drawn in the units that read (:data:`QUANTITIES`): slip ranges and wear depths in
µm, stored in mm. A COF is drawn on the law's scale μ0 … μ_max, so a COF that barely moved
looks like it. Where a point is open over the whole cycle (status 0) its slip range and its
utilised COF mean nothing; a map draws such points grey.

A field is drawn as a field only where the run resolves it. Newton stops once the kinematic
residual is within δ (``contact.solver.NewtonSettings.displacement_tolerance``, mm), so a stuck
joint's slip range, and the dissipation, wear, FDP and FFDP that slip drives, come out as
round-off of about δ (a slip range of 2e-11 mm, an FFDP of 6e-11 MPa²·mm) which a colour
scale would show as hot spots. Such a field is drawn as zero and said to be round-off. A field
whose values differ by less than :data:`SAME_VALUE` of their size is one value: drawn flat, its
value in the title.
"""

from __future__ import annotations

import json
import re
import textwrap
import tomllib
from dataclasses import dataclass
from pathlib import Path

import h5py
import matplotlib
import matplotlib.tri

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import BoundaryNorm, ListedColormap  # noqa: E402
from matplotlib.ticker import MaxNLocator, ScalarFormatter  # noqa: E402

from contact.damage import fretting_damage  # noqa: E402
from contact.solver import NewtonSettings  # noqa: E402
from contact.verdict import COF_EVOLVED_SHARE  # noqa: E402

PATH_POINTS = 400


@dataclass(frozen=True)
class Quantity:
    """How a field is drawn: its name in words, the units drawn, and ``scale``, the drawn
    value per stored one (stored units: those of ``pipelines.output.results.FIELD_UNITS``)."""

    words: str
    units: str
    scale: float = 1.0

    @property
    def label(self) -> str:
        return f"{self.words} [{self.units}]"


QUANTITIES = {
    "pressure": Quantity("contact pressure p", "MPa"),
    "shear": Quantity("shear traction |τ|", "MPa"),
    "cof": Quantity("coefficient of friction μ", "-"),
    "max_utilised_cof": Quantity("max utilised COF |τ|/p over the cycle", "-"),
    "slip_range": Quantity("slip range in the cycle", "µm", 1e3),
    "dissipation_in_cycle": Quantity("frictional dissipation in the cycle", "mJ/mm²"),
    "wear_depth": Quantity("wear depth (both bodies)", "µm", 1e3),
    "fdp": Quantity(r"fretting damage FDP $\tau\cdot\delta$", "MPa·mm"),
    "ffdp": Quantity(r"fretting fatigue FFDP $\sigma_t\cdot\tau\cdot\delta$", "MPa²·mm"),
}

#: fields that mean nothing where a point is open over the whole cycle (status 0): drawn grey
MEANINGLESS_WHEN_OPEN = ("max_utilised_cof", "slip_range")
#: the codes of /final/status and /cycles/fields/status, as drawn (results.STATUS_NAMES)
#: "at the friction limit" (|τ| = μ·p at some increment of the cycle), the CLI's and the report's
#: words, not "slip": such a point need not move (a stuck joint shows it on a quarter of its pads),
#: and an Abaqus user reads "slip" as CSTATUS slip; what slid is the verdict's measure (cycles.png)
STATUS = (("open", "0.82"), ("stick", "tab:blue"), ("at the friction limit (|τ| = μp)", "tab:orange"),
          ("at the friction limit with μ = μ_max", "firebrick"))
OPEN_COLOUR = STATUS[0][1]

#: the status of the cycle's last increment ("at the friction limit": |τ| = μ·p, which a point
#: reaches with a tiny irreversible slip, and a stuck joint shows on much of its area), and
#: what still slid over the cycle, the verdict's measure (:func:`contact.verdict.active_slip_area_fraction`)
AREA_LABELS = {
    "stick_area_fraction": "stick (below the friction limit)",
    "slip_area_fraction": "at the friction limit (|τ| = μp; need not move)",
    "active_slip_area_fraction": "sliding in the cycle (the verdict's measure)",
    "damaged_area_fraction": "at the friction limit with μ = μ_max (damaged)",
    "worn_area_fraction": "worn",
    "cof_evolved_area_fraction": "COF evolved",
}
#: a line style per area fraction: fractions that coincide (a gross slip: three at 1) stay apart
AREA_STYLES = (("-", "o"), ("--", "s"), ("-.", "^"), (":", "v"), ((0, (5, 1, 1, 1)), "D"), ((0, (1, 3)), "x"))
#: the verdict's moments (summary figures, real cycles): the words and the line that mark them
MOMENTS = {"shakedown_at_cycles": ("shakedown", "tab:olive", (0, (6, 2, 1, 2))),
           "loosening_evident_at_cycles": ("loosening evident", "m", (0, (4, 2)))}
#: a cycle axis spanning less than this factor is linear (2-6 cycles on a log axis read "2×10⁰")
LOG_SPAN = 20.0


#: what a field that is zero to within the run's resolution is said to be
ZERO_NAMES = {
    "slip_range": "no slip",
    "dissipation_in_cycle": "no frictional dissipation",
    "wear_depth": "no wear",
    "fdp": "no fretting damage",
    "ffdp": "no fretting fatigue damage",
}
#: relative spread below which a field is one value: a colour scale over less shows noise
#: (a COF of 0.2000000 … 0.2000001 as a full rainbow)
SAME_VALUE = 1e-6
#: characters per line of a stacked panel's y label; of a map's title (9 pt), per inch of figure
LABEL_WIDTH, TITLE_CHARACTERS_PER_INCH = 24, 12
#: characters per inch of figure of a figure's title (12 pt)
SUPTITLE_CHARACTERS_PER_INCH = 10


@dataclass(frozen=True)
class Field:
    """One field of one state: ``values`` in the stored units (results.FIELD_UNITS), drawn in
    those of its :class:`Quantity`; ``round_off``, the largest magnitude the run does not
    resolve (stored units; 0: every nonzero value is resolved)."""

    name: str
    values: np.ndarray
    round_off: float = 0.0

    @property
    def quantity(self) -> Quantity:
        return QUANTITIES[self.name]

    @property
    def largest(self) -> float:
        return float(np.max(np.abs(self.values), initial=0.0))

    @property
    def is_zero(self) -> bool:
        return self.largest <= self.round_off

    @property
    def shown(self) -> np.ndarray:
        """The values drawn, in the drawn units: zero where the field is round-off."""
        return np.zeros_like(self.values) if self.is_zero else self.values * self.quantity.scale

    @property
    def is_uniform(self) -> bool:
        return self.is_zero or float(np.ptp(self.values)) <= SAME_VALUE * self.largest

    def note(self) -> str | None:
        """What a uniform field is, e.g. "no slip (max 2.2e-08 µm, round-off below 2.8e-07 µm)"
        or "uniform: 0.56 everywhere"."""
        if not self.is_uniform:
            return None
        units = "" if self.quantity.units == "-" else f" {self.quantity.units}"
        if not self.is_zero:
            return f"uniform: {self.shown[0]:.6g}{units} everywhere"
        word = ZERO_NAMES.get(self.name, f"no {self.name.replace('_', ' ')}")
        if self.largest == 0.0:
            return f"{word} (0 everywhere)"
        scale = self.quantity.scale
        return (f"{word} (max {self.largest * scale:.2g}{units}, "
                f"round-off below {self.round_off * scale:.2g}{units})")


def colour_limits(field: Field, cof_range: tuple[float, float] | None = None,
                  closed: np.ndarray | None = None) -> tuple[float, float]:
    """The colour scale of a map of ``field`` (drawn units): a COF on the law's μ0 … μ_max
    (``cof_range``; a COF evolved by 1e-3 of it is then a faint tint, not the whole scale),
    anything else its own range over the ``closed`` points (all without)."""
    if field.name == "cof" and cof_range is not None and cof_range[1] > cof_range[0]:
        return float(cof_range[0]), float(cof_range[1])
    values = field.shown if closed is None or not closed.any() else field.shown[closed]
    return float(values.min()), float(values.max())


def cof_range(file: h5py.File) -> tuple[float, float] | None:
    """The contact law's (μ0, μ_max) from the scene the file was run with; None if it does not say."""
    try:
        contact = tomllib.loads(str(file.attrs.get("scene_toml", ""))).get("contact", {})
    except tomllib.TOMLDecodeError:
        return None
    if "cof_initial" not in contact or "cof_max" not in contact:
        return None
    return float(contact["cof_initial"]), float(contact["cof_max"])


def round_off(state: dict[str, np.ndarray], dimension: int) -> dict[str, float]:
    """The largest magnitude of each slip-driven field of ``state`` that a converged run does
    not resolve, in the field's stored units.

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
    for name in (*QUANTITIES, "max_shear", "surface_tangential_stress"):
        if name in group:
            value = np.asarray(group[name][()] if row is None else group[name][row], dtype=float)
            if name == "shear":
                value = np.linalg.norm(value.reshape(value.shape[0], -1), axis=1)
            if name == "wear_depth":
                value = value.sum(axis=0)
            state[name] = value
    floors = round_off(state, dimension)
    return {name: Field(name, state[name], floors.get(name, 0.0)) for name in QUANTITIES if name in state}


def _status(group, row: int | None = None) -> np.ndarray | None:
    """The points' status over the cycle (codes as :data:`STATUS`), None where not recorded."""
    if "status" not in group:
        return None
    return np.asarray(group["status"][()] if row is None else group["status"][row], dtype=int)


def _title(inches: float, *lines: str) -> str:
    """A map's title wrapped to a figure ``inches`` wide."""
    return "\n".join(_wrap(line, int(TITLE_CHARACTERS_PER_INCH * inches)) for line in lines if line)


#: phrases a wrapped title or label keeps on one line ("end of / run" read as two things)
UNBROKEN = re.compile(r"end of (?:the COF phase|the last recorded|cycle \d+|run)|at the friction limit"
                      r"|μ = μ_max|\|τ\| = μ·?p|round-off below \S+ \S+|max \S+ \S+")


def _wrap(text: str, width: int) -> str:
    """``text`` in lines of ``width`` characters, broken at spaces only (a mathtext "$...$"
    split across lines is drawn as its source) and not inside the phrases of :data:`UNBROKEN`."""
    kept = UNBROKEN.sub(lambda match: match.group(0).replace(" ", "\u00a0"), text)
    wrapped = textwrap.fill(kept, width, break_long_words=False, break_on_hyphens=False)
    return wrapped.replace("\u00a0", " ")


def _plane_axes(coordinates: np.ndarray) -> tuple[int, int]:
    spans = np.ptp(coordinates, axis=0)
    first, second = np.argsort(spans)[::-1][:2]
    return int(min(first, second)), int(max(first, second))


def _stacked(count: int):
    """A figure of ``count`` panels over one x axis; constrained layout keeps the suptitle, the
    wrapped y labels and the x label clear of each other."""
    fig, axes = plt.subplots(count, 1, figsize=(7, 0.9 + 1.9 * count), sharex=True, layout="constrained")
    return fig, np.atleast_1d(axes)


def _plain(axis) -> None:
    """Tick labels as plain numbers: no "1e-5" or "+8.98515e2" beside the axis."""
    formatter = ScalarFormatter(useOffset=False)
    formatter.set_powerlimits((-4, 6))
    axis.set_major_formatter(formatter)


def _panel(ax, field: Field, x: np.ndarray, y: np.ndarray, law: tuple[float, float] | None = None,
           **style) -> None:
    """One stacked panel: the field's profile (drawn units), its label wrapped to the panel's
    height, a COF on the law's scale (``law``: μ0, μ_max), and a field that is zero said so."""
    ax.plot(x, y, "-", **style)
    ax.set_ylabel(_wrap(field.quantity.label, LABEL_WIDTH), fontsize=8)
    ax.grid(alpha=0.3)
    _plain(ax.yaxis)
    if field.name == "cof" and law is not None:
        low, high = (law[0], law[1]) if law[1] > law[0] else (0.0, law[0])
        ax.set_ylim(low - 0.05 * (high - low), high + 0.05 * (high - low))
    if field.is_zero:
        ax.text(0.5, 0.5, field.note(), transform=ax.transAxes, ha="center", va="center", fontsize=8,
                bbox={"facecolor": "white", "edgecolor": "0.7", "alpha": 0.9})


def _open_where(field: Field, status: np.ndarray | None) -> np.ndarray | None:
    """The points where ``field`` means nothing (open over the whole cycle); None: none such."""
    if status is None or field.name not in MEANINGLESS_WHEN_OPEN:
        return None
    open_points = status == 0
    return open_points if open_points.any() and not open_points.all() else None


def _path_plot(mesh, fields, a, b, title, out_dir, state: Drawn, law=None, status=None) -> Path:
    """Fields along the straight line through the middle of the interface's ``b`` extent (the
    paper's Figs. 9 and 12), interpolated linearly over the contact facets at PATH_POINTS points;
    gaps where the line crosses a hole or leaves the contact, and where a field means nothing
    because the contact is open."""
    middle = 0.5 * (mesh.y.min() + mesh.y.max())
    x = np.linspace(mesh.x.min(), mesh.x.max(), PATH_POINTS)
    shown = [fields[n] for n in ("pressure", "slip_range", "cof", "wear_depth", "fdp") if n in fields]
    fig, axes = _stacked(len(shown))
    for ax, field in zip(axes, shown):
        open_points = _open_where(field, status)
        triangles = mesh if open_points is None else matplotlib.tri.Triangulation(
            mesh.x, mesh.y, mesh.triangles, mask=open_points[mesh.triangles].all(axis=1))
        values = matplotlib.tri.LinearTriInterpolator(triangles, field.shown)(x, np.full_like(x, middle))
        _panel(ax, field, x, np.ma.filled(values.astype(float), np.nan), law, lw=1.2)
    fig.align_ylabels(axes)
    axes[-1].set_xlabel(f"{'xyz'[a]} [mm] along {'xyz'[b]} = {middle + 0.0:.4g} mm "
                        f"(the middle of the contact's {'xyz'[b]} extent)")
    _suptitle(fig, f"{title}: fields along the line {'xyz'[b]} = {middle + 0.0:.3g} mm through the middle, "
                   f"{state.words}", state.stop)
    return _save(fig, out_dir / "path.png")


def _suptitle(fig, title: str, stop: str | None) -> None:
    """A figure's title wrapped to its width; a run that stopped early says so on a line of
    its own, in red."""
    width = int(SUPTITLE_CHARACTERS_PER_INCH * fig.get_size_inches()[0])
    fig.suptitle("\n".join(_wrap(line, width) for line in (title, stop) if line),
                 color="black" if stop is None else "firebrick")


def _save(fig, target: Path) -> Path:
    fig.savefig(target, dpi=130)
    plt.close(fig)
    return target


def _map_axes(mesh, *lines: str):
    """A map's figure and axes, sized to the interface, its title from ``lines``; ``wide``:
    the colour bar goes under the map (else beside it), so that the bar's label fits along it."""
    width, height = np.ptp(mesh.x), np.ptp(mesh.y)
    wide = height <= width
    if wide:  # 5.8 in of map across, under it its axis and the colour bar
        figsize = (6.5, float(np.clip(5.8 * height / width, 1.0, 7.0)) + 1.3)
    else:  # 4.3 to 7 in of map high, beside it its axis and the colour bar
        map_height = float(np.clip(4.3 * height / width, 4.3, 7.0))
        figsize = (max(4.0, map_height * width / height + 2.4), map_height + 0.9)
    title = _title(figsize[0], *lines)
    fig, ax = plt.subplots(figsize=(figsize[0], figsize[1] + 0.2 * (title.count("\n") + 1)), layout="constrained")
    ax.set_aspect("equal")
    ax.margins(0.0)
    ax.set_title(title, fontsize=9, pad=12)  # clear of the top y tick label, half above the map's edge
    return fig, ax, wide


def _colour_bar(fig, ax, mappable, wide: bool, label: str, a: int, b: int, **options):
    bar = fig.colorbar(mappable, ax=ax, location="bottom" if wide else "right", fraction=0.05, pad=0.02,
                       aspect=60, **options)
    bar.set_label(label, fontsize=9)
    ax.set_xlabel(f"{'xyz'[a]} [mm]")
    ax.set_ylabel(f"{'xyz'[b]} [mm]")
    return bar


def _cof_note(field: Field, law: tuple[float, float] | None) -> str | None:
    """A COF map's word on whether the COF evolved anywhere (contact.verdict's threshold:
    μ0 + 1 % of μ_max − μ0)."""
    if field.name != "cof" or law is None or law[1] <= law[0] or field.is_uniform:
        return None
    threshold = law[0] + COF_EVOLVED_SHARE * (law[1] - law[0])
    if field.values.max() > threshold:
        return None
    return f"nowhere evolved: max {field.values.max():.4g} below μ0 + 1 % of (μ_max − μ0) = {threshold:.4g}"


def _map(mesh, field: Field, a, b, title, target, stop: str | None = None, *,
         law: tuple[float, float] | None = None, status: np.ndarray | None = None) -> Path:
    """A filled contour map of ``field`` and its colour bar (:func:`colour_limits`: a COF on the
    law's ``law`` = (μ0, μ_max)); a uniform field is drawn in one colour and said so, points open
    over the whole cycle (``status`` 0) grey where the field means nothing there, and a run that
    stopped early (``stop``) says so too."""
    open_points = _open_where(field, status)
    closed = None if open_points is None else ~open_points
    low, high = colour_limits(field, law, closed)
    masked = None if open_points is None else open_points[mesh.triangles].all(axis=1)
    if masked is not None and not masked.any():  # open points only at the edges of closed facets
        open_points = None
    narrow = high - low <= SAME_VALUE * max(abs(low), abs(high))  # a scale too narrow to colour
    flat = field.is_uniform or narrow
    units = "" if field.quantity.units == "-" else f" {field.quantity.units}"
    note = field.note() or (f"uniform: {high:.6g}{units} wherever closed" if flat else _cof_note(field, law))
    grey = None if open_points is None else "grey: open over the whole cycle (no contact, nothing to draw)"
    fig, ax, wide = _map_axes(mesh, title, stop, note, grey)
    triangles = mesh
    if open_points is not None:
        triangles = matplotlib.tri.Triangulation(mesh.x, mesh.y, mesh.triangles, mask=masked)
        ax.tripcolor(matplotlib.tri.Triangulation(mesh.x, mesh.y, mesh.triangles[masked]),
                     facecolors=np.zeros(int(masked.sum())), cmap=ListedColormap([OPEN_COLOUR]), vmin=0.0,
                     vmax=1.0, edgecolors="none")
    if flat:
        # one colour: on the law's scale for a COF (μ0 at its foot), else in the middle of ±1
        on_scale = not narrow
        value = float(np.mean(field.shown)) if on_scale else high
        mappable = ax.tripcolor(triangles, np.full(len(field.values), value), cmap="viridis",
                                vmin=low if on_scale else value - 1.0, vmax=high if on_scale else value + 1.0,
                                edgecolors="none", antialiased=False)
        ticks = MaxNLocator(6, steps=[1, 2, 2.5, 5, 10]) if on_scale else [value]
    else:
        # levels spanning the scale, the values clipped to it: with matplotlib's round-number
        # levels a COF of 0.6000000000000002 lay above the top level 0.6 and was left white
        levels = np.linspace(low, high, 25)
        levels[-1] = np.nextafter(levels[-1], np.inf)
        mappable = ax.tricontourf(triangles, np.clip(field.shown, low, high), levels=levels, cmap="viridis")
        ticks = MaxNLocator(6, steps=[1, 2, 2.5, 5, 10])
    bar = _colour_bar(fig, ax, mappable, wide, field.quantity.label, a, b, ticks=ticks)
    _plain(bar.ax.xaxis if wide else bar.ax.yaxis)
    return _save(fig, target)


def _status_map(mesh, status: np.ndarray, a, b, title, target, stop: str | None = None) -> Path:
    """The contact status over the cycle (:data:`STATUS`), each facet drawn in the worst status
    of its corners."""
    fig, ax, wide = _map_axes(mesh, title, stop, "at the friction limit: |τ| = μ·p at some increment of the cycle, "
                              "which a point reaches without sliding; what slid: cycles.png, the verdict's measure")
    codes = status[mesh.triangles].max(axis=1)
    mappable = ax.tripcolor(mesh, facecolors=codes.astype(float),
                            cmap=ListedColormap([colour for _, colour in STATUS]),
                            norm=BoundaryNorm(np.arange(len(STATUS) + 1) - 0.5, len(STATUS)), edgecolors="none")
    bar = _colour_bar(fig, ax, mappable, wide, "contact status over the cycle", a, b, ticks=range(len(STATUS)))
    bar.set_ticklabels([_wrap(name, 22) for name, _ in STATUS], fontsize=8)
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
    def status(self) -> np.ndarray | None:
        return _status(self.group, self.row)

    @property
    def name(self) -> str:
        """The state's legend entry."""
        return "end of run" if self.row is None else f"end of cycle {self.cycle} (last recorded)"

    @property
    def words(self) -> str:
        """Which state a title shows."""
        return "end of run" if self.row is None else f"end of cycle {self.cycle} (the last recorded)"


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
            figures = json.loads(file["summary"].attrs["figures"]) if "summary" in file else {}
            written.append(_cycles_plot(file["cycles"], title, out_dir, state.stop, figures))
    return written


def first_recorded_label(cycles) -> str:
    """What the first recorded cycle's fields are: the end of a COF-phase cycle, or, in a run
    whose wear phase starts at once, the state after its first wear block (which stands for
    the block's real cycles, e.g. 1000: not the unworn joint)."""
    cycle = int(cycles["fields/cycle"][0])
    numbers = list(cycles["cycle"][()])
    if cycle not in numbers:
        return f"end of cycle {cycle}"
    row = numbers.index(cycle)
    phase, real = cycles["phase"][row], float(cycles["equivalent_cycles"][row])
    if phase != 2:
        return f"end of cycle {cycle}"
    first_block = not np.any(cycles["phase"][:row] == 2)
    where = "after the first wear block" if first_block else f"end of wear block {cycle}"
    return f"{where} ({real:,.0f} real cycles)"


def _line_fields(file, state: Drawn, coordinates, title, out_dir) -> Path:
    """2D scenes: every field of the drawn state along the contact, pressure and shear of the
    first recorded cycle too; where a field means nothing (open points), a gap."""
    fields = state.fields(2)
    status = state.status
    law = cof_range(file)
    order = np.argsort(coordinates[:, 0])
    x = coordinates[order, 0]
    fig, axes = _stacked(len(fields))
    first = file["cycles/fields"]
    for ax, field in zip(axes, fields.values()):
        values = field.shown.copy()
        open_points = _open_where(field, status)
        if open_points is not None:
            values[open_points] = np.nan
        _panel(ax, field, x, values[order], law, lw=1.4, label=state.name)
        if field.name in ("pressure", "shear") and field.name in first:
            initial = first[field.name][0]
            if field.name == "shear":
                initial = np.linalg.norm(initial.reshape(initial.shape[0], -1), axis=1)
            ax.plot(x, initial[order], "--", lw=1.0, label=first_recorded_label(file["cycles"]))
            ax.legend(fontsize=7)
        if field.name == "wear_depth" and state.row is None and "master_wear_depth" in state.group:
            _master_profile(ax, file)
    fig.align_ylabels(axes)
    axes[-1].set_xlabel("position along the contact x [mm]")
    words = "" if state.row is None else f", {state.words}"
    _suptitle(fig, f"{title}: interface fields{words}", state.stop)
    return _save(fig, out_dir / "fields.png")


def _master_profile(ax, file) -> None:
    """Finite sliding: the master's own wear depth along its own surface, beside the points'
    gap (the master's depth read at their current partners), which misses the scar they left."""
    x = file["master_surface/coordinates"][()][:, 0]
    order = np.argsort(x)
    ax.lines[0].set_label("end of run, at the points (both bodies)")
    depth = file["final/master_wear_depth"][()] * QUANTITIES["wear_depth"].scale
    ax.plot(x[order], depth[order], "--", lw=1.0, label="master's own surface (its depth alone)")
    ax.legend(fontsize=7)


def _surface_maps(file, state: Drawn, coordinates, title, out_dir) -> list[Path]:
    """3D scenes: the path plot, a map per field of the drawn state and of its status, and the
    maps after the COF phase."""
    fields = state.fields(3)
    status = state.status
    law = cof_range(file)
    a, b = _plane_axes(coordinates)
    facets = file["points/facets"][()] if "points/facets" in file else None
    # Triangles of the interface's own facets: holes (a bolt hole) stay holes.
    triangles = None if facets is None else (
        facets if facets.shape[1] == 3 else np.concatenate([facets[:, [0, 1, 2]], facets[:, [0, 2, 3]]]))
    mesh = matplotlib.tri.Triangulation(coordinates[:, a], coordinates[:, b], triangles)
    written = [_path_plot(mesh, fields, a, b, title, out_dir, state, law, status)]
    for name, field in fields.items():
        written.append(_map(mesh, field, a, b, f"{title}: {field.quantity.words}, {state.words}",
                            out_dir / f"{name}_map.png", state.stop, law=law, status=status))
    if status is not None:
        written.append(_status_map(mesh, status, a, b, f"{title}: contact status over the cycle, {state.words}",
                                   out_dir / "status_map.png", state.stop))
    # the stabilised state before the wear phase (the paper's Figs. 8, 15 and 16a-b)
    phase_of = dict(zip(file["cycles/cycle"][()], file["cycles/phase"][()]))
    recorded = file["cycles/fields/cycle"][()] if "cycles/fields/cycle" in file else np.zeros(0, int)
    cof_rows = [k for k, c in enumerate(recorded) if phase_of.get(c) == 1]
    if cof_rows and any(p == 2 for p in phase_of.values()):
        row = cof_rows[-1]
        at_row = _fields(file["cycles/fields"], 3, row)
        status_at_row = _status(file["cycles/fields"], row)
        for name in ("cof", "slip_range", "max_utilised_cof", "dissipation_in_cycle"):
            field = at_row[name]
            written.append(_map(mesh, field, a, b,
                                f"{title}: {field.quantity.words}, end of the COF phase (cycle {recorded[row]})",
                                out_dir / f"{name}_map_end_of_cof_phase.png", state.stop, law=law,
                                status=status_at_row))
    return written


def clamp_loss_percent(force: np.ndarray, figures: dict) -> tuple[np.ndarray, float]:
    """The clamp force's loss (% of the initial clamp, positive: lost) over the cycles, and the
    initial clamp (N): the summary's ``bolt_force_initial_N``, else the first cycle's force."""
    initial = figures.get("bolt_force_initial_N")
    if initial is None or not np.isfinite(initial) or initial <= 0.0:
        initial = float(force[np.isfinite(force)][0])
    return 100.0 * (initial - force) / initial, float(initial)


def _cycle_axis(ax, equivalent: np.ndarray) -> None:
    """Real cycles on a log axis when they span a factor LOG_SPAN or more (150 COF cycles and
    millions of wear cycles, as on an S-N plot), else a linear axis of whole cycles."""
    positive = equivalent[equivalent > 0]
    if positive.size and positive.max() >= LOG_SPAN * positive.min():
        ax.set_xscale("log")
    else:
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        _plain(ax.xaxis)


def _area_panel(ax, figures, equivalent: np.ndarray) -> None:
    """The area fractions, each in its own line style and marker so that coinciding ones stay
    visible; those zero throughout are named in the legend instead of drawn."""
    zero = []
    for k, (key, name) in enumerate(AREA_LABELS.items()):
        if key not in figures:
            continue
        values = figures[key][()]
        if not np.any(values):
            zero.append(name)
            continue
        style, marker = AREA_STYLES[k % len(AREA_STYLES)]
        ax.plot(equivalent, values, linestyle=style, marker=marker, markersize=4, markerfacecolor="none",
                markevery=(0.1 * k / len(AREA_LABELS), 0.1), label=name, color=f"C{k}")
    if zero:
        ax.plot([], [], " ", label=_wrap("zero throughout: " + ", ".join(zero), 42))
    ax.set_ylabel("area / nominal area [-]")
    # above 1 where wear or a moving patch brings points beyond the preload's area into contact
    largest = max((np.nanmax(figures[key][()], initial=0.0) for key in AREA_LABELS if key in figures), default=1.0)
    ax.set_ylim(-0.03, 1.03 * max(1.0, largest))
    ax.grid(alpha=0.3)


def _clamp_panel(ax, force: np.ndarray, equivalent: np.ndarray, figures: dict, single: dict) -> None:
    """The clamp force's loss in % of the initial clamp, from 0 (at least 0 … 1 %, so that a
    steady force reads steady), and the force itself in kN on the right."""
    loss, initial = clamp_loss_percent(force, figures)
    ax.plot(equivalent, loss, color="k", **single)
    ax.set_ylabel(textwrap.fill(f"clamp force loss [% of the initial {initial / 1000.0:.4g} kN]", 30))
    low, high = np.nanmin(loss), np.nanmax(loss)
    top = max(1.0, 1.1 * high)
    ax.set_ylim(min(-0.03 * top, 1.1 * low), top)  # a steady force's line clear of the axis
    _plain(ax.yaxis)
    kilonewton = initial / 1000.0
    right = ax.secondary_yaxis("right", functions=(lambda p: kilonewton * (1.0 - p / 100.0),
                                                   lambda f: 100.0 * (1.0 - f / kilonewton)))
    right.set_ylabel("clamp (bolt) force [kN]")
    _plain(right.yaxis)
    final = loss[np.isfinite(loss)][-1]
    ax.text(0.01, 0.95, f"final loss {final:.3g} %", transform=ax.transAxes, va="top", fontsize=8,
            bbox={"facecolor": "white", "edgecolor": "0.7", "alpha": 0.9})
    ax.grid(alpha=0.3)


def _wear_panel(ax, depth_mm: np.ndarray, equivalent: np.ndarray, single: dict) -> None:
    scale = QUANTITIES["wear_depth"].scale
    ax.plot(equivalent, depth_mm * scale, color="tab:brown", **single)
    ax.set_ylabel(textwrap.fill("max wear depth (both bodies) [µm]", 24))
    ax.set_ylim(bottom=0.0)
    _plain(ax.yaxis)
    ax.grid(alpha=0.3)


def _cycles_plot(cycles, title, out_dir, stop: str | None = None, figures: dict | None = None) -> Path:
    """Area fractions, the clamp force's loss and the deepest wear over the real load cycles,
    the wear phase marked, the verdict's moments (``figures``, the summary's: shakedown,
    loosening evident) marked and named, and the end of the last converged cycle of a run that
    stopped early (``stop``: how).

    The axis is the equivalent real cycles: the COF phase counts one real cycle per simulated
    one, each wear block stands for as many as its (adaptive) jump (:func:`_cycle_axis`).
    """
    figures = figures or {}
    history = cycles["figures"]
    phase = cycles["phase"][()]
    equivalent = cycles["equivalent_cycles"][()]
    clamp = history["clamp_force_N"][()] if "clamp_force_N" in history else None
    has_clamp = clamp is not None and np.any(np.isfinite(clamp))
    depth = history["max_wear_depth_mm"][()] if "max_wear_depth_mm" in history else None
    has_wear = depth is not None and np.nanmax(depth, initial=0.0) > 0.0
    count = 1 + has_clamp + has_wear
    fig, axes = plt.subplots(count, 1, figsize=(9, 1.2 + 2.2 * count), sharex=True, layout="constrained")
    axes = np.atleast_1d(axes)
    single = {"marker": "o"} if equivalent.size == 1 else {}  # a line through one point draws nothing
    _area_panel(axes[0], history, equivalent)
    if has_clamp:
        _clamp_panel(axes[1], clamp, equivalent, figures, single)
    if has_wear:
        _wear_panel(axes[-1], depth, equivalent, single)
    _cycle_axis(axes[-1], equivalent)
    wear = np.flatnonzero(phase == 2)
    label = "equivalent real load cycles [-]"
    if wear.size and wear[0] > 0:
        start = equivalent[wear[0] - 1]
        for ax in axes:
            ax.axvline(start, color="grey", ls="--", lw=0.8)
        axes[0].text(start, 1.0, " wear phase", transform=axes[0].get_xaxis_transform(),
                     va="bottom", fontsize=7, color="grey")
        label += f"; wear phase after {start:,.0f}: {wear.size} blocks to {equivalent[-1]:,.0f} cycles"
    elif wear.size:
        label += f"; wear phase throughout: {wear.size} blocks to {equivalent[-1]:,.0f} cycles"
    for key, (words, colour, style) in MOMENTS.items():
        at = figures.get(key)
        if at is not None and np.isfinite(at):
            for ax in axes:
                ax.axvline(at, color=colour, ls=style, lw=1.4)
            axes[0].lines[-1].set_label(f"{words} at {at:,.0f} real cycle{'s' if at != 1 else ''}")
    if stop is not None:
        for ax in axes:
            ax.axvline(equivalent[-1], color="firebrick", lw=1.0)
        axes[0].text(equivalent[-1], 1.0, "stopped ", transform=axes[0].get_xaxis_transform(),
                     ha="right", va="bottom", fontsize=7, color="firebrick")
    # beside the axes: the areas fill the whole plot over a run, and a legend inside hid them
    axes[0].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    axes[-1].set_xlabel(label)
    _suptitle(fig, f"{title}: contact condition over cycles", stop)
    return _save(fig, out_dir / "cycles.png")
