"""The margins say what the sampled speeds do not show (QA, after `make demo`): order/mode
crossings that fall between the sampled speeds (the amplitude peaks there, unjudged: the result
is "safe at the sampled speeds", not "at every speed"), the unsampled edge of an unsafe band,
which CW is judged and where another CW's raw multibody amplitude exceeds it. The limit is worded
by what the margins divide (sticks up to …, not at …). `fretwork run`'s summary gives each damage
maximum its own location and enough digits for a small clamp-force loss. Built from MarginResult
and sweep data directly, no run."""

import json

import h5py
import numpy as np
import pytest

from pipelines.cli.main import _damage_maximum, loss_percent
from pipelines.jobs.demo import _summary
from pipelines.jobs.limit import LimitResult
from pipelines.jobs.margins import MarginResult, crossings_between, describe_margins, write_margins
from pipelines.output.report import _read_sweep, job_verdict

SPEEDS = np.arange(600.0, 901.0, 50.0)
# the demo's sweep of examples/counterweight.toml: its crossings and margins at 600…900 rpm
CROSSINGS = (605.5, 615.0, 691.8, 699.3, 727.6, 749.4)
LIMIT = LimitResult(0.2, (0.18333, 0.2), 0.025, range_mm=(0.1, 0.4))  # sticks up to 183.3 µm, not at 200 µm


def _result(amplitude_mm, crossings=CROSSINGS, raw=None, counterweight=1, calibration=1.0) -> MarginResult:
    amplitude = np.asarray(amplitude_mm, dtype=float)
    return MarginResult(SPEEDS, amplitude, calibration, LIMIT, LIMIT.margin_limit_mm / amplitude, 900.0,
                        counterweight=counterweight, crossings_rpm=crossings, multibody_amplitude_mm=raw)


SAFE = np.full(len(SPEEDS), 0.1)  # margin 1.83 at every sampled speed
UNSAFE_AT_600 = np.array([0.3307, 0.1, 0.078, 0.08, 0.1, 0.12, 0.15])  # margin 0.55 at 600 rpm


def test_crossings_within_a_tenth_of_the_step_of_a_sampled_speed_count_as_sampled():
    assert crossings_between(SPEEDS, CROSSINGS) == [605.5, 615.0, 691.8, 727.6]
    # outside the sampled range: not between sampled speeds
    assert crossings_between(SPEEDS, (550.0, 950.0)) == []
    assert crossings_between([600.0, 650.0], (604.9, 605.1)) == [605.1]


def test_crossings_between_the_sampled_speeds_make_it_safe_at_the_sampled_speeds_only():
    said = describe_margins(_result(SAFE))
    assert said.startswith("safe at the sampled speeds (every margin at least 1)")
    assert "every speed" not in said
    assert ("order/mode crossings at 605.5, 615.0, 691.8, 727.6 rpm fall between the sampled speeds: the margins "
            "there are not judged; sweep finer around them (e.g. --speeds 600:650:5)") in said
    assert describe_margins(_result(SAFE, crossings=())).startswith("safe at every speed")
    # a crossing on a sampled speed (699.3 next to 700) is judged there
    assert describe_margins(_result(SAFE, crossings=(699.3, 749.4))).startswith("safe at every speed")
    summary = _result(SAFE).to_json()
    assert summary["crossings_between_speeds_rpm"] == [605.5, 615.0, 691.8, 727.6]


def test_an_unsafe_speed_next_to_a_safe_one_is_a_band_edge_not_sampled():
    said = describe_margins(_result(UNSAFE_AT_600))
    assert ("UNSAFE at 600 rpm: the wing vibration exceeds 183.3 µm, the largest amplitude shown to stick (margin "
            "below 1) (the unsafe band's edge lies between 600 and 650 rpm, not sampled)") in said
    assert "safe at the other sampled speeds" in said
    # an unsafe band in the middle has two edges
    middle = UNSAFE_AT_600[[1, 2, 0, 0, 3, 4, 5]]
    assert ("(the unsafe bands' edges lie between 650 and 700 rpm and between 750 and 800 rpm, not sampled)"
            in describe_margins(_result(middle, crossings=())))


