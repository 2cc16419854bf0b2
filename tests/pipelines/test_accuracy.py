"""Accuracy-versus-time study: errors against the reference, the recommendation rule, the CLI."""

import json
import math

import numpy as np
import pytest

from pipelines import scene as scenes
from pipelines.studies.accuracy import accuracy_study
from pipelines.studies.knobs import (TOLERANCE, Run, base_overrides, errors, knobs_for, pareto_front, recommend,
                                     setting_overrides)
from pipelines.cli.main import main


def _record(label, cpu_time, worst, agrees=True, failure=None):
    return {"label": label, "cpu_time_s": cpu_time, "worst_error": worst, "verdict_agrees": agrees,
            "failure": failure, "within_tolerance": agrees and worst <= TOLERANCE}


def test_recommendation_is_the_cheapest_run_within_two_percent():
    records = [_record("reference", 10.0, 0.0), _record("coarse mesh", 2.0, 0.019),
               _record("fewer increments", 3.0, 0.005), _record("soft kn", 1.0, 0.021),
               _record("big jump", 0.5, 0.0, agrees=False), _record("stiff", 0.1, math.inf, failure="no")]
    assert recommend(records)["label"] == "coarse mesh"
    assert recommend(records, tolerance=0.01)["label"] == "fewer increments"
    assert recommend([_record("a", 1.0, 0.5)]) is None


def test_pareto_front_keeps_only_runs_no_other_beats_in_time_and_error():
    records = [_record("reference", 10.0, 0.0), _record("a", 2.0, 0.019), _record("b", 3.0, 0.05),
               _record("c", 1.0, 0.3), _record("failed", 0.1, math.inf, failure="no")]
    assert [r["label"] for r in pareto_front(records)] == ["c", "a", "reference"]


def test_cof_map_error_takes_the_nearest_point_of_a_different_mesh():
    coarse = np.array([[0.0, 0.0], [1.0, 0.0]])
    fine = np.array([[0.0, 0.0], [0.4, 0.0], [0.6, 0.0], [1.0, 0.0]])
    reference = Run("reference", {}, (), values={"cof_rise": 0.5}, cof=np.array([0.2, 0.2, 0.4, 0.4]),
                    coordinates=fine)
    run = Run("coarse", {}, ("contact_size",), values={"cof_rise": 0.5}, cof=np.array([0.2, 0.5]),
              coordinates=coarse)
    # nearest coarse point of each fine point: 0, 0, 1, 1 → differences 0, 0, 0.1, 0.1
    assert errors(run, reference)["cof_map"] == pytest.approx(np.sqrt(0.02 / 4) / 0.5)


def test_cycle_jump_keeps_the_equivalent_cycles(coarse_cylinder):
    scene = scenes.load(coarse_cylinder)
    knobs, not_applicable = knobs_for(scene, quick=False)
    jump = next(k for k in knobs if k.name == "cycle_jump")
    assert jump.values[0] == 1000.0  # finest: the scene's J with its 2 wear cycles
    overrides = setting_overrides(scene, {"cycle_jump": jump.values[-1]})
    assert overrides["procedure.wear_cycles"] * overrides["procedure.cycle_jump"] == pytest.approx(2000.0)
    assert {"craig_bampton_modes", "mbs_time_step", "cof_cycles"} <= set(not_applicable)


def test_an_adaptive_jump_is_studied_by_its_tolerance(coarse_cylinder):
    """A scene with cycle_jump = "auto" has no J to sweep (QA: the study multiplied the wear
    cycles by the string "auto" and stopped with an internal error on every counterweight
    scene): its knob is the jump tolerance θ, finest (smallest) first."""
    scene = scenes.load(coarse_cylinder, {"procedure.cycle_jump": "auto", "procedure.jump_tolerance": 0.04})
    knobs, not_applicable = knobs_for(scene, quick=False)
    assert "cycle_jump" not in [k.name for k in knobs] and "adaptive" in not_applicable["cycle_jump"]
    tolerance = next(k for k in knobs if k.name == "jump_tolerance")
    assert tolerance.values == (0.02, 0.04, 0.08) and not tolerance.finer_is_larger
    assert next(k for k in knobs_for(scene, quick=True)[0] if k.name == "jump_tolerance").values == (0.04, 0.08)
    overrides = setting_overrides(scene, {"jump_tolerance": 0.08})
    assert overrides == {"procedure.jump_tolerance": 0.08}
    scenes.load(coarse_cylinder, {"procedure.cycle_jump": "auto", **overrides})  # a valid scene


