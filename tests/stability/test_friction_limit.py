"""Hard cases at the friction limit of the whole interface (coarse cylinder on plane, 3D blocks).

* Reversal at the stick–gross-slip boundary: the tangential force goes to Q/μP = 1 − 10⁻⁵
  from below and reverses (force control); the tangential motion is cycled just below and
  just above the displacement at which gross slip starts, so that Q/μP reaches 1 from the
  other side too (displacement control).
* Whole-interface gross slip under displacement control.
* Force control past the slip limit: no static solution exists; the solver must say so in a
  ConvergenceError, quickly, and never return a spurious answer.
"""


import numpy as np
import pytest

from contact.law import Status
from contact.solver import ConvergenceError
from stability_harness import (COF, LINE_LOAD, Watchdog, cylinder, drive, flat, interface_forces,
                               preload, sine_cycles)

ENERGY_TOLERANCE = 0.005
UP = np.concatenate([np.linspace(0.1, 0.9, 9), 1.0 - np.logspace(-2, -5, 4)])  # Q/μP


def rp_x(case, equilibrium) -> float:
    """Tangential displacement (mm) of the cylinder's reference point, a control DOF here."""
    index = case.model.assembly.structure.labels["cylinder.rp.ux"]
    return float(equilibrium.control[np.flatnonzero(case.space.control_dofs == index)[0]])


@pytest.fixture(scope="module")
def force_controlled():
    """Q/μP up to 1 − 10⁻⁵, reversed to −(1 − 10⁻⁵) and back up, at constant P."""
    case = cylinder(tangential="force", tangential_value=COF * LINE_LOAD)
    reversal = np.concatenate([UP[::-1][1:], [0.0], -UP, -UP[::-1][1:], [0.0], UP])
    history = np.concatenate([UP, reversal])
    watchdog = Watchdog(case, max_cutbacks=4)
    steps = drive(case, np.vstack([preload(case), [case.amplitudes(normal=1, tangential=r)
                                                  for r in history]]), watchdog)
    return case, watchdog, steps[10:]


def test_force_control_reverses_at_the_slip_limit_without_cutbacks(force_controlled, record_property):
    case, watchdog, steps = force_controlled
    record_property("outcome", watchdog.summary())
    assert watchdog.cutbacks == 0
    for step in steps:
        normal, tangential = interface_forces(case, step.equilibrium)
        ratio = step.amplitudes[1]
        assert normal == pytest.approx(LINE_LOAD, rel=1e-8)
        assert tangential[0] == pytest.approx(ratio * COF * LINE_LOAD, rel=1e-8, abs=1e-10 * LINE_LOAD)
        closed = step.status != Status.OPEN
        # Below μP some closed point must still stick: if all slid, Q would be μP exactly.
        assert np.any(step.status[closed] == Status.STICK), f"no stick point at Q/μP = {ratio}"


def test_force_control_near_the_limit_stays_bounded_and_reverses(force_controlled):
    """The compliance grows as Q → μP but the displacement stays finite, and the reversal from
    1 − 10⁻⁵ retraces the same peak on the other side (symmetric Masing loop)."""
    case, _, steps = force_controlled
    x = np.array([rp_x(case, s.equilibrium) for s in steps])
    ratios = np.array([s.amplitudes[1] for s in steps])
    top = np.flatnonzero(ratios == UP[-1])
    bottom = np.flatnonzero(ratios == -UP[-1])
    assert np.all(np.isfinite(x)) and np.abs(x).max() < 1.0
    assert np.all(np.diff(x[:top[0] + 1]) > 0.0), "loading must move the cylinder monotonically"
    # First loading reaches half the loop amplitude; later peaks of the loop are symmetric.
    assert x[bottom[0]] == pytest.approx(-x[top[1]], rel=1e-3)
    assert x[top[1]] - x[bottom[0]] > 1.5 * x[top[0]]


def test_force_control_energy_balance(force_controlled):
    _, watchdog, _ = force_controlled
    assert abs(watchdog.energy_error) < ENERGY_TOLERANCE


@pytest.fixture(scope="module")
def gross_slip_start(force_controlled):
    """Reference-point displacement (mm) at Q = (1 − 10⁻⁵)·μP on first loading."""
    case, _, steps = force_controlled
    first_top = next(s for s in steps if s.amplitudes[1] == UP[-1])
    return rp_x(case, first_top.equilibrium)