def test_another_cw_swinging_more_is_listed_with_its_raw_amplitude_ratio():
    raw = np.c_[SAFE / 100, SAFE / 100 * 0.95]  # raw multibody amplitudes, CW1 and CW2
    raw[2, 1] = raw[2, 0] * 1.072  # CW2 swings more at 700 rpm
    calibrated = _result(SAFE, raw=raw, calibration=100.0)  # the ratio needs no calibration
    said = describe_margins(calibrated)
    assert "the margins judge CW1 ([coupling] counterweight = 1)" in said
    assert "CW2 swings 1.07× CW1 at 700 rpm: judge it with [coupling] counterweight = 2" in said
    assert calibrated.to_json()["larger_swings"] == [{"counterweight": 2, "speed_rpm": 700.0,
                                                      "ratio": pytest.approx(1.072)}]
    # judging CW2, CW1 swings more everywhere but at 700 rpm
    judged_2 = describe_margins(_result(SAFE, raw=raw, counterweight=2))
    assert "the margins judge CW2" in judged_2 and "CW1 swings 1.05× CW2 at 600 rpm" in judged_2
    assert "700 rpm" not in judged_2.split("CW1 swings")[1]
    assert "swings" not in describe_margins(_result(SAFE, raw=np.c_[raw[:, 0], raw[:, 0] * 0.5]))


def test_the_report_reads_what_the_sweep_file_holds_of_the_crossings_and_the_cws(tmp_path):
    raw = np.c_[UNSAFE_AT_600, UNSAFE_AT_600 * 0.9]
    raw[2, 1] = raw[2, 0] * 1.072
    path = tmp_path / "sweep.h5"
    with h5py.File(path, "w") as handle:
        handle.attrs["fretwork_format"] = "fretwork-sweep"
    write_margins(path, _result(UNSAFE_AT_600, raw=raw))
    margins, _ = _read_sweep(path)
    said = job_verdict(margins)
    assert said.startswith("UNSAFE at 600 rpm: margin 0.55 < 1")
    assert "(the unsafe band's edge lies between 600 and 650 rpm, not sampled)" in said
    assert "safe at the other sampled speeds, smallest margin" in said and "every speed" not in said
    assert "crossings at 605.5, 615.0, 691.8, 727.6 rpm fall between the sampled speeds" in said
    assert "the margins judge CW1" in said and "CW2 swings 1.07× CW1 at 700 rpm" in said
    # a file without crossings between its speeds, judged on CW1 alone
    write_margins(path, _result(SAFE, crossings=()))
    margins, _ = _read_sweep(path)
    assert job_verdict(margins).startswith("safe at every speed, smallest margin 1.83")


def test_the_demo_summary_leads_with_what_the_margins_divide():
    run = {"engine_speed_rpm": 750.0, "wing_amplitude_mm": 0.1, "verdict": "stick", "cof_evolved_area_fraction": 0.0,
           "bolt_force_initial_N": None}
    summary = _summary("cw", run, LIMIT, _result(SAFE), {"cof_phase_s": 1.0})
    keys = list(summary)
    assert keys.index("margin_amplitude_um") < keys.index("amplitude_limit_um")
    assert summary["margin_basis"].startswith("sticks up to 183.3 µm, not at 200.0 µm")
    assert summary["amplitude_limit_um"] == pytest.approx(200.0)  # the key kept
    assert summary["crossings_between_speeds_rpm"] == [605.5, 615.0, 691.8, 727.6]
    assert "safe at the sampled speeds" in summary["margins"] and summary["counterweight"] == 1
    json.dumps(summary)


def test_run_summary_damage_maxima_and_small_losses():
    assert loss_percent(5.2e-5) == "0.0052" and loss_percent(3.19e-4) == "0.032"
    assert loss_percent(0.0319) == "3.19" and loss_percent(0.0) == "0.00"
    assert _damage_maximum("FDP", 0.0, "MPa·mm", [-100.0, 0.0, -30.0]) == "FDP max 0 MPa·mm"
    assert _damage_maximum("FFDP", 12.5, "MPa²·mm", [1.234, 2.0, 3.0]) == "FFDP max 12.5 MPa²·mm at [1.23, 2.0, 3.0] mm"
