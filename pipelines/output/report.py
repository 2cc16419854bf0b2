"""``fretwork report``: one self-contained HTML page of a run's or a job's folder.

The page answers first, then supports. A job's folder (``fretwork demo``, ``fretwork sweep
--margins``, ``fretwork limit``) opens with the job's verdict in one sentence, the amplitude
limit with its bracket and the speed it was searched at, and the margin at every speed
(``summary.json``, ``limit.json``, ``/margins`` of ``sweep.h5``); then the job's own run (the
operating point), with its figures and plots; then the runs of the amplitude search, one row
each. A run's folder shows its verdict, its operating point (wing amplitude, speed, load cycle,
engine hours: ``/histories`` of ``results.h5``) and its figures; a multibody run's folder
(``fretwork mbs``, ``run.h5``) its speed, wing amplitudes, torsion mode and steadiness. Plots
(PNG) are inlined as base64, so the page is one file to mail or archive; the versions of
fretwork and its main dependencies close it. Nothing is recomputed but what the CLI prints from
the same files. Units: mm, N, MPa, mJ in the files; the page shows µm, kN and hours where an
engineer reads them, labelled.
"""

from __future__ import annotations

import base64
import html
import json
import re
import tomllib
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path

import h5py
import numpy as np

from contact.verdict import VERDICT_MEANINGS, clamp_loss_pace
from pipelines.output.locks import REPORT_TITLE
from reduction.errors import InputError

#: the multibody run's file and the plot drawn beside it (mbs.run.run_model), and the plot every
#: contact run draws in its plots/ folder (pipelines.output.plots)
MULTIBODY_FILE = "run.h5"
MULTIBODY_PLOT = "wing_time_history.png"
RUN_PLOT = "plots/cycles.png"
PACKAGES = ("fretwork", "numpy", "scipy", "scikit-fem", "exudyn", "h5py", "matplotlib", "meshio", "fmpy")
#: the folder a limit search writes each amplitude's run into (pipelines.jobs.limit.run_amplitude)
AMPLITUDE_FOLDER = re.compile(r"amplitude_[0-9.]+um")
#: the endings of a run that stopped and still answer the search: not stuck (pipelines.jobs.limit.STOPPED)
#: Area fractions are sums of point areas over the nominal area: a whole area can sum to 1 + 2e-16.
ROUNDING = 1e-9
AREAS_NOTE = ("Areas are fractions of the contact area closed after the preload. Above 100 %: points beyond "
              "it came into contact, as wear widened the contact or the contact patch moved.")
STYLE = """body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}
table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ccc;padding:.2em .6em;text-align:left}
.verdict{font-size:1.4em;font-weight:bold}.unsafe{color:#b00;font-weight:bold}.note{font-size:.9em;color:#555}
.support{font-size:.9em}h3{font-size:1em}
img{max-width:100%;border:1px solid #ddd;margin:.5em 0}pre{background:#f6f6f6;padding:.8em;overflow:auto}
figure{margin:1em 0}figcaption{font-size:.9em;color:#555}"""


# ----------------------------------------------------------------------------------------- numbers

def _finite(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and bool(np.isfinite(value))


def _number(value, digits: int = 4) -> str:
    """A figure with ``digits`` significant digits, written without an exponent from 0.001 to 10⁶
    (a count of 524 347 cycles reads better than 5.243e+05)."""
    if not _finite(value):
        return "–"
    if value == 0:
        return "0"
    magnitude = int(np.floor(np.log10(abs(value))))
    if not -3 <= magnitude < 6:
        return f"{value:.{digits - 1}e}"
    text = f"{value:.{max(digits - 1 - magnitude, 0)}f}"
    return text.rstrip("0").rstrip(".") if "." in text else text


def _percent(fraction, decimals: int = 1) -> str:
    return f"{100 * fraction:.{decimals}f} %" if _finite(fraction) else "–"


def _kilonewtons(force_n) -> str:
    return f"{_number(force_n / 1e3)} kN" if _finite(force_n) else "–"


def _cycles(count) -> str:
    """A number of load cycles: whole cycles, thousands apart."""
    return f"{count:,.0f}".replace(",", " ") if _finite(count) else "–"


def _plural(count) -> str:
    return "" if count == 1 else "s"


def _duration(hours) -> str:
    """Engine running time, given in hours, in the unit that reads: h, min or s."""
    if not _finite(hours):
        return "–"
    if hours >= 1.0:
        return f"{_number(hours, 3)} h"
    return f"{_number(60 * hours, 3)} min" if hours >= 1 / 60 else f"{_number(3600 * hours, 3)} s"


def _um(amplitude_mm, tolerance_mm=None) -> str:
    from pipelines.jobs.limit import format_um

    return f"{format_um(amplitude_mm, tolerance_mm)} µm"


def _rpm(speeds) -> str:
    return ", ".join(f"{v:.0f}" for v in speeds) + " rpm"


def _table(rows) -> str:
    return "<table>" + "".join(f"<tr><th>{html.escape(k)}</th><td>{v}</td></tr>" for k, v in rows) + "</table>"


def _grid(header, rows, css: str = "") -> str:
    """A table with a header row; ``rows`` of cell texts (HTML)."""
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in row) + "</tr>" for row in rows)
    return f"<table{f' class={css}' if css else ''}><tr>{head}</tr>{body}</table>"


def _relative(path: Path, root: Path) -> str:
    return html.escape(str(path.relative_to(root)))


# -------------------------------------------------------------------------------------- contact runs

@dataclass
class Run:
    """A contact run's results file, read once. summary: its verdict, stationarity and figures
    with the operating point of a coupled run merged in (wing_amplitude_mm, engine_speed_rpm,
    load_cycle, load_cycle_frequency_hz, and the engine hours of pipelines.jobs.run); None when the
    run stopped without one (``stopped`` says why, ``message`` what failed)."""

    path: Path
    name: str
    scene: str
    summary: dict | None
    stopped: str = ""
    ending: str = ""
    message: str = ""
    effects: tuple = ()
    context: dict = field(default_factory=dict)

    @property
    def folder(self) -> Path:
        return self.path.parent

    @property
    def amplitude_mm(self) -> float | None:
        """The wing amplitude run (mm): the coupled run's own, else its search folder's name."""
        if "wing_amplitude_mm" in self.context:
            return self.context["wing_amplitude_mm"]
        return _folder_amplitude_mm(self.folder) if AMPLITUDE_FOLDER.fullmatch(self.folder.name) else None


