"""The rigid-stick limit in 3D: a sphere on a flat under a partial-slip tangential force cycle
with γ_crit = 0.001 µm, at 40 and at 80 increments per cycle.

The elastic stick stiffness μ·p/γ_crit (3e11 N/mm³ at 1 GPa) is then five decades above the
penalty kn: whole rings of points change between stick and slip within one Newton step.
Newton used to crawl back to stick a ring per iteration and failed in the first cycle even
after 10 cutbacks (issue 14). Cattaneo–Mindlin: under Q = μP/2 a slip annulus surrounds a
stuck core of radius c = a·(1 − Q/(μP))^(1/3) ≈ 0.79·a; the check here is the solver's (no
cutbacks, bounded iterations, the invariants of the watchdog, force equilibrium, every
converged increment solving the discrete equations) plus that answer: a stuck core inside a
slipping annulus, whose radius at the load peaks is Cattaneo–Mindlin's within the mesh.
"""

import numpy as np
import pytest

from contact.law import evaluate
from stability_harness import Watchdog, drive, interface_forces, preload, sine_cycles, sphere

NORMAL = 20000.0  # N: a Hertz contact of radius ≈ 3 mm (R = 200 mm, steel on steel)
COF = 0.3
ENERGY_TOLERANCE = 0.005
SIDE = 22  # contact points per side of the 10 mm face
SPACING = 10.0 / (SIDE - 1)  # mm


@pytest.fixture(scope="module", params=[(40, 2), (80, 1)], ids=["40 per cycle", "80 per cycle"])
def rigid_stick(request):
    per_cycle, cycles = request.param
    case = sphere(SIDE, critical_slip=1e-6, cof=COF)
    watchdog = Watchdog(case, max_cutbacks=0)
    rows = np.vstack([preload(case, 40) * NORMAL,
                      sine_cycles(case, {"normal": NORMAL}, {"tangential": 0.5 * COF * NORMAL}, per_cycle, cycles)])
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


def test_every_increment_solves_the_discrete_equations(rigid_stick):
    """Compatibility g − g_f + E·q + W·λ = 0 to the solver's tolerance, with λ the law's
    forces for those kinematics from the previous increment's state, and the control
    DOFs in equilibrium: Newton converged, not just stopped."""
    case, _, steps = rigid_stick
    space, solver = case.space, case.solver
    tolerance = solver.settings.displacement_tolerance
    previous_g, previous_state = np.zeros(space.n_rows), case.state
    for step in steps:
        g, q = step.equilibrium.kinematics, step.equilibrium.control
        per_point, before = g.reshape(solver.n_points, 3), previous_g.reshape(solver.n_points, 3)
        response = evaluate(solver.h0 + per_point[:, 0], per_point[:, 1:] - before[:, 1:], previous_state, case.law)
        forces = (case.area[:, None] * np.column_stack([response.pressure, response.shear])).ravel()
        np.testing.assert_allclose(forces, step.equilibrium.forces, rtol=0, atol=1e-9 * np.abs(forces).max())
        g_f, f_q = space.driving(step.amplitudes)
        assert np.max(np.abs(g - g_f + space.E @ q + space.W @ forces)) <= 1.01 * tolerance
        assert np.max(np.abs(solver.control_stiffness @ q - space.E.T @ forces - f_q)) <= \
            solver.settings.force_tolerance * NORMAL
        previous_g, previous_state = g, step.state


def test_stick_radius_at_the_load_peaks_is_cattaneo_mindlins(rigid_stick):
    """Monotone loading to Q from 0, and a full reversal from Q to −Q, leave a stuck core
    c/a = (1 − Q/(μP))^(1/3) (Mindlin's reloading: (1 − 2Q/(2μP))^(1/3), the same). Radii
    from the areas of the closed and of the sticking points, which at the peak increment are
    the points that did not slide in it; within one point spacing."""
    case, _, steps = rigid_stick
    amplitudes = np.array([step.amplitudes[1] for step in steps])
    for peak in (int(np.argmax(amplitudes)), int(np.argmin(amplitudes))):
        status = steps[peak].status
        contact = np.sqrt(case.area[status > 0].sum() / np.pi)
        stuck = np.sqrt(case.area[status == 1].sum() / np.pi)
        load = abs(amplitudes[peak]) / (COF * NORMAL)
        expected = (1.0 - load) ** (1.0 / 3.0)
        assert 0.0 < load < 1.0
        assert stuck / contact == pytest.approx(expected, abs=SPACING / contact)
