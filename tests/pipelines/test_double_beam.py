"""The bolted double beam (paper §3.2) at a coarse setting, and the verdict measure it needs.

COF phase: low slip (30 kN, ±1.4 mm) is in partial slip from the first cycle, so the COF
evolves over part of the pad only and stays at μ0 elsewhere; high slip (20 kN, ±2.3 mm)
starts in gross slip and the COF evolves over the whole contact (the paper's Fig. 8).
Wear phase: low slip shakes down to stick (its slipping pad ends wear out of contact), high
slip returns to gross slip with the clamp force falling: loosening (the paper's Figs. 11, 13).
"""

from pathlib import Path

import numpy as np
import pytest

from contact import procedure, verdict
from contact.solver import ContactSolver
from contact.structure import ContactSpace
from pipelines import scene as scenes
from pipelines.build import build

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
COARSE = {"bodies.upper.mesh.contact_size": 3.0, "bodies.lower.mesh.contact_size": 3.0,
          "procedure.increments_per_cycle": 8, "procedure.cof_cycles": 6, "procedure.wear_cycles": 0,
          "scene.effects": ["bolts", "cof_evolution"]}


def _run(name, overrides):
    model = build(scenes.load(EXAMPLES / f"{name}.toml", overrides))
    solver = ContactSolver(ContactSpace(model.assembly.structure), model.law, model.settings)
    result = procedure.run(solver, model.initial_state(), model.program, model.procedure,
                           cof_evolution="cof_evolution" in model.scene.effects,
                           wear="wear" in model.scene.effects)
    return solver.area, result


@pytest.fixture(scope="module")
def low():
    return _run("double_beam_low_slip", COARSE)


@pytest.fixture(scope="module")
def high():
    return _run("double_beam_high_slip", COARSE)


def test_bolt_carries_exactly_its_pretension_when_locked(low, high):
    for (_, result), pretension in ((low, 30000.0), (high, 20000.0)):
        assert result.figures["bolt_force_initial_N"] == pytest.approx(pretension, rel=1e-9)
        # Locked at its length, the bolt then follows the joint: a small change, not a reset.
        assert abs(result.figures["bolt_force_final_N"] / pretension - 1.0) < 0.02


def test_low_slip_is_partial_slip_from_the_first_cycle(low):
    _, result = low
    first = result.cycles[0].figures
    assert 0.05 < first["slip_area_fraction"] < 0.6
    assert first["stick_area_fraction"] > 0.4
    cof = result.state.cof
    closed = result.cycles[-1].status > 0
    assert np.any(np.isclose(cof[closed], 0.2))  # behind the hole the COF never moved
    assert np.all(cof <= 0.7 + 1e-12) and np.any(cof > 0.25)


def test_high_slip_starts_in_gross_slip_and_cof_evolves_everywhere(high):
    area, result = high
    first = result.cycles[0].figures
    assert first["slip_area_fraction"] >= 0.9 and first["stick_area_fraction"] < 0.1
    # After six gross-slip cycles the COF has started to rise (by 1e-4 at least, far above
    # round-off) over the whole contact; the reported cof_evolved figure counts only rises
    # beyond 1 % of μ_max − μ0, which the slow-sliding points near the hole reach later.
    risen = result.state.cof > 0.2 + 1e-4
    assert area[risen].sum() / result.figures["nominal_contact_area"] >= 0.95


def test_sliding_area_ignores_points_worn_out_of_contact_and_slips_far_below_critical():
    """Four 1 mm² points, γ_crit 1 µm: one slides 2 µm at μ 0.7 under 100 MPa (sliding); one
    sticks; one slid 2 µm but carries 0.01 MPa (worn out of contact); one at 100 MPa slipped
    1e-6 µm (at the stick limit). Only the first counts."""
    area = np.ones(4)
    pressure = np.array([100.0, 100.0, 0.01, 100.0])
    cof = np.array([0.7, 0.7, 0.2, 0.7])
    slip = np.array([2e-3, 0.0, 2e-3, 1e-9])
    dissipation = cof * pressure * slip
    fraction = verdict.active_slip_area_fraction(area, 4.0, pressure, dissipation, cof, 1e-3, 0.1)
    assert fraction == pytest.approx(0.25)


# The scenes' own procedure (100 COF cycles, wear with J = 1e4, shakedown and loosening
# stops) on a 2.5 mm pad mesh with 8 increments per cycle: about 15 s per case.
COARSE_WEAR = {"bodies.upper.mesh.contact_size": 2.5, "bodies.lower.mesh.contact_size": 2.5,
               "procedure.increments_per_cycle": 8}


def test_low_slip_wears_into_stick_with_a_small_clamp_loss():
    _, result = _run("double_beam_low_slip", COARSE_WEAR)
    figures = result.figures
    assert result.verdict == "stick" and result.stationary
    assert figures["active_slip_area_fraction"] <= 0.01
    assert figures["worn_area_fraction"] > 0.1  # the slipping pad ends wore out of contact
    # The joint keeps its clamp: a small loss (the paper: about 1 kN of 30 kN).
    assert 0.0 < figures["clamp_force_loss_fraction"] < 0.02


def test_high_slip_returns_to_gross_slip_and_loosens():
    _, result = _run("double_beam_high_slip", COARSE_WEAR)
    figures = result.figures
    assert result.verdict == "loosening" and not result.stationary
    assert figures["stick_area_fraction"] < 0.05  # back to gross slip
    assert figures["clamp_force_loss_fraction"] > 0.01
    wear = [c for c in result.cycles if c.phase == "wear"]
    clamp = np.array([c.clamp_force for c in wear])
    assert np.all(np.diff(clamp) < 0.0)  # falling in every cycle of the window
    assert figures["cycles_run"] < 100 + 300  # stopped on loosening, not at the end
    # the cycle that made it evident carries when, for the observers (the progress bar says so)
    assert result.cycles[-1].loosening_evident_at == figures["loosening_evident_at_cycles"]
    assert all(c.loosening_evident_at is None for c in result.cycles[:-1])
