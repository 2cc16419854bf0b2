"""``fretwork report`` reads as an engineer wants: a job's answer first, its search's runs as
supporting rows, figures in the units and with the caveats the command line gives, and nothing
claimed that does not apply to the run (QA's review of the demo, sweep, mbs and run pages).

The folders are small synthetic ones, written with h5py in the layouts the jobs write
(pipelines.output.results, pipelines.jobs.margins.write_margins, mbs.results.write_run)."""

import html
import json
import re

import h5py
import numpy as np
import pytest

from pipelines.output.report import job_verdict, meaning, write_report, Margins

SCENE = '[scene]\nname = "cw"\ndescription = "wing amplitude 100 µm (normal operation)"\n' \
        'effects = ["bolts", "cof_evolution", "wear"]\n'
FIGURES = {"stick_area_fraction": 1.0, "slip_area_fraction": 0.0, "damaged_area_fraction": 0.0,
           "active_slip_area_fraction": 0.0, "cof_evolved_area_fraction": 0.3, "max_wear_depth_mm": 0.0,
           "wear_volume_mm3": 0.0, "dissipated_energy_mJ": 66.6, "min_stick_margin": 0.54,
           "fdp_max_MPa_mm": 0.0, "fdp_max_location_mm": [-130.0, 0.0, -40.0],
           "ffdp_max_MPa2_mm": 0.0, "ffdp_max_location_mm": [-130.0, 0.0, -40.0],
           "cycles_run": 6, "equivalent_cycles": 6.0, "shakedown_at_cycles": 1.0,
           "bolt_force_initial_N": 806222.3, "bolt_force_final_N": 806180.2, "clamp_force_loss_fraction": 5.2e-5}


def _results(folder, verdict="stick", figures=None, *, amplitude_mm=None, speed_rpm=750.0, scene=SCENE,
             stationary=True, ending=None):
    """A results.h5 as pipelines.output.results writes it: a coupled run when amplitude_mm is
    given (its /histories attributes), a run that stopped without a summary when ending is given."""
    folder.mkdir(parents=True, exist_ok=True)
    with h5py.File(folder / "results.h5", "w") as file:
        file.attrs.update(fretwork_format="fretwork-results", format_version=1, scene_name="cw", scene_toml=scene,
                          complete=True, ending=ending or ("shakedown" if verdict == "stick" else "completed"))
        if amplitude_mm is not None:
            file.create_group("histories").attrs.update(
                wing_amplitude=amplitude_mm, speed_rpm=speed_rpm, load_cycle="wing_period",
                load_cycle_frequency_hz=speed_rpm / 2.0, counterweight=1)
        if ending is None:
            file.create_group("summary").attrs.update(verdict=verdict, stationary=stationary,
                                                      figures=json.dumps(dict(FIGURES, **(figures or {}))))
    return folder / "results.h5"


