"""``fretwork report``: one self-contained HTML page of a run's or a job's folder.

The page gathers what the folder holds: the verdict and the key figures of every results
file (``results.h5``), the summaries and margins of a job (``summary.json``, ``limit.json``,
margins in ``sweep.h5``), every plot (PNG files, inlined as base64 so the page is one file to
mail or archive), the scene each run was made from, and the versions of fretwork and its main
dependencies. Nothing is recomputed. Units are those of the files: mm, N, MPa, mJ.
"""

from __future__ import annotations

import base64
import html
import json
from importlib import metadata
from pathlib import Path

import h5py
import numpy as np

from contact.verdict import VERDICT_MEANINGS
from pipelines.output.locks import REPORT_TITLE
from reduction.errors import InputError

PACKAGES = ("fretwork", "numpy", "scipy", "scikit-fem", "exudyn", "h5py", "matplotlib", "meshio", "fmpy")
KEY_FIGURES = (
    ("verdict", "verdict", None), ("stationary", "stationary", None),
    ("cycles_run", "simulated cycles", None), ("equivalent_cycles", "real cycles", None),
    ("stick_area_fraction", "stick area", "%"), ("slip_area_fraction", "at the friction limit", "%"),
    ("damaged_area_fraction", "at μ_max (damaged) area", "%"), ("active_slip_area_fraction", "still sliding (verdict)", "%"),
    ("cof_evolved_area_fraction", "COF evolved area", "%"), ("min_stick_margin", "smallest stick margin of stuck points, 1 − max |τ|/p / μ_max", None),
    ("max_wear_depth_mm", "max wear depth [mm]", None), ("wear_volume_mm3", "wear volume [mm³]", None),
    ("dissipated_energy_mJ", "dissipated energy, simulated cycles [mJ]", None),
    ("bolt_force_initial_N", "clamp force initial [N]", None), ("bolt_force_final_N", "clamp force final [N]", None),
    ("clamp_force_loss_fraction", "clamp force loss", "%"),
    ("fdp_max_MPa_mm", "FDP max τ·δ [MPa·mm]", None), ("fdp_max_location_mm", "FDP max at [mm]", None),
    ("ffdp_max_MPa2_mm", "FFDP max σ_t·τ·δ [MPa²·mm]", None), ("ffdp_max_location_mm", "FFDP max at [mm]", None),
    ("wing_amplitude_mm", "wing amplitude [mm]", None), ("engine_speed_rpm", "engine speed [rpm]", None),
)
STYLE = """body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}
table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ccc;padding:.2em .6em;text-align:left}
.verdict{font-size:1.4em;font-weight:bold}.unsafe{color:#b00;font-weight:bold}
img{max-width:100%;border:1px solid #ddd;margin:.5em 0}pre{background:#f6f6f6;padding:.8em;overflow:auto}
figure{margin:1em 0}figcaption{font-size:.9em;color:#555}"""


def _value(value, unit) -> str:
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return "–"
    if unit == "%":
        return f"{100 * value:.1f} %"
    if isinstance(value, (list, tuple)):
        return "(" + ", ".join(f"{v:.4g}" for v in value) + ")"
    if isinstance(value, float):
        return f"{value:.4g}"
    return html.escape(str(value))


def _table(rows) -> str:
    return "<table>" + "".join(f"<tr><th>{html.escape(k)}</th><td>{v}</td></tr>" for k, v in rows) + "</table>"


def _run_section(path: Path, root: Path) -> str:
    with h5py.File(path, "r") as file:
        attrs = file.attrs
        if attrs.get("fretwork_format") != "fretwork-results":
            return ""
        name, scene = str(attrs.get("scene_name", "")), str(attrs.get("scene_toml", ""))
        if "summary" not in file:
            message = str(file.attrs.get("ending_message", ""))  # why the increment that ended it failed
            return (f"<h2>Run {html.escape(name)} ({html.escape(str(path.relative_to(root)))})</h2>"
                    f"<p class='unsafe'>{html.escape(_no_summary(file))}</p>"
                    + (f"<p>why: {html.escape(message)}</p>" if message else "")
                    + (f"<details><summary>scene</summary><pre>{html.escape(scene)}</pre></details>" if scene else ""))
        summary = {"verdict": file["summary"].attrs["verdict"], "stationary": bool(file["summary"].attrs["stationary"]),
                   **json.loads(file["summary"].attrs["figures"])}
    verdict = str(summary["verdict"])
    rows = [(label, _value(summary[key], unit)) for key, label, unit in KEY_FIGURES if key in summary]
    parts = [f"<h2>Run {html.escape(name)} ({html.escape(str(path.relative_to(root)))})</h2>",
             f"<p class='verdict'>verdict: {html.escape(verdict.upper())}</p>",
             f"<p>{html.escape(VERDICT_MEANINGS.get(verdict, ''))}</p>", _table(rows)]
    if scene:
        parts.append(f"<details><summary>scene</summary><pre>{html.escape(scene)}</pre></details>")
    return "\n".join(parts)


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


