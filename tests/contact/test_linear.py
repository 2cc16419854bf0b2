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
from contact.structure import SYMMETRIC_PRODUCT_BYTES, ContactSpace, symmetric_product
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


def held_punch_space(keep_interior=False):
    """The flat-on-flat case with every reference-point DOF prescribed (pressed and slid by
    motions, no load) on matching faces, so no surface node is left unpaired: no control DOF
    at all (as after a finite-sliding re-pairing, which eliminates every surface DOF)."""
    case = flat_on_flat(6, layers=3)
    motions = {"normal": [("punch", "rp", "uz", -1.0)],
               "tangential": [("punch", "rp", "ux", 1.0), ("punch", "rp", "uy", 0.5)]}
    structure = assemble(case.bodies, case.slave, case.master, loads={}, motions=motions,
                         keep_interior=keep_interior).structure
    return case, structure


@pytest.fixture(scope="module")
def held():
    case, structure = held_punch_space()
    space = ContactSpace(structure)
    assert space.n_control == 0
    return case, space


@pytest.mark.parametrize("direct_below", [np.inf, 0])
@pytest.mark.parametrize("opened", [0, 7])
def test_newton_correction_without_control_dofs_equals_the_dense_solve(held, direct_below, opened):
    """No control DOF: the bordered system is the closed block alone, on the exact and the
    Krylov paths (the border was once reshaped to (points, dim, 0) by inference, which
    numpy refuses), and the correction is the plain dense solve's."""
    case, space = held
    blocks = _tangent(case, space, opened)
    r_kin = np.random.default_rng(2).normal(0.0, 1e-4, space.n_rows)
    expected = np.linalg.solve(_full_system(space, blocks), -r_kin)
    solver = NewtonLinearSolver(space, KrylovSettings(direct_below=direct_below, relative_tolerance=1e-12,
                                                      single_precision=False))
    delta_g, delta_q = solver.solve(blocks, r_kin, np.zeros(0))
    assert delta_q.shape == (0,)
    assert np.max(np.abs(delta_g - expected)) <= 1e-8 * np.max(np.abs(expected))


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_compliance_on_closed_rows_is_w_gathered_and_rounded(flat, dtype):
    """W on the working rows of a partly open interface is W's entries there (rounded to the
    working precision, in the Fortran order the products read), whether it is gathered from
    W or from its kept single-precision copy; with every row closed it is all of W."""
    _, space = flat
    solver = NewtonLinearSolver(space)
    rows = np.flatnonzero(np.arange(space.n_rows) % 5 != 2)  # some rows of every kind left out
    block = solver._closed_compliance(rows, dtype)
    assert block.dtype == dtype and block.flags.f_contiguous
    assert np.array_equal(block, space.W[rows][:, rows].astype(dtype))
    whole = solver._closed_compliance(np.arange(space.n_rows), dtype)
    assert np.array_equal(whole, space.W.astype(dtype))


def _history_end(case, linear: KrylovSettings):
    """Pressure, shear and COF (MPa, MPa, -) at the end of the case's history, and the solver."""
    structure = assemble(case.bodies, case.slave, case.master, loads=case.loads, motions=case.motions).structure
    solver = ContactSolver(ContactSpace(structure), case.law, NewtonSettings(linear=linear))
    equilibrium, state = solver.initial_equilibrium(), case.initial_state(structure.n_points)
    for amplitudes in case.history:
        equilibrium, state, _, _ = solver.increment(equilibrium, state, amplitudes, case.effects)
    traction = equilibrium.forces.reshape(-1, 3) / solver.area[:, None]
    return {"pressure": traction[:, 0], "shear": traction[:, 1:], "cof": state.cof}, solver


def _assert_equal_to_the_exact_lu(case, fields: dict) -> None:
    exact_fields, _ = _history_end(case, KrylovSettings(direct_below=np.inf))
    for key, exact in exact_fields.items():
        difference = np.max(np.abs(fields[key] - exact)) / np.max(np.abs(exact))
        assert difference <= 1e-8, f"{key} differs by {difference:.2e}"


def test_gmres_history_ends_where_the_exact_lu_ends():
    case = flat_on_flat(8, layers=3)
    fields, solver = _history_end(case, KrylovSettings(direct_below=0))
    assert solver.linear.counters.solves > 0 and solver.linear.counters.direct_solves == 0
    _assert_equal_to_the_exact_lu(case, fields)


def test_kept_preconditioners_end_where_the_exact_lu_ends():
    """Gross slip over three cycles, the slip reversing every half cycle: with several
    preconditioners kept (each solve takes the one formed at the nearest tangent), the
    history still ends where the exact LU ends, to 1e-8."""
    case = flat_on_flat(8, layers=3, slip_amplitude=2e-2, cycles=3)
    fields, solver = _history_end(case, KrylovSettings(direct_below=0, factors_kept=16))
    assert len(solver.linear._pool.factors) > 1  # more than one was kept and chosen from
    _assert_equal_to_the_exact_lu(case, fields)


