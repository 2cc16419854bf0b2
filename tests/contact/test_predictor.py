"""The cyclic predictors of Newton (contact/solver.py): the equilibrium last solved for the same
load step, and the extrapolation of the last two.

A triangular tangential cycle passes every level twice, rising and falling; with friction the
two equilibria differ, so a predictor keyed by the load level alone starts the falling branch
from the rising one. Keyed by the load step, a steady cycle is solved by its predictor.
"""

import numpy as np
import pytest

from contact.assembly import assemble
from contact.solver import ContactSolver, Effects, Equilibrium, _extrapolation_factor, _load_step
from contact.structure import ContactSpace
from tests.bench.bench_report import flat_on_flat


@pytest.fixture(scope="module")
def flat():
    # a stroke of ±5 µm (γ_crit = 1 µm) in four increments a cycle: 0 falling, −δ, 0 rising, +δ
    case = flat_on_flat(6, layers=3, cycles=4, slip_amplitude=5e-3, increments_per_quarter=1)
    structure = assemble(case.bodies, case.slave, case.master, loads=case.loads, motions=case.motions).structure
    return case, ContactSpace(structure)


def _run(case, space, effects: Effects, forget: bool = False, history=None, positions=None):
    """Forces (N) and Newton iterations of every increment of the case's history (or of
    ``history``, with the cycle ``positions`` of its increments); with ``forget`` the solver
    forgets its predictors before every increment."""
    solver = ContactSolver(space, case.law)
    equilibrium, state = solver.initial_equilibrium(), case.initial_state(space.structure.n_points)
    forces, iterations = [], []
    history = case.history if history is None else history
    for amplitudes, position in zip(history, positions or [None] * len(history)):
        if forget:
            solver.recall_predictors({})
        equilibrium, state, _, stats = solver.increment(equilibrium, state, amplitudes, effects, position)
        forces.append(equilibrium.forces)
        iterations.append(stats.iterations)
    return np.array(forces), np.array(iterations)


def test_a_steady_cycle_is_solved_by_its_predictor_on_the_rising_and_the_falling_branch(flat):
    case, space = flat
    forces, iterations = _run(case, space, Effects())  # constant COF: steady after one cycle
    per_cycle = 4
    last, before = forces[-per_cycle:], forces[-2 * per_cycle:-per_cycle]
    scale = np.max(np.abs(last))
    assert np.max(np.abs(last - before)) <= 1e-6 * scale  # the physics: a steady cycle
    friction = last.reshape(per_cycle, -1, 3)[:, :, 1:].sum(axis=1)  # (increment, 2) N
    # at the same load (no stroke) the falling and the rising branch hold opposite friction
    # forces, a tenth of the largest or more
    along = np.argmax(np.abs(friction).max(axis=0))  # the stroke's direction
    total = friction[:, along]
    assert total[0] * total[2] < 0.0 and min(abs(total[0]), abs(total[2])) > 0.1 * np.max(np.abs(total))
    # each increment of the last two cycles converges in one Newton step from its predictor;
    # without the predictors (forgotten every increment) it takes more
    assert np.all(iterations[-2 * per_cycle:] == 1), iterations[-2 * per_cycle:]
    _, without = _run(case, space, Effects(), forget=True)
    assert np.all(without[-2 * per_cycle:] > 1), without[-2 * per_cycle:]


def test_the_predictors_do_not_change_the_answer(flat):
    case, space = flat
    effects = Effects(cof_evolution=True)
    remembered, iterations = _run(case, space, effects)
    forgotten, iterations_forgotten = _run(case, space, effects, forget=True)
    scale = np.max(np.abs(forgotten))
    assert np.max(np.abs(remembered - forgotten)) <= 1e-8 * scale
    assert iterations[-8:].sum() < iterations_forgotten[-8:].sum()


def _run_up(case, cycles: int = 10):
    """The case's cycle with its stroke growing from 30 to 100 % over ``cycles`` cycles (a
    vibration that runs up), and the (k, 4) position of every increment in its cycle."""
    one_cycle = case.history[2:6]
    history, positions = list(case.history[:2] * np.array([1.0, 0.3])), [None, None]
    for c in range(cycles):
        for k, amplitudes in enumerate(one_cycle, start=1):
            history.append(amplitudes * np.array([1.0, 0.3 + 0.7 * c / (cycles - 1)]))
            positions.append((k, 4))
    return history, positions


