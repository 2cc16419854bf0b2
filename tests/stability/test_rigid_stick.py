"""The rigid-stick limit in 3D: a sphere on a flat under a partial-slip tangential force cycle
with γ_crit = 0.001 µm.

The elastic stick stiffness μ·p/γ_crit (3e11 N/mm³ at 1 GPa) is then five decades above the
penalty kn: whole rings of points change between stick and slip within one Newton step.
Newton used to crawl back to stick a ring per iteration and failed in the first cycle even
after 10 cutbacks (issue 14). Cattaneo–Mindlin: under Q = μP/2 a slip annulus surrounds a
stuck core of radius c = a·(1 − Q/(μP))^(1/3) ≈ 0.79·a; the check here is the solver's (no
cutbacks, bounded iterations, the invariants of the watchdog, force equilibrium) plus the
shape of that answer: a stuck core, a slipping annulus, in the same place in both cycles.
"""

import numpy as np
import pytest

from stability_harness import Watchdog, drive, interface_forces, preload, sine_cycles, sphere

NORMAL = 20000.0  # N: a Hertz contact of radius ≈ 3 mm (R = 200 mm, steel on steel)
COF = 0.3
ENERGY_TOLERANCE = 0.005


@pytest.fixture(scope="module")
def rigid_stick():
    case = sphere(22, critical_slip=1e-6, cof=COF)
    watchdog = Watchdog(case, max_cutbacks=0)
    rows = np.vstack([preload(case, 40) * NORMAL,
                      sine_cycles(case, {"normal": NORMAL}, {"tangential": 0.5 * COF * NORMAL}, 40, 2)])
    return case, watchdog, drive(case, rows, watchdog)


def test_partial_slip_cycles_converge_without_cutbacks(rigid_stick, record_property):
    case, watchdog, steps = rigid_stick
    record_property("outcome", watchdog.summary())
    assert watchdog.cutbacks == 0
    assert watchdog.max_iterations <= 30
    assert abs(watchdog.energy_error) < ENERGY_TOLERANCE


def test_interface_carries_the_applied_forces(rigid_stick):
    case, _, steps = rigid_stick
    for step in steps:
        normal, tangential = interface_forces(case, step.equilibrium)
        assert normal == pytest.approx(step.amplitudes[0], rel=1e-8)
        # (in the points' tangent frames, which are alike on a flat face)
        assert np.linalg.norm(tangential) == pytest.approx(abs(step.amplitudes[1]), abs=1e-8 * NORMAL)


def test_a_stuck_core_inside_a_slipping_annulus(rigid_stick):
    case, _, steps = rigid_stick
    peak = max(range(len(steps)), key=lambda k: steps[k].amplitudes[1])
    status = steps[peak].status
    radius = np.linalg.norm(case.x[:, :2] - 0.5 * (case.x[:, :2].min(axis=0) + case.x[:, :2].max(axis=0)),
                            axis=1)
    closed = status > 0
    sliding = status >= 2
    assert sliding.any() and (closed & ~sliding).any()
    # every sliding point lies outside every stuck one (up to one mesh row)
    spacing = 10.0 / 21
    assert radius[sliding].min() >= radius[closed & ~sliding].max() - 1.5 * spacing
