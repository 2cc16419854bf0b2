"""The bolted double beam (paper §3.2) at a coarse setting: bolt pretension and the COF phase.

Low slip (30 kN, ±1.4 mm) is in partial slip from the first cycle, so the COF evolves over
part of the pad only and stays at μ0 elsewhere; high slip (20 kN, ±2.3 mm) starts in gross
slip and the COF evolves over the whole contact (the paper's Fig. 8).
"""

from pathlib import Path

import numpy as np
import pytest

from contact import procedure
from contact.solver import ContactSolver
from contact.structure import ContactSpace
from pipelines import scene as scenes
from pipelines.build import build

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
COARSE = {"bodies.upper.mesh.contact_size": 3.0, "bodies.lower.mesh.contact_size": 3.0,
          "procedure.increments_per_cycle": 8, "procedure.cof_cycles": 6, "procedure.wear_cycles": 0,
          "scene.effects": ["bolts", "cof_evolution"]}


def _run(name):
    model = build(scenes.load(EXAMPLES / f"{name}.toml", COARSE))
    solver = ContactSolver(ContactSpace(model.assembly.structure), model.law, model.settings)
    return model, procedure.run(solver, model.initial_state(), model.program, model.procedure,
                                cof_evolution=True, wear=False)


@pytest.fixture(scope="module")
def low():
    return _run("double_beam_low_slip")


@pytest.fixture(scope="module")
def high():
    return _run("double_beam_high_slip")


def test_bolt_carries_exactly_its_pretension_when_locked(low, high):
    for (model, result), pretension in ((low, 30000.0), (high, 20000.0)):
        assert result.figures["bolt_force_initial_N"] == pytest.approx(pretension, rel=1e-9)
        # Locked at its length, the bolt then follows the joint: a small change, not a reset.
        assert abs(result.figures["bolt_force_final_N"] / pretension - 1.0) < 0.02


def test_low_slip_is_partial_slip_from_the_first_cycle(low):
    model, result = low
    first = result.cycles[0].figures
    assert 0.05 < first["slip_area_fraction"] < 0.6
    assert first["stick_area_fraction"] > 0.4
    cof = result.state.cof
    closed = result.cycles[-1].status > 0
    assert np.any(np.isclose(cof[closed], 0.2))  # behind the hole the COF never moved
    assert np.all(cof <= 0.7 + 1e-12) and np.any(cof > 0.25)


def test_high_slip_starts_in_gross_slip_and_cof_evolves_everywhere(high):
    _, result = high
    first = result.cycles[0].figures
    assert first["slip_area_fraction"] >= 0.9 and first["stick_area_fraction"] < 0.1
    assert result.figures["cof_evolved_area_fraction"] >= 0.95
