"""The convergence study's arithmetic: Richardson extrapolation, the converged size, overrides."""

import numpy as np
import pytest

from pipelines.studies.convergence import (
    Level,
    converged_size,
    richardson,
    size_overrides,
)


def test_richardson_recovers_a_second_order_sequence():
    sizes = [10.0, 5.0, 2.5]
    exact, constant = 0.37, 0.004
    values = [exact + constant * h ** 2 for h in sizes]
    found = richardson(sizes, values)
    assert found["order"] == pytest.approx(2.0, rel=1e-9)
    assert found["estimate"] == pytest.approx(exact, rel=1e-12)
    assert found["error_finest"] == pytest.approx(constant * 2.5 ** 2, rel=1e-9)


def test_richardson_uses_the_three_finest_levels_and_any_order():
    sizes = [1.25, 20.0, 5.0, 2.5]
    values = [1.0 - 0.1 * h ** 1.5 for h in sizes]
    values[1] = 123.0  # the coarsest level is outside the asymptotic range: not used
    found = richardson(sizes, values)
    assert found["order"] == pytest.approx(1.5, rel=1e-9)
    assert found["estimate"] == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize("sizes, values", [
    ([10.0, 5.0], [1.0, 1.1]),                    # two levels
    ([10.0, 5.0, 2.5], [1.0, 1.2, 1.0]),          # oscillating
    ([10.0, 5.0, 2.5], [1.0, 1.1, 1.3]),          # the differences grow: not converging
    ([10.0, 6.0, 2.5], [1.0, 1.1, 1.15]),         # no constant refinement ratio
    ([10.0, 5.0, 2.5], [1.0, None, 1.15]),        # a level without the figure
])
def test_richardson_declines_sequences_that_do_not_allow_it(sizes, values):
    assert richardson(sizes, values) is None


def test_an_exact_figure_extrapolates_to_itself():
    assert richardson([4.0, 2.0, 1.0], [0.5, 0.5, 0.5])["estimate"] == 0.5
    # no order where the two finest agree exactly (it was inf, written as Infinity: not JSON)
    assert richardson([4.0, 2.0, 1.0], [0.9, 0.5, 0.5]) == {"estimate": 0.5, "order": None, "error_finest": 0.0}


def test_the_json_of_a_study_is_strict_json():
    import json

    from pipelines.cli import json_text

    text = json_text({"order": float("inf"), "values": [1.0, float("nan")], "nested": {"x": np.float64("-inf")}})
    assert json.loads(text, parse_constant=lambda name: pytest.fail(f"{name} in JSON")) == {
        "order": None, "values": [1.0, None], "nested": {"x": None}}


def _level(size, verdict, limit=None):
    return Level(size, verdict, {}, limit_mm=limit)


def test_converged_size_is_the_coarsest_level_agreeing_with_the_next_and_the_finest_limit():
    levels = [_level(10.0, "loosening", 0.256), _level(5.0, "stick", 0.230), _level(2.5, "stick", 0.236),
              _level(1.25, "stick", 0.240)]
    assert converged_size(levels) == 5.0  # 10 mm flips; 5 mm agrees with 2.5 and is 4 % off the finest
    assert converged_size(levels, limit_tolerance=0.02) == 2.5  # 5 mm is 4.2 % off, 2.5 mm 1.7 %
    assert converged_size(levels, limit_tolerance=0.01) is None  # the finest has no finer level to agree with
    assert converged_size([_level(10.0, "stick"), _level(5.0, "damage")]) is None
    assert converged_size([_level(10.0, "stick"), _level(5.0, "stick")]) == 10.0  # no limits searched
    # agreeing with the next finer level is not enough when the finest says otherwise (QA)
    assert converged_size([_level(4.0, "stick"), _level(2.0, "stick"), _level(1.0, "loosening")]) is None


