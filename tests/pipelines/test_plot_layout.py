"""The figures of a results file: every label inside the figure and clear of the others, and a
field that is the solver's round-off drawn as zero, not as a pattern."""

import json
from itertools import combinations

import h5py
import numpy as np
import pytest
from matplotlib.text import Text

from contact.solver import NewtonSettings
from pipelines.output import plots

DELTA = NewtonSettings().displacement_tolerance  # mm, the kinematics Newton resolves


def _grid(width: float, height: float, n: int = 9):
    """A flat contact of width × height mm in the x-z plane: points and quadrilateral facets."""
    x, z = np.meshgrid(np.linspace(-width / 2, width / 2, n), np.linspace(-height / 2, height / 2, n))
    points = np.column_stack([x.ravel(), np.zeros(x.size), z.ravel()])
    corners = np.arange(n * n).reshape(n, n)[:-1, :-1].ravel()
    return points, np.column_stack([corners, corners + 1, corners + n + 1, corners + n])


def _fields(x: np.ndarray, slip: np.ndarray, dimension: int) -> dict:
    """Final fields of a joint with a pressure hump and the given slip range (mm)."""
    pressure = 200.0 * (1.0 - (x / (1.2 * np.abs(x).max())) ** 2)
    shear = 0.2 * pressure
    tangential = 100.0 + 0.0 * x
    fdp = shear * 0.5 * slip
    return {"pressure": pressure, "shear": np.tile(shear[:, None], (1, dimension - 1)) / np.sqrt(dimension - 1),
            "cof": 0.2 + 0.0 * x, "max_utilised_cof": shear / pressure, "slip_range": slip,
            "dissipation_in_cycle": 2.0 * shear * slip, "wear_depth": np.vstack([slip, slip]) * 1e-2,
            "fdp": fdp, "ffdp": tangential * fdp, "max_shear": shear, "surface_tangential_stress": tangential}


def _results(path, coordinates, facets, slip):
    """A results file of a run with a COF phase (cycles 1-3, fields recorded at 2 and 3) and a
    wear phase (cycles 4-5), the clamp force falling; final fields as :func:`_fields`."""
    dimension = coordinates.shape[1]
    final = _fields(coordinates[:, 0], slip, dimension)
    with h5py.File(path, "w") as file:
        file.attrs["scene_name"] = "layout"
        file["points/coordinates"] = coordinates
        if facets is not None:
            file["points/facets"] = facets
        for name, value in final.items():
            file[f"final/{name}"] = value
            file[f"cycles/fields/{name}"] = np.stack([value, value])
        file["cycles/fields/cycle"] = np.array([2, 3])
        file["cycles/cycle"] = np.arange(1, 6)
        file["cycles/phase"] = np.array([1, 1, 1, 2, 2])
        file["cycles/equivalent_cycles"] = np.array([1.0, 2.0, 3.0, 1e3, 1e6])
        for key in plots.AREA_LABELS:
            file[f"cycles/figures/{key}"] = np.linspace(0.2, 0.8, 5)
        file["cycles/figures/clamp_force_N"] = np.linspace(4.0e5, 3.9e5, 5)
        file.create_group("summary").attrs["figures"] = json.dumps({})
    return path


def _overlap(one, other) -> bool:
    return (one.x0 < other.x1 - 0.5 and other.x0 < one.x1 - 0.5
            and one.y0 < other.y1 - 0.5 and other.y0 < one.y1 - 0.5)


def _tick_labels(fig) -> dict[int, bool]:
    """Every tick label of the figure (by id): whether it is drawn, its tick within the view
    limits (locators place ticks beyond them, which are not drawn)."""
    drawn = {}
    for axis in [axis for ax in fig.axes for axis in (ax.xaxis, ax.yaxis)]:
        low, high = sorted(axis.get_view_interval())
        for tick in axis.get_major_ticks() + axis.get_minor_ticks():
            inside = low - 1e-9 * (high - low) <= tick.get_loc() <= high + 1e-9 * (high - low)
            drawn |= {id(tick.label1): inside, id(tick.label2): inside}
    return drawn


