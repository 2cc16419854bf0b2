"""The sharpest hard cases again at the scene's own contact mesh (0.05 mm, ~100 contact points)
and on 10×10 blocks: the CI suite runs them coarse; these (``make bench``) show that the
fixes hold at the documented resolution. Same assertions as the CI cases."""

import numpy as np
import pytest

from contact.law import Status
from contact.solver import ConvergenceError
from stability_harness import (COF, LINE_LOAD, Watchdog, cylinder, drive, flat, interface_forces, preload,
                               sine_cycles)
from test_contact_changes import APPROACH, lift_off_cycle

pytestmark = pytest.mark.bench
ENERGY_TOLERANCE = 0.005


def test_lift_off_at_scene_resolution(record_property):
    case = cylinder(contact_size=0.05, normal="motion", normal_value=-APPROACH)
    watchdog = Watchdog(case, max_cutbacks=2)
    steps = drive(case, np.vstack([preload(case), lift_off_cycle(400)]), watchdog)
    record_property("outcome", watchdog.summary())
    assert all(np.all(s.status == Status.OPEN) for s in steps if s.amplitudes[0] < -0.05)
    assert abs(watchdog.energy_error) < ENERGY_TOLERANCE


def test_force_past_the_limit_at_scene_resolution(record_property):
    case = cylinder(contact_size=0.05, tangential="force", tangential_value=COF * LINE_LOAD)
    watchdog = Watchdog(case, max_cutbacks=0)
    rows = np.vstack([preload(case), case.amplitudes(normal=1, tangential=0.999),
                      case.amplitudes(normal=1, tangential=1.01)])
    with pytest.raises(ConvergenceError, match="tangential equilibrium is lost"):
        drive(case, rows, watchdog)
    record_property("outcome", watchdog.summary())
    assert watchdog.increments == 11


@pytest.mark.parametrize("normal_stiffness, critical_slip", [(1e3, 1e-5), (1e8, 1e-5), (1e8, 1e-2)])
def test_parameter_corners_at_scene_resolution(normal_stiffness, critical_slip, record_property):
    case = cylinder(contact_size=0.05, tangential_value=0.06,
                    overrides={"contact.normal_stiffness": normal_stiffness,
                               "contact.critical_slip": critical_slip})
    watchdog = Watchdog(case, max_cutbacks=0)
    drive(case, np.vstack([preload(case), sine_cycles(case, {"normal": 1}, {"tangential": 1}, 100)]),
          watchdog)
    record_property("outcome", watchdog.summary())
    assert abs(watchdog.energy_error) < ENERGY_TOLERANCE


def test_blocks_10x10_cof_jump_and_force_limit(record_property):
    case = flat(10, tangential="force")
    force = 100.0 * 10.0 * 10.0
    watchdog = Watchdog(case, max_cutbacks=4)
    steps = drive(case, np.vstack([[force, 0.0], sine_cycles(case, {"normal": force},
                                                             {"tangential": 0.19 * force}, 40)]),
                  watchdog)
    record_property("outcome", watchdog.summary())
    assert all(np.any(s.status == Status.STICK) for s in steps[1:])
    assert interface_forces(case, steps[-1].equilibrium)[0] == pytest.approx(force, rel=1e-8)
    with pytest.raises(ConvergenceError, match="tangential equilibrium is lost"):
        drive(case, np.array([[force, 0.0], [force, 0.21 * force]]), Watchdog(case))