def test_a_running_up_cycle_is_recalled_by_its_position_in_the_cycle(flat):
    """While the stroke grows, no load step repeats: keyed by its start and end amplitudes, no
    cycle is ever recalled. Keyed by the increment's place in the cycle, the same point of the
    last two cycles and their extrapolation are: fewer Newton iterations, the same answer."""
    case, space = flat
    history, positions = _run_up(case)
    effects = Effects(cof_evolution=True)
    by_amplitudes, iterations = _run(case, space, effects, history=history)
    by_position, iterations_position = _run(case, space, effects, history=history, positions=positions)
    scale = np.max(np.abs(by_amplitudes))
    assert np.max(np.abs(by_position - by_amplitudes)) <= 1e-8 * scale
    last = slice(-16, None)  # the last four cycles: gross slip at the stroke's ends
    assert iterations[last].sum() >= 1.5 * iterations_position[last].sum(), (iterations, iterations_position)


def test_extrapolation_factor_follows_the_wear_gap():
    before = np.array([0.0, 1e-3, 2e-3])
    step = np.array([1e-4, 2e-4, 0.0])
    assert _extrapolation_factor(before, before + step, before + 3 * step) == pytest.approx(2.0)
    assert _extrapolation_factor(before, before + step, before + step) == 0.0
    assert _extrapolation_factor(0.0, 0.0, 0.0) == 1.0  # no wear: the step between the two
    assert _extrapolation_factor(before, before + step, before - step) == 0.0  # never backwards



def test_the_predictor_memory_stays_bounded_under_a_load_that_never_repeats(flat):
    case, space = flat
    solver = ContactSolver(space, case.law)
    state = case.initial_state(space.structure.n_points)
    start = solver.initial_equilibrium()
    for k in range(1, 400):
        amplitudes = np.array([1.0, 1e-6 * k])
        solved = Equilibrium(start.kinematics, start.control, start.forces, amplitudes)
        solver._remember(_load_step(start.amplitudes, amplitudes), solved, state)
        start = solved
    assert len(solver._solved_at) <= 128
    # the newest level and step are kept
    assert any(v[0][0] is start for v in solver._solved_at.values())


@pytest.mark.parametrize("by_position", [False, True], ids=["load steps", "cycle positions"])
def test_the_predictor_memory_survives_a_checkpoint_bit_for_bit(flat, by_position):
    """A solver that takes up another's memory (a resumed run) solves the next cycle to the
    same bits as the one that kept it, whether its steps were known by their amplitudes or by
    their place in the cycle."""
    case, space = flat
    effects = Effects(cof_evolution=True)
    history, positions = (_run_up(case, cycles=6) if by_position
                          else (case.history, [None] * len(case.history)))
    kept = ContactSolver(space, case.law)
    equilibrium, state = kept.initial_equilibrium(), case.initial_state(space.structure.n_points)
    split = len(history) - 4  # before the last cycle
    for amplitudes, position in zip(history[:split], positions[:split]):
        equilibrium, state, _, _ = kept.increment(equilibrium, state, amplitudes, effects, position)
    memory = kept.predictor_memory()
    assert memory["last"].size == len(kept._solved_at) and np.all(memory["before"] < memory["kinematics"].shape[0])
    resumed = ContactSolver(space, case.law)
    resumed.recall_predictors({name: value.copy() for name, value in memory.items()})
    assert list(resumed._solved_at) == list(kept._solved_at)
    kept.forget_cached_factorisations()  # as at a checkpoint
    ends = []
    for solver in (kept, resumed):
        e, s = equilibrium, state
        iterations = []
        for amplitudes, position in zip(history[split:], positions[split:]):
            e, s, _, stats = solver.increment(e, s, amplitudes, effects, position)
            iterations.append(stats.iterations)
        # the predictors were there: one Newton step each in the steady cycle, and the
        # resumed solver needs exactly what the one that kept them did
        assert by_position or iterations == [1] * 4, iterations
        ends.append((e.forces, iterations))
    assert np.array_equal(ends[0][0], ends[1][0]) and ends[0][1] == ends[1][1]
