"""A bolted joint that has lost its clamp has loosened, whatever the trend (QA, 2026-11-28: a
double beam whose tilted bolt lost all 20 kN in its second cycle was called `damage`, `stick`
or `loosening` by the length of its wear phase: nothing pressed slides with any pressure, so
the sliding measures read as stick, and the loosening window never filled)."""

from pathlib import Path
from types import SimpleNamespace

import h5py
import pytest

from contact.procedure import Procedure
from contact.verdict import clamp_lost, verdict
from pipelines import scene as scenes
from pipelines.jobs.run import run_scene

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_the_clamp_is_lost_at_the_stated_fraction_of_the_initial_clamp():
    procedure = Procedure(clamp_loss_limit=0.5)
    assert not clamp_lost(10_001.0, 20_000.0, procedure)
    assert clamp_lost(10_000.0, 20_000.0, procedure) and clamp_lost(0.0, 20_000.0, procedure)
    assert not clamp_lost(None, None, procedure) and not clamp_lost(5.0, None, procedure)  # no bolts
    assert clamp_lost(15_000.0, 20_000.0, Procedure(clamp_loss_limit=0.25))


def test_a_lost_clamp_is_loosening_even_where_nothing_slides():
    quiet = SimpleNamespace(figures={"active_slip_area_fraction": 0.0, "slip_area_fraction": 0.0,
                                     "stick_area_fraction": 0.0}, phase="cof", clamp_force=0.0)
    procedure = Procedure()
    assert verdict([quiet], procedure, stationary=True) == "stick"
    assert verdict([quiet], procedure, stationary=True, lost_clamp=True) == "loosening"


def test_a_bolt_that_loses_its_clamp_in_the_cof_phase_ends_the_run_as_loosening(tmp_path):
    # the high-slip double beam with its bolt tilted 5° off the beams' normal: the bolt force
    # falls from 20 kN to nothing in the second COF cycle as the upper beam slides off
    scene_file = tmp_path / "tilted.toml"
    scene_file.write_text(f'''[scene]
base = "{EXAMPLES / 'double_beam_high_slip.toml'}"
name = "tilted_bolt"
[procedure]
cof_cycles = 4
wear_cycles = 3
[bodies.lower]
reference_points.nut = {{ nodes = {{ ring = {{ center = [40.0, 0.0, -8.0], axis = "z", inner_radius = 6.4, outer_radius = 11.0 }} }}, position = [41.4, 0.0, -8.0], rotations = true }}
[bolts.m12]
axis = [0.08715574274765817, 0.0, -0.9961946980917455]
''')
    outcome = run_scene(scenes.load(scene_file), tmp_path / "out", progress=False, plots=False)
    summary = outcome.summary
    assert summary["verdict"] == "loosening"
    assert summary["clamp_force_loss_fraction"] >= 0.5
    assert summary["cycles_run"] < 4  # stopped in the COF phase, the wear phase never began
    assert summary["loosening_evident_at_cycles"] == pytest.approx(summary["cycles_run"])
    with h5py.File(outcome.results_path) as results:
        assert results.attrs["ending"] == "loosening"
