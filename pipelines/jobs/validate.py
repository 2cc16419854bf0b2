"""``fretwork validate``: the cylinder-on-plane case against closed forms and a reference model.

Every check returns records ``{case, quantity, value, reference, rel_error, tolerance,
passed}``. The scene is the shipped ``examples/cylinder_on_plane.toml`` (paper §3.1), with
overrides stated in each check:

* Hertz: p₀ and a after the normal preload (a from a least-squares fit of p² = p₀²(1 − x²/a²)).
* Cattaneo-Mindlin: stick-zone half-width c under Q = 0.5·μP applied after P. CM assumes
  rigid stick, the limit γ_crit → 0 of the elastic-stick law; with the paper's γ_crit = 1 µm
  the reversible slip is as large as the CM slips of this contact, so the check uses
  γ_crit = 0.01 µm.
* Energy identity: worn area = (w₁ + w₂) × dissipation, the dissipation measured globally
  (external work − stored energy − energy released by removed material), no cycle jump;
  and the gross-slip dissipation per cycle against 4·μ·P·δ.
* Wear as a gap versus wear applied to the geometry: the surfaces are moved by the wear
  depth (harmonic mesh motion), re-assembled and re-condensed every few cycles.
* The consistent tangent against central finite differences in stick, slip and slip with
  pressure change, per entry type (normal, friction, coupling), each against its own size.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from contact import procedure  # noqa: E402
from contact.checks import tangent_errors  # noqa: E402
from contact.energy import EnergyMeter, MeterObserver  # noqa: E402
from contact.law import ContactLaw, ContactState, Status, evaluate  # noqa: E402
from contact.solver import ContactSolver, Effects  # noqa: E402
from pipelines import scene as scenes  # noqa: E402
from pipelines.build import build  # noqa: E402
from reduction.mesh.motion import move_surface  # noqa: E402

from pipelines import examples  # noqa: E402

SCENE = examples.scene_path("cylinder_on_plane")
RADIUS, LINE_LOAD, YOUNG, POISSON, COF = 80.0, 1066.0, 120e3, 0.3, 0.56


def record(case, quantity, value, reference, tolerance) -> dict:
    rel = abs(value - reference) / abs(reference)
    return {"case": case, "quantity": quantity, "value": float(value), "reference": float(reference),
            "rel_error": float(rel), "tolerance": tolerance, "passed": bool(rel <= tolerance)}


def hertz_reference() -> tuple[float, float]:
    """Plane-strain Hertz half-width a (mm) and peak pressure p₀ (MPa) for two equal bodies."""
    effective = YOUNG / (2.0 * (1.0 - POISSON ** 2))
    half_width = np.sqrt(4.0 * LINE_LOAD * RADIUS / (np.pi * effective))
    return half_width, 2.0 * LINE_LOAD / (np.pi * half_width)


def _solver(model):
    space = model.contact_space()
    return space, ContactSolver(space, model.law, model.settings)


def _preload(solver, model, increments=10):
    state, equilibrium = model.initial_state(), solver.initial_equilibrium()
    for k in range(1, increments + 1):
        equilibrium, state, status, _ = solver.increment(equilibrium, state, model.program.preload(k / increments),
                                                         Effects())
    return equilibrium, state, status


def check_hertz(model) -> list[dict]:
    _, solver = _solver(model)
    equilibrium, _, _ = _preload(solver, model)
    x = model.assembly.pairing.slave.coordinates[:, 0]
    pressure = equilibrium.forces.reshape(-1, 2)[:, 0] / model.assembly.structure.area
    closed = pressure > 0.05 * pressure.max()
    slope, intercept = np.polyfit(x[closed] ** 2, pressure[closed] ** 2, 1)
    fitted_half_width = np.sqrt(-intercept / slope)
    a, p0 = hertz_reference()
    return [record("cylinder_on_plane/hertz", "peak pressure p0 [MPa]", pressure.max(), p0, 0.02),
            record("cylinder_on_plane/hertz", "half-width a [mm]", fitted_half_width, a, 0.02)]


def check_cattaneo_mindlin(scene_path, overrides, ratio=0.5) -> list[dict]:
    cm_overrides = {**overrides, "contact.critical_slip": 1e-5, "motions": [],
                    "loads": [{"name": "normal", "dof": "cylinder.rp.uy", "value": -LINE_LOAD, "history": "ramp"},
                              {"name": "tangential", "dof": "cylinder.rp.ux", "value": 1.0, "history": "cyclic"}]}
    model = build(scenes.load(scene_path, cm_overrides))
    _, solver = _solver(model)
    equilibrium, state, _ = _preload(solver, model)
    steps = 20
    for k in range(1, steps + 1):
        equilibrium, state, status, _ = solver.increment(
            equilibrium, state, np.array([1.0, ratio * COF * LINE_LOAD * k / steps]), Effects())
    x = model.assembly.pairing.slave.coordinates[:, 0]
    order = np.argsort(x)
    xs, stuck = x[order], np.flatnonzero(status[order] == Status.STICK)
    right = 0.5 * (xs[stuck.max()] + xs[stuck.max() + 1])
    left = 0.5 * (xs[stuck.min()] + xs[stuck.min() - 1])
    a, _ = hertz_reference()
    return [record("cylinder_on_plane/cattaneo_mindlin", f"stick half-width c at Q={ratio}muP [mm]",
                   0.5 * (right - left), a * np.sqrt(1.0 - ratio), 0.05)]


def check_energy(scene_path, overrides, cycles, increments) -> list[dict]:
    model = build(scenes.load(scene_path, {**overrides, "procedure.wear_cycles": cycles,
                                           "procedure.cycle_jump": 1.0,
                                           "procedure.increments_per_cycle": increments}))
    space, solver = _solver(model)
    meter = EnergyMeter(space, model.law)
    result = procedure.run(solver, model.initial_state(), model.program, model.procedure,
                           cof_evolution=False, wear=True, observer=MeterObserver(meter))
    dissipation_global = meter.global_dissipation
    area = model.assembly.structure.area
    worn_area = float(np.sum(result.state.gap * area))
    w_total = sum(model.law.wear_coefficients)
    last = result.cycles[-1]
    centre = np.argmin(np.abs(model.assembly.pairing.slave.coordinates[:, 0]))
    slip_amplitude = 0.5 * last.slip_range[centre] + model.law.critical_slip
    cycle_dissipation = float(np.sum(last.dissipation_in_cycle * area))
    return [
        record("cylinder_on_plane/energy", "worn area / (w x global dissipation)", worn_area,
               w_total * dissipation_global, 0.01),
        record("cylinder_on_plane/energy", "dissipation per gross-slip cycle [mJ/mm]", cycle_dissipation,
               4.0 * COF * LINE_LOAD * (slip_amplitude - model.law.critical_slip), 0.05),
        record("cylinder_on_plane/slip", "slip amplitude at the centre [mm]", slip_amplitude, 0.075, 0.03),
    ]


def _wear_profile_figures(x, depth):
    order = np.argsort(x)
    x, depth = x[order], depth[order]
    threshold = 0.01 * depth.max()
    above = np.flatnonzero(depth > threshold)

    def crossing(i, j):  # linear interpolation of the threshold between nodes i (above) and j
        return x[i] + (threshold - depth[i]) * (x[j] - x[i]) / (depth[j] - depth[i])

    width = crossing(above.max(), above.max() + 1) - crossing(above.min(), above.min() - 1)
    return float(depth.max()), float(width)


def check_wear_geometry(scene_path, overrides, cycles, update_every, out_dir: Path, progress) -> list[dict]:
    settings = {**overrides, "procedure.wear_cycles": cycles}
    scene = scenes.load(scene_path, settings)
    model = build(scene)
    _, solver = _solver(model)
    gap_result = procedure.run(solver, model.initial_state(), model.program, model.procedure,
                               cof_evolution=False, wear=True)
    x = model.assembly.pairing.slave.coordinates[:, 0]
    gap_depth = gap_result.state.gap

    block = scenes.load(scene_path, {**settings, "procedure.wear_cycles": update_every})
    meshes = None
    total_depth = np.zeros_like(gap_depth)
    for _ in range(cycles // update_every):
        model = build(block, meshes)
        _, solver = _solver(model)
        result = procedure.run(solver, model.initial_state(), model.program, model.procedure,
                               cof_evolution=False, wear=True)
        wear = result.state.wear_depth
        total_depth += wear.sum(axis=0)
        pairing = model.assembly.pairing
        slave_mesh = model.meshes[model.assembly.slave_body]
        master_mesh = model.meshes[model.assembly.master_body]
        # Material removal: each surface recedes into its own body by its own wear depth.
        slave_move = -wear[0][:, None] * pairing.normal
        master_x = pairing.master.coordinates[:, 0]
        order = np.argsort(pairing.slave.coordinates[:, 0])
        master_depth = np.interp(master_x, pairing.slave.coordinates[order, 0], wear[1][order])
        master_move = master_depth[:, None] * np.array([0.0, -1.0])
        meshes = {model.assembly.slave_body: move_surface(slave_mesh, pairing.slave.nodes, slave_move),
                  model.assembly.master_body: move_surface(master_mesh, pairing.master.nodes, master_move)}
        if progress:
            print(f"  geometry update: {total_depth.max() * 1000:.2f} µm worn", flush=True)
    gap_max, gap_width = _wear_profile_figures(x, gap_depth)
    geo_max, geo_width = _wear_profile_figures(x, total_depth)
    out_dir.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(7, 3.5))
    order = np.argsort(x)
    ax.plot(x[order], gap_depth[order] * 1000, "-", label="wear as a gap (fretwork)")
    ax.plot(x[order], total_depth[order] * 1000, "--", label=f"geometry updated every {update_every} cycles")
    ax.invert_yaxis()
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("wear depth, both bodies [µm]")
    ax.set_title(f"Cylinder on plane: {cycles * model.procedure.cycle_jump:.0f} cycles, slip ±75 µm")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out_dir / "wear_gap_vs_geometry.png", dpi=130)
    plt.close(fig)
    return [record("cylinder_on_plane/wear_geometry", "max wear depth [mm]", gap_max, geo_max, 0.05),
            record("cylinder_on_plane/wear_geometry", "scar width [mm]", gap_width, geo_width, 0.05)]


def check_tangent() -> list[dict]:
    rng = np.random.default_rng(7)
    law = ContactLaw(normal_stiffness=4e6, critical_slip=1e-3, cof_max=0.7, cof_rate=0.05,
                     wear_coefficients=(0.47e-8, 1.5e-8), wear_form="shear")
    records = []
    for case in ("stick", "slip", "slip with pressure change"):
        n = 200
        overclosure = 1e-4 * (1.0 + rng.random(n))
        direction = rng.normal(size=(n, 2))
        direction /= np.linalg.norm(direction, axis=1, keepdims=True)
        state = ContactState.initial(n, 2, 0.3 + 0.3 * rng.random(n), n_wear_bodies=2)
        state = replace(state, elastic_slip=0.3e-3 * direction)
        if case == "stick":
            increment = 0.25e-3 * np.clip(rng.normal(size=(n, 2)), -1.0, 1.0)
        else:
            increment = (2e-3 + 1e-3 * rng.random((n, 1))) * direction + 0.5e-3 * rng.normal(size=(n, 2))
        if case == "slip with pressure change":
            state = replace(state, wear_depth=np.vstack([0.2e-4 * rng.random(n), 0.1e-4 * rng.random(n)]))
        expected = Status.STICK if case == "stick" else Status.SLIP
        in_regime = bool(np.all(evaluate(overclosure, increment, state, law).status == expected))
        for kind, error in tangent_errors(overclosure, increment, state, law).items():
            records.append({"case": "contact_law/tangent", "quantity": f"FD tangent error, {case}, {kind} entries",
                            "value": error, "reference": 0.0, "rel_error": error, "tolerance": 1e-6,
                            "passed": bool(error < 1e-6 and in_regime)})
    return records


def run_validation(quick: bool = False, out_dir: Path = Path("results/validation"),
                   progress: bool = True, scene_path: Path = SCENE) -> list[dict]:
    """All validation records. ``quick`` shortens the wear histories for CI."""
    overrides: dict = {}
    scene = scenes.load(scene_path, overrides)
    records = check_tangent()
    records += check_hertz(build(scene))
    records += check_cattaneo_mindlin(scene_path, overrides)
    records += check_energy(scene_path, overrides, cycles=3 if quick else 10, increments=40 if quick else 80)
    records += check_wear_geometry(scene_path, overrides, cycles=6 if quick else 20,
                                   update_every=2, out_dir=Path(out_dir), progress=progress)
    return records