def _context(file: h5py.File) -> dict:
    """The operating point of a coupled run: ``/histories`` holds the multibody histories that
    drove it and the load cycle they were played in (pipelines.output.results)."""
    if "histories" not in file:
        return {}
    attrs = file["histories"].attrs
    names = {"wing_amplitude": "wing_amplitude_mm", "speed_rpm": "engine_speed_rpm", "load_cycle": "load_cycle",
             "load_cycle_frequency_hz": "load_cycle_frequency_hz"}
    return {ours: (str(attrs[theirs]) if theirs == "load_cycle" else float(attrs[theirs]))
            for theirs, ours in names.items() if theirs in attrs}


def _effects(scene_toml: str) -> tuple:
    try:
        return tuple(tomllib.loads(scene_toml).get("scene", {}).get("effects", ()))
    except tomllib.TOMLDecodeError:
        return ()


def _open(path: Path) -> h5py.File:
    """The HDF5 file ``path``, open for reading; a folder in its place, or a file that cannot be
    read (truncated when its command was killed, emptied, written over), is an InputError naming it."""
    if path.is_dir():
        raise InputError(f"{path} is a folder, not a results file: move it away and run the command that writes "
                         "it again")
    try:
        return h5py.File(path, "r")
    except OSError:
        raise InputError(f"{path} is damaged ({path.stat().st_size:,} bytes that are not a readable HDF5 file: "
                         "truncated, or written over): it cannot be reported; run the command that wrote it "
                         "again") from None


def read_run(path: Path) -> Run | None:
    """The contact run of a results file, or None for another fretwork file of that name."""
    from pipelines.jobs.run import _engine_hours

    with _open(path) as file:
        attrs = file.attrs
        if attrs.get("fretwork_format") != "fretwork-results" or "model" in file:  # "model": a multibody run
            return None
        name, scene = str(attrs.get("scene_name", "")), str(attrs.get("scene_toml", ""))
        context = _context(file)
        if "summary" not in file:
            return Run(path, name, scene, None, _no_summary(file), str(attrs.get("ending", "")),
                       str(attrs.get("ending_message", "")), _effects(scene), context)
        summary = {"verdict": str(file["summary"].attrs["verdict"]),
                   "stationary": bool(file["summary"].attrs["stationary"]),
                   **json.loads(file["summary"].attrs["figures"]), **context}
    summary.update(_engine_hours(summary))
    return Run(path, name, scene, summary, effects=_effects(scene), context=context)


def _no_summary(file: h5py.File) -> str:
    """Why a results file has no summary: the run stopped early (its recorded ending, see
    pipelines.output.results), or it never ended."""
    from contact.verdict import Ending
    from pipelines.jobs.run import EARLY_ENDINGS, ENDINGS

    cycles = int(file["cycles/cycle"][-1]) if "cycles/cycle" in file and len(file["cycles/cycle"]) else 0
    ending = str(file.attrs.get("ending", ""))
    if ending in {e.value for e in EARLY_ENDINGS}:
        return (f"the run {ENDINGS[Ending(ending)]} (ending '{ending}') after {cycles} complete cycles: "
                "the file holds the cycles run so far, without final fields or a verdict")
    return f"incomplete results file: the run did not end (no ending recorded, {cycles} cycles), no summary"


def _has_bolts(s: dict) -> bool:
    return s.get("bolt_force_initial_N") is not None


def _cof_evolved(s: dict) -> bool:
    return (s.get("cof_evolved_area_fraction") or 0.0) > 0.0


def meaning(s: dict) -> str:
    """What the verdict says about this run, without claims that do not apply to it: no clause on
    an evolved COF where none evolved, none on the clamp force of a joint without bolts
    (:data:`contact.verdict.VERDICT_MEANINGS` states each verdict in general)."""
    falling = s.get("clamp_loss_recent_fraction") is not None
    steady = ("; loosening not evident, but the clamp force was still falling at the end" if falling
              else "; clamp force stable")
    verdict, clamp = s["verdict"], steady if _has_bolts(s) else ""
    if verdict == "partial_slip":
        return ("a stick zone holds" + (clamp.replace(";", " and", 1) if _has_bolts(s) else "")
                + ", but the contact edges keep sliding at a COF that never had to rise: fretting at the edges, "
                  "no friction-driven surface damage; judge crack risk by FFDP")
    if verdict == "damage":
        whole = (s.get("stick_area_fraction") or 0.0) <= ROUNDING
        if _cof_evolved(s):
            how = ("points keep sliding after their COF rose there, at μ_max or still rising towards it when the "
                   "run ended" + (" (the whole contact slides)" if whole else ""))
        else:
            how = "the whole contact keeps sliding (gross slip), no stick zone holds" if whole else \
                "points keep sliding"
        return f"{how}: fretting scars expected{clamp}"
    return VERDICT_MEANINGS.get(verdict, "")


def _operating_rows(s: dict) -> list:
    rows = []
    if "wing_amplitude_mm" in s:
        cycle = str(s.get("load_cycle", "")).replace("_", " ")
        rows.append(("operating point", f"wing amplitude {_number(1e3 * s['wing_amplitude_mm'], 3)} µm at "
                                        f"{s['engine_speed_rpm']:.0f} rpm"))
        if "load_cycle_frequency_hz" in s:
            rows.append(("one load cycle", f"{html.escape(cycle)} ({s['load_cycle_frequency_hz']:.0f} Hz)"))
    hours = s.get("equivalent_engine_hours")
    rows.append(("load cycles", f"{s['cycles_run']} simulated, standing for {_cycles(s['equivalent_cycles'])} real "
                                "cycles" + (f" = {_duration(hours)} of engine running" if hours is not None else "")))
    for key, what in (("shakedown_at", "shakedown"), ("loosening_evident_at", "loosening evident")):
        if s.get(f"{key}_cycles") is not None:
            when = s.get(f"{key}_engine_hours")
            rows.append((what, f"after {_cycles(s[key + '_cycles'])} real cycle{_plural(s[key + '_cycles'])}"
                               + (f" ({_duration(when)})" if when is not None else "")))
    life = s.get("life_cycles")
    if life is not None and s.get("shakedown_at_cycles") is None and s["verdict"] != "loosening" \
            and s["equivalent_cycles"] < (1.0 - 1e-9) * life:
        rows.append(("NOTE", f"the run ended at its wear_cycles budget, {_percent(s['equivalent_cycles'] / life)} of "
                             f"its life ({_cycles(life)} cycles): the verdict covers that running time only"))
    if s.get("clamp_loss_recent_fraction") is not None:
        pace = clamp_loss_pace(s.get("clamp_loss_rate_ratio"))
        rows.append(("NOTE", f"the clamp force was still falling at the end: {_percent(s['clamp_loss_recent_fraction'])} "
                             f"of it lost over the last {_cycles(s['clamp_loss_recent_cycles'])} real cycles, {pace}; "
                             "the joint has not settled, and a longer run tells whether it levels off or loosens"))
    return rows