def test_kept_preconditioners_survive_a_checkpoint_bit_for_bit(tmp_path):
    """At a checkpoint the dense Krylov path keeps its preconditioners (up to 16 formed again
    after every checkpoint were about 5 % of the 2.5 mm counterweight's wear blocks). A resumed
    run forms them again from the tangents the checkpoint stores (through checkpoint.h5 here)
    and goes on as the uninterrupted run does: the same factors to the bit, the same
    rebuilds after, the same forces."""
    import h5py

    from contact.procedure import Snapshot
    from pipelines.output.checkpoint import read_snapshot, write_snapshot

    case = flat_on_flat(8, layers=3, slip_amplitude=2e-2, cycles=3)
    space = ContactSpace(assemble(case.bodies, case.slave, case.master, loads=case.loads,
                                  motions=case.motions).structure)
    settings = NewtonSettings(linear=KrylovSettings(direct_below=0, factors_kept=16))
    kept = ContactSolver(space, case.law, settings)
    equilibrium, state = kept.initial_equilibrium(), case.initial_state(space.structure.n_points)
    split = len(case.history) // 2
    for amplitudes in case.history[:split]:
        equilibrium, state, _, _ = kept.increment(equilibrium, state, amplitudes, case.effects)
    kept.at_checkpoint()
    assert len(kept.linear._pool.factors) > 1  # kept through the checkpoint
    snapshot = Snapshot(split, 0, split, 0, 0.0, 1.0, None, None, state.cof, state, equilibrium,
                        [], predictors=kept.predictor_memory(), linear=kept.linear_memory())
    with h5py.File(tmp_path / "checkpoint.h5", "w") as file:
        write_snapshot(file.create_group("checkpoint"), _with_summary(snapshot), None)
    with h5py.File(tmp_path / "checkpoint.h5", "r") as file:
        read = read_snapshot(file["checkpoint"], None)
    resumed = ContactSolver(space, case.law, settings)
    resumed.recall_predictors(read.predictors)
    resumed.recall_linear(read.linear)
    pairs = list(zip(kept.linear._pool.factors, resumed.linear._pool.factors, strict=True))
    for ours, theirs in pairs:
        assert np.array_equal(ours.lu, theirs.lu) and np.array_equal(ours.pivots, theirs.pivots)
        assert np.array_equal(ours.points, theirs.points) and np.array_equal(ours.control_scale, theirs.control_scale)
        assert (ours.last_used, ours.age) == (theirs.last_used, theirs.age)
    ends, rebuilds = [], []
    for solver in (kept, resumed):
        formed = solver.linear.counters.factorisations
        e, s = equilibrium, state
        for amplitudes in case.history[split:]:
            e, s, _, _ = solver.increment(e, s, amplitudes, case.effects)
        ends.append(e.forces)
        rebuilds.append(solver.linear.counters.factorisations - formed)
    assert np.array_equal(*ends) and rebuilds[0] == rebuilds[1]


def _with_summary(snapshot):
    """``snapshot`` with the one cycle summary a checkpoint stores (its fields only matter
    to a resumed run's verdict, not to its solver)."""
    from contact.procedure import CycleSummary
    from pipelines.output.checkpoint import SUMMARY_ARRAYS

    n = snapshot.state.cof.size
    summary = CycleSummary(cycle=snapshot.cycle_number, phase="cof", equivalent_cycles=1.0, state=snapshot.state,
                           clamp_force=None, **{name: np.zeros(n) for name in SUMMARY_ARRAYS})
    summary.figures = {}
    snapshot.history = [summary]
    return snapshot


