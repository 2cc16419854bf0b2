"""Benchmark: parallel efficiency of independent cases on the embedded LocalCluster (`make bench`).

Two 16-case studies, each run in this process without dask (workers=0) and on a LocalCluster
with one worker and with two (this machine has two cores): a 16-amplitude contact study (the
cylinder on plane, tangential amplitude 0.02-0.14 mm, contact mesh 0.025 mm, 20 wear cycles,
about 5 s a case) and a 16-speed multibody sweep (4 CB modes, 1.5 revolutions). Speed-up is
the wall time on one worker over the wall time on two; efficiency is the speed-up over 2. One
and two workers alternate, best of FRETWORK_BENCH_TRIALS (2) runs each. The results of every
run must equal the in-process ones (contact figures to 1e-9: the contact solver's last digits
differ between two runs of a case even in one process). A third comparison times the sweep
with the counterweight reduced once on the client and sent to the workers (what speed_sweep
does) against reducing it in every case. Prints a table with the load average, which on a
shared machine says how much of the two cores the study really had.
"""

import os
import pickle
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from mbs.counterweight import reduce_counterweight
from mbs.parameters import ModelParams, SolverParams
from mbs.sweep import run_speed
from pipelines.jobs.sweep import speed_sweep
from pipelines.parallel import cluster, map_cases

ROOT = Path(__file__).resolve().parents[2]
CYLINDER = ROOT / "examples" / "cylinder_on_plane.toml"
AMPLITUDES_MM = np.linspace(0.02, 0.14, 16)
SPEEDS_RPM = np.linspace(600.0, 750.0, 16)
TRIALS = int(os.environ.get("FRETWORK_BENCH_TRIALS", "2"))
SWEEP_PARAMS = ModelParams(n_modes=4, effects=frozenset({"gear_mesh"}),
                           solver=SolverParams(revolutions=1.5, time_step=5e-5))


def contact_case(amplitude_mm: float) -> dict:
    """The cylinder on plane at one tangential amplitude (mm): wear depth (mm), slip area, verdict,
    and the case's own wall time (s)."""
    from contact import procedure
    from contact.solver import ContactSolver
    from contact.structure import ContactSpace
    from pipelines import scene as scenes
    from pipelines.build import build

    clock = time.perf_counter()
    scene = scenes.load(CYLINDER, {
        "motions": [{"name": "tangential", "dof": "cylinder.rp.ux", "value": float(amplitude_mm),
                     "history": "cyclic"}],
        "bodies.cylinder.mesh.contact_size": 0.025, "bodies.plane.mesh.contact_size": 0.025,
        "procedure.wear_cycles": 20})
    model = build(scene)
    solver = ContactSolver(ContactSpace(model.assembly.structure), model.law, model.settings)
    result = procedure.run(solver, model.initial_state(), model.program, model.procedure,
                           cof_evolution=False, wear=True)
    return {"max_wear_depth_mm": result.figures["max_wear_depth_mm"],
            "slip_area_fraction": result.figures["slip_area_fraction"], "verdict": result.verdict,
            "wall_s": time.perf_counter() - clock}


def speed_case_reducing(params: ModelParams) -> object:
    """A sweep case that reduces the counterweight itself instead of receiving it."""
    return run_speed(params, reduce_counterweight(params.counterweight, params.n_modes), None)


def _start_and_close_a_two_worker_cluster():
    with cluster(workers=2):
        pass


def _timed(function):
    clock = time.perf_counter()
    value = function()
    return value, time.perf_counter() - clock


def _sweep_arrays(result):
    return [result.wing_amplitude, result.dominant_frequencies, result.system_frequencies]


def _check_contact(outcomes, reference):
    assert all(o.ok for o in outcomes), [o.error for o in outcomes if not o.ok]
    for ours, theirs in zip(outcomes, reference):  # the contact solver differs in the last digits run to run
        assert ours.value["verdict"] == theirs["verdict"]
        for name in ("max_wear_depth_mm", "slip_area_fraction"):
            assert ours.value[name] == pytest.approx(theirs[name], rel=1e-9), (ours.key, name)


def _check_sweep(result, serial):
    assert not result.failures
    for ours, theirs in zip(_sweep_arrays(result), serial):
        np.testing.assert_array_equal(ours, theirs)


@pytest.mark.bench
def test_parallel_efficiency_of_sixteen_independent_cases():
    load_before = os.getloadavg()[0]
    cases = [(float(a), {"amplitude_mm": float(a)}) for a in AMPLITUDES_MM]
    serial, serial_s = _timed(lambda: map_cases(contact_case, cases, workers=0, progress=False))
    reference = [o.value for o in serial]
    sweep_serial, sweep_serial_s = _timed(lambda: speed_sweep(SWEEP_PARAMS, SPEEDS_RPM, workers=0))
    contact, sweep, busy = {0: serial_s}, {0: sweep_serial_s}, {}
    # 1 and 2 workers alternate and the faster of TRIALS runs counts: the neighbours' load on a
    # shared machine changes within minutes, and it only ever slows a run down.
    for _ in range(TRIALS):
        for workers in (1, 2):
            outcomes, wall = _timed(lambda: map_cases(contact_case, cases, workers=workers, progress=False))
            _check_contact(outcomes, reference)
            if wall < contact.get(workers, np.inf):
                contact[workers] = wall
                busy[workers] = sum(o.value["wall_s"] for o in outcomes) / (workers * wall)
            result, wall = _timed(lambda: speed_sweep(SWEEP_PARAMS, SPEEDS_RPM, workers=workers))
            _check_sweep(result, _sweep_arrays(sweep_serial))
            sweep[workers] = min(wall, sweep.get(workers, np.inf))

    speed_cases = [(s, {"params": replace(SWEEP_PARAMS, speed_rpm=float(s))}) for s in SPEEDS_RPM]
    _, per_case = _timed(lambda: map_cases(speed_case_reducing, speed_cases, workers=2, progress=False))
    _, startup_s = _timed(_start_and_close_a_two_worker_cluster)
    reduced, reduction_s = _timed(lambda: reduce_counterweight(SWEEP_PARAMS.counterweight, SWEEP_PARAMS.n_modes))
    size_mb = len(pickle.dumps(reduced)) / 1e6
    load_after = os.getloadavg()[0]

    lines = [f"{'study':<24} {'in-process s':>12} {'1 worker s':>10} {'2 workers s':>11} {'speed-up':>8} "
             f"{'efficiency':>10}"]
    for name, t in (("contact, 16 amplitudes", contact), ("mbs sweep, 16 speeds", sweep)):
        lines.append(f"{name:<24} {t[0]:>12.1f} {t[1]:>10.1f} {t[2]:>11.1f} {t[1] / t[2]:>8.2f} "
                     f"{t[1] / t[2] / 2:>10.0%}")
    lines.append(f"contact: workers busy with cases {busy[1]:.0%} of the time on 1 worker, {busy[2]:.0%} on 2 "
                 f"(a case: {contact[0] / len(cases):.1f} s in-process)")
    lines.append(f"mbs sweep on 2 workers: CW reduced once and sent {sweep[2]:.1f} s, reduced in every case "
                 f"{per_case:.1f} s (one reduction {reduction_s:.2f} s, {size_mb:.0f} MB pickled)")
    lines.append(f"starting and closing the two-worker LocalCluster: {startup_s:.1f} s (paid once per study)")
    lines.append(f"best of {TRIALS} alternating runs; load average (1 min) before {load_before:.2f}, after "
                 f"{load_after:.2f}; {os.cpu_count()} cores")
    print("\n" + "\n".join(lines))
