"""The shipped counterweight scenes reach the paper's verdicts (§3.3) at a coarse setting.

normal (100 µm) → stick; severe (230 µm) → stick after partial slip with the COF evolved;
extreme (300 µm) → loosening, the clamp force still falling and the worn area growing.
The scenes' own mesh and wear phase (65 × J 20); 40 COF cycles instead of 250 (the stuck cases
are stationary after 11–17, and the COF of the extreme case is at μ_max where it slides by then).
"""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest

from pipelines import scene as scenes
from pipelines.jobs.run import run_scene
from pipelines.stages import StageCache

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
COARSE = {"procedure.cof_cycles": 40}


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return StageCache(tmp_path_factory.mktemp("cw-cache"))


def run(name, tmp_path, cache):
    outcome = run_scene(scenes.load(EXAMPLES / f"{name}.toml", COARSE), tmp_path / name, progress=False,
                        plots=False, cache=cache)
    with h5py.File(outcome.results_path) as results:
        figures = {k: results["cycles/figures"][k][:] for k in results["cycles/figures"]}
        phase = results["cycles/phase"][:]
    return outcome.summary, figures, phase


def test_normal_operation_stays_stuck(tmp_path, cache):
    summary, _, phase = run("counterweight", tmp_path, cache)
    assert summary["verdict"] == "stick" and summary["stationary"]
    assert summary["wing_amplitude_mm"] == pytest.approx(0.1)
    assert not np.any(phase == 2)  # shaken down in the COF phase: no wear phase needed
    assert abs(summary["clamp_force_loss_fraction"]) < 1e-3
    assert summary["min_stick_margin"] > 0.2


def test_severe_overload_shakes_down_to_stick_after_partial_slip(tmp_path, cache):
    summary, figures, _ = run("counterweight_severe", tmp_path, cache)
    assert summary["verdict"] == "stick"
    assert figures["slip_area_fraction"][0] > 0.05  # partial slip at first ...
    assert summary["cof_evolved_area_fraction"] > 0.3  # ... so the COF rose over a large area
    assert summary["min_stick_margin"] < 0.2  # closer to the limit than normal operation


def test_extreme_overload_loosens_under_wear(tmp_path, cache):
    summary, figures, phase = run("counterweight_extreme", tmp_path, cache)
    assert summary["verdict"] == "loosening"
    wear = phase == 2
    clamp = figures["clamp_force_N"][wear]
    stick = figures["stick_area_fraction"][wear]
    worn = figures["worn_area_fraction"][wear]
    assert clamp[-1] < clamp[-10] < clamp[0]  # still falling at the end
    assert stick[-1] < stick[0] - 0.1  # the stuck area shrinks
    assert worn[-1] > worn[0] + 0.2 and worn[-1] > 0.4  # the worn area grows
