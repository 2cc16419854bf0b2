"""The sparse contact path against the dense one, on a small flat-on-flat case.

Both eliminate the same bodies exactly, so their contact-space operators must agree to
round-off; the sparse Newton correction must equal the plain dense solve of the full
contact-space Jacobian; and a whole cyclic partial-slip history must end where the dense
path ends, to 1e-8 relative.
"""

import numpy as np
import pytest

from contact.assembly import assemble
from contact.linear import KrylovSettings
from contact.solver import ContactSolver, NewtonSettings
from contact.sparse import (
    SparseContactSpace,
    SparseNewtonSolver,
    choose_path,
    contact_space,
)
from contact.structure import ContactSpace
from reduction.errors import InputError
from tests.bench.bench_report import flat_on_flat
from tests.contact.test_linear import _full_system, _tangent, held_punch_space

pytest.importorskip("pypardiso")


@pytest.fixture(scope="module")
def spaces():
    case = flat_on_flat(6, layers=3)
    structure = assemble(case.bodies, case.slave, case.master, loads=case.loads, motions=case.motions).structure
    whole = assemble(case.bodies, case.slave, case.master, loads=case.loads, motions=case.motions,
                     keep_interior=True).structure
    return case, ContactSpace(structure), SparseContactSpace(whole)