def test_size_overrides_set_every_generated_mesh():
    data = {"bodies": {"cw": {"mesh": {"generator": "counterweight_block", "contact_size": 10.0}},
                       "web": {"mesh": {"generator": "web_block", "contact_size": 10.0}},
                       "file": {"mesh": {"file": "part.inp"}}}}
    assert size_overrides(data, 2.5) == {"bodies.cw.mesh.contact_size": 2.5, "bodies.web.mesh.contact_size": 2.5}
    with pytest.raises(ValueError, match="contact_size"):
        size_overrides({"bodies": {"file": {"mesh": {"file": "part.inp"}}}}, 2.5)


def test_the_study_command_runs_each_size_and_reports_the_converged_one(coarse_cylinder, tmp_path, capsys):
    import json

    from pipelines.cli.main import main

    out = tmp_path / "study"
    assert main(["study", "convergence", str(coarse_cylinder), "--sizes", "0.4,0.2", "--workers", "0",
                 "--out", str(out), "--no-cache", "--json", "--quiet"]) == 0
    study = json.loads(capsys.readouterr().out)
    levels = {level["size_mm"]: level for level in study["levels"]}
    assert levels[0.2]["points"] > 1.8 * levels[0.4]["points"]  # halving the size doubles the 2D points
    assert levels[0.4]["verdict"] == levels[0.2]["verdict"] == "damage"  # gross slip at μ_max
    assert study["converged_size_mm"] == 0.4 and study["verdicts_agree"]
    assert (out / "convergence.png").stat().st_size > 10_000 and (out / "convergence.json").is_file()
    assert study["history_plot"] and (out / "convergence_cycles.png").stat().st_size > 10_000


@pytest.mark.parametrize("sizes", ["5", "5,-1", "a,b"])
def test_bad_sizes_are_one_message(coarse_cylinder, sizes, capsys):
    from pipelines.cli.main import main

    assert main(["study", "convergence", str(coarse_cylinder), "--sizes", sizes]) == 2
    assert "--sizes" in capsys.readouterr().err


def _results(path, real_cycles, clamp, worn, ending, loss):
    """A minimal results.h5: the cycles table (real cycles, clamp force N, worn area) and the summary."""
    import json

    import h5py
    import numpy as np

    with h5py.File(path, "w") as results:
        results.attrs["ending"] = ending
        table = results.create_group("cycles")
        table["equivalent_cycles"] = np.asarray(real_cycles, dtype=float)
        table["figures/clamp_force_N"] = np.asarray(clamp, dtype=float)
        table["figures/worn_area_fraction"] = np.asarray(worn, dtype=float)
        results.create_group("summary").attrs["figures"] = json.dumps(
            {"clamp_force_loss_fraction": loss, "worn_area_fraction": worn[-1], "equivalent_cycles": real_cycles[-1]})
    return str(path)


