"""One run of a shipped scene, end to end, for the benchmarks (one run per process, so that
its peak memory is its own).

``python tests/bench/scene_run.py SCENE [--size H] [--cycles N] [--linear auto|dense]
[--solver auto|dense|sparse] [--set KEY=VALUE ...] [--fields OUT.npz] [--plots]`` runs ``examples/SCENE.toml`` (with
``contact_size = H`` mm on every body that has one; the shipped procedure unless ``--cycles``
keeps only that many COF cycles; ``--solver`` sets ``[contact] solver``, the contact path) and
prints one JSON line: verdict, points, set-up and procedure times, increments,
CPU time per increment of the procedure (energy bookkeeping and results writing included),
peak resident memory (MB) and the load average.

Profiling (issue 14): the per-increment overhead of the counterweight was found with

    .venv/bin/python -m cProfile -s tottime tests/bench/scene_run.py \\
        counterweight_extreme --size 10 --cycles 40 | head -60

and the same with ``--size 5``; the profile itself is not kept.
"""

from __future__ import annotations

import argparse
from dataclasses import replace
import json
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from contact.linear import KrylovSettings  # noqa: E402
from pipelines import scene as scenes  # noqa: E402
from pipelines.cli.accuracy import set_overrides  # noqa: E402
from pipelines.build import build  # noqa: E402
from pipelines.coupling import multibody_loading  # noqa: E402
from pipelines.jobs.run import run_model  # noqa: E402
from pipelines.studies.knobs import run_up_within  # noqa: E402
from reduction.threads import pin_process  # noqa: E402

#: the linear solvers a run can be asked for: the shipped choice, and the exact dense LU of
#: the bordered closed system in every Newton iteration (the reference for equal results)
LINEAR = {"auto": KrylovSettings(), "dense": KrylovSettings(direct_below=np.inf)}


def overrides(path: Path, size: float | None, cycles: int | None, solver: str = "auto") -> dict:
    """Scene overrides: the contact mesh size of every body that has one, the cycles and the
    contact path."""
    out = {} if solver == "auto" else {"contact.solver": solver}
    if size is None and cycles is None:
        return out
    scene = scenes.load(path)
    if size is not None:
        out.update({f"bodies.{name}.mesh.contact_size": size for name, body in scene.data["bodies"].items()
                    if "contact_size" in body.get("mesh", {})})
    if cycles is not None:
        out.update({"procedure.cof_cycles": cycles, "procedure.wear_cycles": 0})
        out.update(run_up_within(scene, cycles))
    return out


FIELDS = ("pressure", "shear", "cof")


def short_extreme_arguments(parser: argparse.ArgumentParser, size: float) -> None:
    """The options of the probes that run a short counterweight extreme: --size, --cof, --wear."""
    parser.add_argument("--size", type=float, default=size, help="contact mesh size, mm")
    parser.add_argument("--cof", type=int, default=20, help="COF cycles")
    parser.add_argument("--wear", type=int, default=10, help="wear blocks")


def short_extreme(args: argparse.Namespace):
    """The model of ``examples/counterweight_extreme.toml`` at ``args.size`` mm with ``args.cof`` COF
    cycles (the vibration's run-up within them) and ``args.wear`` wear blocks, no checkpoints,
    in a process pinned to one BLAS thread."""
    pin_process()
    path = ROOT / "examples" / "counterweight_extreme.toml"
    changes = overrides(path, args.size, None)
    changes.update({"procedure.cof_cycles": args.cof, "procedure.wear_cycles": args.wear,
                    "procedure.checkpoint_every": 0})
    changes.update(run_up_within(scenes.load(path), args.cof))
    return build(scenes.load(path, changes))


def saved_fields(results: h5py.File) -> dict:
    """What ``--fields`` keeps of a results file: the final pressure, shear and COF; the same
    fields at the end of the first phase (``first_phase_*``, when a field snapshot was written
    there and another phase followed); and the clamp force of every cycle (``clamp_force_N``,
    N) with the real cycles it stands at (``equivalent_cycles``). A long loosening run is
    compared on the first-phase fields and judged on the clamp force: explicit wear over
    thousands of blocks amplifies where two Newton iterations stop inside their tolerance, so
    its final fields differ at the edge points whatever the linear solver."""
    out = {name: results["final"][name][()] for name in FIELDS}
    cycles = results["cycles"]
    out["clamp_force_N"] = cycles["figures"]["clamp_force_N"][()]
    out["equivalent_cycles"] = cycles["equivalent_cycles"][()]
    phase, cycle = cycles["phase"][()], cycles["cycle"][()]
    first = cycle[phase == phase[0]]
    snapshots = cycles["fields"]["cycle"][()] if "fields" in cycles else np.zeros(0, int)
    if first.size < cycle.size and np.any(snapshots == first[-1]):
        at = int(np.flatnonzero(snapshots == first[-1])[0])
        out.update({f"first_phase_{name}": cycles["fields"][name][at] for name in FIELDS})
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", help="name of a scene in examples/")
    parser.add_argument("--size", type=float, default=None, help="contact mesh size, mm")
    parser.add_argument("--plots", action="store_true")
    parser.add_argument("--cycles", type=int, default=None, help="COF cycles only, no wear phase")
    parser.add_argument("--linear", choices=LINEAR, default="auto",
                        help="auto: the shipped choice; dense: exact LU of the dense system every iteration")
    parser.add_argument("--solver", choices=("auto", "dense", "sparse"), default="auto",
                        help="the contact path ([contact] solver): auto is the shipped choice")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="a further scene override, e.g. procedure.stop_at_loosening=true (repeat)")
    parser.add_argument("--fields", type=Path, default=None,
                        help="write the final fields (and more: saved_fields) here (.npz)")
    args = parser.parse_args(argv)
    pin_process()  # as the command line does
    path = ROOT / "examples" / f"{args.scene}.toml"
    scene = scenes.load(path, {**overrides(path, args.size, args.cycles, args.solver), **set_overrides(args.set)})
    start_cpu, start = time.process_time(), time.perf_counter()
    multibody = multibody_loading(scene, None) if "coupling" in scene.data else None
    model = build(scene, multibody=multibody)
    model = replace(model, settings=replace(model.settings, linear=LINEAR[args.linear]))
    setup_cpu, setup = time.process_time() - start_cpu, time.perf_counter() - start
    setup_rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    with tempfile.TemporaryDirectory() as out:
        outcome = run_model(model, Path(out), progress=False, plots=args.plots)
        if args.fields is not None:
            with h5py.File(outcome.results_path, "r") as results:
                np.savez(args.fields, **saved_fields(results))
    wall, cpu = time.perf_counter() - start, time.process_time() - start_cpu
    summary = outcome.summary
    proc = model.procedure
    run_up = 2 if "coupling" in scene.data else 1  # a coupled scene ramps its mean loads in too
    increments = run_up * proc.preload_increments + summary["cycles_run"] * proc.increments_per_cycle
    print(json.dumps({
        "scene": args.scene, "size": args.size, "linear": args.linear, "path": model.contact_path,
        "verdict": summary["verdict"],
        "points": model.assembly.structure.n_points, "retained_dofs": model.assembly.structure.n_dofs,
        "increments": increments, "cycles_run": summary["cycles_run"],
        "wall_s": wall, "cpu_s": cpu, "setup_s": setup, "setup_cpu_s": setup_cpu,
        "procedure_cpu_per_increment_s": (cpu - setup_cpu) / increments,
        "stage_times": outcome.stage_times, "setup_peak_rss_mb": setup_rss,
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "load_average": os.getloadavg()}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