def _relative(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def test_operators_equal_the_condensed_ones(spaces):
    _, dense, sparse = spaces
    assert sparse.n_rows == dense.n_rows and sparse.n_control == dense.n_control
    forces = np.random.default_rng(3).normal(0.0, 1.0, dense.n_rows)
    assert _relative(sparse.compliance(forces), dense.W @ forces) < 1e-10
    assert _relative(sparse.E, dense.E) < 1e-10
    # S_q is a difference of large stiffnesses; here the punch floats (S_q = 0 up to round-off)
    assert np.max(np.abs(sparse.Sq - dense.Sq)) < 1e-12 * dense.stiffness_scale
    amplitudes = np.array([1000.0, 1e-3])
    for got, expected in zip(sparse.driving(amplitudes), dense.driving(amplitudes)):
        assert _relative(got, expected) < 1e-10
    rows = np.array([0, 5, 9])
    assert _relative(sparse.compliance_of_change(rows, forces[rows]), dense.W[rows].T @ forces[rows]) < 1e-10


def test_displacements_of_some_dofs_are_those_of_all(spaces):
    """The damage observer asks for the slave surface's displacements only: the dense path then
    solves the slave body's block alone, the sparse path the whole bodies; either way the
    values are those of the full recovery (the dense path's to the bit)."""
    case, dense, sparse = spaces
    rng = np.random.default_rng(5)
    amplitudes = np.array([1000.0, 1e-3])
    for space in (dense, sparse):
        forces, control = rng.normal(0.0, 10.0, space.n_rows), rng.normal(0.0, 1e-3, space.n_control)
        whole = space.displacements(control, forces, amplitudes)
        assert np.all(np.isfinite(whole)) and np.max(np.abs(whole)) > 0.0
        for dofs in (np.arange(whole.size // 3),  # the first third of the retained DOFs
                     # control and prescribed DOFs and a few contact DOFs of the last body
                     np.concatenate([space.control_dofs, space.contact_dofs[-3:], space.prescribed[:2]])):
            part = space.displacements(control, forces, amplitudes, dofs)
            if space is dense:
                assert np.array_equal(part, whole[dofs])
            else:
                assert _relative(part, whole[dofs]) < 1e-12
    # a body block none of whose DOFs is asked for is not solved
    factor = dense._Kcc
    assert len(factor.blocks) == 2
    first, second = factor.blocks
    rhs = rng.normal(0.0, 10.0, factor.index.size)
    part = factor.solve(rhs, first[:1])
    assert np.array_equal(part[first], factor.solve(rhs)[first]) and not np.any(part[second])


@pytest.mark.parametrize("reference", ["diagonal", "tangent"])
@pytest.mark.parametrize("opened", [0, 7])
def test_newton_correction_equals_the_dense_solve(spaces, opened, reference):
    case, dense, sparse = spaces
    blocks = _tangent(case, dense, opened)
    rng = np.random.default_rng(2)
    r_kin, r_ctl = rng.normal(0.0, 1e-4, dense.n_rows), rng.normal(0.0, 10.0, dense.n_control)
    expected = np.linalg.solve(_full_system(dense, blocks), -np.concatenate([r_kin, r_ctl]))
    # fresh_iterations: no work counts as lost, so the first factor serves both solves
    solver = SparseNewtonSolver(sparse, KrylovSettings(relative_tolerance=1e-12, fresh_iterations=1000),
                                reference=reference)
    got = np.concatenate(solver.solve(blocks, r_kin, r_ctl))
    assert _relative(got, expected) < 1e-9
    # an aged preconditioner (the tangent of another status) still gives the exact correction
    other = _tangent(case, dense, 3)
    expected = np.linalg.solve(_full_system(dense, other), -np.concatenate([r_kin, r_ctl]))
    got = np.concatenate(solver.solve(other, r_kin, r_ctl))
    assert _relative(got, expected) < 1e-9
    assert solver.counters.factorisations == 1 and solver.counters.krylov_iterations > 2


def test_newton_correction_without_control_dofs_equals_the_dense_solve():
    """Every reference-point DOF prescribed: no control DOF on the sparse path either, and
    the correction is the plain dense solve's."""
    case, whole = held_punch_space(keep_interior=True)
    sparse, dense = SparseContactSpace(whole), ContactSpace(held_punch_space()[1])
    assert sparse.n_control == dense.n_control == 0
    blocks = _tangent(case, dense, 7)
    r_kin = np.random.default_rng(2).normal(0.0, 1e-4, dense.n_rows)
    expected = np.linalg.solve(_full_system(dense, blocks), -r_kin)
    delta_g, delta_q = SparseNewtonSolver(sparse, KrylovSettings(relative_tolerance=1e-12)).solve(
        blocks, r_kin, np.zeros(0))
    assert delta_q.shape == (0,) and _relative(delta_g, expected) < 1e-9


def test_a_cyclic_history_ends_where_the_dense_path_ends(spaces):
    case, dense, sparse = spaces
    fields = []
    for space in (dense, sparse):
        solver = ContactSolver(space, case.law, NewtonSettings(linear=KrylovSettings(direct_below=np.inf)))
        equilibrium, state = solver.initial_equilibrium(), case.initial_state(space.structure.n_points)
        for amplitudes in case.history:
            equilibrium, state, _, _ = solver.increment(equilibrium, state, amplitudes, case.effects)
        fields.append(np.concatenate([equilibrium.forces, state.cof]))
        if space is sparse:
            assert "sparse" in solver.linear.description()
    assert _relative(fields[1], fields[0]) < 1e-8
    assert np.any(fields[0][len(equilibrium.forces):] > case.cof0)  # the COF evolved: points slid


def test_contact_space_takes_the_path_asked_for(spaces):
    case, dense, _ = spaces
    arguments = (case.bodies, case.slave, case.master)
    space, path = contact_space(*arguments, loads=case.loads, motions=case.motions)
    assert path == "dense" and isinstance(space, ContactSpace)  # 36 points: below the threshold
    space, path = contact_space(*arguments, loads=case.loads, motions=case.motions, path="sparse")
    assert path == "sparse" and isinstance(space, SparseContactSpace) and space.n_rows == dense.n_rows
    with pytest.raises(InputError):
        contact_space(*arguments, path="fast")


def test_the_sparse_path_is_chosen_for_large_3d_interfaces():
    assert choose_path(100, 3) == "dense"
    assert choose_path(10_000, 3) == "sparse"
    assert choose_path(10_000, 2) == "dense"
