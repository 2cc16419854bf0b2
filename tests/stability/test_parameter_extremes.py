"""Hard cases at the extremes of the law's parameters and of the time step.

* Penalty stiffness kn over five decades (1e3–1e8 N/mm³) × γ_crit from 0.01 µm to 10 µm,
  on the coarse cylinder (24 combinations) and on 3D blocks (corners of the range).
* μ jumping from μ₀ to μ_max within one increment (k = 1000 mm/N), 2D and 3D.
* Very coarse (4 per cycle) and very fine (200 per cycle) increments: the same turning
  points give the same dissipation per cycle, since the return mapping of a monotone
  stretch is exact whatever its length.
"""

from dataclasses import replace

import numpy as np
import pytest

from contact.law import Status
from contact.solver import ContactSolver, Effects
from stability_harness import (COF, LINE_LOAD, Watchdog, cylinder, drive, flat, interface_forces,
                               preload, sine_cycles)

ENERGY_TOLERANCE = 0.005
PENALTIES = [1e3, 1e4, 1e5, 1e6, 1e7, 1e8]  # N/mm³
CRITICAL_SLIPS = [1e-5, 1e-4, 1e-3, 1e-2]  # mm: 0.01 µm … 10 µm


def with_law(case, **changes):
    """The same condensed model with other law parameters (no re-assembly)."""
    law = replace(case.law, **changes)
    return replace(case, law=law, solver=ContactSolver(case.space, law, case.solver.settings))


@pytest.fixture(scope="module")
def coarse_cylinder():
    return cylinder(contact_size=0.2, tangential_value=0.06)


@pytest.mark.parametrize("critical_slip", CRITICAL_SLIPS)
@pytest.mark.parametrize("normal_stiffness", PENALTIES)
def test_penalty_and_critical_slip_sweep_2d(coarse_cylinder, normal_stiffness, critical_slip,
                                            record_property):
    """Preload, then one ±60 µm cycle in 60 increments: from stick (γ_crit = 10 µm) to gross
    slip (γ_crit = 0.01 µm), from a contact spread over the whole surface (kn = 1e3) to a
    nearly rigid one (kn = 1e8)."""
    case = with_law(coarse_cylinder, normal_stiffness=normal_stiffness, critical_slip=critical_slip)
    watchdog = Watchdog(case, max_cutbacks=0)
    steps = drive(case, np.vstack([preload(case), sine_cycles(case, {"normal": 1}, {"tangential": 1}, 60)]),
                  watchdog)
    record_property("outcome", watchdog.summary())
    for step in steps:
        assert interface_forces(case, step.equilibrium)[0] == pytest.approx(
            LINE_LOAD * step.amplitudes[0], rel=1e-8)
    assert abs(watchdog.energy_error) < ENERGY_TOLERANCE


@pytest.mark.parametrize("critical_slip", [1e-5, 1e-2])
@pytest.mark.parametrize("normal_stiffness", [1e3, 1e8])
def test_penalty_and_critical_slip_corners_3d(normal_stiffness, critical_slip, record_property):
    """10×10 points (the preconditioned-GMRES Newton path), 100 MPa, ±5 µm, 40 increments
    per cycle."""
    case = flat(10)
    case = with_law(case, normal_stiffness=normal_stiffness, critical_slip=critical_slip)
    force = 100.0 * 10.0 * 10.0
    rows = np.vstack([[force, 0.0], sine_cycles(case, {"normal": force}, {"tangential": 5e-3}, 40)])
    watchdog = Watchdog(case, max_cutbacks=0)
    steps = drive(case, rows, watchdog)
    record_property("outcome", watchdog.summary())
    for step in steps:
        assert interface_forces(case, step.equilibrium)[0] == pytest.approx(force, rel=1e-8)
    assert abs(watchdog.energy_error) < ENERGY_TOLERANCE


def _assert_jump_to_max(steps, cof_initial, cof_max):
    """Some point goes from μ₀ to μ_max in one increment; none ever exceeds μ_max."""
    jumped = False
    for before, after in zip(steps, steps[1:]):
        went = (before.state.cof == cof_initial) & (after.state.cof == cof_max)
        jumped |= bool(np.any(went))
    assert jumped, "no point jumped from μ0 to μ_max within one increment"
    assert max(s.state.cof.max() for s in steps) == cof_max


