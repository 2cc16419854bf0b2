"""The point status an increment reports when it was cut back: the worst of its sub-steps (QA:
a point that slid in a cut-back sub-step and stuck in the last was reported stuck, so the stick
area was overstated, the slip area understated and the stick margin taken from a point that
slid)."""

from types import SimpleNamespace

import numpy as np

from contact.law import ContactLaw, ContactState, Status, evaluate
from contact.solver import Effects, IncrementStats, advance_with_cutbacks

LAW = ContactLaw(normal_stiffness=1e5, critical_slip=1e-3, cof_max=0.5)
STATE = ContactState.initial(3, 2, 0.5)


class ScriptedSolver:
    """Fails the whole increment once; then its two half sub-steps slide point 0 and stick it."""

    law = LAW
    settings = SimpleNamespace(max_cutbacks=4, wear_cap=np.inf)

    def __init__(self):
        self.calls = []

    def _solve_to(self, start, state, target, stats: IncrementStats, position):
        self.calls.append(float(target[0]))
        if len(self.calls) == 1:
            return None  # the whole increment fails: cut back to halves
        overclosure = np.full(3, 1e-3)  # all pressed, p = 100 MPa
        slip = np.zeros((3, 2))
        if len(self.calls) == 2:  # first half: point 0 slides 5 µm, the others stick
            slip[0, 0] = 5e-3
        else:  # second half: it comes back inside its elastic slip
            slip[0, 0] = -state.elastic_slip[0, 0] - 0.5e-3
        return SimpleNamespace(amplitudes=np.asarray(target)), evaluate(overclosure, slip, state, LAW)

    def _failure_reason(self):
        return "scripted"


def test_a_point_that_slid_in_a_cut_back_sub_step_is_reported_sliding():
    solver = ScriptedSolver()
    start = SimpleNamespace(amplitudes=np.zeros(1))
    _, state, status, stats = advance_with_cutbacks(solver, start, STATE, np.ones(1), Effects())
    assert solver.calls == [1.0, 0.5, 1.0] and stats.cutbacks == 1 and stats.substeps == 2
    last = evaluate(np.full(3, 1e-3), np.zeros((3, 2)), state, LAW)
    assert last.status[0] == Status.STICK  # it ends the increment stuck ...
    assert status[0] >= Status.SLIP  # ... but slid within it
    assert np.all(status[1:] == Status.STICK)
    assert state.elastic_slip[0, 0] < 0.0  # the state is the last sub-step's, not merged