def _area_rows(s: dict, effects: tuple) -> list:
    rows = [("stick", _percent(s["stick_area_fraction"])),
            ("at the friction limit (slip)", _percent(s["slip_area_fraction"])),
            ("of it at μ_max (damaged)", _percent(s["damaged_area_fraction"])),
            ("still sliding (the verdict's measure)", _percent(s.get("active_slip_area_fraction",
                                                                      s["slip_area_fraction"])))]
    if "cof_evolution" in effects or _cof_evolved(s):
        rows.append(("COF evolved", _percent(s["cof_evolved_area_fraction"])))
    return [(f"area {label}", text) for label, text in rows]


def _figure_rows(s: dict, effects: tuple) -> list:
    rows = []
    if s.get("min_stick_margin") is not None:
        rows.append(("smallest stick margin of stuck points, 1 − max |τ|/p / μ_max",
                     _number(s["min_stick_margin"], 3)))
    if "wear" in effects or (s.get("max_wear_depth_mm") or 0.0) > 0:
        rows += [("max wear depth", f"{_number(1e3 * s['max_wear_depth_mm'], 3)} µm"),
                 ("wear volume", f"{_number(s['wear_volume_mm3'], 3)} mm³")]
    rows.append(("dissipated energy, simulated cycles", f"{_number(s['dissipated_energy_mJ'])} mJ"))
    if _has_bolts(s):
        rows.append(("clamp force", f"{_kilonewtons(s['bolt_force_initial_N'])} → "
                                    f"{_kilonewtons(s['bolt_force_final_N'])} "
                                    f"({_percent(s['clamp_force_loss_fraction'], 2)} loss)"))
    for key, label, unit in (("fdp", "FDP max τ·δ", "MPa·mm"), ("ffdp", "FFDP max σ_t·τ·δ", "MPa²·mm")):
        value = s.get(f"{key}_max_{unit.replace('²', '2').replace('·', '_')}")
        if value is None:
            continue
        where = s.get(f"{key}_max_location_mm")
        at = f" at ({', '.join(_number(v, 4) for v in where)}) mm" if value != 0 and where is not None else ""
        rows.append((label, f"{_number(value)} {unit}{at}"))
    return rows


def _run_heading(run: Run, root: Path, title: str) -> str:
    return f"<h2>{html.escape(title)} {html.escape(run.name)} ({_relative(run.path, root)})</h2>"


def _scene_block(scene: str, caption: str = "scene") -> str:
    if not scene:
        return ""
    return f"<details><summary>{html.escape(caption)}</summary><pre>{html.escape(scene)}</pre></details>"


def _run_section(run: Run, root: Path, title: str = "Run") -> str:
    if run.summary is None:
        return "\n".join([_run_heading(run, root, title), f"<p class='unsafe'>{html.escape(run.stopped)}</p>",
                          f"<p>why: {html.escape(run.message)}</p>" if run.message else "", _scene_block(run.scene)])
    s = run.summary
    verdict = str(s["verdict"])
    stationary = "" if s["stationary"] else " (not yet stationary)"
    rows = _operating_rows(s) + _area_rows(s, run.effects) + _figure_rows(s, run.effects)
    areas = [s.get(k) for k in ("stick_area_fraction", "slip_area_fraction", "active_slip_area_fraction",
                                "cof_evolved_area_fraction")]
    widened = max((a for a in areas if _finite(a)), default=0.0) > 1.0 + ROUNDING
    note = AREAS_NOTE if widened else AREAS_NOTE.split(" Above")[0]
    return "\n".join([_run_heading(run, root, title),
                      f"<p class='verdict'>verdict: {html.escape(verdict.upper())}{stationary}</p>",
                      f"<p>{html.escape(meaning(s))}</p>", _table(rows), f"<p class='note'>{html.escape(note)}</p>",
                      _scene_block(run.scene)])


# --------------------------------------------------------------------------------- amplitude search

@dataclass
class Search:
    """An amplitude-limit search: its runs (one folder each) and what its job recorded
    (limit.json of ``fretwork limit`` and the demo; a sweep's /margins holds the limit alone)."""

    folder: Path
    runs: list
    unfinished: list
    record: dict | None = None

    @property
    def speed_rpm(self) -> float | None:
        speeds = {r.context.get("engine_speed_rpm") for r in self.runs} - {None}
        return speeds.pop() if len(speeds) == 1 else None

    def verdicts(self) -> list:
        """(amplitude mm, verdict or None) of every run, unfinished ones too, in amplitude order."""
        return sorted([(r.amplitude_mm, r.summary["verdict"] if r.summary else None)
                       for r in self.runs if r.amplitude_mm is not None]
                      + [(_folder_amplitude_mm(p.parent), None) for p in self.unfinished])


