"""Flat-on-flat on the graded and on the uniform blocks: the contact history, increment by increment.

``python -m tests.bench.graded_physics POINTS_PER_SIDE MESH OUT.npz`` runs the benchmark's
history (:func:`tests.bench.bench_report.flat_on_flat`) with the sparse path on one mesh
("graded" or "uniform") in its own process and saves, per increment: the pressure (n,) and
shear (n, 2) fields (MPa), the point status (:class:`contact.law.Status`) and the point
areas (mm²). :func:`compare` gives the figures of two such files. Units: mm, N, MPa.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from contact.law import Status
from tests.bench.bench_report import flat_on_flat


def history(points_per_side: int, mesh: str) -> dict:
    """Pressure, shear, status at every increment of the history (arrays with a leading
    increment axis), the point areas and the cycle's rows (start, stop)."""
    from contact import full_model
    from contact.solver import ContactSolver
    from contact.sparse import SparseContactSpace

    case = flat_on_flat(points_per_side, mesh=mesh)
    model = full_model.build(case.bodies, case.slave, case.master, loads=case.loads, motions=case.motions)
    solver = ContactSolver(SparseContactSpace(model), case.law)
    equilibrium, state = solver.initial_equilibrium(), case.initial_state(solver.n_points)
    pairing = model.pairing
    # the points sorted by (x, y): the two meshes number their face nodes differently
    xy = pairing.slave.coordinates[:, :2]
    order = np.lexsort((xy[:, 1], xy[:, 0]))
    pressure, shear, status = [], [], []
    for amplitudes in case.history:
        equilibrium, state, point_status, _ = solver.increment(equilibrium, state, amplitudes, case.effects)
        forces = equilibrium.forces.reshape(-1, 3)
        pressure.append(forces[order, 0] / solver.area[order])
        # shear in the global (x, y) frame, so that the tangent frames of the meshes do not matter
        traction = np.einsum("nk,nkd->nd", forces[:, 1:], pairing.tangents)[:, :2]
        shear.append(traction[order] / solver.area[order, None])
        status.append(np.asarray(point_status)[order])
    return {"pressure": np.array(pressure), "shear": np.array(shear), "status": np.array(status),
            "area": np.asarray(solver.area)[order], "coordinates": xy[order],
            "cycle": np.array([case.cycle.start, case.cycle.stop])}


def compare(graded: dict, uniform: dict) -> dict:
    """Differences over the cycle's increments, each relative to the uniform blocks' largest
    value of that field over the cycle: pressure, shear (both MPa, pointwise), slip area
    (mm², the area of the points that slide) and the resultant tangential force (N, along x).
    Fields as saved by :func:`history` (points sorted by position)."""
    if not np.array_equal(graded["coordinates"], uniform["coordinates"]):
        raise ValueError("the two runs do not have the same contact points")
    rows = slice(*uniform["cycle"])
    area = uniform["area"]

    def slip_area(run):
        sliding = np.isin(run["status"][rows], (Status.SLIP, Status.SLIP_AT_MAX))
        return sliding @ run["area"]

    def tangential(run):
        return run["shear"][rows, :, 0] @ run["area"]

    p_u, p_g = uniform["pressure"][rows], graded["pressure"][rows]
    t_u, t_g = uniform["shear"][rows], graded["shear"][rows]
    a_u, a_g = slip_area(uniform), slip_area(graded)
    f_u, f_g = tangential(uniform), tangential(graded)
    return {
        "pressure_max_rel": float(np.abs(p_g - p_u).max() / np.abs(p_u).max()),
        "pressure_peak_uniform": float(p_u.max()), "pressure_peak_graded": float(p_g.max()),
        "shear_max_rel": float(np.abs(t_g - t_u).max() / np.abs(t_u).max()),
        "shear_peak_uniform": float(np.abs(t_u).max()), "shear_peak_graded": float(np.abs(t_g).max()),
        "slip_area_max_rel": float(np.abs(a_g - a_u).max() / max(a_u.max(), 1e-300)),
        "slip_area_uniform": a_u.tolist(), "slip_area_graded": a_g.tolist(),
        "total_area": float(area.sum()),
        "tangential_force_max_rel": float(np.abs(f_g - f_u).max() / np.abs(f_u).max()),
        "pressure_rms_rel": float(np.sqrt(np.mean((p_g - p_u) ** 2)) / np.abs(p_u).max()),
        "shear_rms_rel": float(np.sqrt(np.mean((t_g - t_u) ** 2)) / np.abs(t_u).max()),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("points_per_side", type=int)
    parser.add_argument("mesh", choices=("graded", "uniform"))
    parser.add_argument("out", type=Path)
    args = parser.parse_args(argv)
    np.savez(args.out, **history(args.points_per_side, args.mesh))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
