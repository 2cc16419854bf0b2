"""The run plots read as physics (QA's review of every plot): a COF on the law's μ0 … μ_max, a
field of negligible spread drawn flat, wear and slip in µm, points out of contact grey, and
the cycles plot marking shakedown and loosening on an axis that suits the run's length."""

import json

import h5py
import matplotlib.pyplot as plt
import numpy as np
import pytest

from pipelines.output import plots
from tests.pipelines.test_plot_layout import _grid, _results

LAW = '[contact]\ncof_initial = 0.2\ncof_max = 0.7\n'


@pytest.fixture
def drawn(monkeypatch):
    """The figures plot_results saves, by file name (closed by the test's end)."""
    figures = {}

    def keep(fig, target):
        figures[target.name] = fig
        return target

    monkeypatch.setattr(plots, "_save", keep)
    yield figures
    for fig in figures.values():
        plt.close(fig)


def _bar_limits(fig) -> tuple[float, float]:
    """The colour bar's value range (the bar lies under a wide map)."""
    bar = fig.axes[1]
    return bar.get_xlim() if bar.get_xlim() != (0.0, 1.0) else bar.get_ylim()


def _run(tmp_path, edit=None, summary=None):
    """A wide 3D results file (test_plot_layout's) run with μ0 = 0.2, μ_max = 0.7, edited by ``edit``."""
    points, facets = _grid(260.0, 80.0)
    path = _results(tmp_path / "r.h5", points, facets, 1e-3 * np.ones(len(points)))
    with h5py.File(path, "a") as file:
        file.attrs["scene_toml"] = LAW
        if summary is not None:
            file["summary"].attrs["figures"] = json.dumps(summary)
        if edit is not None:
            edit(file, points)
    return path


def test_a_cof_that_barely_moved_is_drawn_on_the_laws_scale(tmp_path, drawn):
    """The counterweight's COF, 0.200000 … 0.202679 with μ0 = 0.2, μ_max = 0.7: the bar spans
    the law's 0.2 … 0.7, not the field's 0.2 … 0.2027, and the title says nothing evolved
    (the verdict's threshold, μ0 + 1 % of μ_max − μ0 = 0.205)."""
    def barely(file, points):
        del file["final/cof"]
        file["final/cof"] = 0.2 + 0.002679 * np.abs(points[:, 0]) / np.abs(points[:, 0]).max()

    plots.plot_results(_run(tmp_path, barely), tmp_path / "plots")
    fig = drawn["cof_map.png"]
    assert _bar_limits(fig) == pytest.approx((0.2, 0.7))
    assert "nowhere evolved" in fig.axes[0].get_title() and "0.205" in fig.axes[0].get_title()
    assert all(len(t.get_text()) <= 4 for t in fig.axes[1].get_xticklabels() if t.get_text())  # 0.2, 0.45
    # the helper itself: a COF on the law's scale, any other field on its own
    cof = plots.Field("cof", np.array([0.2, 0.2027]))
    assert plots.colour_limits(cof, (0.2, 0.7)) == (0.2, 0.7)
    assert plots.colour_limits(plots.Field("pressure", np.array([3.0, 8.0])), (0.2, 0.7)) == (3.0, 8.0)


def test_a_field_of_negligible_spread_is_drawn_flat_and_said_uniform(tmp_path, drawn):
    """A pressure of 50 MPa ± 1e-9 is one value: one colour, "uniform: 50 MPa" in the title."""
    def flat(file, points):
        del file["final/pressure"]
        file["final/pressure"] = 50.0 + 1e-9 * np.sin(points[:, 0])

    plots.plot_results(_run(tmp_path, flat), tmp_path / "plots")
    fig = drawn["pressure_map.png"]
    assert "uniform: 50 MPa everywhere" in fig.axes[0].get_title()
    drawn_values = np.asarray(fig.axes[0].collections[0].get_array())
    assert np.ptp(drawn_values) == 0.0