def test_levels_are_compared_at_equal_running_time(tmp_path):
    """A coarse level whose 4 blocks reach 4e6 real cycles, a fine one whose 4 smaller blocks reach
    2e6: both are compared at 2e6 cycles (the coarse one's figures of its block ending there),
    with the clamp-force loss relative to each run's own initial clamp (1000 N); a level that
    shook down early keeps its last figures and does not shorten the horizon."""
    from pipelines.studies.convergence import Level, common_horizon

    coarse = _results(tmp_path / "c.h5", [1e6, 2e6, 3e6, 4e6], [990, 980, 970, 960], [0.1, 0.2, 0.3, 0.4],
                      "completed", 0.04)
    fine = _results(tmp_path / "f.h5", [5e5, 1e6, 1.5e6, 2e6], [995, 990, 985, 980], [0.1, 0.15, 0.2, 0.25],
                    "completed", 0.02)
    stuck = _results(tmp_path / "s.h5", [10.0, 20.0], [1000, 1000], [0.0, 0.0], "shakedown", 0.0)
    levels = [Level(10.0, "loosening", {"equivalent_cycles": 4e6}, extra={"results": coarse}),
              Level(5.0, "loosening", {"equivalent_cycles": 2e6}, extra={"results": fine}),
              Level(2.5, "stick", {"equivalent_cycles": 20.0}, extra={"results": stuck})]
    assert common_horizon(levels) == 2e6
    at = [level.extra["at_common_cycles"] for level in levels]
    assert at[0]["equivalent_cycles"] == 2e6 and abs(at[0]["clamp_force_loss_fraction"] - 0.02) < 1e-12
    assert at[0]["worn_area_fraction"] == 0.2 and at[1]["worn_area_fraction"] == 0.25
    assert abs(at[1]["clamp_force_loss_fraction"] - 0.02) < 1e-12
    assert at[2]["equivalent_cycles"] == 20.0 and at[2]["clamp_force_loss_fraction"] == 0.0
    together = [Level(10.0, "damage", {"equivalent_cycles": 2e6}, extra={"results": fine}),
                Level(5.0, "damage", {"equivalent_cycles": 2e6}, extra={"results": fine})]
    assert common_horizon(together) is None and "at_common_cycles" not in together[0].extra


def _double_beam_running_on(tmp_path, wear_cycles: int):
    """The high-slip double beam (it loosens; 8 increments per cycle, as the double-beam tests
    run it) told to run on past evident loosening to ``wear_cycles`` wear blocks."""
    from pathlib import Path

    example = Path(__file__).resolve().parents[2] / "examples" / "double_beam_high_slip.toml"
    scene = tmp_path / f"runs_on_{wear_cycles}.toml"
    scene.write_text(f'[scene]\nbase = "{example}"\nname = "runs_on"\n\n'
                     f"[procedure]\nstop_at_loosening = false\nincrements_per_cycle = 8\n"
                     f"wear_cycles = {wear_cycles}\n")
    return scene


def test_a_verdict_check_stops_each_level_once_loosening_is_evident(tmp_path):
    """stop_at_loosening overrides a scene that runs on to its horizon: the level ends at the
    block where loosening became evident, with the verdict and that block's real cycles of the
    run that went on (the same increments up to there), a fraction of its cycles."""
    from pipelines.studies.convergence import convergence_study, run_level

    whole = run_level(str(_double_beam_running_on(tmp_path, 40)), 2.5, str(tmp_path / "whole"), None)
    assert whole.verdict == "loosening"
    evident = whole.figures["loosening_evident_at_cycles"]
    assert evident is not None and evident < 0.5 * whole.figures["equivalent_cycles"]

    study = convergence_study(_double_beam_running_on(tmp_path, 300), [2.5], tmp_path / "study", workers=0,
                              progress=False, stop_at_loosening=True)
    level, = study["levels"]
    assert study["stop_at_loosening"] and level["verdict"] == "loosening"
    assert level["figures"]["loosening_evident_at_cycles"] == evident  # bit for bit: the same increments
    assert level["figures"]["equivalent_cycles"] == evident  # and no further


def test_the_study_command_passes_on_stop_at_loosening(coarse_cylinder, tmp_path, monkeypatch, capsys):
    """--stop-at-loosening reaches the study, and each level's evident loosening is printed."""
    from pipelines.cli.main import main
    from pipelines.studies import convergence

    asked = {}

    def study(scene, sizes, out, **options):
        asked.update(options)
        figures = dict.fromkeys(convergence.FIGURES, 0.0) | {"min_stick_margin": None,
                                                             "loosening_evident_at_cycles": 1.5e6}
        levels = [{"size_mm": size, "points": 10, "verdict": "loosening", "figures": figures, "limit_mm": None,
                   "extra": {}} for size in sizes]
        return {"scene": str(scene), "levels": levels, "extrapolated": {}, "converged_size_mm": 10.0,
                "verdicts_agree": True, "common_cycles": None, "stop_at_loosening": options["stop_at_loosening"]}

    monkeypatch.setattr(convergence, "convergence_study", study)
    monkeypatch.setattr(convergence, "plot_convergence", lambda study, path: path)
    monkeypatch.setattr(convergence, "plot_histories", lambda study, path: None)
    # sizes the cylinder's meshes take (contact zone 2 mm wide): the CLI checks them before the study
    assert main(["study", "convergence", str(coarse_cylinder), "--sizes", "0.4,0.2", "--stop-at-loosening",
                 "--out", str(tmp_path)]) == 0
    assert asked["stop_at_loosening"] is True
    assert "0.2 mm: loosening evident after 1.5e+06 real cycles (the run stopped there)" in capsys.readouterr().out


