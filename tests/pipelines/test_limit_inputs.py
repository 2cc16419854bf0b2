"""The limit search's inputs: a range typed in mm, a tolerance as wide as the range, and the
digits an amplitude is printed with."""

from __future__ import annotations

from pathlib import Path

import pytest

from pipelines.cli.main import main
from pipelines.jobs import limit as limits
from reduction.errors import InputError

SCENE = Path(__file__).resolve().parents[2] / "examples" / "counterweight.toml"


def _no_run(*args, **kwargs):
    raise AssertionError("a contact run started")


def test_a_range_typed_in_mm_is_refused_before_any_run(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(limits, "run_amplitude", _no_run)
    assert main(["limit", str(SCENE), "--amplitude", "0.1:0.4", "--workers", "0", "--cache", str(tmp_path),
                 "--out", str(tmp_path / "o")]) == 2
    error = capsys.readouterr().err
    assert error.startswith("fretwork: error:") and "below 1 µm: probably mm" in error
    assert "--amplitude 100:400" in error  # what the user meant, in the unit the option takes
    assert limits.parse_range_um("1:400") == (0.001, 0.4)  # 1 µm and up is taken as typed


def test_a_tolerance_not_narrower_than_the_range_is_refused_before_any_run(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(limits, "run_amplitude", _no_run)
    with pytest.raises(InputError, match=r"tolerance, 10\.0 µm, is not narrower than the amplitude range "
                                         r"100\.0:105\.0 µm \(5\.0 µm wide\)"):
        limits.find_limit(SCENE, 0.1, 0.105, tolerance_mm=0.01, cache_dir=str(tmp_path), workers=0, progress=False)
    assert main(["limit", str(SCENE), "--amplitude", "100:400", "--tolerance", "300", "--workers", "0",
                 "--cache", str(tmp_path), "--out", str(tmp_path / "o")]) == 2
    assert "not narrower than the amplitude range" in capsys.readouterr().err


def test_every_problem_of_a_search_is_said_at_once():
    with pytest.raises(InputError) as refused:
        limits.check_search(0.4, 0.1, 0.0, grid=1)
    assert str(refused.value).count(";") == 2  # range, tolerance, grid


def test_amplitudes_below_a_micrometre_keep_their_digits():
    result = limits.LimitResult(None, (None, None), 0.0001, range_mm=(0.0001, 0.0004))
    assert limits.describe_limit(result) == "stuck up to 0.40 µm: the limit lies above the range"
    stuck_low = limits.LimitResult(0.0001, (None, 0.0001), 0.0001, range_mm=(0.0001, 0.0004))
    assert limits.describe_limit(stuck_low) == "not stuck even at 0.10 µm: the limit lies below the range"


def test_amplitudes_are_printed_to_the_tolerance():
    assert limits.format_um(0.2637) == "263.7"  # 10 µm tolerance or none: one decimal, as before
    assert limits.format_um(0.2637, 0.01) == "263.7"
    assert limits.format_um(0.26374, 0.00005) == "263.74"  # a 0.05 µm tolerance: its two decimals
    assert limits.format_um(0.0004) == "0.40"
    assert limits.format_um(0.000004) == "0.0040"


def test_a_too_wide_tolerance_is_refused_before_earlier_outputs_are_cleared(tmp_path, monkeypatch, capsys):
    """The CLI checks the search (range, tolerance, grid) with the other inputs, before it touches
    the output folder: an earlier limit's outputs stay."""
    monkeypatch.setattr(limits, "run_amplitude", _no_run)
    out = tmp_path / "o"
    out.mkdir()
    earlier = out / "limit.json"
    earlier.write_text("{}")
    status = earlier.lstat()  # recorded as an earlier limit's output, which a run would remove
    (out / ".fretwork-outputs").write_text(f"{status.st_mtime_ns} {status.st_size} limit.json\n")
    assert main(["limit", str(SCENE), "--amplitude", "100:105", "--tolerance", "10", "--workers", "0",
                 "--cache", str(tmp_path), "--out", str(out)]) == 2
    assert "not narrower than the amplitude range" in capsys.readouterr().err
    assert earlier.read_text() == "{}"


def test_limit_json_is_strict_json_when_a_run_has_no_finite_figures(tmp_path):
    """A run that slid off has NaN figures and an unbounded stick margin: limit.json (and the
    demo's summary.json, written the same way) give them as null, which any JSON reader takes;
    Python's default wrote NaN and Infinity, which a strict reader refuses."""
    import json
    import math

    from pipelines.jobs.limit import AmplitudeRun, LimitResult, write_limit

    runs = [AmplitudeRun(0.1, "stick", {"min_stick_margin": math.inf, "max_wear_depth_mm": 0.0}),
            AmplitudeRun(0.2, "loosening", {"min_stick_margin": math.nan, "max_wear_depth_mm": 1.5e-3})]
    result = LimitResult(0.2, (0.1, 0.2), 0.01, runs, (0.1, 0.2))

    def refuse(constant):
        raise ValueError(f"not JSON: {constant}")

    read = json.loads(write_limit(result, tmp_path / "limit.json").read_text(), parse_constant=refuse)
    assert [run["min_stick_margin"] for run in read["runs"]] == [None, None]
    assert [run["max_wear_depth_mm"] for run in read["runs"]] == [0.0, 1.5e-3]
    assert read["limit_um"] == 200.0


@pytest.mark.parametrize("low, high, tolerance", [(0.1, float("inf"), 0.01), (float("nan"), 0.4, 0.01),
                                                  (0.1, 0.4, float("nan")), (0.1, 0.4, float("inf"))])
def test_a_library_caller_cannot_search_a_non_finite_range_or_tolerance(low, high, tolerance):
    """find_limit's own check (not only the command line's) refuses inf and NaN: a range to inf
    ran cases at nan and inf µm and reported a limit below the range (QA)."""
    with pytest.raises(InputError, match="finite"):
        limits.check_search(low, high, tolerance)


def test_an_infinite_amplitude_range_is_refused_when_parsed():
    with pytest.raises(InputError, match="finite"):
        limits.parse_range_um("100:inf")


def test_the_amplitudes_a_search_runs_do_not_depend_on_the_workers(tmp_path, monkeypatch):
    """The refining rounds run the same amplitudes however many workers run them, so the bracket
    (and the margins dividing its lower end) are the scene's, not the machine's (QA: the user
    joint's bracket was 218.8–228.1 µm serially, 225.0–233.3 µm on two workers)."""
    from contextlib import contextmanager

    import pipelines.parallel as parallel

    def fake_run(scene_path, overrides, amplitude_mm, cache_dir, out_dir=None, models=None):
        return limits.AmplitudeRun(amplitude_mm, "stick" if amplitude_mm < 0.2234 else "damage", {})

    @contextmanager
    def in_process(scheduler, workers):
        yield {"scheduler": None, "workers": 0}

    monkeypatch.setattr(limits, "run_amplitude", fake_run)
    monkeypatch.setattr(parallel, "cluster", in_process)
    found = {workers: limits.find_limit(SCENE, 0.05, 0.5, tolerance_mm=0.002, workers=workers, progress=False)
             for workers in (0, 1, 2, 8)}
    amplitudes = {w: sorted(r.amplitude_mm for r in result.runs) for w, result in found.items()}
    assert amplitudes[0] == amplitudes[1] == amplitudes[2] == amplitudes[8]
    assert {result.bracket_mm for result in found.values()} == {found[0].bracket_mm}
    low, high = found[0].bracket_mm
    assert low < 0.2234 <= high and high - low <= 0.002
