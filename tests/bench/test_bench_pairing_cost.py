"""Cost of mortar pairing and finite sliding per increment, against node-to-segment with fixed
pairing, measured in the same run (``make bench``; prints the figures).

* 3D: a 20×20 face on a 27×27 face (non-matching), pressed and then sheared through a
  partial-slip cycle; mortar against node-to-segment pairing of the same meshes.
* 2D: examples/gross_slip_fretting.toml, two gross-slip cycles with wear; finite sliding
  (mortar re-pairing) against small sliding (node-to-segment, fixed pairing).
"""

import time
from contextlib import nullcontext

import numpy as np
import pytest

from contact import procedure
from contact.sliding import SlidingSolver
from contact.solver import ContactSolver, Effects
from contact.structure import ContactSpace
from pipelines import scene as scenes
from pipelines.build import build
from pipelines.jobs.validate import SCENE

try:
    from threadpoolctl import threadpool_limits
except ImportError:
    threadpool_limits = None

pytestmark = pytest.mark.bench


def _blocks(pairing, n_upper=20, n_lower=27):
    overrides = {
        "scene.dimension": 3, "scene.effects": [], "materials.ti64.poisson_ratio": 0.0,
        "bodies.cylinder.mesh": {"generator": "flat_block", "size_x": 10.0, "size_y": 10.0, "height": 4.0,
                                 "n_x": n_upper, "n_y": n_upper, "n_z": 3, "z0": 0.0},
        "bodies.plane.mesh": {"generator": "flat_block", "size_x": 10.0, "size_y": 10.0, "height": 4.0,
                              "n_x": n_lower, "n_y": n_lower, "n_z": 3, "z0": -4.0},
        "bodies.cylinder.reference_points.rp": {"nodes": {"axis": "z", "value": 4.0}, "position": [0.0, 0.0, 4.0]},
        "bodies.plane.fixed": {"nodes": {"axis": "z", "value": -4.0}, "components": ["ux", "uy", "uz"]},
        "contact.slave": {"body": "cylinder", "axis": "z", "value": 0.0},
        "contact.master": {"body": "plane", "axis": "z", "value": 0.0},
        "contact.pairing": pairing,
        "loads": [{"name": "press", "dof": "cylinder.rp.uz", "value": -1000.0, "history": "ramp"}],
        "motions": [{"name": "shear", "dof": "cylinder.rp.ux", "value": 2e-3, "history": "cyclic"},
                    {"name": "hold_y", "dof": "cylinder.rp.uy", "value": 0.0, "history": "constant"}],
    }
    return scenes.load(SCENE, overrides)


def _time_blocks(pairing):
    clock = time.perf_counter()
    model = build(_blocks(pairing))
    built = time.perf_counter() - clock
    clock = time.perf_counter()
    solver = ContactSolver(ContactSpace(model.assembly.structure), model.law, model.settings)
    space_time = time.perf_counter() - clock
    equilibrium, state = solver.initial_equilibrium(), model.initial_state()
    for k in range(1, 4):
        equilibrium, state, _, _ = solver.increment(equilibrium, state, model.program.preload(k / 3), Effects())
    clock = time.perf_counter()
    n, iterations = 16, 0
    for k in range(1, n + 1):
        equilibrium, state, _, stats = solver.increment(equilibrium, state, model.program.cycle(k / n), Effects())
        iterations += stats.iterations
    return {"build_s": built, "contact_space_s": space_time, "per_increment_s": (time.perf_counter() - clock) / n,
            "newton_iterations": iterations / n, "points": model.assembly.structure.n_points,
            "G_nonzeros": model.assembly.structure.contact_operator.nnz}


def _time_gross_slip(mode):
    model = build(scenes.load("examples/gross_slip_fretting.toml", {"contact.sliding": mode}))
    solver = SlidingSolver(model.assembly, model.law, model.settings, mode=mode)
    counter = []

    class Count(procedure.Observer):
        def increment(self, record):
            counter.append(record.iterations)

    clock = time.perf_counter()
    procedure.run(solver, model.initial_state(), model.program, model.procedure, cof_evolution=False,
                  wear=True, observer=Count())
    elapsed = time.perf_counter() - clock
    return {"per_increment_s": elapsed / len(counter), "newton_iterations": float(np.mean(counter)),
            "repairings": solver.repairs}


def test_cost_of_mortar_and_finite_sliding(record_property):
    with threadpool_limits(limits=1, user_api="blas") if threadpool_limits else nullcontext():
        results = {"node_to_segment_3d": _time_blocks("node_to_segment"), "mortar_3d": _time_blocks("mortar"),
                   "small_sliding_2d": _time_gross_slip("small"), "finite_sliding_2d": _time_gross_slip("finite")}
    ratios = {
        "mortar/node_to_segment per increment (3D)":
            results["mortar_3d"]["per_increment_s"] / results["node_to_segment_3d"]["per_increment_s"],
        "mortar/node_to_segment contact space set-up (3D)":
            results["mortar_3d"]["contact_space_s"] / results["node_to_segment_3d"]["contact_space_s"],
        "mortar/node_to_segment build incl. pairing (3D)":
            results["mortar_3d"]["build_s"] / results["node_to_segment_3d"]["build_s"],
        "finite/small sliding per increment (2D gross slip)":
            results["finite_sliding_2d"]["per_increment_s"] / results["small_sliding_2d"]["per_increment_s"],
    }
    for name, figures in results.items():
        print(name, {k: round(v, 5) if isinstance(v, float) else v for k, v in figures.items()})
    for name, ratio in ratios.items():
        print(f"{name}: {ratio:.2f}")
    record_property("pairing_cost", {"results": results, "ratios": ratios})
    assert all(np.isfinite(list(ratios.values())))