def test_wear_and_slip_are_drawn_in_micrometres(tmp_path, drawn):
    """Wear depth (both bodies) and slip range: bars labelled µm, spanning 1e3 × the stored mm."""
    plots.plot_results(_run(tmp_path), tmp_path / "plots")
    with h5py.File(tmp_path / "r.h5") as file:
        wear = file["final/wear_depth"][()].sum(axis=0)
        slip = file["final/slip_range"][()]
    for name, stored in (("wear_depth", wear), ("slip_range", slip)):
        fig = drawn[f"{name}_map.png"]
        assert fig.axes[1].get_xlabel().endswith("[µm]"), name
        if np.ptp(stored) > 0:
            assert _bar_limits(fig)[1] == pytest.approx(1e3 * stored.max(), rel=1e-9), name
        else:
            assert f"uniform: {1e3 * stored[0]:.6g} µm" in fig.axes[0].get_title(), name
    wear_panel = next(ax for ax in drawn["path.png"].axes if "wear depth" in ax.get_ylabel())
    assert "µm" in wear_panel.get_ylabel()
    assert np.nanmax(wear_panel.lines[0].get_ydata()) == pytest.approx(1e3 * wear.max(), rel=1e-6)


def test_points_open_over_the_cycle_are_grey_not_zero(tmp_path, drawn):
    """A corner of the interface open over the whole cycle: its utilised COF (0 there, as a
    stuck point's) is not on the colour scale, which spans the closed points only; the map says
    which points are grey, and a status map is drawn."""
    def corner_open(file, points):
        status = np.where((points[:, 0] < -60.0) & (points[:, 2] < -20.0), 0, 1)
        utilised = np.where(status == 0, 0.0, 0.3 + 0.1 * points[:, 0] / 130.0)
        del file["final/max_utilised_cof"]
        file["final/max_utilised_cof"] = utilised
        file["final/status"] = status

    plots.plot_results(_run(tmp_path, corner_open), tmp_path / "plots")
    fig = drawn["max_utilised_cof_map.png"]
    assert "grey: open over the whole cycle" in fig.axes[0].get_title()
    low, high = _bar_limits(fig)
    with h5py.File(tmp_path / "r.h5") as file:
        closed = file["final/max_utilised_cof"][()][file["final/status"][()] == 1]
    assert (low, high) == pytest.approx((closed.min(), closed.max())) and low > 0.1
    assert "status_map.png" in drawn
    labels = [t.get_text() for t in drawn["status_map.png"].axes[1].get_xticklabels()]
    # the CLI's and the report's words: a point at the friction limit need not move ("slip" is
    # what an Abaqus user reads as CSTATUS slip)
    assert [label.replace("\n", " ") for label in labels] == [
        "open", "stick", "at the friction limit (|τ| = μp)", "at the friction limit with μ = μ_max"]
    assert not any("slip" in label for label in labels)


@pytest.mark.parametrize("width", range(8, 60))
def test_titles_keep_their_phrases_on_one_line(width):
    """A title wrapped to any width breaks between words but never inside "end of run" (QA: the
    FFDP map's title read "end of / run") nor "at the friction limit"."""
    text = "counterweight: fretting fatigue FFDP $\\sigma_t$, end of run, at the friction limit"
    lines = plots._wrap(text, width).split("\n")
    assert " ".join(lines) == text
    assert any("end of run" in line for line in lines)
    assert any("at the friction limit" in line for line in lines)


def _cycles(tmp_path, monkeypatch, real, phase, figures, clamp=None, depth=None):
    """The figure _cycles_plot draws of these cycles and summary ``figures``."""
    kept = []
    monkeypatch.setattr(plots, "_save", lambda fig, target: kept.append(fig) or target)
    with h5py.File(tmp_path / "cycles.h5", "w") as file:
        cycles = file.create_group("cycles")
        cycles["phase"] = np.asarray(phase)
        cycles["equivalent_cycles"] = np.asarray(real, dtype=float)
        cycles["figures/stick_area_fraction"] = np.linspace(0.8, 0.4, len(real))
        cycles["figures/slip_area_fraction"] = np.linspace(0.2, 0.6, len(real))
        cycles["figures/worn_area_fraction"] = np.zeros(len(real))
        if clamp is not None:
            cycles["figures/clamp_force_N"] = np.asarray(clamp)
        if depth is not None:
            cycles["figures/max_wear_depth_mm"] = np.asarray(depth)
        plots._cycles_plot(cycles, "test", tmp_path, None, figures)
    return kept[0]