def _limit_facts(record: dict | None, search: Search | None, margins: Margins | None) -> dict:
    """The limit, its bracket, range, tolerance, monotony and what the margins divide
    (``margin_mm``, ``margin_bound`` as :class:`pipelines.jobs.limit.LimitResult` says them): from
    the job's limit.json (``fretwork limit``, the demo, and ``sweep --margins`` in its limit_runs/),
    else read off the search's runs (a run without a verdict stopped: not stuck), for folders
    written before sweep --margins wrote limit.json. ``margin_bound`` is None where neither a
    record nor the runs tell what stuck."""
    from pipelines.jobs.limit import LimitResult

    mm = (lambda um: None if um is None else 1e-3 * um)
    limit_mm = margins.limit_mm if margins is not None else None
    if record:
        facts = {"limit_mm": record.get("limit_mm"), "stuck_mm": mm((record.get("bracket_um") or [None])[0]),
                 "range_mm": [mm(v) for v in record.get("range_um") or (None, None)],
                 "tolerance_mm": mm(record.get("tolerance_um")), "monotone": record.get("monotone", True),
                 "margin_mm": mm(record.get("margin_amplitude_um")), "margin_bound": record.get("margin_bound")}
        known = True
    else:
        facts = {"limit_mm": limit_mm, "stuck_mm": None, "range_mm": (None, None), "tolerance_mm": None,
                 "monotone": True, "margin_mm": None, "margin_bound": None}
        runs = search.verdicts() if search is not None else []
        known = bool(runs)
        if runs:
            facts["range_mm"] = (runs[0][0], runs[-1][0])
            if limit_mm is not None:
                facts["stuck_mm"] = max((a for a, v in runs if v == "stick" and a < limit_mm), default=None)
                facts["monotone"] = not any(v == "stick" and a > limit_mm for a, v in runs)
    if facts["margin_bound"] is None and margins is not None and margins.margin_bound is not None:
        facts["margin_mm"], facts["margin_bound"] = margins.margin_amplitude_mm, margins.margin_bound
    if facts["stuck_mm"] is None and facts["margin_bound"] == "stuck":  # /margins says what stuck
        facts["stuck_mm"] = facts["margin_mm"]
    if facts["margin_bound"] is None and known:  # a record or runs of before the margins were conservative
        limit = LimitResult(facts["limit_mm"], (facts["stuck_mm"] if facts["limit_mm"] is not None
                                                else facts["range_mm"][1], facts["limit_mm"]),
                            facts["tolerance_mm"] or 0.0, range_mm=tuple(facts["range_mm"]))
        facts["margin_mm"], facts["margin_bound"] = limit.margin_limit_mm, limit.margin_bound
    return facts


def _limit_result(facts: dict):
    """The facts as a :class:`pipelines.jobs.limit.LimitResult`, whose rules judge the margins;
    where nothing tells what stuck (``margin_bound`` None), the bracket is the limit alone."""
    from pipelines.jobs.limit import LimitResult

    limit_mm = facts["limit_mm"]
    if limit_mm is None:
        bracket = (facts["margin_mm"] or facts["range_mm"][1], None)
    else:
        bracket = (limit_mm if facts["margin_bound"] is None else facts["stuck_mm"], limit_mm)
    return LimitResult(limit_mm, bracket, facts["tolerance_mm"] or 0.0, range_mm=tuple(facts["range_mm"]))


def _limit_sentence(facts: dict, speed_rpm: float | None, why_speed: str = "") -> str:
    tolerance = facts["tolerance_mm"]
    low, high = facts["range_mm"]
    searched = " (" + ", ".join(part for part in (
        f"searched at {speed_rpm:.0f} rpm{why_speed}" if speed_rpm is not None else "",
        f"over {_um(low, tolerance)} to {_um(high, tolerance)}" if low is not None else "",
        f"tolerance {_um(tolerance)}" if tolerance else "") if part) + ")"
    searched = "" if searched == " ()" else searched
    if facts["limit_mm"] is None:
        top = f" {_um(high, tolerance)}" if high is not None else ""
        return (f"Sticks over the whole searched range, up to{top}{searched}: the amplitude limit lies above it; "
                "margins are lower bounds.")
    limit = _um(facts["limit_mm"], tolerance)
    if facts["stuck_mm"] is not None:  # what the margins divide first: the limit is not an allowable
        text = f"Sticks up to {_um(facts['stuck_mm'], tolerance)}, not at {limit}, the amplitude limit"
    else:
        text = f"Not stuck even at {limit}, the bottom of the searched range: the amplitude limit lies below it"
    text += searched + "."
    if not facts["monotone"]:
        text += " NOT MONOTONE: the joint sticks again above the limit (the search's runs below)."
    return text


def _search_section(search: Search, root: Path, with_scene: bool) -> str:
    """The search's runs as supporting material: one compact row each."""
    from pipelines.jobs.limit import STOPPED

    not_stuck = {ending.value for ending in STOPPED}  # the endings a search counts as loosening
    rows = []
    for run in sorted(search.runs, key=lambda r: (r.amplitude_mm is None, r.amplitude_mm or 0.0)):
        amplitude = _number(1e3 * run.amplitude_mm, 4) if run.amplitude_mm is not None else "–"
        where = _relative(run.folder, root)
        if run.summary is None:
            rows.append([amplitude, "not stuck (counted as loosening)" if run.ending in not_stuck else "none",
                         html.escape(_stopped(run.ending)), *["–"] * 6, where])
            continue
        s = run.summary
        cycles = _cycles(s["equivalent_cycles"]) + (f" ({_duration(s['equivalent_engine_hours'])})"
                                                    if s.get("equivalent_engine_hours") is not None else "")
        loss = _percent(s["clamp_force_loss_fraction"], 2) if _has_bolts(s) else "–"
        depth = _number(1e3 * s["max_wear_depth_mm"], 3) if s.get("max_wear_depth_mm") is not None else "–"
        rows.append([amplitude, html.escape(s["verdict"]), html.escape(_ending(s)),
                     _percent(s["stick_area_fraction"]), _percent(s["damaged_area_fraction"]),
                     _percent(s.get("cof_evolved_area_fraction")), loss, depth, cycles, where])
    for path in search.unfinished:
        rows.append([_number(1e3 * _folder_amplitude_mm(path.parent), 4), "none",
                     "did not finish: only results.h5.part (not converged, or interrupted)", *["–"] * 6,
                     _relative(path.parent, root)])
    speed = search.speed_rpm
    first = next((r for r in search.runs if r.scene), None)
    scene = _scene_block(first.scene, "the scene of the search (its own wing amplitude and description, not the "
                                      "amplitudes run above)") if with_scene and first else ""
    return (f"<div class='support'><h3>The amplitude search's runs ({_relative(search.folder, root)}), supporting the "
            f"limit</h3><p>Each run is the scene with its wing vibration scaled to the amplitude in the first column"
            + (f", at {speed:.0f} rpm" if speed is not None else "") + ". Areas are fractions of the area closed "
            "after the preload; real cycles are the load cycles the run stands for.</p>"
            + _grid(("wing amplitude [µm]", "verdict", "how it ended", "stick area", "damaged area", "COF evolved",
                     "clamp-force loss", "max wear depth [µm]", "real cycles (engine running)", "folder"), rows)
            + scene + "</div>")