def test_the_study_runs_the_scene_as_fretwork_run_does(coarse_cylinder, tmp_path):
    """Finite sliding where the scene asks for it (QA: the study always ran small sliding, so its
    reference differed from `fretwork run`'s by 0.24 % in max wear on the cylinder)."""
    from contact.sliding import SlidingSolver
    from contact.solver import ContactSolver
    from pipelines.build import build

    from pipelines.jobs.run import run_scene
    from pipelines.studies.accuracy import run_setting

    assert isinstance(build(scenes.load(coarse_cylinder)).solver(), SlidingSolver)  # sliding "auto"
    small = build(scenes.load(coarse_cylinder, {"contact.sliding": "small"})).solver()
    assert isinstance(small, ContactSolver)
    # on the shipped 0.05 mm elements the 75 µm slip re-pairs (14 times in 2 cycles of 12 increments)
    fine = {"bodies.cylinder.mesh.contact_size": 0.05, "bodies.plane.mesh.contact_size": 0.05}
    studied = run_setting(coarse_cylinder, fine, "as shipped", {}, ())
    run = run_scene(scenes.load(coarse_cylinder, fine), tmp_path / "run", progress=False, plots=False)
    assert run.summary["repairings"] > 0
    assert studied.values["max_wear_depth_mm"] == run.summary["max_wear_depth_mm"]  # the same bits
    fixed = run_setting(coarse_cylinder, {**fine, "contact.sliding": "small"}, "small", {}, ())
    assert fixed.values["max_wear_depth_mm"] != run.summary["max_wear_depth_mm"]  # 0.24 % apart


def test_a_shortened_cof_phase_keeps_the_vibration_run_up_inside_it():
    """The counterweight's vibration runs up over most of its COF phase; the study's caps (40,
    or 10 with --quick) and the cof_cycles knob keep that share, and the scenes they make are
    valid."""
    from pathlib import Path
    path = Path(__file__).resolve().parents[2] / "examples" / "counterweight.toml"
    scene = scenes.load(path)
    share = scene.data["procedure"]["vibration_run_up"] / scene.data["procedure"]["cof_cycles"]
    assert 0.0 < share < 1.0
    for quick, cof_cycles in ((False, 40), (True, 10)):
        overrides = base_overrides(scene, quick)
        assert overrides["procedure.cof_cycles"] == cof_cycles
        assert abs(overrides["procedure.vibration_run_up"] - share * cof_cycles) <= 0.5
        scenes.load(path, overrides)  # raises InputError if the run-up exceeded the COF phase
    assert abs(setting_overrides(scene, {"cof_cycles": 30})["procedure.vibration_run_up"] - share * 30) <= 0.5
    longer = scene.data["procedure"]["vibration_run_up"] + 1
    assert "procedure.vibration_run_up" not in setting_overrides(scene, {"cof_cycles": longer})


def test_study_on_a_tiny_sweep_of_the_coarse_cylinder(coarse_cylinder):
    study = accuracy_study(coarse_cylinder, quick=True,
                           sweeps={"contact_size": [0.2, 0.4], "increments_per_cycle": [12, 6],
                                   "normal_stiffness": [4.0e6], "critical_slip": [1.0e-3], "cycle_jump": [1000.0]})
    reference, *others = study.records
    assert reference["label"] == "reference" and reference["errors"]["max_wear_depth_mm"] == 0.0
    assert reference["worst_error"] == 0.0 and reference["verdict_agrees"]
    assert {r["label"] for r in others} >= {"contact_size=0.4", "increments_per_cycle=6"}
    for record in others:
        assert record["failure"] is None
        assert set(record["errors"]) == {"max_wear_depth_mm", "slip_area_fraction"}
        assert all(np.isfinite(list(record["errors"].values()))) and record["cpu_time_s"] > 0
    # fewer increments per cycle change the wear of a gross-slip scar: the error is seen
    coarse_increments = next(r for r in others if r["label"] == "increments_per_cycle=6")
    assert coarse_increments["errors"]["max_wear_depth_mm"] > 0.0
    assert study.recommendation is not None and study.recommendation["worst_error"] <= TOLERANCE


