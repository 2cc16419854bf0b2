"""The 3D flat-on-flat benchmark: one case, one cyclic partial-slip history, two solvers.

Two equal square blocks of hexahedra touch on z = 0: tensor grids graded in z only
("uniform"), or fine at the contact face and coarsening 3:1 in plane with depth ("graded",
:func:`reduction.mesh.generators.graded_flat_block`: the same contact face, a fraction of the
nodes; the scale bench's bodies). The lower block is clamped at its
bottom; the top face of the upper block is rigidly coupled to a reference point that is
pressed down (force control) and then moved tangentially back and forth (displacement
control). The slave face (upper block) has ``points_per_side``² nodes: the contact points.
The rigid top and the finite blocks give stress peaks at the edges, so the edges slip while
the centre sticks (partial slip), and the COF evolves where the points slide. Steel blocks
(210 GPa, ν 0.3), 100 MPa nominal pressure, kn 4e6 N/mm³, γ_crit 1 µm, μ_0 0.2, μ_max 0.7,
COF rate 2 mm/N, tangential amplitude 5 µm.

Used by the benchmark (tests/bench) and the condensed-versus-full comparison test. The
functions return data; only the command line (:func:`main`, one run per process so that its
peak memory is its own) prints. Units: mm, N, MPa, s.
"""

from __future__ import annotations

import cProfile
import json
import resource
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import skfem

from contact.assembly import Body, ReferencePoint
from contact.law import ContactLaw, ContactState
from contact.solver import Effects
from reduction.elasticity import ElasticBody, assemble_elastic_body
from reduction.mesh.generators import flat_block, graded_flat_block


@dataclass(frozen=True)
class FlatOnFlat:
    """Inputs of :func:`contact.assembly.assemble` and :func:`contact.full_model.build` for the case.

    history: (n_increments, 2) amplitudes of the patterns ("normal" N, "tangential" mm).
    cycle: slice of ``history`` rows that make one full tangential cycle (+δ → −δ → +δ).
    """

    bodies: list
    slave: tuple
    master: tuple
    loads: dict
    motions: dict
    law: ContactLaw
    cof0: float
    effects: Effects
    history: np.ndarray
    cycle: slice

    def initial_state(self, n_points: int) -> ContactState:
        return ContactState.initial(n_points, 2, self.cof0)


def box_body(mesh: skfem.MeshHex, youngs_modulus: float, poisson_ratio: float) -> ElasticBody:
    """Elastic body of a mesh of boxes (MPa): :func:`reduction.elasticity.assemble_elastic_body`
    (2×2×2 Gauss points per hexahedron, assembled in element blocks; the body keeps one
    element's quadrature data only, which matters at 10,000 contact points: two bodies of
    60,000 hexahedra, whose full quadrature data would take 2 GB)."""
    return assemble_elastic_body(mesh, youngs_modulus, poisson_ratio)