def _stopped(ending: str) -> str:
    from contact.verdict import Ending
    from pipelines.jobs.run import ENDINGS

    try:
        return ENDINGS[Ending(ending)]
    except ValueError:
        return "did not end"


def _folder_amplitude_mm(folder: Path) -> float:
    """The amplitude a search's run folder is named after (pipelines.jobs.limit.run_amplitude, µm)."""
    return 1e-3 * float(folder.name.removeprefix("amplitude_").removesuffix("um"))


def _ending(s: dict) -> str:
    if s.get("loosening_evident_at_cycles") is not None:
        count = s["loosening_evident_at_cycles"]
        return f"loosening evident after {_cycles(count)} real cycle{_plural(count)}"
    if s.get("shakedown_at_cycles") is not None:
        count = s["shakedown_at_cycles"]
        return f"shakedown after {_cycles(count)} real cycle{_plural(count)}"
    return "ran its cycles"


# ------------------------------------------------------------------------------------- job verdict

@dataclass
class Margins:
    """``/margins`` of a sweep file (pipelines.jobs.margins.write_margins), mm and rpm."""

    speeds_rpm: np.ndarray
    wing_amplitude_mm: np.ndarray
    margin: np.ndarray
    limit_mm: float | None
    limit_speed_rpm: float
    calibration: float
    margin_amplitude_mm: float | None = None  # what the margins divide; None in files of before 3efc5ce
    margin_bound: str | None = None  # "stuck", "lower bound", "upper bound" (LimitResult.margin_bound)
    counterweight: int | None = None  # the CW judged; None in files of before it was written
    crossings_between_rpm: tuple = ()  # order/mode crossings between the sampled speeds
    larger_swings: tuple = ()  # (CW, speed rpm, ratio): another CW swings more than the judged one


def _read_sweep(path: Path) -> tuple[Margins | None, dict | None]:
    """(its margins or None, the plain multibody sweep's table or None) of a sweep file."""
    with _open(path) as file:
        if file.attrs.get("fretwork_format") != "fretwork-sweep":
            return None, None
        if "margins" in file and "speed_rpm" in file["margins"]:
            group = file["margins"]
            limit = float(group.attrs.get("limit_mm", np.nan))
            divided = group.attrs.get("margin_amplitude_mm")
            bound = group.attrs.get("margin_bound")
            judged = group.attrs.get("counterweight")
            swings = json.loads(group.attrs.get("larger_swings_json", "[]"))
            return Margins(group["speed_rpm"][()], group["wing_amplitude"][()], group["margin"][()],
                           limit if np.isfinite(limit) else None, float(group.attrs.get("limit_speed_rpm", np.nan)),
                           float(group.attrs.get("calibration_factor", 1.0)),
                           None if divided is None else float(divided), None if bound is None else str(bound),
                           None if judged is None else int(judged),
                           tuple(float(c) for c in np.atleast_1d(group.attrs.get("crossings_between_speeds_rpm", []))),
                           tuple((int(w["counterweight"]), float(w["speed_rpm"]), float(w["ratio"])) for w in swings)), None
        if "sweep" not in file:
            return None, None
        group = file["sweep"]
        return None, {"speeds_rpm": group["speed"][()], "wing_amplitude_mm": group["wing_amplitude"][()],
                      "frequencies_hz": group["dominant_frequencies"][()], "resonance": group["resonance"][()],
                      "failures": json.loads(group.attrs.get("failures_json", "{}")),
                      "unsettled": json.loads(group.attrs.get("unsettled_json", "{}"))}


def _states(m: Margins, facts: dict) -> list:
    """'not judged', 'unsafe', 'at the limit', 'not shown safe' (nothing of the searched range
    stuck) or 'safe' at each speed, as :meth:`pipelines.jobs.margins.MarginResult.state` judges
    the file's margins against the limit's bracket."""
    from pipelines.jobs.margins import MarginResult

    judged = MarginResult(m.speeds_rpm, m.wing_amplitude_mm, m.calibration, _limit_result(facts), m.margin,
                          m.limit_speed_rpm)
    return [judged.shown_state(k) for k in range(len(m.speeds_rpm))]


def _divided(facts: dict, m: Margins) -> str:
    """What the margins divide, in words, as pipelines.jobs.margins.describe_margins says it."""
    tolerance = facts["tolerance_mm"]
    amplitude = _um(facts["margin_mm"], tolerance) if facts["margin_mm"] is not None else ""
    return {"stuck": f"{amplitude}, the largest amplitude shown to stick",
            "lower bound": f"{amplitude}, the top of the searched range, all of which stuck",
            "upper bound": f"{amplitude}, the bottom of the searched range, which did not stick"}.get(
        facts["margin_bound"] if m.margin_amplitude_mm is not None else None, "the amplitude limit")


