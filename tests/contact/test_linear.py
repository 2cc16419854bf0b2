"""The Newton linear solves in contact space: each path against the plain dense system.

The contact-space Jacobian is written out in full (every row, open points included, control
rows unscaled) and solved by numpy; the exact path (bordered LU of the closed block) and the
iterative path (GMRES preconditioned by an earlier LU) must give the same correction, and a
whole cyclic history solved by GMRES must end where the exact LU ends, to 1e-8 relative.
"""

import numpy as np
import pytest

from contact.assembly import assemble
from contact.law import evaluate
from contact.linear import KrylovSettings, NewtonLinearSolver, tangent_blocks
from contact.solver import ContactSolver, NewtonSettings
from contact.structure import ContactSpace
from tests.bench.bench_report import flat_on_flat


@pytest.fixture(scope="module")
def flat():
    case = flat_on_flat(6, layers=3)
    structure = assemble(case.bodies, case.slave, case.master, loads=case.loads, motions=case.motions).structure
    return case, ContactSpace(structure)


def _full_system(space, blocks):
    """J = [[I + W·A·D, E], [−Eᵀ·A·D, S_q]] on every row."""
    n, dim, _ = blocks.shape
    tangent = np.zeros((n * dim, n * dim))
    for k in range(n):
        tangent[k * dim:(k + 1) * dim, k * dim:(k + 1) * dim] = blocks[k]
    top = np.hstack([np.eye(n * dim) + space.W @ tangent, space.E])
    bottom = np.hstack([-space.E.T @ tangent, space.Sq])
    return np.vstack([top, bottom])


def _tangent(case, space, opened: int):
    """A partial-slip tangent: closed points pressed and sheared, the first ``opened`` open."""
    n = space.structure.n_points
    rng = np.random.default_rng(1)
    overclosure = np.full(n, 1e-4)
    overclosure[:opened] = -1e-4
    state = case.initial_state(n)
    response = evaluate(overclosure, rng.normal(0.0, 1e-3, (n, 2)), state, case.law)
    return tangent_blocks(response, space.structure.area)


@pytest.mark.parametrize("direct_below", [np.inf, 0])
@pytest.mark.parametrize("opened", [0, 7])
def test_newton_correction_equals_the_dense_solve(flat, direct_below, opened):
    case, space = flat
    blocks = _tangent(case, space, opened)
    rng = np.random.default_rng(2)
    r_kin, r_ctl = rng.normal(0.0, 1e-4, space.n_rows), rng.normal(0.0, 10.0, space.n_control)
    expected = np.linalg.solve(_full_system(space, blocks), -np.concatenate([r_kin, r_ctl]))
    solver = NewtonLinearSolver(space, KrylovSettings(direct_below=direct_below, relative_tolerance=1e-12,
                                                      single_precision=False))
    delta_g, delta_q = solver.solve(blocks, r_kin, r_ctl)
    got = np.concatenate([delta_g, delta_q])
    scale = np.max(np.abs(expected))
    assert np.max(np.abs(got - expected)) <= 1e-8 * scale


def test_gmres_history_ends_where_the_exact_lu_ends():
    case = flat_on_flat(8, layers=3)
    structure = assemble(case.bodies, case.slave, case.master, loads=case.loads, motions=case.motions).structure
    fields = {}
    for name, linear in (("gmres", KrylovSettings(direct_below=0)), ("exact", KrylovSettings(direct_below=np.inf))):
        solver = ContactSolver(ContactSpace(structure), case.law, NewtonSettings(linear=linear))
        equilibrium, state = solver.initial_equilibrium(), case.initial_state(structure.n_points)
        for amplitudes in case.history:
            equilibrium, state, _, _ = solver.increment(equilibrium, state, amplitudes, case.effects)
        traction = equilibrium.forces.reshape(-1, 3) / solver.area[:, None]
        fields[name] = {"pressure": traction[:, 0], "shear": traction[:, 1:], "cof": state.cof}
        if name == "gmres":
            assert solver.linear.counters.solves > 0 and solver.linear.counters.direct_solves == 0
    for key, exact in fields["exact"].items():
        difference = np.max(np.abs(fields["gmres"][key] - exact)) / np.max(np.abs(exact))
        assert difference <= 1e-8, f"{key} differs by {difference:.2e}"