@pytest.mark.parametrize("factor", [0.98, 1.02])
def test_displacement_cycles_just_below_and_above_gross_slip(gross_slip_start, factor, record_property):
    """Q/μP at the turning points approaches 1 from below (0.98 δ) or reaches it (1.02 δ)."""
    case = cylinder(tangential_value=factor * gross_slip_start)
    watchdog = Watchdog(case, max_cutbacks=4)
    steps = drive(case, np.vstack([preload(case), sine_cycles(case, {"normal": 1}, {"tangential": 1},
                                                              40, cycles=2)]), watchdog)
    record_property("outcome", watchdog.summary())
    utilisation = np.array([abs(interface_forces(case, s.equilibrium)[1][0]) / (COF * LINE_LOAD)
                            for s in steps[10:]])
    assert watchdog.cutbacks == 0
    if factor < 1.0:
        assert 0.9 < utilisation.max() < 1.0
        assert all(np.any(s.status == Status.STICK) for s in steps[10:])
    else:
        assert utilisation.max() == pytest.approx(1.0, abs=1e-9)
        peak = steps[10 + int(np.argmax(utilisation))]
        closed = peak.status != Status.OPEN
        assert np.all(peak.status[closed] >= Status.SLIP)
    assert abs(watchdog.energy_error) < ENERGY_TOLERANCE


def test_gross_slip_under_displacement_control(record_property):
    """±107 µm at the reference point, two cycles of 100 increments: Q = ±μP while sliding."""
    case = cylinder()
    watchdog = Watchdog(case, max_cutbacks=0)
    steps = drive(case, np.vstack([preload(case), sine_cycles(case, {"normal": 1}, {"tangential": 1},
                                                              100, cycles=2)]), watchdog)
    record_property("outcome", watchdog.summary())
    sliding = [s for s in steps[10:] if np.all(s.status[s.status != Status.OPEN] >= Status.SLIP)]
    assert len(sliding) > 100
    for step in sliding:
        normal, tangential = interface_forces(case, step.equilibrium)
        assert abs(tangential[0]) == pytest.approx(COF * normal, rel=1e-9)
    assert abs(watchdog.energy_error) < ENERGY_TOLERANCE


def test_force_control_reversal_near_the_limit_3d(record_property):
    """10×10 points (Krylov Newton solve), Q cycled to ±0.999·μP at 10 kN: converges, the
    centre keeps sticking, P and Q are transmitted exactly."""
    case = flat(10, tangential="force", cof0=0.2)
    force = 100.0 * 10.0 * 10.0
    watchdog = Watchdog(case, max_cutbacks=2)
    rows = np.vstack([[force, 0.0], sine_cycles(case, {"normal": force}, {"tangential": 0.1998 * force}, 20)])
    steps = drive(case, rows, watchdog)
    record_property("outcome", watchdog.summary())
    for step in steps:
        normal, tangential = interface_forces(case, step.equilibrium)
        assert normal == pytest.approx(force, rel=1e-8)
        assert np.linalg.norm(tangential) == pytest.approx(abs(step.amplitudes[1]), rel=1e-6, abs=1e-6 * force)
        assert np.any(step.status == Status.STICK)
    assert abs(watchdog.energy_error) < ENERGY_TOLERANCE


def _assert_clear_failure(case, rows):
    """The overload ends in the named failure. How long it takes to say so is bounded by the
    solver's attempts (NewtonSettings.max_iterations per sub-step, max_cutbacks halvings), not
    timed here: the machine is shared, and a wall-clock bound would judge its load."""
    watchdog = Watchdog(case, max_cutbacks=0)
    with pytest.raises(ConvergenceError, match="tangential equilibrium is lost") as failure:
        drive(case, rows, watchdog)
    message = str(failure.value)
    assert failure.value.cause == "slid_off"  # what code reads; the words are for the engineer
    assert "exceeds what friction can carry" in message
    assert "prescribe a motion" in message
    return watchdog, message


@pytest.mark.parametrize("overload", [1.0001, 1.5])
def test_force_control_past_the_limit_reports_lost_equilibrium_2d(overload, record_property):
    case = cylinder(tangential="force", tangential_value=COF * LINE_LOAD)
    rows = np.vstack([preload(case), case.amplitudes(normal=1, tangential=0.9),
                      case.amplitudes(normal=1, tangential=overload)])
    watchdog, message = _assert_clear_failure(case, rows)
    record_property("outcome", {**watchdog.summary(), "message": message})
    # Every increment before the overload converged and was checked.
    assert watchdog.increments == 11


@pytest.mark.parametrize("points_per_side", [4, 10])
def test_force_control_past_the_limit_reports_lost_equilibrium_3d(points_per_side, record_property):
    """Blocks pressed by 10 kN (μ = 0.2): a tangential 2.5 kN cannot be carried. 16 points
    take the dense direct Newton solve, 100 points the preconditioned GMRES one."""
    case = flat(points_per_side, tangential="force", cof0=0.2)
    force = 100.0 * 10.0 * 10.0
    rows = np.array([[force, 0.0], [force, 0.15 * force], [force, 0.25 * force]])
    watchdog, message = _assert_clear_failure(case, rows)
    record_property("outcome", {**watchdog.summary(), "message": message})
    assert watchdog.increments == 2