def job_verdict(m: Margins, facts: dict | None = None) -> str:
    """The job's answer in one sentence, e.g. 'UNSAFE at 600 rpm: margin 0.60 < 1, ...' or 'safe
    at every speed, smallest margin 1.16 at 900 rpm'. facts: the limit's (:func:`_limit_facts`;
    read off ``m`` alone when not given)."""
    from pipelines.jobs.margins import band_edges, crossings_sentence, edges_sentence, judged_sentence, swings_sentence

    facts = facts if facts is not None else _limit_facts(None, None, m)
    states = np.array(_states(m, facts))
    parts = []
    unsafe = states == "unsafe"
    if unsafe.any():
        margins = ", ".join(f"{v:.2f}" for v in m.margin[unsafe])
        edges = edges_sentence(band_edges(m.speeds_rpm, list(states)))
        parts.append(f"UNSAFE at {_rpm(m.speeds_rpm[unsafe])}: margin{'s' if unsafe.sum() > 1 else ''} {margins} < 1, "
                     f"the wing vibration exceeds {_divided(facts, m)}" + (f" {edges}" if edges else ""))
    if (states == "at the limit").any():
        parts.append(f"at the limit at {_rpm(m.speeds_rpm[states == 'at the limit'])}: the wing amplitude lies within "
                     "the limit's tolerance of its bracket")
    if (states == "not shown safe").any():
        parts.append(f"not shown safe at {_rpm(m.speeds_rpm[states == 'not shown safe'])}: nothing in the searched "
                     "range stuck, the margins are upper bounds")
    if (states == "not judged").any():
        parts.append(f"NOT JUDGED at {_rpm(m.speeds_rpm[states == 'not judged'])}: the multibody run failed there")
    safe = states == "safe"
    bound = " (a lower bound: the joint stuck over the whole searched range)" \
        if facts["margin_bound"] == "lower bound" or (facts["margin_bound"] is None and m.limit_mm is None) else ""
    if safe.any():
        k = np.flatnonzero(safe)[int(np.argmin(m.margin[safe]))]
        smallest = f"smallest margin {m.margin[k]:.2f} at {m.speeds_rpm[k]:.0f} rpm{bound}"
        sampled = " sampled" if m.crossings_between_rpm else ""
        parts.append(f"safe at {'the sampled' if sampled else 'every'} speed{'s' if sampled else ''}, {smallest}"
                     if safe.all() else f"safe at the {'other sampled speeds' if sampled else 'others'}, {smallest}")
    for sentence in (crossings_sentence(m.speeds_rpm, list(m.crossings_between_rpm)), judged_sentence(m.counterweight),
                     swings_sentence(list(m.larger_swings), m.counterweight or 1)):
        if sentence:
            parts.append(sentence)
    return "; ".join(parts)


def _margins_table(m: Margins, facts: dict) -> str:
    rows = []
    for speed, amplitude, margin, state in zip(m.speeds_rpm, m.wing_amplitude_mm, m.margin, _states(m, facts)):
        css = " class=unsafe" if state != "safe" else ""
        rows.append([f"{speed:.0f}", _number(1e3 * amplitude, 3) if np.isfinite(amplitude) else "–",
                     f"{margin:.2f}" if np.isfinite(margin) else "–", f"<span{css}>{html.escape(state)}</span>"])
    calibrated = "" if m.calibration == 1.0 else (
        f" The wing amplitudes are the multibody model's times {_number(m.calibration)}, the scene's stated wing "
        "amplitude over the multibody one at the scene's own speed.")
    if m.margin_amplitude_mm is None:  # written before the margins divided an amplitude that stuck
        said = ("margin = amplitude limit (the lowest amplitude found not stuck) / wing amplitude at that speed, as "
                "this older file holds it: inside the limit's bracket a margin of 1 or more is not shown safe.")
    else:
        said = (f"margin = {_divided(facts, m)} / wing amplitude at that speed; below 1 the wing vibrates more than "
                "that." + (" The margins are lower bounds." if facts["margin_bound"] == "lower bound" else
                           " The margins are upper bounds: no speed is shown safe."
                           if facts["margin_bound"] == "upper bound" else ""))
    return (_grid(("speed [rpm]", "wing amplitude [µm]", "margin", "state"), rows)
            + f"<p class='note'>{html.escape(said + calibrated)}</p>")


def _job_section(demo: dict | None, margins: Margins | None, search: Search | None,
                 record: dict | None = None) -> str:
    """The job's answer first: its verdict, the amplitude limit, the margins per speed, the
    operating point. record: the job's limit.json (the search's own when not given)."""
    facts = _limit_facts(record if record is not None else search.record if search is not None else None,
                         search, margins)
    parts = ["<h2>Job verdict</h2>"]
    if margins is not None:
        parts.append(f"<p class='verdict'>{html.escape(job_verdict(margins, facts))}</p>")
    if demo is not None:
        parts.append(f"<p>{html.escape(_operating_sentence(demo))}</p>")
    speed = margins.limit_speed_rpm if margins is not None and np.isfinite(margins.limit_speed_rpm) else \
        search.speed_rpm if search is not None else None
    why = ", the sweep's fastest speed, where the centrifugal load is largest" if margins is not None else ""
    limit = _limit_sentence(facts, speed, why)
    parts.append(f"<p class='verdict'>{html.escape(limit)}</p>" if margins is None else f"<p>{html.escape(limit)}</p>")
    if margins is not None:
        parts.append(_margins_table(margins, facts))
    for warning in (demo or {}).get("warnings") or ():
        parts.append(f"<p class='unsafe'>WARNING: {html.escape(str(warning))}</p>")
    if (demo or {}).get("multibody_warning"):
        parts.append(f"<p class='unsafe'>WARNING (operating run): {html.escape(demo['multibody_warning'])}</p>")
    return "\n".join(parts)


def _operating_sentence(d: dict) -> str:
    margin, speed, amplitude = (d.get(key) for key in
                                ("margin_at_operating_point", "engine_speed_rpm", "wing_amplitude_um"))
    text = "At the operating point" + (f", {speed:.0f} rpm" if _finite(speed) else "") + (
        f" with a wing amplitude of {_number(amplitude, 3)} µm" if _finite(amplitude) else "")
    text += f": verdict {str(d.get('verdict', '–')).upper()}"
    if _finite(margin):
        text += f", margin {margin:.2f} ({d.get('operating_point', 'unsafe' if margin < 1 else 'safe')})"
    return text + " (the operating run below)."


def _sweep_section(table: dict) -> str:
    """A multibody speed sweep without margins: wing amplitude and dominant frequency per speed."""
    amplitudes = np.atleast_2d(table["wing_amplitude_mm"])
    rows = []
    for k, speed in enumerate(table["speeds_rpm"]):
        key = f"{float(speed)}"
        note = ("FAILED: " + table["failures"][key] if key in table["failures"] else
                "NOT STEADY (amplitude not to be trusted)" if key in table["unsettled"] else
                "order/mode crossing" if table["resonance"][k] else "")
        rows.append([f"{speed:.0f}", *(_number(1e3 * a, 3) for a in amplitudes[k]),
                     _number(table["frequencies_hz"][k][0], 4), html.escape(note)])
    header = ("speed [rpm]", *(f"CW{c + 1} wing amplitude [µm]" for c in range(amplitudes.shape[1])),
              "strongest CW1 wing frequency [Hz]", "note")
    return "<h2>Speed sweep (multibody)</h2>" + _grid(header, rows)


