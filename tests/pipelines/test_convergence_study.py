"""The convergence study's arithmetic: Richardson extrapolation, the converged size, overrides."""

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


@pytest.mark.parametrize("sizes", ["5", "5,-1", "a,b"])
def test_bad_sizes_are_one_message(coarse_cylinder, sizes, capsys):
    from pipelines.cli.main import main

    assert main(["study", "convergence", str(coarse_cylinder), "--sizes", sizes]) == 2
    assert "--sizes" in capsys.readouterr().err
