"""What the cylinder's re-pairing threshold costs and changes (docs/performance.md).

``python tests/bench/repair_fraction.py [FRACTIONS]`` runs ``examples/cylinder_on_plane.toml``
once per fraction (default 0.05,0.1,0.2,0.35,0.5,1.0; the first is the reference) with
:class:`contact.sliding.SlidingSolver` re-pairing once a pressed point has slid that fraction
of a master element, and prints one JSON line per run: re-pairings, CPU ms per increment and
the largest differences of the final wear and pressure fields from the reference's, relative
to the reference's largest value. Only ``repair_fraction`` changes between runs.
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import contact.sliding as sliding  # noqa: E402
from pipelines import scene as scenes  # noqa: E402
from pipelines.build import build  # noqa: E402
from pipelines.jobs.run import run_model  # noqa: E402
from reduction.threads import pin_process  # noqa: E402


def run(fraction: float) -> dict:
    """One run at ``fraction``: its cost and final fields."""
    # the run builds its SlidingSolver with the default threshold: change the default
    sliding.SlidingSolver.__init__.__kwdefaults__["repair_fraction"] = fraction
    model = build(scenes.load(ROOT / "examples" / "cylinder_on_plane.toml"))
    with tempfile.TemporaryDirectory() as out:
        start = time.process_time()
        outcome = run_model(model, Path(out), progress=False, plots=False)
        cpu = time.process_time() - start
        with h5py.File(outcome.results_path, "r") as results:
            increments = results["increments/cycle"].shape[0]
            wear = results["final/wear_depth"][()].sum(axis=0)
            pressure = results["final/pressure"][()]
    return {"fraction": fraction, "repairings": outcome.summary["repairings"],
            "cpu_ms_per_increment": 1e3 * cpu / increments, "max_wear_um": 1e3 * float(wear.max()),
            "wear": wear, "pressure": pressure}


def main(argv: list[str]) -> int:
    pin_process()
    fractions = [float(f) for f in (argv[0] if argv else "0.05,0.1,0.2,0.35,0.5,1.0").split(",")]
    reference = None
    for fraction in fractions:
        row = run(fraction)
        fields = {name: row.pop(name) for name in ("wear", "pressure")}
        reference = reference or fields
        for name, field in fields.items():
            row[f"{name}_difference"] = float(np.abs(field - reference[name]).max() / np.abs(reference[name]).max())
        print(json.dumps(row), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
