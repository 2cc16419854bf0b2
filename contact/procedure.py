"""The analysis procedure of the paper's section 3: preload, COF phase, wear phase, verdict.

1. Preload: load patterns marked ``ramp`` go from 0 to full in ``preload_increments``; bolts
   are locked; a program with a ``run_up`` (operating mean loads, e.g. a counterweight's
   centrifugal load) then ramps those in as many increments. Nothing evolves or wears here.
2. COF stabilisation: ``cof_cycles`` cycles of the cyclic patterns with COF evolution (if the
   scene asks for it) and no wear.
3. Wear: ``wear_cycles`` simulated cycles with wear (if asked), COF frozen or evolving, each
   standing for ``cycle_jump`` real cycles.
Each phase stops early once the contact is stationary: over ``stationary_window`` cycles
no more than ``area_tolerance`` of the nominal area still slid (shakedown to stick; see
:func:`active_slip_area_fraction` for what counts as sliding). The wear phase also stops when
loosening is evident: the clamp force has kept falling over the window while the stick area
shrank.

No I/O here: every increment and cycle is handed to an observer; the pipeline writes files
and draws progress bars. Units: mm, N, MPa, mJ.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from contact.law import ContactState, Status, utilised_cof
from contact.solver import ContactSolver, Effects, Equilibrium

PHASES = ("preload", "cof", "wear")
HISTORY_SHAPES = ("ramp", "cyclic", "constant")


@dataclass(frozen=True)
class LoadProgram:
    """How each pattern's amplitude moves in time.

    shapes: pattern name → "ramp" (0→1 in the preload, then held), "cyclic" (0 in the
    preload, then sin 2πt per cycle) or "constant" (1 throughout).
    held: pattern → amplitude replacing 1 after the preload (locked bolt pretensions).
    """

    patterns: tuple[str, ...]
    shapes: dict
    held: dict = field(default_factory=dict)

    def preload(self, fraction: float) -> np.ndarray:
        return np.array([fraction if self.shapes[p] == "ramp" else
                         1.0 if self.shapes[p] == "constant" else 0.0 for p in self.patterns])

    def cycle(self, phase: float) -> np.ndarray:
        """Amplitudes at the fraction ``phase`` ∈ [0, 1] of a load cycle."""
        return np.array([np.sin(2 * np.pi * phase) if self.shapes[p] == "cyclic" else
                         self.held.get(p, 1.0) for p in self.patterns])


@dataclass(frozen=True)
class Procedure:
    """Settings of the analysis procedure (counts are simulated cycles).

    area_tolerance: fraction of the nominal area that may still slide in a stuck contact.
    slip_tolerance: a point slides in a cycle when its pressure-weighted irreversible slip
    exceeds this fraction of γ_crit (see :func:`active_slip_area_fraction`).
    """

    preload_increments: int = 10
    increments_per_cycle: int = 40
    cof_cycles: int = 0
    wear_cycles: int = 0
    cycle_jump: float = 1.0
    cof_during_wear: bool = True
    stationary_window: int = 10
    loosening_window: int = 20
    area_tolerance: float = 0.01
    slip_tolerance: float = 0.1


@dataclass
class CycleSummary:
    """Per-point results of one cycle plus its global figures (what the observer records)."""

    cycle: int
    phase: str
    equivalent_cycles: float
    pressure: np.ndarray
    shear: np.ndarray
    cof: np.ndarray
    max_utilised_cof: np.ndarray
    max_shear: np.ndarray
    status: np.ndarray
    slip_range: np.ndarray
    dissipation_in_cycle: np.ndarray
    state: ContactState
    clamp_force: float | None
    figures: dict = field(default_factory=dict)


@dataclass
class IncrementRecord:
    """Global quantities after a converged increment."""

    phase: str
    cycle: int
    time: float
    equilibrium: Equilibrium
    state: ContactState
    status: np.ndarray
    iterations: int
    max_iterations: int
    cutbacks: int
    substeps: int
    bolt_forces: np.ndarray | None = None


@dataclass
class RunResult:
    """What a procedure run ends with: final state, the verdict and its figures."""

    verdict: str
    stationary: bool
    figures: dict
    state: ContactState
    equilibrium: Equilibrium
    cycles: list = field(default_factory=list)


class Observer:
    """Receives increments and cycles; the default does nothing. Pipelines subclass it."""

    def increment(self, record: IncrementRecord) -> None:
        pass

    def cycle(self, summary: CycleSummary) -> None:
        pass

    def phase(self, name: str, n_cycles: int) -> None:
        pass


def _fractions(area, nominal, mask):
    return float(area[mask].sum() / nominal) if nominal > 0 else 0.0


def cycle_figures(area: np.ndarray, nominal_area: float, status: np.ndarray,
                  max_utilised: np.ndarray, state: ContactState, cof_initial: np.ndarray,
                  cof_max, area_tolerance: float) -> dict:
    """Global figures of a cycle: area fractions, margin, wear, dissipation.

    Fractions refer to the nominal contact area (closed after the preload). The stick margin
    is 1 − max utilised COF / μ_max over points that stayed stuck.
    """
    stuck = status == Status.STICK
    slipped = status >= Status.SLIP
    damaged = status == Status.SLIP_AT_MAX
    wear = state.gap if state.wear_depth is not None else np.zeros_like(area)
    margins = 1.0 - max_utilised[stuck] / np.broadcast_to(cof_max, area.shape)[stuck]
    return {
        "stick_area_fraction": _fractions(area, nominal_area, stuck),
        "slip_area_fraction": _fractions(area, nominal_area, slipped),
        "damaged_area_fraction": _fractions(area, nominal_area, damaged),
        "worn_area_fraction": _fractions(area, nominal_area, np.asarray(wear) > 1e-9),
        # evolved: risen by more than 1 % of its range (numerical micro-slips of equilibrium
        # iterations raise μ by round-off amounts that are not fretting)
        "cof_evolved_area_fraction": _fractions(area, nominal_area, state.cof > cof_initial + 0.01 * (
            np.broadcast_to(cof_max, area.shape) - cof_initial)),
        "max_wear_depth_mm": float(np.max(wear, initial=0.0)),
        "wear_volume_mm3": float(np.sum(np.asarray(wear) * area)),
        "dissipated_energy_mJ": float(np.sum(state.dissipation * area)),
        "min_stick_margin": float(margins.min()) if margins.size else None,
    }


def active_slip_area_fraction(area: np.ndarray, nominal_area: float, pressure: np.ndarray,
                              dissipation_in_cycle: np.ndarray, cof: np.ndarray,
                              critical_slip, slip_tolerance: float) -> float:
    """Fraction of the nominal area that still slides in a cycle, in the sense of the verdict.

    A point slides when its pressure-weighted irreversible slip over the cycle,
    Σ p·Δγ_sl / p̄ (Σ p·Δγ_sl = dissipation / μ, the Archard wear driver; p̄ the mean pressure
    over the nominal area at the end of the cycle), exceeds ``slip_tolerance``·γ_crit.
    Two kinds of point fail that test although their status says slip: points worn out of
    contact, whose pressure Archard wear drives towards zero only asymptotically (w·Δγ·p
    vanishes with p), and points at the stick limit whose irreversible slip is a tiny
    fraction of the elastic slip γ_crit the law already treats as stick. Neither carries
    friction load nor wears or evolves its COF any more. Units: area mm², pressure MPa,
    dissipation mJ/mm², critical_slip mm.
    """
    mean_pressure = float(np.sum(pressure * area) / nominal_area) if nominal_area > 0 else 0.0
    if mean_pressure <= 0.0:
        return 0.0
    weighted_slip = np.divide(dissipation_in_cycle, cof, out=np.zeros_like(dissipation_in_cycle),
                              where=cof > 0.0) / mean_pressure
    sliding = weighted_slip > slip_tolerance * np.broadcast_to(critical_slip, area.shape)
    return _fractions(area, nominal_area, sliding)


def _verdict(history: list[CycleSummary], procedure: Procedure, stationary: bool) -> str:
    """``loosening`` (see :func:`_loosening`), else ``stick`` when at most ``area_tolerance``
    of the area still slid in the last cycle (:func:`active_slip_area_fraction`; histories
    without it fall back to the status-based slip area), else ``damage``."""
    last = history[-1].figures
    if _loosening(history, procedure):
        return "loosening"
    sliding = last.get("active_slip_area_fraction", last["slip_area_fraction"])
    if sliding <= procedure.area_tolerance:
        return "stick"
    return "damage"


def _loosening(history: list[CycleSummary], procedure: Procedure) -> bool:
    """Loosening is evident when, over the last ``loosening_window`` wear cycles, the clamp
    force keeps falling without its rate decaying (second half at least 0.8 of the first),
    by a visible amount (0.5 % of the clamp force), while the stick area shrinks or the
    whole contact slides. The shrinking is the least-squares trend of the stick area over
    the window, not its first and last values: points at the stick limit flicker between
    stick and slip from cycle to cycle by a few per cent of the area, and an endpoint
    comparison called a contact loosening whose stick area was steady or regrowing."""
    wear_cycles = [c for c in history if c.phase == "wear" and c.clamp_force is not None]
    if len(wear_cycles) < procedure.loosening_window:
        return False
    recent = wear_cycles[-procedure.loosening_window:]
    force = np.array([c.clamp_force for c in recent])
    stick = np.array([c.figures["stick_area_fraction"] for c in recent])
    middle = len(force) // 2
    first_rate = (force[0] - force[middle]) / middle
    second_rate = (force[middle] - force[-1]) / (len(force) - 1 - middle)
    falling = second_rate > 0.0 and second_rate >= 0.8 * first_rate
    visible = force[0] - force[-1] > 5e-3 * abs(force[0])
    stick_change = np.polyfit(np.arange(len(stick)), stick, 1)[0] * (len(stick) - 1)
    stick_shrinks = stick_change < -procedure.area_tolerance or stick[-1] <= procedure.area_tolerance
    return bool(falling and visible and stick_shrinks)


@dataclass
class Snapshot:
    """What the procedure needs to continue after a checkpoint (all between two cycles).

    phase_index: 0 COF phase, 1 wear phase; cycles_in_phase: cycles of it completed.
    history: the last cycles (enough for the loosening window; only the last one keeps its
    per-point fields). locked_elongation: ε_lock of the bolts (mm), or None.
    """

    cycle_number: int
    phase_index: int
    cycles_in_phase: int
    quiet_cycles: int
    equivalent: float
    nominal_area: float
    initial_clamp: float | None
    locked_elongation: np.ndarray | None
    cof_initial: np.ndarray
    state: ContactState
    equilibrium: Equilibrium
    history: list


def run(solver: ContactSolver, state: ContactState, program: LoadProgram, procedure: Procedure, *,
        cof_evolution: bool, wear: bool, observer: Observer | None = None,
        start: Equilibrium | None = None, checkpoint=None, checkpoint_every: int = 0,
        resume: Snapshot | None = None) -> RunResult:
    """Run the procedure. Effects not asked for (``cof_evolution``, ``wear``) are never computed.

    Bolts of the structure carry their pretension in the preload and are locked at their
    length before the first cycle; the clamp force is the sum of the bolt forces.
    ``checkpoint(snapshot)`` is called every ``checkpoint_every`` cycles; ``resume`` continues
    from such a snapshot. Cached factorisations are dropped at every checkpoint boundary, so a
    resumed run repeats the uninterrupted one bit for bit.
    """
    observer = observer or Observer()
    law = solver.law
    area = solver.area
    bolts = solver.space.structure.bolts

    def bolt_forces(eq):
        return None if bolts is None else bolts.forces(solver.space, eq)

    def step(amplitudes, effects, phase, cycle, t):
        nonlocal equilibrium, state
        equilibrium, state, status, stats = solver.increment(equilibrium, state, amplitudes, effects)
        observer.increment(IncrementRecord(phase, cycle, t, equilibrium, state, status, stats.iterations,
                                           stats.max_iterations, stats.cutbacks, stats.substeps,
                                           bolt_forces(equilibrium)))
        return status

    def lock(elongation):
        nonlocal bolts, solver, program
        bolts, space = bolts.lock_at(solver.space, elongation)
        solver = ContactSolver(space, law, solver.settings)

    if resume is None:
        cof_initial = state.cof.copy()
        equilibrium = start or solver.initial_equilibrium()
        observer.phase("preload", 0)
        for k in range(1, procedure.preload_increments + 1):
            step(program.preload(k / procedure.preload_increments), Effects(), "preload", 0,
                 k / procedure.preload_increments)
        if bolts is not None:
            lock(bolts.elongation(solver.space, equilibrium.control))
            equilibrium = replace(equilibrium, amplitudes=bolts.locked_amplitudes(solver.space, equilibrium))
            program = replace(program, held={p: equilibrium.amplitudes[program.patterns.index(p)]
                                             for p in bolts.patterns})
        run_up = getattr(program, "run_up", None)
        if run_up is not None:  # operating mean loads come on after the bolts are locked (engine run-up)
            for k in range(1, procedure.preload_increments + 1):
                step(run_up(k / procedure.preload_increments), Effects(), "preload", 0,
                     1.0 + k / procedure.preload_increments)
        closed = equilibrium.forces.reshape(solver.n_points, -1)[:, 0] > 0.0
        nominal_area = float(area[closed].sum())
        history: list[CycleSummary] = []
        cycle_number, first_phase, done_in_phase, quiet_cycles, equivalent = 0, 0, 0, 0, 0.0
        initial_clamp = None if bolts is None else float(bolt_forces(equilibrium).sum())
    else:
        cof_initial, state, equilibrium = resume.cof_initial, resume.state, resume.equilibrium
        nominal_area, initial_clamp, history = resume.nominal_area, resume.initial_clamp, list(resume.history)
        cycle_number, first_phase = resume.cycle_number, resume.phase_index
        done_in_phase, quiet_cycles, equivalent = resume.cycles_in_phase, resume.quiet_cycles, resume.equivalent
        if bolts is not None:
            lock(resume.locked_elongation)
    if bolts is not None:
        program = replace(program, held={p: equilibrium.amplitudes[program.patterns.index(p)]
                                         for p in bolts.patterns})

    stationary = False
    phases = [("cof", procedure.cof_cycles, Effects(cof_evolution=cof_evolution)),
              ("wear", procedure.wear_cycles if wear else 0,
               Effects(cof_evolution=cof_evolution and procedure.cof_during_wear, wear=wear,
                       cycle_jump=procedure.cycle_jump))]
    keep = max(procedure.loosening_window, 1)
    for phase_index, (phase, n_cycles, effects) in enumerate(phases):
        if phase_index < first_phase or n_cycles <= 0:
            continue
        resuming_this_phase = phase_index == first_phase and done_in_phase > 0
        start_count = done_in_phase if resuming_this_phase else 0
        if not resuming_this_phase:
            quiet_cycles = 0
        observer.phase(phase, n_cycles)
        finished = False
        for count in range(start_count, n_cycles):
            cycle_number += 1
            n_inc = procedure.increments_per_cycle
            start_slip = state.slip_vector.copy()
            low, high = start_slip.copy(), start_slip.copy()
            start_dissipation = state.dissipation.copy()
            start_cof = state.cof.copy()
            max_util = np.zeros(solver.n_points)
            max_shear = np.zeros(solver.n_points)
            worst = np.zeros(solver.n_points, dtype=np.int8)
            ever_closed = np.zeros(solver.n_points, dtype=bool)
            for k in range(1, n_inc + 1):
                status = step(program.cycle(k / n_inc), effects, phase, cycle_number,
                              cycle_number - 1 + k / n_inc)
                utilisation, shear_now = _utilisation(equilibrium, solver)
                max_util = np.maximum(max_util, utilisation)
                max_shear = np.maximum(max_shear, shear_now)
                worst = np.maximum(worst, status)
                ever_closed |= status != Status.OPEN
                low = np.minimum(low, state.slip_vector)
                high = np.maximum(high, state.slip_vector)
            equivalent += effects.cycle_jump if phase == "wear" else 1.0
            cycle_status = np.where(ever_closed, np.maximum(worst, Status.STICK), Status.OPEN).astype(np.int8)
            per_point = equilibrium.forces.reshape(solver.n_points, -1) / area[:, None]
            summary = CycleSummary(
                cycle=cycle_number, phase=phase, equivalent_cycles=equivalent,
                pressure=per_point[:, 0], shear=per_point[:, 1:], cof=state.cof.copy(),
                max_utilised_cof=max_util, max_shear=max_shear, status=cycle_status,
                slip_range=np.linalg.norm(high - low, axis=1),
                dissipation_in_cycle=state.dissipation - start_dissipation, state=state,
                clamp_force=None if bolts is None else float(bolt_forces(equilibrium).sum()))
            summary.figures = cycle_figures(area, nominal_area, cycle_status, max_util, state,
                                            cof_initial, law.cof_max, procedure.area_tolerance)
            summary.figures["active_slip_area_fraction"] = active_slip_area_fraction(
                area, nominal_area, summary.pressure, summary.dissipation_in_cycle, start_cof,
                law.critical_slip, procedure.slip_tolerance)
            summary.figures["clamp_force_N"] = summary.clamp_force
            history.append(summary)
            del history[:-keep]
            observer.cycle(summary)
            slid = summary.figures["active_slip_area_fraction"] > procedure.area_tolerance
            quiet_cycles = 0 if slid else quiet_cycles + 1
            if quiet_cycles >= procedure.stationary_window:
                stationary = True
            elif phase == "wear" and _loosening(history, procedure):
                finished = True
            if checkpoint_every and cycle_number % checkpoint_every == 0:
                solver.forget_cached_factorisations()
                if checkpoint is not None and not (stationary or finished or count + 1 == n_cycles):
                    checkpoint(Snapshot(cycle_number, phase_index, count + 1, quiet_cycles, equivalent,
                                        nominal_area, initial_clamp,
                                        None if bolts is None else bolts.locked_elongation,
                                        cof_initial, state, equilibrium, list(history)))
            if stationary or finished:
                break
        if stationary:
            break
    if not history:
        raise ValueError("the procedure has no load cycles: set cof_cycles or wear_cycles > 0")
    figures = dict(history[-1].figures)
    figures["cycles_run"] = cycle_number
    figures["equivalent_cycles"] = equivalent
    figures["nominal_contact_area"] = nominal_area
    if bolts is not None:
        final_clamp = history[-1].clamp_force
        figures["bolt_force_initial_N"] = initial_clamp
        figures["bolt_force_final_N"] = final_clamp
        figures["clamp_force_loss_fraction"] = (initial_clamp - final_clamp) / initial_clamp
    verdict = _verdict(history, procedure, stationary)
    return RunResult(verdict, stationary, figures, state, equilibrium, history)


def _utilisation(equilibrium: Equilibrium, solver: ContactSolver) -> tuple[np.ndarray, np.ndarray]:
    """Utilised COF |τ|/p and shear traction |τ| (MPa) of every point."""
    per_point = equilibrium.forces.reshape(solver.n_points, -1)
    return (utilised_cof(per_point[:, 0], per_point[:, 1:]),
            np.linalg.norm(per_point[:, 1:], axis=1) / solver.area)


__all__ = ["LoadProgram", "Procedure", "run", "Observer", "CycleSummary", "IncrementRecord",
           "RunResult", "Snapshot", "cycle_figures", "active_slip_area_fraction"]