def _margins(path, speeds, amplitudes_mm, limit_mm, limit_speed, divided_mm=None, bound=None):
    """/margins as write_margins writes it; without divided_mm as files of before 3efc5ce, whose
    margins divided the limit."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with h5py.File(path, "w") as file:
        file.attrs.update(fretwork_format="fretwork-sweep", format_version=1)
        group = file.create_group("margins")
        group.attrs.update(limit_mm=limit_mm, limit_speed_rpm=limit_speed, calibration_factor=1.0)
        if divided_mm is not None:
            group.attrs.update(margin_amplitude_mm=divided_mm, margin_bound=bound)
        amplitudes = np.asarray(amplitudes_mm)
        margin = (limit_mm if divided_mm is None else divided_mm) / amplitudes
        for name, data in (("speed_rpm", speeds), ("wing_amplitude", amplitudes), ("margin", margin),
                           ("unsafe", margin < 1)):
            group.create_dataset(name, data=data)


def _text(page_path) -> str:
    """The page as a reader sees it: tags stripped, entities resolved."""
    page = re.sub(r"<(style|pre)>.*?</\1>", "", page_path.read_text(), flags=re.S)
    return html.unescape(re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", page)))


def _search(folder, stuck_um, damaged_um, speed_rpm=900.0):
    for amplitude in stuck_um:
        _results(folder / f"amplitude_{amplitude:07.2f}um", amplitude_mm=1e-3 * amplitude, speed_rpm=speed_rpm)
    for amplitude in damaged_um:
        _results(folder / f"amplitude_{amplitude:07.2f}um", "damage", {
            "stick_area_fraction": 0.93, "slip_area_fraction": 0.07, "damaged_area_fraction": 0.07,
            "active_slip_area_fraction": 0.07, "cof_evolved_area_fraction": 1.0, "shakedown_at_cycles": None},
            amplitude_mm=1e-3 * amplitude, speed_rpm=speed_rpm, stationary=False)


@pytest.fixture
def demo(tmp_path):
    """A demo's folder: the operating run at 750 rpm and 100 µm, a limit search at 900 rpm between
    183.3 µm (stuck) and 200 µm (damage), margins that fail at 600 rpm."""
    job = tmp_path / "demo"
    _results(job / "operating", amplitude_mm=0.1)
    _search(job / "limit", (100.0, 183.333333), (200.0, 400.0))
    (job / "limit" / "limit.json").write_text(json.dumps({
        "limit_um": 200.0, "limit_mm": 0.2, "bracket_um": [183.333333, 200.0], "tolerance_um": 25.0,
        "range_um": [100.0, 400.0], "monotone": True, "changes": [], "runs": []}))
    _margins(job / "sweep.h5", [600.0, 750.0, 900.0], [0.33075646, 0.1, 0.0882], 0.2, 900.0)
    (job / "summary.json").write_text(json.dumps({"summary": {
        "scene": "cw", "engine_speed_rpm": 750.0, "wing_amplitude_um": 100.0, "verdict": "stick",
        "margin_at_operating_point": 2.0, "operating_point": "safe", "amplitude_limit_um": 200.0, "warnings": []}}))
    return job


def test_a_demo_page_opens_with_the_jobs_verdict_and_keeps_the_search_runs_subordinate(demo):
    text = _text(write_report(demo))
    verdict = "UNSAFE at 600 rpm: margin 0.60 < 1"
    assert verdict in text
    assert "At the operating point, 750 rpm with a wing amplitude of 100 µm: verdict STICK, margin 2.00 (safe)" in text
    assert ("Sticks up to 183.3 µm, not at 200.0 µm, the amplitude limit (searched at 900 rpm, the sweep's "
            "fastest speed") in text
    order = [text.index(s) for s in (verdict, "Operating run cw (operating/results.h5)", "The amplitude search's runs")]
    assert order == sorted(order)
    # one headline verdict (the operating run's); the four search runs are rows, not sections
    assert text.count("verdict: ") == 1 and "Run cw (limit/" not in text
    rows = re.findall(r"limit/amplitude_\d+\.\d+um", text)
    assert sorted(set(rows)) == [f"limit/amplitude_{a}um" for a in ("0100.00", "0183.33", "0200.00", "0400.00")]
    # the scene's description (100 µm) is not printed beside runs at other amplitudes
    assert "normal operation" not in text
    # the margins table: one row per speed, the unsafe one said so
    assert re.search(r"600 331 0\.60 unsafe .*750 100 2\.00 safe .*900 88\.2 2\.27 safe", text)


def test_a_sweep_page_states_the_limit_its_bracket_and_speed_read_off_the_search(tmp_path):
    """A sweep --margins folder of before 3efc5ce holds no limit.json: the bracket comes from its
    runs' verdicts."""
    job = tmp_path / "sweep"
    _margins(job / "sweep.h5", [600.0, 700.0, 800.0, 900.0], [0.05636, 0.08334, 0.12151, 0.19617], 0.228125, 900.0)
    _search(job / "limit_runs", (50.0, 218.75), (228.125, 237.5))
    _results(job / "limit_runs" / "amplitude_0350.00um", amplitude_mm=0.35, speed_rpm=900.0, ending="wear_runaway")
    (job / "limit_runs" / "amplitude_0500.00um").mkdir()
    (job / "limit_runs" / "amplitude_0500.00um" / "results.h5.part").write_bytes(b"")
    text = _text(write_report(job))
    assert text.index("safe at every speed, smallest margin 1.16 at 900 rpm") < text.index("The amplitude search")
    assert ("Sticks up to 218.8 µm, not at 228.1 µm, the amplitude limit (searched at 900 rpm, the sweep's "
            "fastest speed, where the centrifugal load is largest, over 50.0 µm to 500.0 µm)") in text
    assert "350 not stuck (counted as loosening) stopped: runaway wear" in text
    assert "500 none did not finish" in text


def test_the_job_verdict_names_each_unsafe_speed_or_the_smallest_margin():
    limit = 0.2
    speeds, amplitudes = np.array([600.0, 700.0, 900.0]), np.array([0.4, 0.25, 0.1])
    unsafe = Margins(speeds, amplitudes, limit / amplitudes, limit, 900.0, 1.0)
    assert job_verdict(unsafe).startswith("UNSAFE at 600, 700 rpm: margins 0.50, 0.80 < 1")
    assert job_verdict(unsafe).endswith("safe at the others, smallest margin 2.00 at 900 rpm")
    safe = Margins(speeds, amplitudes / 4, 4 * limit / amplitudes, limit, 900.0, 1.0)
    assert job_verdict(safe) == "safe at every speed, smallest margin 2.00 at 600 rpm"
    # a file whose margins divide 183.3 µm, the largest amplitude shown to stick: 190 µm is unsafe
    amplitudes = np.array([0.1, 0.19, 0.1])
    stuck = Margins(speeds, amplitudes, 0.1833 / amplitudes, limit, 900.0, 1.0, 0.1833, "stuck")
    assert job_verdict(stuck).startswith("UNSAFE at 700 rpm: margin 0.96 < 1, the wing vibration exceeds 183.3 µm, "
                                         "the largest amplitude shown to stick")


