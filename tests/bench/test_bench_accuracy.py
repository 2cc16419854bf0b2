"""Accuracy versus time on the shipped scenes (`make bench`): Pareto plots and recommended settings.

Writes results/bench/accuracy/accuracy_<scene>.{png,json}, the settings of the figures in
examples/figures/. Both run the default study (wear ≤ 20, COF ≤ 40 simulated cycles). The
cylinder's mesh and increments are also swept one level finer than the scene's; the beam mesh
generator needs half the beam width (15 mm) to be a multiple of the pad element size, so the
double beam sweeps 1.5, 2.5 and 3 mm. The counterweight is the multibody model's default throw
at 750 rpm (no scene file is shipped for it), Craig–Bampton modes and time step one level finer
and coarser than the study's default.
"""

import json
from pathlib import Path

import pytest

from pipelines.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "results" / "bench" / "accuracy"
CASES = {
    "cylinder_on_plane": ["--knob", "contact_size=0.025,0.05,0.1,0.2", "--knob", "increments_per_cycle=80,40,20,10"],
    "double_beam_low_slip": ["--knob", "contact_size=1.5,2.5,3"],
    "counterweight": ["--knob", "craig_bampton_modes=24,12,6,3", "--knob", "mbs_time_step=1.25e-5,2.5e-5,5e-5,1e-4"],
}
COUNTERWEIGHT_SCENE = '[scene]\nname = "counterweight"\n\n[mbs]\nspeed_rpm = 750.0\n'



@pytest.mark.bench
@pytest.mark.parametrize("scene", sorted(CASES))
def test_accuracy_study_on_shipped_scene(scene, capsys, tmp_path):
    path = ROOT / "examples" / f"{scene}.toml"
    if scene == "counterweight":
        path = tmp_path / "counterweight.toml"
        path.write_text(COUNTERWEIGHT_SCENE)
    code = main(["study", "accuracy", str(path), "--json", "--out", str(OUT), *CASES[scene]])
    assert code == 0
    study = json.loads(capsys.readouterr().out)
    reference, *others = study["records"]
    assert reference["worst_error"] == 0.0
    assert others and all(r["failure"] or r["wall_time_s"] > 0 for r in others)
    assert (OUT / f"accuracy_{scene}.png").stat().st_size > 10_000
    recommendation = study["recommendation"]
    with capsys.disabled():
        print(f"\n{scene}: reference CPU {reference['cpu_time_s']:.1f} s; recommended "
              + (f"{recommendation['label']} (CPU {recommendation['cpu_time_s']:.1f} s, worst error "
                 f"{100 * recommendation['worst_error']:.2f} %)" if recommendation else "none within 2 %"))
