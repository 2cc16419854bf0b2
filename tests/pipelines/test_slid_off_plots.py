"""A run whose joint slides off (tangential equilibrium lost) still draws what converged: the
fields of its last recorded cycle and the cycle history up to the failure, each figure saying
in which cycle the run stopped and why; its results file stays marked as a run that stopped
early (no final fields, no verdict) and keeps the failure's message.

The coarse cylinder on plane (plane strain, P = 1066 N/mm, μ = 0.56: friction carries
Q = μP = 597 N/mm) under a tangential force of 1000 N/mm brought in over six COF cycles (the
vibration run-up): the amplitude of cycle k is k/6 · 1000 N/mm, 500 in cycle 3 and 667 in
cycle 4, so the joint slides off in cycle 4 after three complete cycles.
"""

import html

import h5py
import numpy as np
import pytest

from pipelines.cli.main import main
from pipelines.output import plots
from pipelines.output.report import write_report
from tests.pipelines.test_plot_layout import _layout_problems

FORCE = '[[loads]]\nname = "tangential"\ndof = "cylinder.rp.ux"\nvalue = 1000.0'
MOTION = '[[motions]]\nname = "tangential"\ndof = "cylinder.rp.ux"\nvalue = 0.107'


@pytest.fixture
def drawn(monkeypatch):
    """The figures plot_results saves, by file name: their titles and layout problems."""
    figures, original = {}, plots._save

    def keep_then_save(fig, target):
        titles = [fig._suptitle.get_text() if fig._suptitle else ""] + [ax.get_title() for ax in fig.axes]
        figures[target.name] = (" ".join(" ".join(titles).split()), _layout_problems(fig))  # wrapping aside
        return original(fig, target)

    monkeypatch.setattr(plots, "_save", keep_then_save)
    return figures


def _sliding_scene(coarse_cylinder, run_up: int):
    text = coarse_cylinder.read_text()
    assert MOTION in text and "cof_cycles = 0" in text
    text = text.replace(MOTION, FORCE).replace("cof_cycles = 0", f"cof_cycles = 6\nvibration_run_up = {run_up}")
    coarse_cylinder.write_text(text)
    return coarse_cylinder


def test_a_run_that_slides_off_draws_its_last_converged_cycle(coarse_cylinder, tmp_path, drawn, capsys):
    out = tmp_path / "out"
    assert main(["run", str(_sliding_scene(coarse_cylinder, 6)), "--out", str(out), "--quiet"]) == 1
    assert "marked 'slid_off'" in capsys.readouterr().err
    with h5py.File(out / "results.h5") as results:
        assert results.attrs["ending"] == "slid_off" and "tangential equilibrium is lost" in results.attrs[
            "ending_message"]
        assert "final" not in results and "summary" not in results  # no verdict: the run did not end
        assert list(results["cycles/cycle"][()]) == [1, 2, 3]
        # the slip zones at the contact's edges grew with the force until friction gave way
        assert np.all(np.diff(results["cycles/figures/slip_area_fraction"][()]) > 0)
    assert sorted(p.name for p in (out / "plots").iterdir()) == ["cycles.png", "fields.png"]
    stop = "the run stopped in cycle 4: the joint slides off"
    assert set(drawn) == {"cycles.png", "fields.png"}
    assert all(stop in titles for titles, _ in drawn.values()), drawn
    assert "cycle 3 (the last recorded)" in drawn["fields.png"][0]
    assert {name: problems for name, (_, problems) in drawn.items() if problems} == {}
    page = html.unescape(write_report(out).read_text())  # the page shows why, and the plots
    assert "<p>why: " in page and "tangential equilibrium is lost" in page
    assert "plots/cycles.png" in page and "plots/fields.png" in page


def test_a_run_that_slides_off_in_its_first_cycle_has_nothing_to_draw(coarse_cylinder, tmp_path, drawn, capsys):
    """At full amplitude from the first cycle no cycle ends: no plots, and no empty folder."""
    out = tmp_path / "out"
    assert main(["run", str(_sliding_scene(coarse_cylinder, 0)), "--out", str(out), "--quiet"]) == 1
    assert "marked 'slid_off'" in capsys.readouterr().err
    with h5py.File(out / "results.h5") as results:
        assert results.attrs["ending"] == "slid_off" and "cycles/cycle" not in results
    assert drawn == {} and not (out / "plots").exists()


def test_the_maps_of_a_run_that_slid_off_in_its_wear_phase_say_so(tmp_path, drawn):
    """A 3D run's figures (maps, path, cycles with the clamp force) from its last recorded
    cycle, the state after the COF phase too; every title says where the run stopped."""
    from tests.pipelines.test_plot_layout import _grid, _results

    points, facets = _grid(260.0, 80.0)
    path = _results(tmp_path / "r.h5", points, facets, 1e-3 * np.ones(len(points)))
    with h5py.File(path, "a") as results:  # as ResultsWriter.stop leaves a run that slid off
        del results["final"], results["summary"]
        results.attrs.update(complete=True, ending="slid_off", ending_message="tangential equilibrium is lost")
    written = plots.plot_results(path, tmp_path / "plots")
    assert {"pressure_map.png", "path.png", "cycles.png", "cof_map_end_of_cof_phase.png"} <= set(drawn)
    assert len(written) == len(drawn)
    assert all("the run stopped in cycle 6: the joint slides off" in titles for titles, _ in drawn.values())
    assert "contact pressure p, end of cycle 3 (the last recorded)" in drawn["pressure_map.png"][0]
    assert {name: problems for name, (_, problems) in drawn.items() if problems} == {}


def test_a_stopped_run_still_answers_json(coarse_cylinder, tmp_path, capsys):
    """`run --json` of a run that stops prints how it ended, so a script gets valid JSON (QA: it
    printed nothing)."""
    import json

    out = tmp_path / "out"
    assert main(["run", str(_sliding_scene(coarse_cylinder, 6)), "--out", str(out), "--quiet", "--json"]) == 1
    printed = json.loads(capsys.readouterr().out)
    assert printed["verdict"] is None and printed["ending"] == "slid_off"
    assert "tangential equilibrium is lost" in printed["error"] and printed["out"] == str(out)
