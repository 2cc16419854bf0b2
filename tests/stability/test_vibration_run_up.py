"""The vibration run-up ([procedure] vibration_run_up): an overload that exceeds the friction
capacity at μ0 but not at μ_max.

Blocks pressed by P = 10 kN (16 points, μ0 = 0.2, μ_max = 0.5), a force-controlled tangential
load cycled to Q = 0.3·P. Applied at full amplitude from the first cycle, Q passes μ0·P before
any COF has risen: no static solution exists and the run says so (slid off). Brought in over
20 cycles, the COF hardens where the edges slide while Q grows, the capacity Σ μ·p·A stays
above Q, and the joint shakes down to stick, judged only once the full amplitude acts.
"""

import tomllib
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pytest

from contact import procedure
from contact.procedure import LoadProgram, Observer, Procedure, RunStopped
from contact.tabulated import TabulatedProgram
from contact.verdict import Ending
from pipelines import scene as scenes
from stability_harness import flat

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
P, Q_RATIO, RUN_UP, N_INC, WINDOW = 1.0e4, 0.3, 20, 12, 5


@dataclass(frozen=True)
class Scaled(LoadProgram):
    """The program with each pattern's unit amplitude scaled to N."""

    scale: np.ndarray = 1.0

    def preload(self, fraction):
        return super().preload(fraction) * self.scale

    def cycle(self, phase, vibration=1.0):
        return super().cycle(phase, vibration) * self.scale


class Amplitudes(Observer):
    def __init__(self):
        self.rows = []

    def increment(self, record):
        if record.phase == "cof":
            self.rows.append((record.time, *record.equilibrium.amplitudes))


def _run(run_up, observer=None):
    base = flat(4, tangential="force")
    case = flat(4, tangential="force", law=replace(base.law, cof_max=0.5, cof_rate=1.0), cof0=0.2)
    program = Scaled(case.patterns, {"normal": "ramp", "tangential": "cyclic"},
                     scale=np.array([P, Q_RATIO * P]))
    settings = Procedure(preload_increments=2, increments_per_cycle=N_INC, cof_cycles=60,
                         vibration_run_up=run_up, stationary_window=WINDOW)
    return case, procedure.run(case.solver, case.state, program, settings, cof_evolution=True, wear=False,
                               observer=observer)


def test_a_step_to_the_overload_slides_off():
    with pytest.raises(RunStopped) as stopped:
        _run(0)
    assert stopped.value.ending == Ending.SLID_OFF


def test_run_up_hardens_the_cof_and_the_joint_shakes_down():
    observer = Amplitudes()
    case, result = _run(RUN_UP, observer)
    assert result.verdict == "stick" and result.stationary
    # Shakedown needs WINDOW quiet cycles at the full amplitude: none counts during the run-up;
    # it is dated from the last cycle that slid, the window only confirms it.
    assert result.figures["shakedown_at_cycles"] >= RUN_UP
    assert result.figures["equivalent_cycles"] == result.figures["shakedown_at_cycles"] + WINDOW
    per_point = result.equilibrium.forces.reshape(case.solver.n_points, -1)
    capacity = float(np.sum(result.state.cof * per_point[:, 0]))
    assert capacity >= Q_RATIO * P  # the hardened contact carries the load it could not carry at μ0
    assert float(np.sum(0.2 * per_point[:, 0])) < Q_RATIO * P
    assert np.all(result.state.cof <= 0.5)
    # The applied loads: P held, Q·sin 2πt growing linearly over the run-up, then full.
    time, normal, tangential = np.array(observer.rows).T
    expected = Q_RATIO * P * np.sin(2 * np.pi * (time % 1.0)) * np.minimum(1.0, time / RUN_UP)
    assert normal == pytest.approx(np.full_like(normal, P), rel=1e-12)
    assert tangential == pytest.approx(expected, abs=1e-9 * P)


def test_tabulated_history_keeps_its_mean_and_scales_its_vibration():
    samples = np.array([3.0, 5.0, 3.0, 1.0])  # mean 3, departure ±2
    program = TabulatedProgram(("h",), {"h": "history"}, tables={"h": samples})
    for phase in (0.25, 0.5, 0.6, 1.0):
        full = program.cycle(phase)[0]
        assert program.cycle(phase, 0.25)[0] == pytest.approx(3.0 + 0.25 * (full - 3.0), rel=1e-14)
        assert program.cycle(phase, 0.0)[0] == pytest.approx(3.0, rel=1e-14)


def test_run_up_longer_than_the_cof_phase_is_reported():
    data = tomllib.loads((EXAMPLES / "cylinder_on_plane.toml").read_text())
    data.setdefault("procedure", {}).update(cof_cycles=10, vibration_run_up=20)
    problems = scenes.validate(data)
    assert any("vibration_run_up" in p and "cof_cycles" in p for p in problems), problems
    data["procedure"]["vibration_run_up"] = 10
    assert not scenes.validate(data)