# ------------------------------------------------------------------------------------ multibody run

def _is_multibody_run(path: Path) -> bool:
    """Whether an HDF5 file is a multibody run's (``fretwork mbs``: run.h5, or the name --out gave it);
    a run.h5 that cannot be read is an InputError (:func:`_open`)."""
    if path.name in ("results.h5", "sweep.h5", "checkpoint.h5") or path.name.startswith("interface"):
        return False
    if path.name == MULTIBODY_FILE:
        _open(path).close()
    try:
        with h5py.File(path, "r") as file:
            return file.attrs.get("fretwork_format") == "fretwork-results" and "model" in file \
                and "parameters_json" in file["model"].attrs
    except OSError:  # not an HDF5 file
        return False


def _mbs_section(path: Path, root: Path) -> str:
    """A multibody run (``fretwork mbs``): its numbers as the CLI prints them (pipelines.cli.mbs)."""
    from mbs.histories import SETTLED_CHANGE, steady_part, unsettled_change, wing_amplitude
    from mbs.results import read_histories

    # a run cut short, with NaN samples or without time is refused (QA)
    histories = read_histories(path, required=("crank_angle", "cw1_wing_torsion"))
    with _open(path) as file:
        params = json.loads(file["model"].attrs["parameters_json"])
        torsion_hz = float(file["model/eigenfrequencies"][int(file["model"].attrs["torsion_mode"])])
        real_time = float(file["model"].attrs.get("real_time_factor", np.nan))
    names = sorted((n for n in histories if re.fullmatch(r"cw\d+_wing_torsion", n)),
                   key=lambda n: int(n[2:].split("_")[0]))
    torsion = np.array([histories[n] for n in names])
    crank = histories["crank_angle"]
    amplitudes = wing_amplitude(torsion[:, steady_part(torsion.shape[1])])
    change = unsettled_change(crank, torsion)
    solver = params.get("solver", {})
    if change is None:
        steady = "too short to tell whether it is steady (its second half must span two engine cycles)"
    else:
        steady = (f"{'steady' if change <= SETTLED_CHANGE else 'NOT STEADY'}: the wing amplitude changes by "
                  f"{100 * change:.1f} % between its first and last engine cycle "
                  f"(at most {100 * SETTLED_CHANGE:.0f} %)")
    rows = [("engine speed", f"{params['speed_rpm']:g} rpm"),
            ("wing amplitude (half peak-to-peak over the second half)",
             ", ".join(f"{n[:3].upper()} {_number(1e3 * a, 3)} µm" for n, a in zip(names, amplitudes))),
            ("second half of the run", steady),
            ("CW torsion mode (fixed interface)", f"{torsion_hz:.1f} Hz"),
            ("run", f"{solver.get('revolutions', np.nan):g} revolutions, "
                    f"time step {solver.get('time_step', np.nan):g} s, "
                    f"{params.get('n_modes')} Craig–Bampton modes per CW"),
            ("run time", f"{_number(real_time, 3)} simulated s per wall-clock s")]
    css = "" if change is not None and change <= SETTLED_CHANGE else " class='unsafe'"
    return (f"<h2>Multibody run ({_relative(path, root)})</h2>"
            + (f"<p{css}>the response is {html.escape(steady.split(':')[0])}</p>") + _table(rows))


# ------------------------------------------------------------------------------------------- page

def _image(path: Path, root: Path) -> str:
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    caption = _relative(path, root)
    return (f"<figure><img alt='{caption}' src='data:image/png;base64,{data}'>"
            f"<figcaption>{caption}</figcaption></figure>")


def versions() -> dict:
    out = {}
    for package in PACKAGES:
        try:
            out[package] = metadata.version(package)
        except metadata.PackageNotFoundError:
            out[package] = "not installed"
    return out


def _searches(root: Path, runs: list) -> tuple[list, list]:
    """(the amplitude searches, the other runs): a run in an ``amplitude_…um`` folder belongs to
    the search of the folder above it."""
    grouped, others = {}, []
    for run in runs:
        if AMPLITUDE_FOLDER.fullmatch(run.folder.name):
            grouped.setdefault(run.folder.parent, []).append(run)
        else:
            others.append(run)
    for part in root.rglob("results.h5.part"):
        if AMPLITUDE_FOLDER.fullmatch(part.parent.name) and not (part.parent / "results.h5").exists():
            grouped.setdefault(part.parent.parent, [])
    searches = []
    for folder, members in sorted(grouped.items()):
        unfinished = sorted(p for p in folder.glob("amplitude_*um/results.h5.part")
                            if not (p.parent / "results.h5").exists())
        record = next((json.loads(p.read_text()) for p in (folder / "limit.json", folder.parent / "limit.json")
                       if p.is_file()), None)
        searches.append(Search(folder, members, unfinished, record))
    return searches, others


def _margins_limit_record(root: Path) -> dict | None:
    """The limit.json `sweep --margins` wrote beside its limit's runs (limit_runs/), read even when
    no run folder is there (every run came from the stage cache); None in older sweep folders."""
    path = root / "limit_runs" / "limit.json"
    return json.loads(path.read_text()) if path.is_file() else None


def _plots(images: list, root: Path, heading: str) -> str:
    return f"<h2>{html.escape(heading)}</h2>" + "".join(_image(p, root) for p in images) if images else ""


@dataclass
class Folder:
    """What a run's or a job's folder holds, read once: contact runs (own runs and amplitude
    searches), multibody runs, sweep files (margins or a plain sweep), the demo's summary, plots."""

    root: Path
    own_runs: list
    searches: list
    multibody: list
    sweeps: list
    demo: dict | None
    images: list
    missing: list = field(default_factory=list)  # results files missing beside their plots

    @property
    def margins(self) -> Margins | None:
        return next((m for m, _ in self.sweeps if m is not None), None)

    @property
    def is_job(self) -> bool:
        return self.demo is not None or self.margins is not None or bool(self.searches)