def test_pool_chooses_the_preconditioner_of_the_nearest_tangent_that_covers_the_closed_points():
    from contact.linear import _Factor, _Pool

    n, dim = 6, 3
    rng = np.random.default_rng(3)
    tangents = [rng.normal(size=(n, dim, dim)) for _ in range(3)]
    pool = _Pool()
    pool.size = 3
    covered = [np.arange(n), np.arange(n), np.arange(3)]  # the third covers points 0-2 only
    factors = []
    for blocks, points in zip(tangents, covered):
        factors.append(_Factor(np.eye(2), np.arange(2), points, blocks[points].copy(), np.ones(0), 1.0))
        pool.add(factors[-1], n)
    near_second = tangents[1] + 1e-3 * rng.normal(size=(n, dim, dim))
    assert pool.nearest(near_second, np.arange(n)) is factors[1]
    # the third is nearest on its points but does not cover point 4
    near_third = tangents[0].copy()
    near_third[:3] = tangents[2][:3]
    assert pool.nearest(near_third, np.array([0, 4])) is not factors[2]
    only_third = np.zeros((n, dim, dim))
    only_third[:3] = tangents[2][:3]  # points 3-5 open: the third is exact, and covers 0 and 1
    assert pool.nearest(only_third, np.array([0, 1])) is factors[2]
    # equal distance: the most recently used
    pool = _Pool()
    pool.size = 2
    twins = [_Factor(np.eye(2), np.arange(2), np.arange(n), tangents[0].copy(), np.ones(0), 1.0) for _ in range(2)]
    for twin in twins:
        pool.add(twin, n)
    assert pool.nearest(tangents[0], np.arange(n)) is twins[1]
    # beyond its size, the least recently used goes
    pool.nearest(tangents[0], np.arange(n))
    third = _Factor(np.eye(2), np.arange(2), np.arange(n), tangents[2].copy(), np.ones(0), 1.0)
    pool.add(third, n)
    assert third in pool.factors and twins[0] not in pool.factors


def test_a_preconditioner_that_fails_on_one_tangent_is_kept_for_its_own(flat):
    """GMRES that does not converge with the nearest factor rebuilds one at the current
    tangent, and the factor that failed stays for the tangents it is near (under a cyclic
    load, the same step of the next cycle): solving at its own tangent again takes it, in
    one Krylov iteration, and both corrections equal the dense solve."""
    case, space = flat
    first, second = _tangent(case, space, 0), _tangent(case, space, 7)
    second[7:] *= 3.0  # far from the first: one Krylov iteration cannot bridge it
    rng = np.random.default_rng(2)
    r_kin, r_ctl = rng.normal(0.0, 1e-4, space.n_rows), rng.normal(0.0, 10.0, space.n_control)
    solver = NewtonLinearSolver(space, KrylovSettings(direct_below=0, relative_tolerance=1e-12, max_iterations=1,
                                                      single_precision=False))
    for blocks in (first, second):
        expected = np.linalg.solve(_full_system(space, blocks), -np.concatenate([r_kin, r_ctl]))
        got = np.concatenate(solver.solve(blocks, r_kin, r_ctl))
        assert np.max(np.abs(got - expected)) <= 1e-8 * np.max(np.abs(expected))
    assert solver.counters.factorisations == 2  # the second solve failed and rebuilt
    kept = solver._pool.factors
    assert len(kept) == 2 and np.array_equal(kept[0].blocks, first)
    iterations = solver.counters.krylov_iterations
    solver.solve(first, r_kin, r_ctl)
    assert solver.counters.factorisations == 2 and solver.counters.krylov_iterations == iterations + 1


def test_pool_keeps_as_many_preconditioners_as_fit_in_its_memory(flat):
    """factors_bytes bounds the preconditioners' memory: as many as fit are kept (at most
    factors_kept, at least one), each a (rows + controls)² array of 4 (single) or 8 bytes."""
    _, space = flat
    size = space.n_rows + space.n_control
    for precision, itemsize in ((True, 4), (False, 8)):
        for room, expected in ((0.5, 1), (1, 1), (3.5, 3), (100, 16)):
            settings = KrylovSettings(single_precision=precision, factors_kept=16,
                                      factors_bytes=room * itemsize * size**2)
            assert NewtonLinearSolver(space, settings)._pool.size == expected


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("rows", [40, 1500])
def test_symmetric_product_reads_one_triangle_and_equals_the_general_product(dtype, rows):
    """W·λ of a symmetric W equals the general product to the product's own error bound
    (rows·eps of |W|·|λ|); from SYMMETRIC_PRODUCT_BYTES up only W's upper triangle is read,
    so a matrix whose lower triangle is garbage gives the product of the symmetric one."""
    rng = np.random.default_rng(3)
    upper = rng.standard_normal((rows, rows))
    symmetric = np.triu(upper) + np.triu(upper, 1).T
    matrix, vector = symmetric.astype(dtype), rng.standard_normal(rows)
    bound = rows * np.finfo(dtype).eps * (np.abs(symmetric) @ np.abs(vector))
    expected = symmetric @ vector
    assert np.all(np.abs(symmetric_product(matrix, vector) - expected) <= bound)
    # a principal submatrix gathered as W[rows][:, rows] comes out in Fortran order
    assert np.all(np.abs(symmetric_product(np.asfortranarray(matrix), vector) - expected) <= bound)
    if matrix.nbytes >= SYMMETRIC_PRODUCT_BYTES:
        garbage = matrix + np.tril(np.full_like(matrix, 1e3), -1)
        assert np.all(np.abs(symmetric_product(garbage, vector) - expected) <= bound)
        assert np.all(np.abs(symmetric_product(np.asfortranarray(garbage), vector) - expected) <= bound)