def test_a_size_the_meshes_refuse_is_said_before_any_level_runs(tmp_path, capsys):
    """The double beam's hole block must be a whole number of elements: 2 mm does not fit. The
    study says so naming the size, and no level has run (no level folder)."""
    from pathlib import Path

    from pipelines.cli.main import main

    scene = Path(__file__).resolve().parents[2] / "examples" / "double_beam_high_slip.toml"
    out = tmp_path / "study"
    assert main(["study", "convergence", str(scene), "--sizes", "3,2", "--workers", "0", "--out", str(out),
                 "--no-cache", "--quiet"]) == 2
    said = capsys.readouterr().err
    assert "--sizes: 2 mm does not suit body" in said and "multiples of the contact element size" in said
    assert not list(out.glob("size_*"))



def test_a_scene_of_mesh_files_is_refused_with_the_way_out(tmp_path, capsys):
    """Mesh files are fixed: the study says so as an input error (exit 2), not an internal one."""
    from pathlib import Path

    from pipelines.cli.main import main
    from reduction.errors import InputError

    with pytest.raises(InputError, match="generated meshes"):
        size_overrides({"bodies": {"cw": {"mesh": {"file": "cw.inp"}}}}, 5.0)
    scene = Path(__file__).resolve().parents[2] / "examples" / "user_joint.toml"
    assert main(["study", "convergence", str(scene), "--sizes", "10,5", "--workers", "0",
                 "--out", str(tmp_path / "out")]) == 2
    assert "generated meshes" in capsys.readouterr().err


def test_a_joint_without_bolts_gets_no_clamp_force_line_or_panel(tmp_path, monkeypatch):
    """QA: a scene without bolts had its missing clamp-force loss drawn as 0 % and an empty
    clamp-force panel over the run."""
    import h5py
    import matplotlib.pyplot as plt

    from pipelines.studies.convergence import plot_convergence, plot_histories

    results = tmp_path / "results.h5"
    with h5py.File(results, "w") as file:
        file["cycles/equivalent_cycles"] = [1000.0, 2000.0]
        file["cycles/figures/clamp_force_N"] = [np.nan, np.nan]
        file["cycles/figures/stick_area_fraction"] = [0.4, 0.3]
    figures = {"stick_area_fraction": 0.3, "active_slip_area_fraction": 0.7, "worn_area_fraction": 1.0,
               "clamp_force_loss_fraction": None}
    study = {"scene": "cyl.toml", "levels": [
        {"size_mm": size, "points": 10, "verdict": "damage", "limit_mm": None, "figures": figures,
         "extra": {"results": str(results)}} for size in (0.2, 0.1)]}
    kept = []
    monkeypatch.setattr(plt, "close", kept.append)
    plot_convergence(study, tmp_path / "convergence.png")
    plot_histories(study, tmp_path / "convergence_cycles.png")
    sizes, over_run = kept
    labels = [line.get_label() for line in sizes.axes[0].get_lines()]
    assert "clamp-force loss" not in labels and "stick area" in labels
    assert sizes.axes[0].get_ylabel() == "% of nominal area"
    assert [ax.get_ylabel() for ax in over_run.axes] == ["stick area (% of nominal)"]