def flat_on_flat(points_per_side: int, *, size: float = 10.0, height: float = 5.0,
                 layers: int = 6, pressure: float = 100.0, slip_amplitude: float = 5.0e-3,
                 increments_per_quarter: int = 4, cycles: int = 1,
                 youngs_modulus: float = 210e3, poisson_ratio: float = 0.3,
                 mesh: str = "uniform") -> FlatOnFlat:
    """Two ``size``×``size``×``height`` mm blocks, ``points_per_side``² contact points.

    mesh: "uniform" (n×n elements in plane through ``layers`` layers growing ×1.4 away from
    the contact) or "graded" (:func:`reduction.mesh.generators.graded_flat_block`; ``layers``
    is not used). Both have the same contact face nodes.

    pressure: nominal contact pressure (MPa) applied as a force on the reference point.
    slip_amplitude: tangential reference-point motion amplitude (mm) in x.
    history: the normal load in one increment, then a quarter cycle to +δ and ``cycles`` full
    cycles, each quarter in ``increments_per_quarter`` increments.
    """
    n_el = points_per_side - 1
    if mesh == "uniform":
        upper = flat_block(size, size, height, n_el, n_el, layers, z0=0.0, z_growth=1.4)
        lower = flat_block(size, size, height, n_el, n_el, layers, z0=-height, z_growth=1.4, top_fine=True)
    elif mesh == "graded":
        upper = graded_flat_block(size, size, height, n_el, n_el, z0=0.0)
        lower = graded_flat_block(size, size, height, n_el, n_el, z0=-height, top_fine=True)
    else:
        raise ValueError(f"mesh must be 'uniform' or 'graded', got {mesh!r}")
    upper_body = box_body(upper, youngs_modulus, poisson_ratio)
    lower_body = box_body(lower, youngs_modulus, poisson_ratio)
    top = np.flatnonzero(np.isclose(upper.p[2], height))
    bottom = np.flatnonzero(np.isclose(lower.p[2], -height))
    bodies = [
        Body("punch", upper_body, reference_points={"rp": ReferencePoint(top, np.array([0.0, 0.0, height]))}),
        Body("base", lower_body, fixed_nodes=bottom, fixed_components=(0, 1, 2)),
    ]
    slave = ("punch", upper.facets_satisfying(lambda x: np.isclose(x[2], 0.0), boundaries_only=True))
    master = ("base", lower.facets_satisfying(lambda x: np.isclose(x[2], 0.0), boundaries_only=True))
    force = pressure * size * size
    loads = {"normal": [("punch", "rp", "uz", -1.0)]}
    motions = {"tangential": [("punch", "rp", "ux", 1.0)]}
    law = ContactLaw(normal_stiffness=4e6, critical_slip=1e-3, cof_max=0.7, cof_rate=2.0)
    n = increments_per_quarter
    quarter = np.linspace(0.0, 1.0, n + 1)[1:]
    one_cycle = np.concatenate([1.0 - 2.0 * np.linspace(0.0, 1.0, 2 * n + 1)[1:],
                                -1.0 + 2.0 * np.linspace(0.0, 1.0, 2 * n + 1)[1:]])
    tangential = np.concatenate([[0.0], quarter] + [one_cycle] * cycles) * slip_amplitude
    history = np.column_stack([np.full(tangential.size, force), tangential])
    start = 1 + n + (cycles - 1) * 4 * n
    return FlatOnFlat(bodies=bodies, slave=slave, master=master, loads=loads, motions=motions,
                      law=law, cof0=0.2, effects=Effects(cof_evolution=True), history=history,
                      cycle=slice(start, start + 4 * n))


@dataclass
class RunRecord:
    """Figures of one solver on one case; times in s, memory in MB."""

    solver: str
    points: int
    dofs: int
    setup_time: float
    increment_times: list
    increment_cpu_times: list
    iterations: list
    max_iterations: list
    cutbacks: int

    def summary(self, cycle: slice) -> dict:
        """Per-increment and per-cycle figures over the rows ``cycle`` of the history."""
        times = np.asarray(self.increment_times[cycle])
        cpu_times = np.asarray(self.increment_cpu_times[cycle])
        iterations = np.asarray(self.iterations[cycle])
        return {
            "solver": self.solver, "points": self.points, "dofs": self.dofs,
            "setup_s": self.setup_time,
            "increment_mean_s": float(times.mean()), "increment_max_s": float(times.max()),
            "cycle_s": float(times.sum()),
            "increment_mean_cpu_s": float(cpu_times.mean()), "cycle_cpu_s": float(cpu_times.sum()),
            "history_s": float(np.sum(self.increment_times)),
            "history_cpu_s": float(np.sum(self.increment_cpu_times)),
            "history_max_cpu_s": float(np.max(self.increment_cpu_times)),
            "newton_mean": float(iterations.mean()),
            "newton_max": int(np.max(self.max_iterations[cycle])),
            "newton_max_history": int(np.max(self.max_iterations)),
            "cutbacks": self.cutbacks,
        }


