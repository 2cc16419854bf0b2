"""Accuracy versus time on the shipped scenes (`make bench`): Pareto plots and recommended settings.

Writes results/bench/accuracy/accuracy_<scene>.{png,json}. The cylinder runs the default study
(wear ≤ 20, COF ≤ 40 simulated cycles); the double beam is slow, so it runs the quick study
on coarse pads (contact size 3, 4, 6 mm) with 10 COF and 4 wear cycles.
"""

import json
from pathlib import Path

import pytest

from pipelines.cli import main

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "results" / "bench" / "accuracy"
CASES = {
    "cylinder_on_plane": [],
    "double_beam_low_slip": ["--quick", "--knob", "contact_size=3,4,6"],
}


@pytest.mark.bench
@pytest.mark.parametrize("scene", sorted(CASES))
def test_accuracy_study_on_shipped_scene(scene, capsys):
    code = main(["study", "accuracy", str(ROOT / "examples" / f"{scene}.toml"), "--json", "--out", str(OUT),
                 *CASES[scene]])
    assert code == 0
    study = json.loads(capsys.readouterr().out)
    reference, *others = study["records"]
    assert reference["worst_error"] == 0.0
    assert others and all(r["failure"] or r["wall_time_s"] > 0 for r in others)
    assert (OUT / f"accuracy_{scene}.png").stat().st_size > 10_000
    recommendation = study["recommendation"]
    with capsys.disabled():
        print(f"\n{scene}: reference {reference['wall_time_s']:.1f} s; recommended "
              + (f"{recommendation['label']} ({recommendation['wall_time_s']:.1f} s, worst error "
                 f"{100 * recommendation['worst_error']:.2f} %)" if recommendation else "none within 2 %"))