def _sweep_job(tmp_path, amplitudes_mm, record: dict, divided_mm, bound):
    """A sweep --margins folder as written since 3efc5ce: limit_runs/limit.json, and no run folder
    (every run of the limit came from the stage cache)."""
    job = tmp_path / "sweep"
    _margins(job / "sweep.h5", [600.0, 750.0, 900.0], amplitudes_mm, record["limit_mm"], 900.0, divided_mm, bound)
    (job / "limit_runs").mkdir()
    (job / "limit_runs" / "limit.json").write_text(json.dumps(dict(
        {"tolerance_um": 25.0, "range_um": [100.0, 400.0], "monotone": True, "changes": [], "runs": []}, **record)))
    return _text(write_report(job))


def test_a_sweep_page_reads_the_bracket_and_what_the_margins_divide_from_its_limit_json(tmp_path):
    text = _sweep_job(tmp_path, [0.1, 0.17, 0.19], {
        "limit_um": 200.0, "limit_mm": 0.2, "bracket_um": [183.3, 200.0], "margin_amplitude_um": 183.3,
        "margin_bound": "stuck"}, 0.1833, "stuck")
    assert ("Sticks up to 183.3 µm, not at 200.0 µm, the amplitude limit (searched at 900 rpm, the sweep's "
            "fastest speed, where the centrifugal load is largest, over 100.0 µm to 400.0 µm, tolerance 25.0 µm)"
            ) in text
    # 170 µm lies within the tolerance of the bracket's lower end; 190 µm inside the bracket
    assert ("UNSAFE at 900 rpm: margin 0.96 < 1, the wing vibration exceeds 183.3 µm, the largest amplitude shown to "
            "stick; at the limit at 750 rpm") in text
    assert re.search(r"600 100 1\.83 safe .*750 170 1\.08 at the limit .*900 190 0\.96 unsafe", text)
    assert "margin = 183.3 µm, the largest amplitude shown to stick / wing amplitude at that speed" in text


def test_a_sweep_page_where_nothing_stuck_calls_no_speed_safe(tmp_path):
    text = _sweep_job(tmp_path, [0.05, 0.08, 0.2], {
        "limit_um": 100.0, "limit_mm": 0.1, "bracket_um": [None, 100.0], "margin_amplitude_um": 100.0,
        "margin_bound": "upper bound"}, 0.1, "upper bound")
    assert ("not shown safe at 600, 750 rpm: nothing in the searched range stuck, the margins are upper bounds"
            in text)
    assert "safe at every speed" not in text and "safe at the others" not in text
    assert re.search(r"600 50 2\.00 not shown safe .*750 80 1\.25 not shown safe .*900 200 0\.50 unsafe", text)
    assert "The margins are upper bounds: no speed is shown safe." in text


def test_an_older_sweep_page_does_not_call_safe_an_amplitude_inside_the_bracket(tmp_path):
    """Its margins divided the limit (228.1 µm): 220 µm, above the 218.8 µm that stuck, is not safe."""
    job = tmp_path / "sweep"
    _margins(job / "sweep.h5", [600.0, 900.0], [0.05636, 0.22], 0.228125, 900.0)
    _search(job / "limit_runs", (50.0, 218.75), (228.125, 237.5))
    text = _text(write_report(job))
    assert "at the limit at 900 rpm" in text and "safe at the others, smallest margin 4.05 at 600 rpm" in text
    assert "as this older file holds it: inside the limit's bracket a margin of 1 or more is not shown safe" in text


def test_a_runs_table_gives_forces_in_kN_its_operating_point_and_when_it_shook_down(tmp_path):
    text = _text(write_report(_results(tmp_path / "run", amplitude_mm=0.1).parent))
    assert "wing amplitude 100 µm at 750 rpm" in text and "wing period (375 Hz)" in text
    assert "6 simulated, standing for 6 real cycles = 0.016 s of engine running" in text
    assert "shakedown after 1 real cycle (0.00267 s)" in text
    assert "clamp force 806.2 kN → 806.2 kN (0.01 % loss)" in text and "e+0" not in text
    assert "FDP max τ·δ 0 MPa·mm FFDP" in text  # a maximum of zero has no location
    assert "(-130" not in text
    assert "What the verdicts" not in text  # the run's own section says what its verdict means


