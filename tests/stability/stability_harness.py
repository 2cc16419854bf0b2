"""Machinery of the hard-case suite: small models, a load driver and the invariant watchdog.

Every case drives a :class:`contact.solver.ContactSolver` through a load history (its own
amplitude rows, or the procedure of :mod:`contact.procedure`) and hands each converged
increment to a :class:`Watchdog`, which asserts on the spot:

* no NaN or Inf in the equilibrium or in any history variable;
* p ≥ 0 and |τ| ≤ μ·p (+ round-off) at every point, μ being the COF after the increment;
* μ non-decreasing and ≤ μ_max; wear depth non-negative and non-decreasing; accumulated
  slip and dissipation non-decreasing;
* at most ``max_cutbacks`` cutbacks in any increment;

and keeps the global energy account of :class:`contact.energy.EnergyMeter`: external work
plus the elastic-stick source against stored energy + local frictional dissipation + wear
release (``Watchdog.energy_error``).

Models are the shipped cylinder-on-plane scene, coarsened through scene overrides, and
small 3D flat-on-flat blocks. Units: mm, N, MPa, mJ.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from contact.assembly import assemble
from contact.energy import EnergyMeter
from contact.law import ContactLaw, ContactState
from contact.procedure import IncrementRecord, Observer
from contact.solver import ContactSolver, Effects, NewtonSettings
from contact.structure import ContactSpace
from pipelines import scene as scenes
from tests.bench.bench_report import flat_on_flat
from pipelines.build import build

SCENE = Path(__file__).resolve().parents[2] / "examples" / "cylinder_on_plane.toml"
LINE_LOAD = 1066.0  # N/mm, the scene's normal load
COF = 0.56
ROUND_OFF = 1e-9  # relative slack of the friction bound: the law caps τ exactly at μ·p


@dataclass
class Case:
    """A solver ready to drive, with what the checks need to know about its interface."""

    name: str
    solver: ContactSolver
    space: ContactSpace
    law: ContactLaw
    state: ContactState
    patterns: tuple
    x: np.ndarray  # (n_points, dim) contact point coordinates, mm
    model: object = None  # the pipelines Model when built from a scene

    @property
    def area(self) -> np.ndarray:
        return self.solver.area

    def amplitudes(self, **values) -> np.ndarray:
        """Amplitude vector in pattern order from keyword values (missing patterns: 0)."""
        unknown = set(values) - set(self.patterns)
        assert not unknown, f"no patterns {unknown} in {self.patterns}"
        return np.array([float(values.get(p, 0.0)) for p in self.patterns])


def cylinder(*, contact_size: float = 0.1, normal: str = "force", tangential: str = "motion",
             normal_value: float = -LINE_LOAD, tangential_value: float = 0.107,
             overrides: dict | None = None, settings: NewtonSettings | None = None) -> Case:
    """The cylinder-on-plane scene at element size ``contact_size`` (mm) in the contact zone.

    normal / tangential: "force" (N per mm, on the reference point) or "motion" (mm).
    Patterns are named "normal" (history "ramp") and "tangential" ("cyclic"); drive them
    with unit amplitudes scaled by ``normal_value`` / ``tangential_value``, or run the
    scene's procedure.
    """
    entries = {"loads": [], "motions": []}
    for name, kind, dof, value, history in (
            ("normal", normal, "cylinder.rp.uy", normal_value, "ramp"),
            ("tangential", tangential, "cylinder.rp.ux", tangential_value, "cyclic")):
        entries["loads" if kind == "force" else "motions"].append(
            {"name": name, "dof": dof, "value": value, "history": history})
    data = {"bodies.cylinder.mesh.contact_size": contact_size,
            "bodies.plane.mesh.contact_size": contact_size, **entries, **(overrides or {})}
    model = build(scenes.load(SCENE, data))
    space = ContactSpace(model.assembly.structure)
    solver = ContactSolver(space, model.law, settings or model.settings)
    return Case(f"cylinder h={contact_size}", solver, space, model.law, model.initial_state(),
                model.assembly.structure.patterns, model.assembly.pairing.slave.coordinates, model)


def flat(points_per_side: int = 5, *, normal: str = "force", tangential: str = "motion",
         law: ContactLaw | None = None, cof0: float = 0.2, wear_bodies: int | None = None,
         settings: NewtonSettings | None = None, **geometry) -> Case:
    """Two 10×10×5 mm steel blocks, ``points_per_side``² contact points; the punch is pressed
    down ("normal") and driven in x ("tangential"), each by a force (N per unit amplitude)
    or a motion (mm per unit amplitude) as ``normal`` / ``tangential`` say."""
    case = flat_on_flat(points_per_side, layers=geometry.pop("layers", 3), **geometry)
    loads, motions = dict(case.loads), dict(case.motions)
    if normal == "motion":
        motions["normal"] = loads.pop("normal")
    if tangential == "force":
        loads["tangential"] = motions.pop("tangential")
    structure = assemble(case.bodies, case.slave, case.master, loads=loads,
                         motions=motions).structure
    space = ContactSpace(structure)
    law = law or case.law
    solver = ContactSolver(space, law, settings or NewtonSettings())
    state = ContactState.initial(structure.n_points, 2, cof0, wear_bodies)
    return Case(f"flat {points_per_side}x{points_per_side}", solver, space, law, state,
                structure.patterns, _flat_points(case))


def sphere(points_per_side: int = 22, *, radius: float = 200.0, critical_slip: float = 1e-6,
           cof: float = 0.3, settings: NewtonSettings | None = None) -> Case:
    """Sphere on flat in 3D: the punch of :func:`flat` (10×10 mm faces, force-controlled in z
    and x) with the initial gap r²/(2R) of a sphere of ``radius`` (mm) centred on its face,
    ``points_per_side``² contact points, constant COF ``cof``, critical slip in mm."""
    case = flat_on_flat(points_per_side, layers=4)
    points = _flat_points(case)
    centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
    gap = np.sum((points[:, :2] - centre[:2]) ** 2, axis=1) / (2.0 * radius)
    loads = {"normal": case.loads["normal"], "tangential": case.motions["tangential"]}
    structure = assemble(case.bodies, case.slave, case.master, loads=loads, initial_gap=gap).structure
    space = ContactSpace(structure)
    law = ContactLaw(normal_stiffness=4e6, critical_slip=critical_slip)
    solver = ContactSolver(space, law, settings or NewtonSettings())
    return Case(f"sphere {points_per_side}x{points_per_side}, γ_crit {critical_slip:g} mm", solver, space,
                law, ContactState.initial(structure.n_points, 2, cof), structure.patterns, points)


def _flat_points(case) -> np.ndarray:
    from contact.interface import surface_from_facets
    body = next(b for b in case.bodies if b.name == case.slave[0])
    return surface_from_facets(body.elastic.mesh, case.slave[1]).coordinates


@dataclass
class Watchdog(Observer):
    """Checks every converged increment and keeps the counters and the energy account."""

    case: Case
    max_cutbacks: int = 4
    track_energy: bool = True
    increments: int = 0
    iterations: int = 0
    max_iterations: int = 0
    cutbacks: int = 0
    max_cutbacks_seen: int = 0
    started: float = field(default_factory=time.perf_counter)
    external_work: float = 0.0
    stored: float = 0.0
    meter: EnergyMeter | None = None
    previous: ContactState | None = None
    max_excess: float = 0.0  # largest (|τ| − μ·p)/(μ·p)_max seen, for the report

    def __post_init__(self):
        if self.track_energy:
            self.meter = EnergyMeter(self.case.space, self.case.law)
        self.previous = self.case.state

    def increment(self, record: IncrementRecord) -> None:
        where = f"{self.case.name}, increment {self.increments + 1} ({record.phase})"
        equilibrium, state = record.equilibrium, record.state
        self.increments += 1
        self.iterations += record.iterations
        self.max_iterations = max(self.max_iterations, record.max_iterations)
        self.cutbacks += record.cutbacks
        self.max_cutbacks_seen = max(self.max_cutbacks_seen, record.cutbacks)
        assert record.cutbacks <= self.max_cutbacks, f"{where}: {record.cutbacks} cutbacks"
        check_finite(equilibrium, state, where)
        check_friction_bound(self.case, equilibrium, state, where, self)
        check_history(self.previous, state, self.case.law, where)
        self.previous = state
        if self.meter is not None:
            self.external_work, self.stored = self.meter.update(equilibrium, state, record.locked_elongation)
            assert np.isfinite(self.external_work) and np.isfinite(self.stored), where

    @property
    def dissipation(self) -> float:
        """Frictional dissipation summed from the local densities, mJ (per mm in 2D)."""
        return float(np.sum(self.previous.dissipation * self.case.area))

    @property
    def energy_error(self) -> float:
        """(W + S − U − D − R) relative to W: external work plus the elastic-stick source
        against stored, dissipated and wear-released energy; 0 for an exact account."""
        residual = (self.external_work + self.meter.stick_source - self.stored - self.dissipation
                    - self.meter.wear_release)
        return residual / max(abs(self.external_work), 1e-300)

    @property
    def elapsed(self) -> float:
        return time.perf_counter() - self.started

    def summary(self) -> dict:
        out = {"increments": self.increments, "newton_total": self.iterations,
               "newton_max": self.max_iterations, "cutbacks": self.cutbacks,
               "cutbacks_max": self.max_cutbacks_seen, "seconds": round(self.elapsed, 2),
               "friction_excess_max": self.max_excess}
        if self.meter is not None:
            out.update(work_mJ=self.external_work, dissipation_mJ=self.dissipation,
                       stick_source_mJ=self.meter.stick_source, energy_error=self.energy_error)
        return out


def check_finite(equilibrium, state: ContactState, where: str) -> None:
    arrays = {"kinematics": equilibrium.kinematics, "control": equilibrium.control,
              "forces": equilibrium.forces, "elastic slip": state.elastic_slip, "cof": state.cof,
              "accumulated slip": state.accumulated_slip, "dissipation": state.dissipation,
              "slip vector": state.slip_vector}
    if state.wear_depth is not None:
        arrays["wear depth"] = state.wear_depth
    for name, values in arrays.items():
        assert np.all(np.isfinite(values)), f"{where}: {name} has NaN or Inf"


def check_friction_bound(case: Case, equilibrium, state: ContactState, where: str,
                         watchdog: Watchdog | None = None) -> None:
    """p ≥ 0 and |τ| ≤ μ·p at every point (μ after the increment; it never decreases)."""
    per_point = equilibrium.forces.reshape(case.solver.n_points, -1) / case.area[:, None]
    pressure, shear = per_point[:, 0], np.linalg.norm(per_point[:, 1:], axis=1)
    assert np.all(pressure >= 0.0), f"{where}: tensile contact pressure {pressure.min():.3g} MPa"
    capacity = state.cof * pressure
    scale = max(float(capacity.max(initial=0.0)), 1e-300)
    excess = (shear - capacity) / scale
    if watchdog is not None:
        watchdog.max_excess = max(watchdog.max_excess, float(excess.max(initial=-np.inf)))
    worst = int(np.argmax(excess))
    assert excess[worst] <= ROUND_OFF, (
        f"{where}: |τ| = {shear[worst]:.6g} MPa exceeds μ·p = {capacity[worst]:.6g} MPa at point {worst}")


def check_history(before: ContactState, after: ContactState, law: ContactLaw, where: str) -> None:
    """μ non-decreasing and ≤ μ_max; wear ≥ 0 and non-decreasing; slip sums non-decreasing."""
    cof_max = np.broadcast_to(law.cof_max, after.cof.shape)
    assert np.all(after.cof >= before.cof), f"{where}: the COF decreased"
    assert np.all(after.cof <= cof_max * (1.0 + 1e-12)), f"{where}: COF {after.cof.max()} > μ_max"
    if after.wear_depth is not None:
        assert np.all(after.wear_depth >= 0.0), f"{where}: negative wear depth"
        assert np.all(after.wear_depth >= before.wear_depth), f"{where}: wear depth decreased"
    assert np.all(after.accumulated_slip >= before.accumulated_slip), f"{where}: slip sum decreased"
    assert np.all(after.dissipation >= before.dissipation), f"{where}: dissipation decreased"


@dataclass
class Step:
    """One converged increment of :func:`drive`."""

    amplitudes: np.ndarray
    equilibrium: object
    state: ContactState
    status: np.ndarray
    iterations: int
    cutbacks: int


def drive(case: Case, rows, watchdog: Watchdog, effects: Effects = Effects()) -> list[Step]:
    """Solve the amplitude ``rows`` (n, n_patterns) one increment each, from the unloaded start."""
    equilibrium, state, steps = case.solver.initial_equilibrium(), case.state, []
    for k, amplitudes in enumerate(np.atleast_2d(rows)):
        equilibrium, state, status, stats = case.solver.increment(equilibrium, state, amplitudes, effects)
        watchdog.increment(IncrementRecord("history", 0, float(k), equilibrium, state, status,
                                           stats.iterations, stats.max_iterations, stats.cutbacks,
                                           stats.substeps))
        steps.append(Step(np.asarray(amplitudes), equilibrium, state, status, stats.iterations,
                          stats.cutbacks))
    return steps


def preload(case: Case, n: int = 10) -> np.ndarray:
    """Rows that ramp the "normal" pattern from 0 to 1 in ``n`` increments."""
    return ramp(case.amplitudes(), case.amplitudes(normal=1), n)


def interface_forces(case: Case, equilibrium) -> tuple[float, np.ndarray]:
    """Total normal force P and tangential force vector Q the contact transmits (N, N/mm in 2D)."""
    per_point = equilibrium.forces.reshape(case.solver.n_points, -1)
    return float(per_point[:, 0].sum()), per_point[:, 1:].sum(axis=0)


def ramp(start, stop, n: int) -> np.ndarray:
    """``n`` rows from just after ``start`` to ``stop`` (both amplitude vectors), linearly."""
    fractions = np.linspace(0.0, 1.0, n + 1)[1:, None]
    return np.asarray(start)[None, :] * (1.0 - fractions) + np.asarray(stop)[None, :] * fractions


def sine_cycles(case: Case, held: dict, cyclic: dict, n_per_cycle: int, cycles: int = 1) -> np.ndarray:
    """Rows of ``cycles`` sine cycles of the ``cyclic`` amplitudes on top of ``held`` ones."""
    phases = np.arange(1, n_per_cycle * cycles + 1) / n_per_cycle
    base = case.amplitudes(**held)
    shape = case.amplitudes(**cyclic)
    return base[None, :] + np.sin(2 * np.pi * phases)[:, None] * shape[None, :]

