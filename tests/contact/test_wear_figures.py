"""The run's wear figures count each body's own worn volume (contact.verdict.wear_figures).

In finite sliding each body's wear depth lives on its own surface (SPEC §4): the master's scar
reaches beyond the points' current partners by the stroke. examples/gross_slip_fretting.toml
(R = 80 mm, 1066 N/mm, Hertz a = 1.28 mm, energy wear w = 1e-8 cylinder, 3e-8 mm²/N flat)
driven by ±1.5 mm: a stroke of 3 mm, longer than the contact width 2a = 2.57 mm. Energy wear
removes w_i·|τ|·Δγ_sl of each body wherever the dissipation |τ|·Δγ_sl happens, so each body's
worn volume is w_i × the frictional dissipation D, and the run's ``wear_volume_mm3`` is their
sum, (w₁ + w₂)·D. The master's wear read at the points' partners (the gap) misses the part of
its scar the cylinder has left.
"""

from pathlib import Path

import numpy as np
import pytest

from contact.law import ContactState
from contact.sliding import worn_volumes
from contact.verdict import wear_figures
from pipelines import scene as scenes
from pipelines.build import build
from pipelines.jobs.validate import sliding_run
from reduction.threads import single_threaded_blas

SCENE = str(Path(__file__).resolve().parents[2] / "examples" / "gross_slip_fretting.toml")
STROKE = 1.5  # mm at the cylinder's reference point: 3 mm peak to peak, longer than 2a = 2.57 mm


def _state(slave, master_at_points):
    state = ContactState.initial(len(slave), 1, 0.5, n_wear_bodies=2)
    state.wear_depth[:] = [slave, master_at_points]
    return state


def test_fixed_pairing_counts_the_gap_at_the_points():
    """Small sliding: both depths of a point lie on top of each other, the gap is their sum."""
    area = np.array([0.1, 0.2, 0.1])
    state = _state([1e-4, 2e-4, 0.0], [3e-4, 1e-4, 1e-4])
    figures = wear_figures(area, state)
    assert figures["wear_volume_mm3"] == pytest.approx(0.1 * 4e-4 + 0.2 * 3e-4 + 0.1 * 1e-4, rel=1e-12)
    assert figures["max_wear_depth_mm"] == pytest.approx(4e-4, rel=1e-12)


def test_own_surfaces_count_each_body_alone():
    """Finite sliding: the master's own field on its own nodes, not its depth at the partners;
    the deepest wear where the scars overlap (the gap) or in either body's own field."""
    area = np.array([0.1, 0.2, 0.1])
    state = _state([1e-4, 2e-4, 0.0], [3e-5, 1e-5, 1e-5])
    master_wear, master_area = np.array([0.0, 5e-5, 1.5e-4, 5e-5]), np.array([0.1, 0.1, 0.1, 0.1])
    figures = wear_figures(area, state, master_wear, master_area)
    assert figures["wear_volume_mm3"] == pytest.approx(0.1 * 1e-4 + 0.2 * 2e-4 + 0.1 * 2.5e-4, rel=1e-12)
    assert figures["max_wear_depth_mm"] == pytest.approx(2.1e-4, rel=1e-12)  # overlapping at point 1
    left_behind = np.array([0.0, 5e-5, 3e-4, 5e-5])  # the master's scar where no point is now
    assert wear_figures(area, state, left_behind, master_area)["max_wear_depth_mm"] == 3e-4


def test_no_wear_no_figures():
    state = ContactState.initial(3, 1, 0.5)
    assert wear_figures(np.ones(3), state) == {"max_wear_depth_mm": 0.0, "wear_volume_mm3": 0.0}


@pytest.fixture(scope="module")
def long_stroke():
    with single_threaded_blas():
        model = build(scenes.load(SCENE, {"contact.sliding": "finite", "motions": [
            {"name": "tangential", "dof": "cylinder.rp.ux", "value": STROKE, "history": "cyclic"}]}))
        return (model, *sliding_run(model, "finite"))


def test_each_body_wears_its_coefficient_times_the_dissipation(long_stroke):
    model, solver, result, global_dissipation = long_stroke
    w_cylinder, w_flat = model.law.wear_coefficients
    state, master = result.state, solver.pairing.master
    cylinder = float(np.sum(state.wear_depth[0] * solver.area))
    flat = float(np.sum(state.master_wear * master.area))
    dissipation = result.figures["dissipated_energy_mJ"]
    assert cylinder == pytest.approx(w_cylinder * dissipation, rel=1e-9)
    assert flat == pytest.approx(w_flat * dissipation, rel=1e-9)
    assert flat / cylinder == pytest.approx(w_flat / w_cylinder, rel=1e-9)
    assert (cylinder, flat) == pytest.approx(worn_volumes(solver.pairing, state), rel=1e-12)
    # the energy balance of the bodies (work − stored − released) agrees within the known
    # finite-sliding floor of the local dissipation (about 1 %)
    assert cylinder + flat == pytest.approx((w_cylinder + w_flat) * global_dissipation, rel=0.02)


def test_run_figures_are_the_bodies_own_wear(long_stroke):
    model, solver, result, _ = long_stroke
    state, master = result.state, solver.pairing.master
    cylinder = float(np.sum(state.wear_depth[0] * solver.area))
    flat = float(np.sum(state.master_wear * master.area))
    deepest = max(state.gap.max(), state.wear_depth[0].max(), state.master_wear.max())
    for figures in (result.figures, result.cycles[-1].figures):
        assert figures["wear_volume_mm3"] == pytest.approx(cylinder + flat, rel=1e-12)
        assert figures["max_wear_depth_mm"] == deepest
    # what the points see of the flat (its depth at their partners) misses the scar they left
    at_points = float(np.sum(state.gap * solver.area))
    assert at_points < 0.97 * result.figures["wear_volume_mm3"]