def _job_section(path: Path, root: Path) -> str:
    data = json.loads(path.read_text())
    summary = data.get("summary", data)
    if not isinstance(summary, dict):
        return ""
    rows = []
    for key, value in summary.items():
        if isinstance(value, dict) or (isinstance(value, list) and any(isinstance(v, (dict, list)) for v in value)):
            continue  # tables of their own (a limit search's runs and changes)
        text = _value(value, None)
        if key in ("smallest_margin", "margin_at_operating_point") and isinstance(value, (int, float)) and value < 1:
            text = f"<span class='unsafe'>{text} (below 1: NOT SAFE)</span>"
        rows.append((key, text))
    return f"<h2>{html.escape(str(path.relative_to(root)))}</h2>" + _table(rows)


def _margins_section(path: Path, root: Path) -> str:
    with h5py.File(path, "r") as file:
        group = next((file[name] for name in ("margins",) if name in file), None)
        if group is None or "speed_rpm" not in group or "margin" not in group:
            return ""
        speeds, margins = group["speed_rpm"][()], group["margin"][()]
    rows = "".join(f"<tr><td>{s:.0f}</td><td{' class=unsafe' if m < 1 else ''}>{m:.2f}"
                   f"{' NOT SAFE' if m < 1 else ''}</td></tr>" for s, m in zip(speeds, margins))
    return (f"<h2>Safety margins ({html.escape(str(path.relative_to(root)))})</h2>"
            "<p>margin = amplitude limit / wing amplitude at that speed; below 1 the vibration exceeds the "
            "stick limit.</p><table><tr><th>speed [rpm]</th><th>margin</th></tr>" + rows + "</table>")


def _image(path: Path, root: Path) -> str:
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    caption = html.escape(str(path.relative_to(root)))
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


def write_report(results_dir: str | Path, out_path: str | Path | None = None) -> Path:
    """Write ``report.html`` (or ``out_path``) for the run or job in ``results_dir``."""
    root = Path(results_dir)
    if not root.is_dir():
        raise InputError(f"{root} is not a folder of results (give the --out folder of a run or a job)")
    def shallow_first(paths):  # a job's own summary and run before the runs of its search
        return sorted(paths, key=lambda path: (len(path.relative_to(root).parts), path))

    results = shallow_first(root.rglob("results.h5"))
    jobs = shallow_first(p for p in root.rglob("*.json") if p.name in ("summary.json", "limit.json", "margins.json"))
    sweeps = shallow_first(root.rglob("sweep.h5"))
    images = sorted(root.rglob("*.png"))
    if not (results or jobs or images):
        unfinished = sorted(root.rglob("results.h5.part"))
        if unfinished:
            raise InputError(f"{root} holds only {unfinished[0].relative_to(root)}: its run stopped before it "
                             "finished a cycle (the error it printed says why); nothing converged to report")
        raise InputError(f"{root} holds no fretwork results (results.h5, summary.json or plots)")
    sections = [_job_section(p, root) for p in jobs] + [_run_section(p, root) for p in results]
    sections += [_margins_section(p, root) for p in sweeps]
    plots = "".join(_image(p, root) for p in images)
    version_rows = [(k, html.escape(v)) for k, v in versions().items()]
    labels = _table([(k, html.escape(v)) for k, v in VERDICT_MEANINGS.items()])
    page = (f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>{REPORT_TITLE}"
            f"{html.escape(root.resolve().name)}</title><style>{STYLE}</style></head><body>"
            f"<h1>fretwork report: {html.escape(str(root))}</h1>"
            + "\n".join(s for s in sections if s)
            + f"<h2>Plots</h2>{plots or '<p>no plots</p>'}"
            + f"<h2>What the verdicts mean</h2>{labels}"
            + f"<h2>Versions</h2>{_table(version_rows)}</body></html>")
    target = Path(out_path) if out_path is not None else root / "report.html"
    try:
        target.write_text(page, encoding="utf-8")
    except OSError as error:
        raise InputError(f"cannot write the report {target}: {error.strerror}") from None
    return target