def read_folder(root: Path) -> Folder:
    """The folder's files (see :class:`Folder`); an InputError when it holds nothing to report."""
    def shallow_first(paths):  # a job's own run before the runs of its search
        return sorted(paths, key=lambda path: (len(path.relative_to(root).parts), path))

    runs = [r for r in (read_run(p) for p in shallow_first(root.rglob("results.h5"))) if r is not None]
    multibody = [p for p in shallow_first(root.rglob("*.h5")) if _is_multibody_run(p)]
    sweeps = [_read_sweep(p) for p in shallow_first(root.rglob("sweep.h5"))]
    demo_file = root / "summary.json"
    demo = json.loads(demo_file.read_text()).get("summary") if demo_file.is_file() else None
    images = sorted(root.rglob("*.png"))
    missing = _missing_results(root, multibody)
    if not (runs or multibody or sweeps or demo or any(root.rglob("limit.json"))):
        unfinished = sorted(root.rglob("results.h5.part"))
        if unfinished:
            raise InputError(_unfinished(root, unfinished[0]))
        if missing:
            raise InputError(missing[0])
        if not images:
            raise InputError(f"{root} holds no fretwork results (results.h5, summary.json or plots)")
    searches, own_runs = _searches(root, runs)
    return Folder(root, own_runs, searches, multibody, sweeps, demo, images, missing)


def _unfinished(root: Path, part: Path) -> str:
    """Why a folder holds no results but a run's half-written results file ``part`` (written as
    the run goes, renamed results.h5 at its end), and how to go on: continue the run from its
    checkpoint (``fretwork run --resume``), or run it again."""
    folder, name = part.parent, part.relative_to(root)
    cycles, scene = 0, ""
    try:
        if part.stat().st_size:  # else created, nothing written yet
            with h5py.File(part, "r") as file:
                cycles = int(file["cycles/cycle"][-1]) if "cycles/cycle" in file and len(file["cycles/cycle"]) else 0
                scene = str(file.attrs.get("scene_name", ""))
    except OSError:  # killed while it wrote the file
        return (f"{root} holds only {name}, which cannot be read: its run was killed while writing it; nothing to "
                f"report: run it again (fretwork run SCENE --out {folder})")
    if cycles == 0:
        return (f"{root} holds only {name}: its run stopped before it finished a cycle (the error it printed says "
                "why); nothing converged to report")
    stopped = (f"{root} holds only {name}: the run{f' of scene {scene!r}' if scene else ''} was interrupted after "
               f"{cycles} cycle{_plural(cycles)}, before it ended: there is no verdict to report yet")
    checkpoint = folder / "checkpoint.h5"
    try:
        h5py.File(checkpoint, "r").close()
    except OSError:  # none, or damaged
        damaged = ", and its checkpoint.h5 is damaged" if checkpoint.exists() else ""
        return f"{stopped}{damaged}; run it again (fretwork run SCENE --out {folder})"
    return (f"{stopped}; continue it from its checkpoint with fretwork run SCENE --out {folder} --resume (SCENE: "
            "the scene file it ran, unchanged)")


def _missing_results(root: Path, multibody: list) -> list:
    """A sentence for every run whose plots are in the folder but whose results file is not (removed,
    or the run was interrupted between its plots and its file): the plots alone are no result."""
    missing = []
    for plot in sorted(root.rglob(RUN_PLOT)):
        folder = plot.parent.parent
        if not (folder / "results.h5").exists() and not (folder / "results.h5.part").exists():
            missing.append(f"results.h5 is missing in {folder}: only the plots of its run are there, without the "
                           "verdict and figures they belong to; run it again (fretwork run SCENE --out "
                           f"{folder})")
    for plot in sorted(root.rglob(MULTIBODY_PLOT)):
        if not any(path.parent == plot.parent for path in multibody):
            missing.append(f"{MULTIBODY_FILE} is missing in {plot.parent}: only the plots of its multibody run are "
                           f"there, without the run they belong to; run it again (fretwork mbs SCENE --out "
                           f"{plot.parent})")
    return missing


def _sections(folder: Folder) -> list:
    """The page's sections in reading order: the job's answer, its own runs, the supporting search."""
    root, is_job = folder.root, folder.is_job
    sections = [f"<p class='unsafe'>MISSING: {html.escape(sentence)}</p>" for sentence in folder.missing]
    if is_job:
        sections.append(_job_section(folder.demo, folder.margins, folder.searches[0] if folder.searches else None,
                                     _margins_limit_record(root)))
    sections += [_sweep_section(table) for _, table in folder.sweeps if table is not None]
    run_folders = [run.folder for run in folder.own_runs]
    other_images = [p for p in folder.images if not any(f in p.parents for f in run_folders)]
    if is_job:
        sections.append(_plots(other_images, root, "Plots of the job"))
    for run in folder.own_runs:
        title = "Operating run" if is_job else "Run"
        sections.append(_run_section(run, root, title))
        sections.append(_plots([p for p in folder.images if run.folder in p.parents], root,
                               f"Plots of the {title.lower()}"))
    sections += [_mbs_section(p, root) for p in folder.multibody]
    if not is_job:
        sections.append(_plots(other_images, root, "Plots"))
    sections += [_search_section(s, root, with_scene=not folder.own_runs) for s in folder.searches]
    shown = {r.summary["verdict"] for s in folder.searches for r in s.runs if r.summary}
    if shown:  # a run's own section says what its verdict means for it
        sections.append("<h2>What the verdicts of the search mean</h2>" + _table(
            [(k, html.escape(v)) for k, v in VERDICT_MEANINGS.items() if k in shown]))
    sections.append(f"<h2>Versions</h2>{_table([(k, html.escape(v)) for k, v in versions().items()])}")
    return [s for s in sections if s]


def write_report(results_dir: str | Path, out_path: str | Path | None = None) -> Path:
    """Write ``report.html`` (or ``out_path``) for the run or job in ``results_dir``."""
    root = Path(results_dir)
    if not root.is_dir():
        raise InputError(f"{root} is not a folder of results (give the --out folder of a run or a job)")
    page = (f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>{REPORT_TITLE}"
            f"{html.escape(root.resolve().name)}</title><style>{STYLE}</style></head><body>"
            f"<h1>fretwork report: {html.escape(str(root))}</h1>" + "\n".join(_sections(read_folder(root)))
            + "</body></html>")
    target = Path(out_path) if out_path is not None else root / "report.html"
    try:
        target.write_text(page, encoding="utf-8")
    except OSError as error:
        raise InputError(f"cannot write the report {target}: {error.strerror}") from None
    return target