def _assert_jump_energy(watchdog):
    """The COF is updated after the increment, so a jump raises the stick energy of the
    sliding points by ½·Δμ·p·γ_crit at fixed slip (booked as stick source S) and the next
    increment re-equilibrates from that state, losing part of it, never more: the balance
    must close between W + S and W (within 0.5 % of W either side)."""
    work, source = watchdog.external_work, watchdog.meter.stick_source
    assert source > 0.0
    error_with_source = watchdog.energy_error
    assert -ENERGY_TOLERANCE < error_with_source < source / work + ENERGY_TOLERANCE


def test_cof_jumps_to_max_within_one_increment_2d(record_property):
    """μ₀ = 0.2 → μ_max = 0.56 with k = 1000 mm/N, ±30 µm in 100 increments per cycle: the
    first sliding increment puts the slipping points at μ_max; stick zone and Q follow the
    jump."""
    case = cylinder(tangential_value=0.03, overrides={
        "scene.effects": ["cof_evolution"], "contact.cof_initial": 0.2, "contact.cof_rate": 1000.0})
    watchdog = Watchdog(case, max_cutbacks=4)
    effects = Effects(cof_evolution=True)
    steps = drive(case, np.vstack([preload(case), sine_cycles(case, {"normal": 1}, {"tangential": 1}, 100,
                                                              cycles=2)]), watchdog, effects)
    record_property("outcome", watchdog.summary())
    _assert_jump_to_max(steps, 0.2, COF)
    utilisation = max(abs(interface_forces(case, s.equilibrium)[1][0]) for s in steps)
    assert utilisation > 0.2 * LINE_LOAD, "the evolved COF must carry more than μ0·P"
    _assert_jump_energy(watchdog)


def test_cof_jumps_to_max_within_one_increment_3d(record_property):
    """10×10 points, μ₀ = 0.2 → μ_max = 0.7 with k = 1000 mm/N."""
    case = flat(10)
    case = with_law(case, cof_rate=1000.0, cof_max=0.7)
    force = 100.0 * 10.0 * 10.0
    rows = np.vstack([[force, 0.0], sine_cycles(case, {"normal": force}, {"tangential": 5e-3}, 40, cycles=2)])
    watchdog = Watchdog(case, max_cutbacks=4)
    steps = drive(case, rows, watchdog, Effects(cof_evolution=True))
    record_property("outcome", watchdog.summary())
    _assert_jump_to_max(steps, 0.2, 0.7)
    _assert_jump_energy(watchdog)


def _cycle_dissipation(case, rows, n_per_cycle, watchdog):
    steps = drive(case, rows, watchdog)
    area = case.area
    second = steps[-1].state.dissipation - steps[-1 - n_per_cycle].state.dissipation
    return float(np.sum(second * area)), steps


@pytest.mark.parametrize("control", ["gross slip, motion", "partial slip, force"])
def test_coarse_and_fine_increments_agree(control, record_property):
    """4 and 200 increments per cycle: both converge (coarse steps may cut back), and the
    dissipation of the second cycle agrees within 0.5 % (same turning points)."""
    outcome, dissipation = {}, {}
    for n in (4, 200):
        if control.endswith("motion"):
            case = cylinder()
            held, cyclic = {"normal": 1}, {"tangential": 1}
        else:
            case = cylinder(tangential="force", tangential_value=COF * LINE_LOAD)
            held, cyclic = {"normal": 1}, {"tangential": 0.8}
        watchdog = Watchdog(case, max_cutbacks=6)
        rows = np.vstack([preload(case), sine_cycles(case, held, cyclic, n, cycles=2)])
        dissipation[n], steps = _cycle_dissipation(case, rows, n, watchdog)
        outcome[n] = watchdog.summary()
        if n == 200:
            assert abs(watchdog.energy_error) < ENERGY_TOLERANCE
        if control.startswith("partial"):
            assert all(np.any(s.status == Status.STICK) for s in steps)
    record_property("outcome", {**outcome, "second_cycle_dissipation_mJ": dissipation})
    assert dissipation[4] > 0.0
    assert dissipation[4] == pytest.approx(dissipation[200], rel=0.005)