def drive(solver, state: ContactState, case: FlatOnFlat, *, label: str, points: int, dofs: int,
          setup_time: float, profile: tuple[int, Path] | None = None):
    """Run ``case.history`` through ``solver.increment``; returns the record and per-point fields.

    Wall and CPU (process) time are both kept: on a shared machine the CPU time of a
    single-threaded run is the better measure of the work done. profile: (row of the history,
    file): that increment runs under cProfile, its statistics written to the file (pstats);
    choose a row before ``case.cycle`` to keep the cycle's figures free of the profiler's cost.

    fields: pressure (n,) MPa, shear (n, 2) MPa and COF (n,) at the end of the history.
    """
    equilibrium = solver.initial_equilibrium()
    times, cpu_times, iterations, max_iterations, cutbacks = [], [], [], [], 0
    for row, amplitudes in enumerate(case.history):
        profiler = cProfile.Profile() if profile is not None and row == profile[0] else None
        start, start_cpu = time.perf_counter(), time.process_time()
        if profiler is not None:
            profiler.enable()
        equilibrium, state, _, stats = solver.increment(equilibrium, state, amplitudes, case.effects)
        if profiler is not None:
            profiler.disable()
            profiler.dump_stats(profile[1])
        times.append(time.perf_counter() - start)
        cpu_times.append(time.process_time() - start_cpu)
        iterations.append(stats.iterations)
        max_iterations.append(stats.max_iterations)
        cutbacks += stats.cutbacks
    area = solver.area
    forces = equilibrium.forces.reshape(-1, 3)
    fields = {"pressure": forces[:, 0] / area, "shear": forces[:, 1:] / area[:, None], "cof": state.cof}
    record = RunRecord(label, points, dofs, setup_time, times, cpu_times, iterations, max_iterations, cutbacks)
    return record, fields