def _layout_problems(fig) -> list[str]:
    """Every visible text drawn by the Agg renderer: outside the figure, or overlapping another."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    ticks = _tick_labels(fig)
    texts = [t for t in fig.findobj(Text) if t.get_visible() and t.get_text().strip() and ticks.get(id(t), True)]
    boxes = [(t.get_text(), t.get_window_extent(renderer)) for t in texts]
    problems = [f"{text!r} leaves the figure: {box} in {fig.bbox}" for text, box in boxes
                if box.x0 < -0.5 or box.y0 < -0.5 or box.x1 > fig.bbox.x1 + 0.5 or box.y1 > fig.bbox.y1 + 0.5]
    problems += [f"{a!r} overlaps {b!r}" for (a, one), (b, other) in combinations(boxes, 2) if _overlap(one, other)]
    return problems


@pytest.fixture
def drawn(monkeypatch):
    """The figures plot_results saves, by file name, each checked for its layout before saving."""
    figures, original = {}, plots._save

    def check_then_save(fig, target):
        figures[target.name] = (fig, _layout_problems(fig), [ax.get_title() for ax in fig.axes])
        return original(fig, target)

    monkeypatch.setattr(plots, "_save", check_then_save)
    return figures


@pytest.mark.parametrize("width, height", [(260.0, 80.0), (40.0, 160.0)], ids=["wide", "tall"])
def test_every_label_of_a_3d_run_lies_inside_its_figure_and_apart(tmp_path, drawn, width, height):
    """The counterweight's pads (wide) and a tall interface: the maps' colour-bar labels (the
    longest, FFDP's, with its units), the stacked path panels' labels and the titles are whole
    and overlap nothing."""
    points, facets = _grid(width, height)
    written = plots.plot_results(_results(tmp_path / "r.h5", points, facets, 1e-3 * np.ones(len(points))),
                                 tmp_path / "plots")
    assert {"ffdp_map.png", "path.png", "cycles.png", "slip_range_map_end_of_cof_phase.png"} <= set(drawn)
    assert len(written) == len(drawn)
    assert {name: problems for name, (_, problems, _) in drawn.items() if problems} == {}


def test_every_label_of_a_2d_run_lies_inside_its_figure_and_apart(tmp_path, drawn):
    """Nine stacked profiles of a 2D contact: FDP's and FFDP's labels, the suptitle and the top
    panel's legend apart."""
    x = np.linspace(-2.5, 2.5, 41)
    plots.plot_results(_results(tmp_path / "r.h5", np.column_stack([x, 0.0 * x]), None, 0.1 + 0.0 * x),
                       tmp_path / "plots")
    assert set(drawn) == {"fields.png", "cycles.png"}
    assert {name: problems for name, (_, problems, _) in drawn.items() if problems} == {}


def test_a_stuck_joints_round_off_is_zero_and_a_micro_slip_is_not():
    """A stuck joint's slip range (2e-11 mm: below δ, Newton's resolution) and the FDP, FFDP and
    dissipation it drives are zero; a micro-slip of 1e-6 mm (a thousandth of a typical γ_crit)
    and its FDP are a field. The bounds follow the field's own stresses, not one number."""
    x = np.linspace(-1.0, 1.0, 50)
    noise = 2e-11 * np.abs(np.sin(7.0 * x))
    state = {name: value for name, value in _fields(x, noise, 3).items() if name != "shear"}
    state["shear"] = state["max_shear"]
    floors = plots.round_off(state, 3)
    assert floors["slip_range"] == pytest.approx(2.0 * np.sqrt(2.0) * DELTA)
    assert floors["fdp"] == pytest.approx(np.max(state["max_shear"]) * np.sqrt(2.0) * DELTA)
    assert floors["ffdp"] == pytest.approx(100.0 * floors["fdp"])
    for name in ("slip_range", "fdp", "ffdp", "dissipation_in_cycle", "wear_depth"):
        stuck = plots.Field(name, state[name], floors[name])
        assert stuck.is_zero and not stuck.shown.any(), name
    note = plots.Field("slip_range", noise, floors["slip_range"]).note()
    assert note.startswith(f"no slip (max {1e3 * noise.max():.2g} µm, round-off below")  # drawn in µm
    sliding = _fields(x, 1e-6 + noise, 3)
    for name in ("slip_range", "fdp", "ffdp", "dissipation_in_cycle"):
        field = plots.Field(name, sliding[name], floors[name])
        drawn_values = sliding[name] * plots.QUANTITIES[name].scale
        assert not field.is_zero and field.note() is None and np.array_equal(field.shown, drawn_values), name
    # a joint under a hundredth of the stresses resolves a hundredth of the FDP
    low = {name: value / 100.0 if name in ("max_shear", "shear") else value for name, value in state.items()}
    assert plots.round_off(low, 3)["fdp"] == pytest.approx(floors["fdp"] / 100.0)


def test_a_stuck_joints_maps_are_uniform_and_say_round_off(tmp_path, drawn):
    """The demo's case: slip range 2e-11 mm. Its map, and the FDP's, FFDP's and dissipation's,
    draw one colour (a single zero) and say so in the title; the pressure map stays a field."""
    points, facets = _grid(260.0, 80.0)
    slip = 2e-11 * np.abs(np.sin(points[:, 0]))
    plots.plot_results(_results(tmp_path / "r.h5", points, facets, slip), tmp_path / "plots")
    for name, word in [("slip_range", "no slip"), ("fdp", "no fretting damage"),
                       ("ffdp", "no fretting fatigue damage"), ("dissipation_in_cycle", "no frictional dissipation")]:
        fig, _, titles = drawn[f"{name}_map.png"]
        assert any(f"{word} (max" in title and "round-off" in title for title in titles), (name, titles)
        drawn_values = [c.get_array() for c in fig.axes[0].collections if c.get_array() is not None]
        assert drawn_values and all(np.all(np.asarray(v) == 0.0) for v in drawn_values), name
    _, _, titles = drawn["pressure_map.png"]
    assert not any("everywhere" in title or "round-off" in title for title in titles)
    fig, _, _ = drawn["path.png"]
    notes = [t.get_text() for t in fig.findobj(Text) if t.get_text().startswith("no slip (max")]
    assert len(notes) == 1


def _history(path, real, clamp):
    with h5py.File(path, "w") as file:
        file["cycles/equivalent_cycles"] = np.asarray(real, dtype=float)
        file["cycles/figures/clamp_force_N"] = np.asarray(clamp, dtype=float)
        file["cycles/figures/stick_area_fraction"] = np.linspace(0.5, 0.9, len(real))
    return str(path)


@pytest.mark.parametrize("evident", [None, 2e5], ids=["none loosened", "one loosened"])
def test_the_convergence_histories_legend_lists_only_what_is_drawn(tmp_path, monkeypatch, evident):
    from pipelines.studies import convergence

    legends, original = [], convergence._save

    def keep_legend(figure, axes, title, path):
        legends.append([text.get_text() for text in axes[0].get_legend().get_texts()])
        return original(figure, axes, title, path)

    monkeypatch.setattr(convergence, "_save", keep_legend)
    real = [1.0, 1e3, 1e5, 1e6]
    levels = [{"size_mm": 10.0, "points": 52, "verdict": "stick", "figures": {"loosening_evident_at_cycles": None},
               "extra": {"results": _history(tmp_path / "c.h5", real, [4e5, 4e5, 4e5, 4e5])}},
              {"size_mm": 5.0, "points": 158, "verdict": "loosening" if evident else "damage",
               "figures": {"loosening_evident_at_cycles": evident},
               "extra": {"results": _history(tmp_path / "f.h5", real, [4e5, 3.9e5, 3.5e5, 3e5])}}]
    assert convergence.plot_histories({"scene": "s.toml", "levels": levels}, tmp_path / "h.png").is_file()
    assert legends[0][:2] == ["10 mm (52 points): stick", f"5 mm (158 points): {levels[1]['verdict']}"]
    assert ("loosening evident" in legends[0]) == (evident is not None)