def test_a_loosening_run_says_when_and_explains_areas_above_100_percent(tmp_path):
    figures = {"stick_area_fraction": 0.0087, "slip_area_fraction": 1.1168, "damaged_area_fraction": 0.135,
               "active_slip_area_fraction": 1.078, "cof_evolved_area_fraction": 1.002, "shakedown_at_cycles": None,
               "loosening_evident_at_cycles": 100100.0, "equivalent_cycles": 100100.0, "cycles_run": 110,
               "bolt_force_initial_N": 20000.0, "bolt_force_final_N": 19637.2, "clamp_force_loss_fraction": 0.0181,
               "fdp_max_MPa_mm": 0.0533, "fdp_max_location_mm": [52.0, 0.0, 0.0]}
    text = _text(write_report(_results(tmp_path / "run", "loosening", figures, stationary=False).parent))
    assert "loosening evident after 100 100 real cycles" in text
    assert "clamp force 20 kN → 19.64 kN (1.81 % loss)" in text
    assert "at the friction limit (slip) 111.7 %" in text
    assert "Above 100 %: points beyond it came into contact" in text
    assert "FDP max τ·δ 0.0533 MPa·mm at (52, 0, 0) mm" in text


def test_a_gross_slip_run_without_bolts_or_cof_evolution_is_not_told_about_them():
    s = dict(FIGURES, verdict="damage", stick_area_fraction=0.0, slip_area_fraction=1.7, cof_evolved_area_fraction=0.0,
             bolt_force_initial_N=None)
    said = meaning(s)
    assert "whole contact keeps sliding" in said
    assert "COF" not in said and "clamp" not in said
    bolted = meaning(dict(FIGURES, verdict="damage", stick_area_fraction=0.9, cof_evolved_area_fraction=1.0))
    assert "after their COF rose there" in bolted and "clamp force stable" in bolted


def test_an_mbs_page_gives_the_runs_numbers_and_no_verdict_glossary(tmp_path):
    """run.h5 as mbs.results.write_run writes it: speed, wing amplitudes (half peak-to-peak over
    the second half), torsion mode and steadiness are read back."""
    folder = tmp_path / "mbs"
    folder.mkdir()
    revolutions, speed = 12.0, 750.0
    time = np.linspace(0.0, revolutions * 60.0 / speed, 4801)
    crank = 2 * np.pi * speed / 60.0 * time
    with h5py.File(folder / "run.h5", "w") as file:
        file.attrs.update(fretwork_format="fretwork-results", format_version=1)
        model = file.create_group("model")
        model.attrs.update(parameters_json=json.dumps({"speed_rpm": speed, "n_modes": 4, "solver": {
            "revolutions": revolutions, "time_step": 5e-5}}), torsion_mode=1, real_time_factor=0.24)
        model.create_dataset("eigenfrequencies", data=[500.0, 673.54, 1236.5])
        histories = file.create_group("histories")
        histories.create_dataset("time", data=time)
        histories.create_dataset("crank_angle", data=crank)
        histories.create_dataset("cw1_wing_torsion", data=7.5e-5 * np.sin(30 * crank))
        histories.create_dataset("cw2_wing_torsion", data=4.3e-5 * np.sin(30 * crank))
    text = _text(write_report(folder))
    assert "engine speed 750 rpm" in text
    assert "CW1 0.075 µm, CW2 0.043 µm" in text
    assert "CW torsion mode (fixed interface) 673.5 Hz" in text
    assert "the response is steady" in text
    assert "What the verdicts" not in text and "verdict" not in text.lower()


def test_a_limit_page_leads_with_the_limit_and_shows_the_scene_once_with_a_caveat(tmp_path):
    """`fretwork limit`'s folder: limit.json beside runs/amplitude_…um; no operating run."""
    job = tmp_path / "limit"
    _search(job / "runs", (100.0, 150.0), (175.0,), speed_rpm=750.0)
    (job / "limit.json").write_text(json.dumps({
        "limit_um": 175.0, "limit_mm": 0.175, "bracket_um": [150.0, 175.0], "tolerance_um": 10.0,
        "range_um": [100.0, 175.0], "monotone": True, "changes": [], "runs": []}))
    page = write_report(job).read_text()
    text = _text(job / "report.html")
    limit = "Sticks up to 150.0 µm, not at 175.0 µm, the amplitude limit (searched at 750 rpm"
    assert limit in text and text.index(limit) < text.index("The amplitude search's runs")
    assert "sweep's fastest speed" not in text and "margin" not in text
    assert page.count("<pre>") == 1 and "not the amplitudes run above" in text