def run(points_per_side: int, solver: str, increments_per_quarter: int = 4,
        mesh: str = "graded", profile: tuple[int, Path] | None = None) -> tuple[dict, dict]:
    """Set up and run the case with the ``condensed``, ``dense`` (condensed, exact dense LU in
    every Newton iteration), ``sparse`` (:mod:`contact.sparse`: bodies kept sparse, no dense W),
    ``auto`` (``sparse`` or ``condensed`` by :func:`contact.sparse.choose_path`) or ``full``
    solver: (summary, fields). mesh: the blocks' mesh (:func:`flat_on_flat`), graded by default;
    profile: one increment under cProfile (:func:`drive`).

    setup_s is the condensation (assemble, split into condense_s: coupling and Schur
    complements of the bodies, and contact_space_s: the elimination to W, E, S_q) or the
    full-model build (setup_cpu_s: its CPU time). peak_rss_mb is the process's peak resident
    memory from set-up on (the case's meshes and bodies included, the transient of building
    them not: Linux), process_peak_rss_mb over the whole process; meaningful when each run has
    its own process (as in :func:`main`).
    """
    from contact import full_model
    from contact.assembly import assemble
    from contact.linear import KrylovSettings
    from contact.solver import ContactSolver, NewtonSettings
    from contact.structure import ContactSpace

    from contact.sparse import choose_path

    case = flat_on_flat(points_per_side, increments_per_quarter=increments_per_quarter, mesh=mesh)
    _reset_peak_memory()  # the solver's peak, not the transient of building the meshes
    if solver == "auto":  # what a run would choose: the dense W below the measured threshold
        solver = "sparse" if choose_path(points_per_side**2, 3) == "sparse" else "condensed"
    start, start_cpu = time.perf_counter(), time.process_time()
    split = {}
    if solver in ("condensed", "dense"):
        structure = assemble(case.bodies, case.slave, case.master, loads=case.loads,
                             motions=case.motions).structure
        split["condense_s"] = time.perf_counter() - start
        # "dense": the exact LU of the dense bordered system in every Newton iteration, the
        # reference the shipped choice (preconditioned GMRES on large interfaces) must equal.
        linear = KrylovSettings(direct_below=np.inf) if solver == "dense" else KrylovSettings()
        engine = ContactSolver(ContactSpace(structure), case.law, NewtonSettings(linear=linear))
        dofs = structure.n_dofs
        split["contact_space_s"] = time.perf_counter() - start - split["condense_s"]
    elif solver == "sparse":
        from contact.sparse import SparseContactSpace

        structure = assemble(case.bodies, case.slave, case.master, loads=case.loads, motions=case.motions,
                             keep_interior=True).structure
        split["condense_s"] = time.perf_counter() - start
        engine, dofs = ContactSolver(SparseContactSpace(structure), case.law), structure.n_dofs
        split["contact_space_s"] = time.perf_counter() - start - split["condense_s"]
    elif solver == "full":
        model = full_model.build(case.bodies, case.slave, case.master, loads=case.loads,
                                 motions=case.motions)
        engine, dofs = full_model.FullModelSolver(model, case.law), model.n_dofs
    else:
        raise ValueError(f"solver must be 'condensed', 'dense', 'sparse', 'auto' or 'full', got {solver!r}")
    setup = time.perf_counter() - start
    split["setup_cpu_s"] = time.process_time() - start_cpu
    record, fields = drive(engine, case.initial_state(engine.n_points), case, label=solver,
                           points=engine.n_points, dofs=dofs, setup_time=setup, profile=profile)
    summary = record.summary(case.cycle) | split | {"mesh": mesh}
    summary["process_peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    summary["peak_rss_mb"] = _peak_memory_mb() or summary["process_peak_rss_mb"]
    if solver != "full":
        summary["linear"] = dict(vars(engine.linear.counters))
        summary["linear_solver"] = engine.linear.description()
    return summary, fields


def _reset_peak_memory() -> None:
    """Reset the process's peak resident memory (Linux: /proc/self/clear_refs), if possible."""
    try:
        Path("/proc/self/clear_refs").write_text("5")
    except OSError:
        pass


def _peak_memory_mb() -> float | None:
    """Peak resident memory (MB) since the last reset (Linux VmHWM), or None."""
    try:
        status = Path("/proc/self/status").read_text().splitlines()
    except OSError:
        return None
    peak = [line.split()[1] for line in status if line.startswith("VmHWM:")]
    return float(peak[0]) / 1024.0 if peak else None


def relative_difference(reference: dict, other: dict) -> float:
    """Largest difference of the per-point fields, relative to each field's largest magnitude."""
    worst = 0.0
    for name, value in reference.items():
        scale = max(float(np.max(np.abs(value))), 1e-300)
        worst = max(worst, float(np.max(np.abs(other[name] - value))) / scale)
    return worst


COLUMNS = ("solver", "points", "dofs", "setup_s", "increment_mean_s", "increment_mean_cpu_s",
           "increment_max_s", "cycle_s", "newton_mean", "newton_max", "peak_rss_mb", "speedup",
           "speedup_cpu", "rel_diff")


def format_table(rows: list[dict], columns: tuple[str, ...] = COLUMNS) -> str:
    """Fixed-width text table of benchmark summaries (``columns``: which keys, in order)."""
    width = {c: max(len(c), 9) for c in columns}
    lines = [" ".join(f"{c:>{width[c]}}" for c in columns)]
    for row in rows:
        cells = []
        for c in columns:
            value = row.get(c, "")
            cells.append(f"{value:>{width[c]}.4g}" if isinstance(value, float) else f"{value!s:>{width[c]}}")
        lines.append(" ".join(cells))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """``python -m tests.bench.bench_report POINTS_PER_SIDE SOLVER FIELDS.npz``: one run, JSON summary on stdout."""
    import argparse

    parser = argparse.ArgumentParser(description=main.__doc__)
    parser.add_argument("points_per_side", type=int)
    parser.add_argument("solver", choices=("condensed", "dense", "sparse", "auto", "full"))
    parser.add_argument("fields", type=Path, help="where to write the final per-point fields (.npz)")
    parser.add_argument("--increments-per-quarter", type=int, default=4)
    parser.add_argument("--mesh", choices=("graded", "uniform"), default="graded")
    parser.add_argument("--profile", nargs=2, metavar=("ROW", "STATS"),
                        help="run the history's row ROW under cProfile, its statistics to the file STATS")
    args = parser.parse_args(argv)
    profile = None if args.profile is None else (int(args.profile[0]), Path(args.profile[1]))
    summary, fields = run(args.points_per_side, args.solver, args.increments_per_quarter, args.mesh, profile)
    np.savez(args.fields, **fields)
    print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
