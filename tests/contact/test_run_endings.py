"""How a run ends when its contact is not there: surfaces that slide or wear apart after the run
has started end it (ending ``separated``, a stopped simulation, not an input error); a preload
that closes no contact point is refused before any cycle instead of being judged stuck."""

from pathlib import Path

import pytest

from contact import procedure
from contact.procedure import Observer, RunStopped
from contact.sliding import SlidingSolver
from contact.verdict import Ending
from pipelines import scene as scenes
from pipelines.build import build
from reduction.errors import InputError
from reduction.threads import single_threaded_blas

SCENE = str(Path(__file__).resolve().parents[2] / "examples" / "gross_slip_fretting.toml")
#: the slave (the cylinder's ±2 mm) and the master (the plane's ±3 mm) overlap while the
#: cylinder has moved less than 5 mm along the plane
APART_MM = 5.0


@pytest.fixture(autouse=True, scope="module")
def one_blas_thread():
    with single_threaded_blas():
        yield


class Cycles(Observer):
    def __init__(self):
        self.cycles, self.increments = [], 0

    def increment(self, record):
        self.increments += 1

    def cycle(self, summary):
        self.cycles.append(summary.cycle)


def _model(stroke_mm: float, normal: dict | None):
    """The scene pressed by ``normal`` (a load, or none) and slid ±``stroke_mm`` by its reference point."""
    return build(scenes.load(SCENE, {
        "scene.effects": [], "loads": [normal] if normal else [],
        "motions": [{"name": "tangential", "dof": "cylinder.rp.ux", "value": stroke_mm, "history": "cyclic"}],
        "procedure.preload_increments": 2, "procedure.increments_per_cycle": 8,
        "procedure.cof_cycles": 2, "procedure.wear_cycles": 0}))


NORMAL = {"name": "normal", "dof": "cylinder.rp.uy", "value": -1066.0, "history": "ramp"}


def test_surfaces_that_slide_apart_after_the_start_end_the_run_as_separated():
    """A stroke of twice the distance at which the surfaces part: the build pairs them (its
    selections are right), the first cycle's re-pairing finds no master facet facing the slave."""
    model = _model(2 * APART_MM, NORMAL)
    solver = SlidingSolver(model.assembly, model.law, model.settings, mode="finite")
    seen = Cycles()
    with pytest.raises(RunStopped) as stopped:
        procedure.run(solver, model.initial_state(), model.program, model.procedure, cof_evolution=False,
                      wear=False, observer=seen)
    assert stopped.value.ending == Ending.SEPARATED and not isinstance(stopped.value, InputError)
    message = str(stopped.value)
    assert message.startswith("the contact surfaces no longer face each other") and "selection" not in message
    slid = float(message.split("moved up to ")[1].split(" mm along")[0])
    assert APART_MM - 1.0 < slid < 2 * APART_MM  # where they parted, within the stroke
    assert seen.increments > model.procedure.preload_increments  # it ran before it stopped


def test_a_stroke_within_the_surfaces_runs_to_its_end():
    model = _model(0.5 * APART_MM, NORMAL)
    solver = SlidingSolver(model.assembly, model.law, model.settings, mode="finite")
    result = procedure.run(solver, model.initial_state(), model.program, model.procedure, cof_evolution=False,
                           wear=False)
    assert result.ending == Ending.COMPLETED and solver.repairs > 0


def test_a_preload_that_closes_nothing_is_refused_before_any_cycle():
    """Without its normal load the cylinder only touches the plane: the preload closes no point,
    and a run of that open contact (nominal area 0) read as stuck."""
    model = _model(0.05, None)
    seen = Cycles()
    with pytest.raises(InputError, match="nothing presses the contact surfaces together after the preload: no "
                                         r"contact point is closed \(nominal contact area 0"):
        procedure.run(model.solver(), model.initial_state(), model.program, model.procedure, cof_evolution=False,
                      wear=False, observer=seen)
    assert seen.cycles == [] and seen.increments == model.procedure.preload_increments


def test_a_preload_that_closes_the_contact_is_judged():
    model = _model(0.05, NORMAL)
    result = procedure.run(model.solver(), model.initial_state(), model.program, model.procedure,
                           cof_evolution=False, wear=False)
    assert result.figures["nominal_contact_area"] > 0.0
