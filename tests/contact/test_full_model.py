"""The condensed interface against the full, uncondensed sparse model of the same bodies.

Static condensation is exact, so both must give the same contact fields at every increment of
a cyclic partial-slip history with COF evolution: the condensed solver's whole chain
(coupling, condensation, contact-space elimination, Newton linear solve) is checked against
plain finite elements with the same contact law.
"""

from dataclasses import replace

import numpy as np
import pytest

from contact import full_model, linear
from contact.assembly import assemble
from contact.law import Status
from contact.solver import ContactSolver
from contact.structure import ContactSpace
from tests.bench.bench_report import flat_on_flat

TOLERANCE = 1e-6


@pytest.fixture(scope="module")
def histories():
    case = flat_on_flat(8, layers=4, slip_amplitude=5e-3, increments_per_quarter=4)
    structure = assemble(case.bodies, case.slave, case.master, loads=case.loads,
                         motions=case.motions).structure
    model = full_model.build(case.bodies, case.slave, case.master, loads=case.loads,
                             motions=case.motions)
    krylov_space = ContactSpace(structure)
    # Force the iterative Newton solve (GMRES with a reused preconditioner) on this small case.
    krylov = linear.NewtonLinearSolver(krylov_space, linear.KrylovSettings(direct_below=0))
    runs = {}
    for name, solver in (("condensed", ContactSolver(ContactSpace(structure), case.law)),
                         ("condensed, GMRES", ContactSolver(krylov_space, case.law, linear=krylov)),
                         ("full", full_model.FullModelSolver(model, case.law))):
        equilibrium, state = solver.initial_equilibrium(), case.initial_state(structure.n_points)
        records = []
        for amplitudes in case.history:
            equilibrium, state, status, _ = solver.increment(equilibrium, state, amplitudes, case.effects)
            traction = equilibrium.forces.reshape(-1, 3) / solver.area[:, None]
            records.append((traction[:, 0], traction[:, 1:], state.cof.copy(), status))
        runs[name] = records
    assert krylov.counters.solves > 0 and krylov.counters.direct_solves == 0
    return case, runs


def test_the_history_reaches_partial_slip_and_evolves_the_cof(histories):
    case, runs = histories
    statuses = np.array([record[3] for record in runs["condensed"]])
    partial = ((statuses == Status.STICK).any(axis=1) & (statuses >= Status.SLIP).any(axis=1))
    assert partial.sum() >= 2, "the comparison must cover increments with stick and slip together"
    assert runs["condensed"][-1][2].max() > case.cof0 + 0.02
    assert np.all(statuses > Status.OPEN)


@pytest.mark.parametrize("condensed_run", ["condensed", "condensed, GMRES"])
def test_condensed_and_full_models_give_the_same_pressure_shear_and_cof(histories, condensed_run):
    _, runs = histories
    for k, (condensed, full) in enumerate(zip(runs[condensed_run], runs["full"])):
        # Before the tangential motion the shear is round-off: measure it against 0.1 % of
        # the peak pressure instead of its own (vanishing) peak.
        floors = (0.0, 1e-3 * np.max(condensed[0]), 0.0)
        for name, a, b, floor in zip(("pressure", "shear", "cof"), condensed[:3], full[:3], floors):
            scale = max(np.max(np.abs(a)), floor)
            difference = np.max(np.abs(a - b)) / scale
            assert difference < TOLERANCE, f"increment {k}: {name} differs by {difference:.2e} (relative)"
        np.testing.assert_array_equal(condensed[3], full[3], err_msg=f"increment {k}: status differs")


def test_full_model_reports_a_control_dof_that_does_not_exist():
    case = flat_on_flat(4, layers=2)
    with pytest.raises(full_model.InputError, match="punch.rp.uw"):
        full_model.build(case.bodies, case.slave, case.master,
                         loads={"normal": [("punch", "rp", "uw", -1.0)]}, motions=case.motions)


def _contact_history(solver, case, n_points):
    """(pressure, shear, status) per increment of the case's history, MPa and Status."""
    equilibrium, state = solver.initial_equilibrium(), case.initial_state(n_points)
    records = []
    for amplitudes in case.history:
        equilibrium, state, status, _ = solver.increment(equilibrium, state, amplitudes, case.effects)
        traction = equilibrium.forces.reshape(-1, 3) / solver.area[:, None]
        records.append((traction[:, 0], traction[:, 1:], status))
    return records


def test_a_symmetry_plane_through_the_contact_is_held_alike_in_the_full_and_condensed_models():
    """Half of a punch twice as deep (y), its symmetry plane y = -5 mm cutting the contact
    surface: uy held there on both bodies (below the punch's coupled top). The full model holds
    those contact DOFs as the condensed one does, so both give the same contact history."""
    case = flat_on_flat(5, layers=2, slip_amplitude=5e-3, increments_per_quarter=2)
    punch, base = case.bodies

    def symmetry_plane(body, below):
        x = body.elastic.coordinates
        return (np.flatnonzero(np.isclose(x[:, 1], x[:, 1].min()) & (x[:, 2] < below)), (1,))

    bodies = [replace(punch, supports=(symmetry_plane(punch, 5.0 - 1e-6),)),
              replace(base, supports=(symmetry_plane(base, np.inf),))]
    assembly = assemble(bodies, case.slave, case.master, loads=case.loads, motions=case.motions)
    assert assembly.bodies["punch"].held.size == 5 and assembly.bodies["base"].held.size == 5
    model = full_model.build(bodies, case.slave, case.master, loads=case.loads, motions=case.motions)
    condensed = _contact_history(ContactSolver(ContactSpace(assembly.structure), case.law), case,
                                 assembly.structure.n_points)
    full = _contact_history(full_model.FullModelSolver(model, case.law), case, model.n_points)
    statuses = np.array([record[2] for record in condensed])
    assert (statuses == Status.STICK).any() and (statuses >= Status.SLIP).any()
    for k, (a, b) in enumerate(zip(condensed, full)):
        for name, x, y in (("pressure", a[0], b[0]), ("shear", a[1], b[1])):
            scale = max(np.max(np.abs(x)), 1e-3 * np.max(a[0]))
            assert np.max(np.abs(x - y)) / scale < TOLERANCE, f"increment {k}: {name} differs"
        np.testing.assert_array_equal(a[2], b[2], err_msg=f"increment {k}: status differs")