def test_cli_writes_plot_and_json(coarse_cylinder, tmp_path, capsys):
    out = tmp_path / "acc"
    code = main(["study", "accuracy", str(coarse_cylinder), "--quick", "--json", "--out", str(out),
                 "--knob", "contact_size=0.2", "--knob", "increments_per_cycle=12,6",
                 "--knob", "normal_stiffness=4e6", "--knob", "critical_slip=1e-3",
                 "--set", "procedure.wear_cycles=1"])
    assert code == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed["base_overrides"] == {"procedure.wear_cycles": 1}
    assert [r["label"] for r in printed["records"]] == ["reference", "increments_per_cycle=6"]
    assert (out / "accuracy_cylinder_on_plane.png").stat().st_size > 10_000
    assert json.loads((out / "accuracy_cylinder_on_plane.json").read_text())["scene"] == "cylinder_on_plane"


def test_cli_bad_input_exits_2(coarse_cylinder, tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(coarse_cylinder.read_text().replace("critical_slip", "critcal_slip"))
    assert main(["study", "accuracy", str(bad), "--out", str(tmp_path / "o")]) == 2
    assert "critcal_slip" in capsys.readouterr().err
    assert main(["study", "accuracy", str(tmp_path / "missing.toml")]) == 2
    assert main(["study", "accuracy", str(coarse_cylinder), "--knob", "cof_cycles=5,10"]) == 2
    assert "cof_cycles" in capsys.readouterr().err
    assert main(["study", "accuracy", str(coarse_cylinder), "--knob", "contact_size=-1"]) == 2


def test_a_contact_size_the_mesh_generator_rejects_stops_before_any_run(tmp_path, capsys):
    from pathlib import Path
    beam = Path(__file__).resolve().parents[2] / "examples" / "double_beam_low_slip.toml"
    # half the beam width (15 mm) is not a multiple of 4 mm
    assert main(["study", "accuracy", str(beam), "--knob", "contact_size=3,4", "--out", str(tmp_path)]) == 2
    error = capsys.readouterr().err
    assert "contact_size 4 mm" in error and "multiples" in error
    assert not list(tmp_path.iterdir())


def test_a_failing_combination_steps_back_the_knob_that_erred_most_alone():
    from pipelines.studies.knobs import Knob, _step_back
    knobs = [Knob("contact_size", "h", (0.05, 0.1, 0.2), False), Knob("cycle_jump", "J", (1000.0, 2000.0), False)]
    records = [{"varied": ["contact_size"], "settings": {"contact_size": 0.2, "cycle_jump": 1000.0},
                "worst_error": 0.015},
               {"varied": ["contact_size"], "settings": {"contact_size": 0.1, "cycle_jump": 1000.0},
                "worst_error": 0.004},
               {"varied": ["cycle_jump"], "settings": {"contact_size": 0.05, "cycle_jump": 2000.0},
                "worst_error": 0.010}]
    combined = {"contact_size": 0.2, "cycle_jump": 2000.0}
    assert _step_back(knobs, records, combined, ("contact_size", "cycle_jump")) == {
        "contact_size": 0.1, "cycle_jump": 2000.0}


def test_multibody_scene_sweeps_modes_and_time_step(tmp_path):
    scene = tmp_path / "cw.toml"
    scene.write_text('[scene]\nname = "cw"\n\n[mbs]\nspeed_rpm = 750.0\nn_modes = 4\n\n'
                     '[mbs.solver]\nrevolutions = 1.0\ntime_step = 1.0e-4\n')
    study = accuracy_study(scene, quick=True, sweeps={"craig_bampton_modes": [4, 2]})
    assert [r["label"] for r in study.records] == ["reference", "craig_bampton_modes=2", "mbs_time_step=0.0002"]
    reference, *others = study.records
    assert reference["errors"] == {"wing_amplitude_mm": 0.0} and reference["values"]["wing_amplitude_mm"] > 0
    assert all(np.isfinite(r["errors"]["wing_amplitude_mm"]) and r["cpu_time_s"] > 0 for r in others)
    assert "contact_size" in study.not_applicable
    assert study.recommendation["overrides"].keys() == {"mbs.n_modes", "mbs.solver.time_step"}
