"""The analysis procedure of the paper's section 3: preload, COF phase, wear phase, verdict.

1. Preload: load patterns marked ``ramp`` go from 0 to full in ``preload_increments``; bolts
   are locked; a program with a run-up (:meth:`LoadProgram.run_up`: operating mean loads, e.g. a counterweight's
   centrifugal load) then ramps those in as many increments. Nothing evolves or wears here.
2. COF stabilisation: ``cof_cycles`` cycles of the cyclic patterns with COF evolution (if the
   scene asks for it) and no wear.
3. Wear: ``wear_cycles`` simulated cycles with wear (if asked), COF frozen or evolving, each
   standing for ``cycle_jump`` real cycles.
Each phase stops early once the contact is stationary: over ``stationary_window`` cycles
no more than ``area_tolerance`` of the nominal area still slid (shakedown to stick; see
:func:`contact.verdict.active_slip_area_fraction` for what counts as sliding). The wear phase
also stops when loosening is evident: the clamp force has kept falling over the window while the
stick area shrank. A run ends with its :class:`contact.verdict.Ending`; a run whose increment
fails raises :class:`RunStopped`, which carries the ending too (slid off, wear runaway, separated,
diverged). A preload that closes no contact point is an InputError before any cycle: the area
fractions refer to the area it closes, and an open contact would read as stuck.

No I/O here: every increment and cycle is handed to an observer; the pipeline writes files
and draws progress bars. Units: mm, N, MPa, mJ.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from contact.cycle_jump import AdaptiveJump, local_stiffness, next_jump, wear_rate
from contact.law import ContactState, Status, utilised_cof
from contact.solver import ContactSolver, ConvergenceError, Effects, Equilibrium
from contact.verdict import (Ending, active_slip_area_fraction, clamp_lost, clamp_still_falling, cycle_figures,
                             loosening_evident, loosening_window_blocks, verdict)
from reduction.errors import InputError

PHASES = ("preload", "cof", "wear")
HISTORY_SHAPES = ("ramp", "cyclic", "constant")


@dataclass(frozen=True)
class LoadProgram:
    """How each pattern's amplitude moves in time.

    shapes: pattern name → "ramp" (0→1 in the preload, then held), "cyclic" (0 in the
    preload, then sin 2πt per cycle) or "constant" (1 throughout).
    held: pattern → amplitude replacing 1 after the preload (locked bolt pretensions).
    A cycle's ``vibration`` ∈ [0, 1] scales what vibrates in it (the cyclic patterns; a
    tabulated history's departure from its mean) while the vibration runs up
    (:attr:`Procedure.vibration_run_up`).
    """

    patterns: tuple[str, ...]
    shapes: dict
    held: dict = field(default_factory=dict)

    def preload(self, fraction: float) -> np.ndarray:
        return np.array([fraction if self.shapes[p] == "ramp" else
                         1.0 if self.shapes[p] == "constant" else 0.0 for p in self.patterns])

    def run_up(self, fraction: float) -> np.ndarray | None:
        """Amplitudes at ``fraction`` of the run-up after the bolts are locked (operating mean
        loads coming on, e.g. an engine's centrifugal load); None: the program has no run-up."""
        return None

    def cycle(self, phase: float, vibration: float = 1.0) -> np.ndarray:
        """Amplitudes at the fraction ``phase`` ∈ [0, 1] of a load cycle, the vibration at
        ``vibration`` of its full amplitude."""
        return np.array([vibration * np.sin(2 * np.pi * phase) if self.shapes[p] == "cyclic" else
                         self.held.get(p, 1.0) for p in self.patterns])


@dataclass(frozen=True)
class Procedure:
    """Settings of the analysis procedure (counts are simulated cycles).

    area_tolerance: fraction of the nominal area that may still slide in a stuck contact.
    slip_tolerance: a point slides in a cycle when its pressure-weighted irreversible slip
    exceeds this fraction of γ_crit (see :func:`active_slip_area_fraction`).
    cycle_jump: real cycles each simulated wear cycle stands for, or "auto": chosen block by
    block (:mod:`contact.cycle_jump`) so that no point's pressure changes by more than
    ``jump_tolerance`` of the mean contact pressure in one block, at most ``max_cycle_jump``.
    life_cycles: the wear phase ends once it stands for this many real cycles.
    loosening_window: wear blocks over which loosening is judged (:func:`loosening_evident`);
    with ``loosening_window_cycles`` the least number of blocks the window holds.
    loosening_window_cycles: judge loosening over the blocks of the last this many real cycles
    (at least ``loosening_window`` blocks), so that the window means the same engine running
    time whatever the adaptive jump, which shrinks as the mesh is refined; None: over the last
    ``loosening_window`` blocks.
    cof_jump: with ``cof_during_wear``, a wear block's COF change stands for its J real cycles as
    its wear does (μ then saturates within a block wherever the contact slides, k ≫ w): the
    default, so that COF and wear stand for the same running time and the result does not
    depend on the number of blocks; False (the paper's practice with accelerated wear): the
    COF changes once per block, which makes a wear phase with the COF evolving depend on the
    jump tolerance (more blocks, more COF per real cycle).
    vibration_run_up: the first this many COF-phase cycles bring the vibration in linearly from
    0 to its full amplitude (an engine reaching the operating point, or an overload building
    up, over many cycles: the COF hardens as the vibration grows, instead of a step to full
    amplitude that can exceed the friction capacity at μ0 before the COF has risen); 0: full
    amplitude from the first cycle. Shakedown is not judged before the run-up ends.
    clamp_loss_limit: a bolted joint that has lost this fraction of its clamp force (the bolts'
    summed force after the preload) has loosened, in any phase and whatever the trend
    (:func:`contact.verdict.clamp_lost`): loosening is then evident at once.
    stop_at_loosening: end the run as soon as loosening is evident (:func:`loosening_evident`);
    False runs the wear phase on to ``life_cycles`` (or ``wear_cycles``) so that the clamp-force
    trend of a loosening joint is seen over the whole horizon; the verdict is the same.
    """

    preload_increments: int = 10
    increments_per_cycle: int = 40
    cof_cycles: int = 0
    wear_cycles: int = 0
    cycle_jump: float | str = 1.0
    jump_tolerance: float = 0.05
    max_cycle_jump: float = float("inf")
    life_cycles: float = float("inf")
    cof_during_wear: bool = True
    cof_jump: bool = True
    vibration_run_up: int = 0
    stationary_window: int = 10
    loosening_window: int = 20
    loosening_window_cycles: float | None = None
    stop_at_loosening: bool = True
    clamp_loss_limit: float = 0.5
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
    damage: dict = field(default_factory=dict)  # fretting damage fields an observer adds (pipelines.output.damage)
    #: real cycles at which loosening became evident (:func:`contact.verdict.loosening_evident`),
    #: in this cycle or earlier in the run; None while it is not: once set, the verdict is
    #: loosening unless the joint shakes down later
    loosening_evident_at: float | None = None


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
    #: ε_lock (mm) of each bolt once locked (:mod:`contact.bolts`), None before or without bolts
    locked_elongation: np.ndarray | None = None


@dataclass
class RunResult:
    """What a procedure run ends with: final state, the verdict and its figures, and why it ended."""

    verdict: str
    stationary: bool
    figures: dict
    state: ContactState
    equilibrium: Equilibrium
    cycles: list = field(default_factory=list)
    ending: Ending = Ending.COMPLETED


class RunStopped(ConvergenceError):
    """An increment of the run failed; ``ending`` says how (slid off, wear runaway, separated,
    diverged)."""

    def __init__(self, message: str, ending: Ending):
        super().__init__(message)
        self.ending = ending


def failure_ending(error: ConvergenceError) -> Ending:
    """The ending of a run whose increment raised ``error``: read from its typed cause."""
    return {"slid_off": Ending.SLID_OFF, "wear_runaway": Ending.WEAR_RUNAWAY,
            "separated": Ending.SEPARATED}.get(error.cause, Ending.DIVERGED)


class Observer:
    """Receives increments and cycles; the default does nothing. Pipelines subclass it."""

    def increment(self, record: IncrementRecord) -> None:
        pass

    def cycle(self, summary: CycleSummary) -> None:
        pass

    def phase(self, name: str, n_cycles: int) -> None:
        pass


@dataclass
class Snapshot:
    """What the procedure needs to continue after a checkpoint (all between two cycles).

    phase_index: 0 COF phase, 1 wear phase; cycles_in_phase: cycles of it completed.
    history: the last cycles (enough for the loosening window; only the last one keeps its
    per-point fields). locked_elongation: ε_lock of the bolts (mm), or None.
    predictors: the solver's cyclic predictors (:meth:`contact.solver.ContactSolver.predictor_memory`).
    linear: its linear solver's kept preconditioners (:meth:`contact.solver.ContactSolver.linear_memory`).
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
    jump: float = 1.0
    loosening_at: float | None = None
    predictors: dict = field(default_factory=dict)
    linear: dict = field(default_factory=dict)


class _Run:
    """The state a run carries from increment to increment: solver, bolts, program, contact
    state and equilibrium, and the bookkeeping of cycles and phases (:func:`run`)."""

    def __init__(self, solver, state, program, procedure, observer):
        self.solver, self.state, self.program, self.procedure = solver, state, program, procedure
        self.observer = observer
        self.bolts = solver.space.structure.bolts
        self.equilibrium = None
        self.history: list[CycleSummary] = []
        self.cycle_number, self.first_phase, self.done_in_phase, self.quiet_cycles = 0, 0, 0, 0
        self.equivalent, self.nominal_area, self.initial_clamp, self.cof_initial = 0.0, 0.0, None, None
        self.stationary = False
        self.adaptive = procedure.cycle_jump == "auto"
        self.jump_settings = AdaptiveJump(tolerance=procedure.jump_tolerance, maximum=procedure.max_cycle_jump)
        self.jump = self.jump_settings.initial if self.adaptive else float(procedure.cycle_jump)
        self._local_stiffness = None
        self.loosening_at: float | None = None  # real cycles when loosening first became evident

    def bolt_forces(self):
        return None if self.bolts is None else self.bolts.forces(self.solver.space, self.equilibrium)

    def clamp_force(self):
        return None if self.bolts is None else float(self.bolt_forces().sum())

    def step(self, amplitudes, effects, phase, cycle, t, position=None):
        """One load increment (``position``: its (k, n) in a load cycle); the observer sees it.
        Returns the point status."""
        self.equilibrium, self.state, status, stats = self.solver.increment(self.equilibrium, self.state,
                                                                           amplitudes, effects, position)
        self.observer.increment(IncrementRecord(phase, cycle, t, self.equilibrium, self.state, status,
                                                stats.iterations, stats.max_iterations, stats.cutbacks,
                                                stats.substeps, self.bolt_forces(),
                                                None if self.bolts is None else self.bolts.locked_elongation))
        return status

    def lock(self, elongation):
        """Lock the bolts at ``elongation`` (mm): the solver works on the locked structure from now on."""
        self.bolts, space = self.bolts.lock_at(self.solver.space, elongation)
        self.solver = ContactSolver(space, self.solver.law, self.solver.settings)

    def hold_bolt_amplitudes(self):
        if self.bolts is not None:
            self.program = replace(self.program, held={p: self.equilibrium.amplitudes[self.program.patterns.index(p)]
                                                       for p in self.bolts.patterns})

    def preload(self, start):
        """Pretension and static loads, bolts locked, then the operating mean loads (run-up)."""
        n = self.procedure.preload_increments
        self.cof_initial = self.state.cof.copy()
        self.equilibrium = start or self.solver.initial_equilibrium()
        self.observer.phase("preload", 0)
        for k in range(1, n + 1):
            self.step(self.program.preload(k / n), Effects(), "preload", 0, k / n)
        if self.bolts is not None:
            self.lock(self.bolts.elongation(self.solver.space, self.equilibrium.control))
            self.equilibrium = replace(self.equilibrium,
                                       amplitudes=self.bolts.locked_amplitudes(self.solver.space, self.equilibrium))
            self.hold_bolt_amplitudes()
        for k in range(1, n + 1):  # operating mean loads come on after the bolts are locked
            amplitudes = self.program.run_up(k / n)
            if amplitudes is None:
                break
            self.step(amplitudes, Effects(), "preload", 0, 1.0 + k / n)
        closed = self.equilibrium.forces.reshape(self.solver.n_points, -1)[:, 0] > 0.0
        self.nominal_area = float(self.solver.area[closed].sum())
        if self.nominal_area == 0.0:
            raise InputError(_nothing_pressed(self.solver.space.structure.initial_overclosure))
        self.initial_clamp = self.clamp_force()

    def resume(self, snapshot: Snapshot):
        """Continue after a checkpoint: the state between two cycles."""
        self.cof_initial, self.state, self.equilibrium = snapshot.cof_initial, snapshot.state, snapshot.equilibrium
        self.nominal_area, self.initial_clamp = snapshot.nominal_area, snapshot.initial_clamp
        self.history = list(snapshot.history)
        self.cycle_number, self.first_phase = snapshot.cycle_number, snapshot.phase_index
        self.done_in_phase, self.quiet_cycles = snapshot.cycles_in_phase, snapshot.quiet_cycles
        self.equivalent, self.jump = snapshot.equivalent, snapshot.jump
        self.loosening_at = snapshot.loosening_at
        if self.bolts is not None:
            self.lock(snapshot.locked_elongation)
        self.solver.recall_predictors(snapshot.predictors)
        self.solver.recall_linear(snapshot.linear)

    def cycle(self, phase: str, effects: Effects) -> CycleSummary:
        """One load cycle of ``increments_per_cycle`` increments and its summary."""
        solver, n_inc = self.solver, self.procedure.increments_per_cycle
        self.cycle_number += 1
        start_slip = self.state.slip_vector.copy()
        low, high = start_slip.copy(), start_slip.copy()
        start_dissipation, start_cof = self.state.dissipation.copy(), self.state.cof.copy()
        max_util, max_shear = np.zeros(solver.n_points), np.zeros(solver.n_points)
        worst = np.zeros(solver.n_points, dtype=np.int8)
        ever_closed = np.zeros(solver.n_points, dtype=bool)
        for k in range(1, n_inc + 1):
            t = self.cycle_number - 1 + k / n_inc
            status = self.step(self.program.cycle(k / n_inc, self.vibration(phase, t)), effects, phase,
                               self.cycle_number, t, (k, n_inc))
            utilisation, shear_now = _utilisation(self.equilibrium, solver)
            max_util, max_shear = np.maximum(max_util, utilisation), np.maximum(max_shear, shear_now)
            worst = np.maximum(worst, status)
            ever_closed |= status != Status.OPEN
            low, high = np.minimum(low, self.state.slip_vector), np.maximum(high, self.state.slip_vector)
        self.equivalent += effects.cycle_jump if phase == "wear" else 1.0
        cycle_status = np.where(ever_closed, np.maximum(worst, Status.STICK), Status.OPEN).astype(np.int8)
        per_point = self.equilibrium.forces.reshape(solver.n_points, -1) / solver.area[:, None]
        summary = CycleSummary(
            cycle=self.cycle_number, phase=phase, equivalent_cycles=self.equivalent,
            pressure=per_point[:, 0], shear=per_point[:, 1:], cof=self.state.cof.copy(),
            max_utilised_cof=max_util, max_shear=max_shear, status=cycle_status,
            slip_range=np.linalg.norm(high - low, axis=1),
            dissipation_in_cycle=self.state.dissipation - start_dissipation, state=self.state,
            clamp_force=self.clamp_force())
        law = solver.law
        # finite sliding: the master's wear lives on its own surface (contact.sliding)
        master_wear = getattr(self.state, "master_wear", None)
        summary.figures = cycle_figures(solver.area, self.nominal_area, cycle_status, max_util, self.state,
                                        self.cof_initial, law.cof_max, self.procedure.area_tolerance,
                                        master_wear=master_wear,
                                        master_area=None if master_wear is None else solver.pairing.master.area)
        summary.figures["active_slip_area_fraction"] = active_slip_area_fraction(
            solver.area, self.nominal_area, summary.pressure, summary.dissipation_in_cycle, start_cof,
            law.critical_slip, self.procedure.slip_tolerance)
        summary.figures["clamp_force_N"] = summary.clamp_force
        return summary

    def vibration(self, phase: str, t: float) -> float:
        """The vibration's fraction of its full amplitude at cycle time ``t`` (cycles since the
        preload) of ``phase``: it runs up linearly over the first ``vibration_run_up`` cycles."""
        run_up = self.procedure.vibration_run_up
        return 1.0 if phase != "cof" or run_up <= 0 else min(1.0, t / run_up)

    def phase(self, phase_index, phase, n_cycles, effects, checkpoint, checkpoint_every, last=True) -> bool:
        """Run the cycles of one phase; True when the run stops early (shakedown or loosening).
        last: no phase follows it, so its last cycle writes no checkpoint (the run ends there);
        the last cycle of an earlier phase does (a run interrupted in the wear phase resumed
        from the COF phase's last checkpoint before it, up to a whole phase lost; QA, 2026-11-28)."""
        resuming = phase_index == self.first_phase and self.done_in_phase > 0
        if not resuming:
            self.quiet_cycles = 0
        self.observer.phase(phase, n_cycles)
        for count in range(self.done_in_phase if resuming else 0, n_cycles):
            if phase == "wear":
                if self.equivalent >= self.procedure.life_cycles:
                    return False
                effects = replace(effects, cycle_jump=min(self.jump, self.procedure.life_cycles - self.equivalent))
                worn_before = np.array(self.state.gap, copy=True)
            summary = self.cycle(phase, effects)
            if phase == "wear" and self.adaptive:
                self.jump = self.next_jump(self.state.gap - worn_before, summary, effects.cycle_jump)
            self.history.append(summary)
            del self.history[:-max(loosening_window_blocks(self.history, self.procedure),
                                   self.procedure.stationary_window + 1)]
            slid = summary.figures["active_slip_area_fraction"] > self.procedure.area_tolerance
            running_up = self.vibration(phase, self.cycle_number - 1) < 1.0  # began below full amplitude
            self.quiet_cycles = 0 if slid or running_up else self.quiet_cycles + 1
            loosening = False
            if clamp_lost(summary.clamp_force, self.initial_clamp, self.procedure):
                loosening = self.procedure.stop_at_loosening  # nothing pressed slides: never a shakedown
                if self.loosening_at is None:
                    self.loosening_at = self.equivalent
            elif self.quiet_cycles >= self.procedure.stationary_window:
                self.stationary = True
            elif phase == "wear" and loosening_evident(self.history, self.procedure):
                loosening = self.procedure.stop_at_loosening
                if self.loosening_at is None:
                    self.loosening_at = self.equivalent
            summary.loosening_evident_at = self.loosening_at
            self.observer.cycle(summary)
            if checkpoint_every and self.cycle_number % checkpoint_every == 0:
                self.solver.at_checkpoint()
                if checkpoint is not None and not (self.stationary or loosening or (last and count + 1 == n_cycles)):
                    checkpoint(self.snapshot(phase_index, count + 1))
            if self.stationary or loosening:
                return True
        return False

    def next_jump(self, worn: np.ndarray, summary: CycleSummary, jump: float) -> float:
        """The jump of the next block from the wear ``worn`` (mm) this one of ``jump`` added."""
        area = self.solver.area
        mean_pressure = float(np.sum(summary.pressure * area) / self.nominal_area) if self.nominal_area else 0.0
        return next_jump(wear_rate(worn, jump), mean_pressure, self.local_stiffness(), jump, self.jump_settings)

    def local_stiffness(self) -> np.ndarray:
        """Pressure per mm of gap of each point alone (N/mm³): the penalty kn in series with the
        bodies' own compliance there, 1/(1/kn + W_ii·A_i) (W's normal diagonal, mm/N)."""
        if self._local_stiffness is None:
            self._local_stiffness = local_stiffness(self.solver.space.normal_compliance(), self.solver.area,
                                                    self.solver.law.normal_stiffness)
        return self._local_stiffness

    def stuck_since(self) -> float:
        """Real cycles after which the contact no longer slid: the end of the cycle before the
        quiet window that made it stationary (the window only confirms it, and with an adaptive
        jump its blocks grow twofold each, so its end would overstate the time to shakedown
        about a thousandfold)."""
        window = self.procedure.stationary_window
        return self.history[-window - 1].equivalent_cycles if len(self.history) > window else 0.0

    def snapshot(self, phase_index, cycles_in_phase) -> Snapshot:
        return Snapshot(self.cycle_number, phase_index, cycles_in_phase, self.quiet_cycles, self.equivalent,
                        self.nominal_area, self.initial_clamp,
                        None if self.bolts is None else self.bolts.locked_elongation,
                        self.cof_initial, self.state, self.equilibrium, list(self.history), self.jump,
                        self.loosening_at, self.solver.predictor_memory(), self.solver.linear_memory())

    def result(self, stopped_early: bool) -> RunResult:
        if not self.history:
            raise ValueError("the procedure has no load cycles: set cof_cycles or wear_cycles > 0")
        figures = dict(self.history[-1].figures)
        figures["cycles_run"] = self.cycle_number
        figures["equivalent_cycles"] = self.equivalent
        figures["nominal_contact_area"] = self.nominal_area
        if np.isfinite(self.procedure.life_cycles):
            figures["life_cycles"] = float(self.procedure.life_cycles)
        if self.stationary:
            figures["shakedown_at_cycles"] = self.stuck_since()
        if self.loosening_at is not None:
            figures["loosening_evident_at_cycles"] = self.loosening_at
        if self.bolts is not None:
            final_clamp = self.history[-1].clamp_force
            figures["bolt_force_initial_N"] = self.initial_clamp
            figures["bolt_force_final_N"] = final_clamp
            figures["clamp_force_loss_fraction"] = (self.initial_clamp - final_clamp) / self.initial_clamp
        ending = (Ending.SHAKEDOWN if self.stationary else Ending.LOOSENING if stopped_early else Ending.COMPLETED)
        said = verdict(self.history, self.procedure, self.stationary, loosened_before=self.loosening_at is not None,
                       lost_clamp=clamp_lost(self.history[-1].clamp_force, self.initial_clamp, self.procedure))
        if said != "loosening" and self.bolts is not None:
            figures.update(clamp_still_falling(self.history, self.procedure, self.initial_clamp))
        return RunResult(said, self.stationary, figures, self.state, self.equilibrium, self.history, ending)


def run(solver: ContactSolver, state: ContactState, program: LoadProgram, procedure: Procedure, *,
        cof_evolution: bool, wear: bool, observer: Observer | None = None,
        start: Equilibrium | None = None, checkpoint=None, checkpoint_every: int = 0,
        resume: Snapshot | None = None) -> RunResult:
    """Run the procedure. Effects not asked for (``cof_evolution``, ``wear``) are never computed.

    Bolts of the structure carry their pretension in the preload and are locked at their
    length before the first cycle; the clamp force is the sum of the bolt forces.
    ``checkpoint(snapshot)`` is called every ``checkpoint_every`` cycles; ``resume`` continues
    from such a snapshot. Cached factorisations are dropped at every checkpoint boundary, so a
    resumed run repeats the uninterrupted one bit for bit. Raises :class:`RunStopped` (a
    ConvergenceError with its :class:`Ending`) when an increment fails.
    """
    current = _Run(solver, state, program, procedure, observer or Observer())
    try:
        if resume is None:
            current.preload(start)
        else:
            current.resume(resume)
        current.hold_bolt_amplitudes()
        phases = [("cof", procedure.cof_cycles, Effects(cof_evolution=cof_evolution)),
                  ("wear", procedure.wear_cycles if wear else 0,
                   Effects(cof_evolution=cof_evolution and procedure.cof_during_wear, wear=wear,
                           cycle_jump=current.jump, cof_jump=procedure.cof_jump))]
        stopped_early = False
        for phase_index, (phase, n_cycles, effects) in enumerate(phases):
            if phase_index < current.first_phase or n_cycles <= 0:
                continue
            last = not any(n > 0 for _, n, _ in phases[phase_index + 1:])
            stopped_early = current.phase(phase_index, phase, n_cycles, effects, checkpoint, checkpoint_every, last)
            if current.stationary or stopped_early:  # a lost clamp stops the COF phase too
                break
    except RunStopped:
        raise
    except ConvergenceError as error:
        raise RunStopped(str(error), failure_ending(error)) from error
    return current.result(stopped_early)


def _nothing_pressed(overclosure: np.ndarray) -> str:
    """Why a run whose preload closed no contact point is refused, with the initial gap (mm)."""
    gap = -float(np.max(overclosure, initial=-np.inf))
    where = (f"the surfaces start {gap:.3g} mm apart at their closest" if gap > 0.0 else
             "the surfaces touch at the start but nothing holds them together")
    return ("nothing presses the contact surfaces together after the preload: no contact point is closed "
            f"(nominal contact area 0; {where}), and a run on an open contact would read as stuck; check the "
            "loads (a normal load with history = \"ramp\" or \"constant\" acts in the preload, a \"cyclic\" one "
            "does not), the bolts and their pretension, and the initial gap")


def _utilisation(equilibrium: Equilibrium, solver: ContactSolver) -> tuple[np.ndarray, np.ndarray]:
    """Utilised COF |τ|/p and shear traction |τ| (MPa) of every point."""
    per_point = equilibrium.forces.reshape(solver.n_points, -1)
    return (utilised_cof(per_point[:, 0], per_point[:, 1:]),
            np.linalg.norm(per_point[:, 1:], axis=1) / solver.area)


__all__ = ["LoadProgram", "Procedure", "run", "Observer", "CycleSummary", "IncrementRecord",
           "RunResult", "RunStopped", "Snapshot", "failure_ending"]
