"""``fretwork report``: one self-contained HTML page, opened in a headless browser."""

import base64
import re
import shutil
import subprocess

import pytest

from pipelines import scene as scenes
from pipelines.cli.main import main
from pipelines.jobs.run import run_scene
from pipelines.output.report import write_report

BROWSERS = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    from pathlib import Path

    folder = tmp_path_factory.mktemp("report")
    text = (Path(__file__).resolve().parents[2] / "examples" / "cylinder_on_plane.toml").read_text()
    scene = folder / "coarse.toml"
    scene.write_text(text.replace("contact_size = 0.05", "contact_size = 0.2")
                     .replace("wear_cycles = 20 ", "wear_cycles = 2 ")
                     .replace("increments_per_cycle = 40", "increments_per_cycle = 12"))
    outcome = run_scene(scenes.load(scene), folder / "run", progress=False)
    return write_report(folder / "run"), outcome


def test_report_is_self_contained_with_every_plot(report):
    path, outcome = report
    page = path.read_text()
    images = re.findall(r"<img alt='([^']+)' src='data:image/png;base64,([^']+)'>", page)
    assert sorted(name for name, _ in images) == sorted(f"plots/{p.name}" for p in outcome.plots)
    for _, data in images:
        assert base64.b64decode(data)[:8] == b"\x89PNG\r\n\x1a\n"
    assert "src='http" not in page and "href='http" not in page  # nothing fetched from elsewhere
    assert f"verdict: {outcome.summary['verdict'].upper()}" in page
    assert "[scene]" in page  # the scene file itself
    assert "numpy" in page  # the versions


def test_report_command_refuses_a_folder_without_results(tmp_path, capsys):
    assert main(["report", str(tmp_path)]) == 2
    assert "no fretwork results" in capsys.readouterr().err


def test_report_opens_in_a_headless_browser(report, tmp_path):
    browser = next((b for b in BROWSERS if shutil.which(b)), None)
    if browser is None:
        pytest.skip("no Chromium found (apt-get install chromium): the page is not opened in a browser")
    path, outcome = report
    # a copy with a probe: after loading, count the images the browser decoded
    probe = tmp_path / "probe.html"
    probe.write_text(path.read_text().replace(
        "</body>", "<script>window.addEventListener('load',()=>{document.body.setAttribute('data-decoded',"
                   "[...document.images].filter(i=>i.complete&&i.naturalWidth>100).length)})</script></body>"))
    result = subprocess.run([shutil.which(browser), "--headless", "--no-sandbox", "--disable-gpu",
                             "--virtual-time-budget=5000", "--dump-dom", probe.as_uri()],
                            capture_output=True, text=True, timeout=120, check=False)
    decoded = re.search(r'data-decoded="(\d+)"', result.stdout)
    assert decoded, f"the page did not load: {result.stderr[-500:]}"
    assert int(decoded.group(1)) == len(outcome.plots) > 0


def test_report_of_a_run_that_stopped_says_how(coarse_cylinder, tmp_path, capsys):
    """A run that slid off (a tangential force beyond what friction carries) ends with a results
    file marked 'slid_off', without a summary: the page says the run stopped, and how."""
    import html

    scene = tmp_path / "slide.toml"
    scene.write_text(coarse_cylinder.read_text().replace(
        '[[motions]]\nname = "tangential"\ndof = "cylinder.rp.ux"\nvalue = 0.107',
        '[[loads]]\nname = "tangential"\ndof = "cylinder.rp.ux"\nvalue = 1000.0'))
    assert main(["run", str(scene), "--out", str(tmp_path / "out"), "--quiet"]) == 1
    assert "marked 'slid_off'" in capsys.readouterr().err
    page = html.unescape(write_report(tmp_path / "out").read_text())
    assert ("the run stopped: the joint slides off (ending 'slid_off') after 0 complete cycles: the file holds "
            "the cycles run so far, without final fields or a verdict") in page
    assert "incomplete" not in page and "[scene]" in page


def test_report_names_its_positional_argument(tmp_path, capsys):
    afile = tmp_path / "afile"
    afile.write_text("not a folder")
    assert main(["report", str(afile)]) == 2
    assert capsys.readouterr().err == (f"fretwork: error: {afile} is not a folder of results (give the --out "
                                       "folder of a run or a job)\n")


def test_a_jobs_report_leads_with_its_summary_and_its_own_run(report, tmp_path):
    """The demo's page began with nine limit runs, the first verdict on it a 900 rpm scan run's
    (QA): the job's summary comes first, then its shallowest run, then the search's runs."""
    import json

    _, outcome = report
    job = tmp_path / "demo"
    for folder in ("limit/amplitude_0100.00um", "limit/amplitude_0400.00um", "operating"):
        (job / folder).mkdir(parents=True)
        shutil.copy(outcome.results_path, job / folder / "results.h5")
    (job / "summary.json").write_text(json.dumps({"summary": {"verdict": "stick", "margin_at_operating_point": 2.0}}))
    page = write_report(job).read_text()
    order = [page.index(name) for name in ("<h2>Job verdict", "operating/results.h5",
                                           "limit/amplitude_0100.00um", "limit/amplitude_0400.00um")]
    assert order == sorted(order)


def test_a_run_that_stopped_before_its_first_cycle_is_said_so(tmp_path, capsys):
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "results.h5.part").write_bytes(b"")
    assert main(["report", str(tmp_path / "out")]) == 2
    assert "holds only results.h5.part: its run stopped before it finished a cycle" in capsys.readouterr().err