def test_the_cycles_plot_marks_loosening_and_shakedown(tmp_path, monkeypatch):
    """double_beam_high_slip ends LOOSENING with loosening_evident_at_cycles = 100100: a line
    there on every panel, named in the legend; a shakedown likewise."""
    real = np.r_[1.0:101.0, 100.0 + 1e4 * np.arange(1, 11)]
    phase = np.r_[np.ones(100), 2 * np.ones(10)].astype(int)
    clamp = 20000.0 * (1.0 - 0.018 * np.linspace(0.0, 1.0, real.size) ** 4)
    summary = {"loosening_evident_at_cycles": 100100.0, "shakedown_at_cycles": 50.0, "bolt_force_initial_N": 20000.0}
    fig = _cycles(tmp_path, monkeypatch, real, phase, summary, clamp, 3.4e-3 * np.linspace(0, 1, real.size))
    assert len(fig.axes) >= 3 and fig.axes[0].get_xscale() == "log"
    for ax in (a for a in fig.axes if a.get_xscale() == "log"):  # the panels, not the kN axis
        verticals = {float(line.get_xdata()[0]) for line in ax.lines
                     if len(line.get_xdata()) == 2 and np.ptp(line.get_xdata()) == 0}
        assert {100100.0, 50.0} <= verticals
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "loosening evident at 100,100 real cycles" in legend and "shakedown at 50 real cycles" in legend
    assert "zero throughout: worn" in legend  # drawn as a word, not a line hidden under others
    plt.close(fig)


def test_a_short_run_has_a_linear_cycle_axis_and_its_wear_against_cycles(tmp_path, monkeypatch):
    """gross_slip_fretting: two cycles, no bolt: whole cycles on a linear axis, and the deepest
    wear in µm against them."""
    fig = _cycles(tmp_path, monkeypatch, [1.0, 2.0], [2, 2], {}, clamp=np.full(2, np.nan), depth=[2.3e-5, 4.6e-5])
    assert len(fig.axes) == 2 and fig.axes[-1].get_xscale() == "linear"
    assert "µm" in fig.axes[1].get_ylabel()
    assert np.allclose(fig.axes[1].lines[0].get_ydata(), [0.023, 0.046])
    plt.close(fig)


def test_the_first_recorded_state_of_a_run_worn_from_the_start_is_said_to_be_worn(tmp_path):
    """cylinder_on_plane: its first recorded cycle is a wear block of 1000 real cycles, not the
    unworn contact."""
    with h5py.File(tmp_path / "c.h5", "w") as file:
        cycles = file.create_group("cycles")
        cycles["cycle"], cycles["phase"] = np.arange(1, 4), np.full(3, 2)
        cycles["equivalent_cycles"] = 1000.0 * np.arange(1, 4)
        cycles["fields/cycle"] = np.arange(1, 4)
        assert plots.first_recorded_label(cycles) == "after the first wear block (1,000 real cycles)"
        cycles["phase"][...] = 1
        assert plots.first_recorded_label(cycles) == "end of cycle 1"


def test_the_ffdp_label_is_mathtext():
    """σ_t is typeset as a subscript, not drawn as "σ_t" with an underscore."""
    from matplotlib.mathtext import MathTextParser

    label = plots.QUANTITIES["ffdp"].label
    assert r"$\sigma_t" in label and "σ_t" not in label
    MathTextParser("agg").parse(label[label.index("$"):label.rindex("$") + 1])
