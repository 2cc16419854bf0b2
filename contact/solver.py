"""Incremental Newton solution of the contact problem in contact space.

Unknowns are the contact kinematics ``g`` and the free control DOFs ``q`` of a
:class:`contact.structure.ContactSpace`. Each increment is solved by Newton with the
consistent, unsymmetric tangent of :mod:`contact.law`, reduced to the closed points (open
points carry no force, so their rows decouple), with a backtracking line search; an
increment that does not converge, or whose wear exceeds the cap, is cut back and re-solved
in sub-steps. History variables advance only from converged sub-steps.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from contact.law import (ContactLaw, ContactState, Response, Status, advance, evaluate,
                         wear_increment)
from contact.linear import KrylovSettings, NewtonLinearSolver, tangent_blocks
from contact.structure import ContactSpace
from reduction.threads import blas_threads


class ConvergenceError(RuntimeError):
    """An increment did not converge within the allowed cutbacks; the message says why.

    cause: the reason, for code to read: "slid_off" (tangential equilibrium lost: the load
    exceeds what friction can carry), "wear_runaway" (the wear increment does not shrink with
    the step) or "diverged" (anything else).
    """

    def __init__(self, message: str, cause: str = "diverged"):
        super().__init__(message)
        self.cause = cause


@dataclass(frozen=True)
class NewtonSettings:
    """Iteration controls.

    max_iterations: Newton iterations per attempt before a cutback.
    max_cutbacks: how many times a sub-step may be halved (smallest: 2^-max_cutbacks
        of the increment).
    displacement_tolerance: converged when the kinematic residual is below this (mm) ...
    force_tolerance: ... and the control-DOF force residual below this fraction of the
        force scale.
    wear_cap: largest wear depth increment (mm) one sub-step may add (explicit wear
        integration); larger increments are cut back.
    linear: how the Newton corrections are solved (:class:`contact.linear.KrylovSettings`).
    line_search_window: a sub-step whose Newton iteration fails with the monotone
        backtracking line search is tried again, before any cutback, with a non-monotone one
        that accepts a step when it lowers the largest merit of this many last iterates (1:
        no second try). With a stiff elastic stick (γ_crit of 0.001 µm) a full step moves
        whole rings of points between stick and slip at once and raises the merit for an
        iteration or two before it falls quadratically; the monotone search cuts those steps
        to slivers and Newton crawls a ring per iteration (150 iterations for a
        sphere-on-flat step). When the window passes without the merit halving (points
        cycling between stick and slip), steps stop just past the first status change until
        it does. The monotone search comes first because elsewhere (the counterweight's wear
        phase) the non-monotone one can reach another of the non-unique frictional
        equilibria, from which explicit wear then runs away.
    blas_threads: BLAS threads inside an increment. One: the contact matrices are small
        enough (a 4,500-row LU in 0.8 s) that a second thread gains little on two cores and
        loses much when they are shared (tiny products spin-wait for a busy core), and the
        results then do not depend on the machine's thread settings.
    """

    max_iterations: int = 30
    max_cutbacks: int = 10
    displacement_tolerance: float = 1e-10
    force_tolerance: float = 1e-9
    wear_cap: float = np.inf
    linear: KrylovSettings = field(default_factory=KrylovSettings)
    line_search_window: int = 5
    blas_threads: int = 1


@dataclass(frozen=True)
class Effects:
    """The history effects a scene asks for; what is off is not computed."""

    cof_evolution: bool = False
    wear: bool = False
    cycle_jump: float = 1.0
    cof_jump: bool = False  # the COF's change scaled by cycle_jump too (Procedure.cof_jump)


@dataclass(frozen=True)
class Equilibrium:
    """A converged configuration.

    kinematics: g (n_rows,) mm, relative to h₀.  control: q (n_control,) mm.
    forces: λ (n_rows,) N, nodal contact forces [A·p, A·τ] per point.
    amplitudes: the pattern amplitudes it was solved for.
    """

    kinematics: np.ndarray
    control: np.ndarray
    forces: np.ndarray
    amplitudes: np.ndarray


@dataclass
class IncrementStats:
    """Counters of one increment, for benchmarks and stability tests."""

    iterations: int = 0
    max_iterations: int = 0
    cutbacks: int = 0
    substeps: int = 0


def _load_step(start: np.ndarray | None, target: np.ndarray) -> tuple:
    """The key of a load step: where it starts and where it ends (``start`` None: the load
    level ``target`` however it was reached). The level alone does not name a point of a
    cycle: a harmonic load passes every level twice, rising and falling, and with friction
    the two equilibria differ."""
    end = np.asarray(target, dtype=float).tobytes()
    return ("level", end) if start is None else ("step", np.asarray(start, dtype=float).tobytes(), end)


def _cycle_step(position: tuple[int, int]) -> tuple:
    """The key of the k-th of n increments of a load cycle, whatever its amplitudes: the same
    point of successive cycles also while the vibration runs up or the COF evolves."""
    k, n = position
    return ("position", int(k), int(n))


def _extrapolation_factor(before_gap, earlier_gap, gap) -> float:
    """How far to extrapolate two equilibria solved at the same load of successive cycles to
    the current one: the wear gap's change since the later one, in units of its change
    between the two (projected: fields r, mm, or 0 without wear); 1 (the same step as
    between the two) where the gap has not changed, e.g. while only the COF evolves."""
    last = np.asarray(earlier_gap) - np.asarray(before_gap)
    norm = float(np.vdot(last, last))
    if norm == 0.0:
        return 1.0
    return float(np.clip(np.vdot(np.asarray(gap) - np.asarray(earlier_gap), last) / norm, 0.0, 4.0))


def _rigid_modes(space: ContactSpace, stiffness_scale: float) -> np.ndarray:
    """Orthonormal rigid-body motions of the free control DOFs, (n_control, k).

    These are the directions in which a body is held by the contact alone (S_q singular,
    e.g. a cylinder under force control). Other control DOFs (surface nodes outside the
    pairing, supported bodies) have an equilibrium of their own when every point is open.
    """
    if space.n_control == 0:
        return np.zeros((0, 0))
    values, vectors = np.linalg.eigh(space.Sq)
    return vectors[:, values <= 1e-8 * stiffness_scale]


class ContactSolver:
    """Owns the Newton iteration for one :class:`ContactSpace` and one :class:`ContactLaw`.

    linear: the solver of the Newton corrections; it keeps factorisations between calls, so
    it belongs to this solver alone. Default: one built from ``settings.linear``.
    """

    def __init__(self, space: ContactSpace, law: ContactLaw, settings: NewtonSettings = NewtonSettings(),
                 linear: NewtonLinearSolver | None = None):
        self.space = space
        self.law = law
        self.settings = settings
        self.linear = linear if linear is not None else space.linear_solver(settings.linear)
        structure = space.structure
        self.dim = structure.dim
        self.n_points = structure.n_points
        self.area = structure.area
        self.h0 = structure.initial_overclosure
        self.stiffness_scale = space.stiffness_scale  # N/mm
        self.rigid_modes = _rigid_modes(space, self.stiffness_scale)
        self._last_failure = None  # (response, r_ctl, force scale, loaded, f_q, μ) of the last failed attempt
        self._last_compliance = None  # (λ, W·λ) of the last residual
        self._solved_at: dict[tuple, tuple] = {}  # the last equilibria at each load step and level (cyclic predictors)
        # S_q without the round-off stiffness (~1e-8 N/mm) of the rigid modes: left in, it
        # would let a body loaded beyond the friction limit find a spurious equilibrium
        # kilometres away instead of reporting the loss of tangential equilibrium.
        self.control_stiffness = space.Sq - self.rigid_modes @ (self.rigid_modes.T @ space.Sq
                                                                @ self.rigid_modes) @ self.rigid_modes.T

    @cached_property
    def _mode_images(self) -> np.ndarray:
        """(n_points, dim, k): what each rigid mode of the free control DOFs moves each point by
        (E·modes, normal then tangential rows), for the contact search and the friction check."""
        return (self.space.E @ self.rigid_modes).reshape(self.n_points, self.dim, self.rigid_modes.shape[1])

    def forget_cached_factorisations(self) -> None:
        """Drop the factorisations the linear solver keeps across increments (at a checkpoint,
        those it cannot store: :meth:`at_checkpoint`). The cyclic predictors stay."""
        self.linear = self.space.linear_solver(self.linear.settings)
        self._last_compliance = None

    def at_checkpoint(self) -> None:
        """A checkpoint boundary: go on from a state a resumed run can take up again. A linear
        solver that can store what it keeps (:meth:`linear_memory`: the dense Krylov path's
        preconditioners, as the tangents they were formed at) keeps it; one that cannot drops
        its factorisations, as a resumed run starts without them."""
        if hasattr(self.linear, "memory"):
            self._last_compliance = None
        else:
            self.forget_cached_factorisations()

    def linear_memory(self) -> dict[str, np.ndarray]:
        """What the linear solver keeps across increments, as arrays for a checkpoint ({} if
        it cannot store it)."""
        return self.linear.memory() if hasattr(self.linear, "memory") else {}

    def recall_linear(self, memory: dict[str, np.ndarray]) -> None:
        """Take up a :meth:`linear_memory` (a resumed run). The factors are formed again with
        as many BLAS threads as an increment forms them with: their digits depend on it."""
        if memory:
            with blas_threads(self.settings.blas_threads):
                self.linear.recall(memory)

    def predictor_memory(self) -> dict[str, np.ndarray]:
        """The cyclic predictors' memory as arrays, for a checkpoint (:meth:`recall_predictors`).

        Each distinct remembered equilibrium once (``kinematics``, ``control``, ``forces``,
        ``amplitudes``, ``gap``: stacked), and per key in memory order its ``start`` and ``end``
        amplitudes (``start`` NaN for a load level; both NaN for a point of the cycle), its
        ``position`` in the cycle (k, n; −1 for a load step or level) and the indices of its
        last and earlier equilibria (``before`` −1 for none)."""
        solved, index = [], {}
        def number(entry) -> int:
            if entry[0] is None:
                return -1
            if id(entry[0]) not in index:
                index[id(entry[0])] = len(solved)
                solved.append(entry)
            return index[id(entry[0])]
        n_patterns = len(self.space.structure.patterns)
        starts, ends, positions, last, before = [], [], [], [], []
        nothing = np.full(n_patterns, np.nan)
        for key, (latest, earlier) in self._solved_at.items():
            kind, *rest = key
            if kind == "position":
                starts.append(nothing)
                ends.append(nothing)
                positions.append(rest)
            else:
                positions.append((-1, -1))
                starts.append(np.frombuffer(rest[0], dtype=float) if kind == "step" else nothing)
                ends.append(np.frombuffer(rest[-1], dtype=float))
            last.append(number(latest))
            before.append(number(earlier))
        if not solved:
            return {}
        memory = {name: np.stack([getattr(e, name) for e, _ in solved])
                  for name in ("kinematics", "control", "forces", "amplitudes")}
        shape = max((np.shape(gap) for _, gap in solved), key=len)  # a scalar 0 before any wear
        memory.update(gap=np.stack([np.broadcast_to(gap, shape) for _, gap in solved]),
                      start=np.array(starts).reshape(len(starts), n_patterns),
                      end=np.array(ends).reshape(len(ends), n_patterns),
                      position=np.array(positions, dtype=int).reshape(len(positions), 2),
                      last=np.array(last), before=np.array(before))
        return memory

    def recall_predictors(self, memory: dict[str, np.ndarray]) -> None:
        """Take up a memory written by :meth:`predictor_memory` (a resumed run)."""
        self._solved_at = {}
        if not memory:
            return
        solved = [(Equilibrium(*(memory[name][k] for name in ("kinematics", "control", "forces", "amplitudes"))),
                   memory["gap"][k]) for k in range(memory["kinematics"].shape[0])]
        # a checkpoint written before cycle positions were keys has none
        positions = memory.get("position", np.full((len(memory["last"]), 2), -1))
        for start, end, position, last, before in zip(memory["start"], memory["end"], positions,
                                                       memory["last"], memory["before"]):
            if position[0] >= 0:
                key = _cycle_step(position)
            else:
                key = _load_step(None if np.all(np.isnan(start)) else start, end)
            self._solved_at[key] = (solved[last], solved[before] if before >= 0 else (None, None))

    def initial_equilibrium(self) -> Equilibrium:
        n_patterns = len(self.space.structure.patterns)
        return Equilibrium(np.zeros(self.space.n_rows), np.zeros(self.space.n_control),
                           np.zeros(self.space.n_rows), np.zeros(n_patterns))

    def _split(self, kinematics: np.ndarray, reference: np.ndarray):
        per_point = kinematics.reshape(self.n_points, self.dim)
        overclosure = self.h0 + per_point[:, 0]
        slip_increment = per_point[:, 1:] - reference.reshape(self.n_points, self.dim)[:, 1:]
        return overclosure, slip_increment

    def _forces(self, response: Response) -> np.ndarray:
        traction = np.concatenate([response.pressure[:, None], response.shear], axis=1)
        return (self.area[:, None] * traction).ravel()

    def _compliance_times(self, forces: np.ndarray) -> np.ndarray:
        """W·λ (mm), updated from the last product where only a few forces changed.

        The first residual of an increment (the stay-put predictor) differs from the last
        converged forces only where the history advanced, so one pass over W is saved per
        increment. W is symmetric: rows are read instead of strided columns.
        """
        last = self._last_compliance
        if last is not None:
            changed = np.flatnonzero(forces != last[0])
            if changed.size < 0.2 * forces.size:
                product = last[1] + self.space.compliance_of_change(changed, forces[changed] - last[0][changed])
                self._last_compliance = (forces, product)
                return product
        product = self.space.compliance(forces)
        self._last_compliance = (forces, product)
        return product

    def _residual(self, g, q, state, reference, g_f, f_q):
        response = evaluate(*self._split(g, reference), state, self.law)
        forces = self._forces(response)
        r_kin = g - g_f + self.space.E @ q + self._compliance_times(forces)
        r_ctl = self.control_stiffness @ q - self.space.E.T @ forces - f_q
        return r_kin, r_ctl, response, forces

    def _converged(self, r_kin, r_ctl, force_scale) -> bool:
        ok = np.max(np.abs(r_kin), initial=0.0) <= self.settings.displacement_tolerance
        return ok and np.max(np.abs(r_ctl), initial=0.0) <= self.settings.force_tolerance * force_scale

    def _merit(self, r_kin, r_ctl, force_scale) -> float:
        return float(np.sqrt(np.sum((r_kin / self.settings.displacement_tolerance) ** 2)
                             + np.sum((r_ctl / (self.settings.force_tolerance * force_scale)) ** 2)))

    def _newton_step(self, response: Response, g, state: ContactState, r_kin, r_ctl, loaded: bool,
                     settled: bool = False):
        """Solve J·[Δg, Δq] = −[r_kin, r_ctl] for the current consistent tangent.

        With no point pressed (p > 0) a body held by the contact alone has a singular J: an
        open interface has no stiffness, and points that just touch (flat blocks placed
        face to face) have the normal one but no tangential one. If a load acts along such
        a rigid mode (``loaded``) the body must be brought into contact: the points nearest
        to contact get the penalty stiffness, normal and tangential, in the tangent only,
        so the step carries the body into contact without sliding it (a tangentially free
        body would otherwise be moved arbitrarily far along its singular rigid modes and
        land with every point sliding); the residual stays exact, so the converged answer
        does too. If no load acts along them and every point is open, the exact step is
        taken with no motion along the rigid modes (the body stays where it is).
        """
        blocks = tangent_blocks(response, self.area)
        unpressed = not np.any(response.pressure > 0.0) and self.rigid_modes.shape[1] > 0
        if unpressed and not loaded and not np.any(blocks):
            return (*self._open_step(r_kin, r_ctl), False)
        searching = unpressed
        if searching:
            penetration = self.h0 + g.reshape(self.n_points, self.dim)[:, 0] - state.gap
            nearest = self._search_points(penetration)
            kn = np.broadcast_to(self.law.normal_stiffness, penetration.shape)
            penalty = kn[nearest] * self.area[nearest]
            blocks[nearest] = penalty[:, None, None] * np.eye(self.dim)
        # The next step should be the last within a few decades of the tolerance, or once the
        # status of every point is that of the last iterate (``settled``): the law is linear
        # between status changes, so an exact step lands on the equilibrium, while one solved
        # to the loose Krylov tolerance gains only its three decades (one more Newton
        # iteration, a residual and a solve, for every three decades left).
        final = settled or np.max(np.abs(r_kin), initial=0.0) <= 1e3 * self.settings.displacement_tolerance
        return (*self.linear.solve(blocks, r_kin, r_ctl, final), searching)

    def _search_points(self, penetration: np.ndarray) -> np.ndarray:
        """The points a contact-search step gives the penalty stiffness (mask, n_points): those
        nearest to contact (within 1e-9 mm of the nearest), and then the next nearest in
        turn until together they hold every rigid mode the whole interface holds.

        One point, or one line of points, does not hold a body in 3D: the body is free to
        turn about it, the search step is singular along that turn, and its Newton step is
        round-off (10⁸ mm). Flat faces that start just touching have every point nearest;
        but a body load that bends the loose body away from the joint (a counterweight's
        centrifugal load, ramped in with the bolt pretension) opens them unevenly in the
        drive-following predictor, one point is left nearest, and every cut-back sub-step
        scales the bending without changing which point that is."""
        nearest = penetration >= penetration.max() - 1e-9
        images = self._mode_images
        order = np.argsort(-penetration, kind="stable")
        held = np.cumsum(np.einsum("pdi,pdj->pij", images[order], images[order]), axis=0)
        # the rank of the modes' images on the first k points, k = 1 … n (Gram eigenvalues)
        eigenvalues = np.linalg.eigvalsh(held)
        ranks = np.sum(eigenvalues > 1e-12 * eigenvalues[-1, -1], axis=1)
        enough = int(np.argmax(ranks == ranks[-1])) + 1
        if enough <= nearest.sum():
            return nearest
        chosen = np.zeros(self.n_points, dtype=bool)
        chosen[order[:enough]] = True
        return chosen

    def _first_kink(self, g, delta_g, state: ContactState, reference) -> float:
        """Fraction of the step g → g + Δg at which the first point opens, closes or crosses
        the stick limit |γ_tr| = γ_crit (just past it), or 1 if none does."""
        penetration, slip = self._split(g, reference)
        penetration = penetration - state.gap
        change = delta_g.reshape(self.n_points, self.dim)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            contact = np.where(penetration * (penetration + change[:, 0]) < 0.0,
                               -penetration / change[:, 0], np.inf)
            a = state.elastic_slip + slip
            b = change[:, 1:]
            bb, ab = np.einsum("ij,ij->i", b, b), np.einsum("ij,ij->i", a, b)
            cc = np.einsum("ij,ij->i", a, a) - np.broadcast_to(self.law.critical_slip, penetration.shape) ** 2
            root = np.sqrt(ab * ab - bb * cc)
            candidates = np.stack([(-ab - root) / bb, (-ab + root) / bb])
            candidates = np.where((candidates > 0.0) & (penetration > 0.0), candidates, np.inf)
        first = float(min(contact.min(initial=np.inf), np.nanmin(candidates, initial=np.inf)))
        return min(1.0, 1.001 * first) if first > 1e-6 else 1.0

    def _open_step(self, r_kin, r_ctl):
        """Exact Newton step with every point open: S_q·Δq = −r_ctl off the rigid modes."""
        modes = self.rigid_modes
        delta_q = np.linalg.solve(self.control_stiffness + self.stiffness_scale * modes @ modes.T, -r_ctl)
        delta_q -= modes @ (modes.T @ delta_q)
        return -r_kin - self.space.E @ delta_q, delta_q

    def _solve_to(self, start: Equilibrium, state: ContactState, amplitudes: np.ndarray,
                  stats: IncrementStats, position: tuple[int, int] | None = None
                  ) -> tuple[Equilibrium, Response] | None:
        """Newton from ``start`` to the load ``amplitudes``; None if it does not converge.
        ``position``: (k, n) when this is the whole k-th increment of a load cycle of n.

        A monotone line search first; if that fails, once more with the non-monotone one
        (``settings.line_search_window``) before the caller cuts the step back."""
        key = _load_step(start.amplitudes, amplitudes) if position is None else _cycle_step(position)
        solved = self._newton(start, state, amplitudes, stats, key, window=1)
        if solved is None and self.settings.line_search_window > 1:
            solved = self._newton(start, state, amplitudes, stats, key, window=self.settings.line_search_window)
        return solved

    def _scales(self, start: Equilibrium, amplitudes: np.ndarray, f_q: np.ndarray) -> tuple[float, bool]:
        """The force scale (N) of the convergence test, and whether a load acts along a rigid
        mode of the free control DOFs (``loaded``)."""
        force_scale = max(1.0, float(np.max(np.abs(f_q), initial=0.0)),
                          float(np.max(np.abs(start.forces), initial=0.0)))
        # A load along a rigid mode: with no point pressed the body floats (no equilibrium).
        # Prescribed motions leave round-off there (K·rigid mode ≈ 0), hence their scale.
        motion = float(np.max(np.abs(self.space.pattern_motion @ amplitudes), initial=0.0))
        drive_scale = force_scale + self.stiffness_scale * motion
        loaded = bool(np.any(np.abs(self.rigid_modes.T @ f_q)
                             > self.settings.force_tolerance * drive_scale))
        return force_scale, loaded

    def _pressure_shift(self, start: Equilibrium, state: ContactState) -> np.ndarray | float:
        """Normal kinematics (mm) that give the points pressed in ``start`` their pressure of
        ``start`` again against the current gap, less those of ``start``; 0 where that
        changes nothing beyond the displacement tolerance.

        The gap moves between increments when the last one wore the surfaces, and the
        kinematics do when a finite-sliding solver re-pairs them; then ``start`` presses
        fewer points than it was solved with."""
        per_point = start.forces.reshape(self.n_points, self.dim)
        pressed = per_point[:, 0] > 0.0
        if not np.any(pressed):
            return 0.0
        kn = np.broadcast_to(self.law.normal_stiffness, pressed.shape)[pressed]
        penetration = per_point[pressed, 0] / self.area[pressed] / kn
        gap = np.broadcast_to(state.gap, pressed.shape)[pressed]
        normal = start.kinematics.reshape(self.n_points, self.dim)[pressed, 0]
        change = penetration + gap - self.h0[pressed] - normal
        if np.max(np.abs(change)) <= self.settings.displacement_tolerance:
            return 0.0
        shift = np.zeros((self.n_points, self.dim))
        shift[pressed, 0] = change
        return shift.ravel()

    def _predictor(self, start: Equilibrium, state: ContactState, amplitudes, g_f, f_q, force_scale, key):
        """(merit, g, q, residual) of the best of the predictors: the contact kinematics follow
        the drive (right in gross slip and for a free approach) or stay put (right where the
        interface sticks; with a stiff elastic stick, small γ_crit, following the drive makes
        every point slide at first and Newton then crawls back to stick a few points per
        iteration). Both press the points that were pressed with their last pressures
        (:meth:`_pressure_shift`): with a large cycle jump one increment wears as deep as the
        penalty penetration, and from the half-open interface of an unshifted predictor the
        first Newton step overshoots and is cut to a sliver by the line search (the
        cylinder-on-plane scene: 3.6 residuals per Newton iteration). A third recalls the last
        equilibrium at the same load level, however it was reached, pressed again against the
        current gap.

        Once a load step (``key``: the same place in the load cycle, or without one the same
        start and end amplitudes) has been solved twice, the load is cyclic and two others
        replace all three: the last equilibrium of that step (the same point of the previous
        cycle; in a steady cycle nearly the answer, where the first two start from the
        previous increment's load) and the extrapolation of the last two, by the wear gap's
        change since the later one in units of its change between them (one cycle's change
        where the gap has not moved): under wear, an evolving COF or a vibration that runs up
        the cycles drift, smoothly from one to the next (the adaptive jump keeps it so). The
        counterweight's wear phase (10 mm): 4.5 → 2.5 Newton iterations per increment. Each
        candidate costs a residual pass; with the cyclic two on offer, staying put won 1.4 %
        of the counterweight's increments (10 mm) and following the drive none, and dropping
        them took 6.9 → 4.8 residual passes per increment (and 2 % fewer Newton iterations).
        Known by their amplitudes alone, the steps of a run-up never repeat (the vibration
        grows every cycle), so its 300 cycles went without the cyclic two: known by their
        place in the cycle, the counterweight's run-up at 10 mm took 2.0 instead of 4.4–4.9
        Newton iterations and 4.0 instead of 7.8–9.7 residual passes per increment."""
        candidates = []
        solved = self._solved_at.get(key)
        if solved is not None and solved[1][0] is not None:  # a step solved twice before: a cycle
            (earlier, earlier_gap), (before, before_gap) = solved
            factor = _extrapolation_factor(before_gap, earlier_gap, state.gap)
            extrapolated = Equilibrium(*(e + factor * (e - b) for e, b in (
                (earlier.kinematics, before.kinematics), (earlier.control, before.control),
                (earlier.forces, before.forces))), earlier.amplitudes)
            recalled = [earlier, extrapolated]
        else:  # the last equilibrium at this load level, however it was reached
            shift = self._pressure_shift(start, state)
            candidates = [(start.kinematics + shift, start.control),
                          (start.kinematics + shift + (g_f - self.space.driving(start.amplitudes)[0]), start.control)]
            level = self._solved_at.get(_load_step(None, amplitudes))
            recalled = [] if level is None else [level[0][0]]
        candidates += [(e.kinematics + self._pressure_shift(e, state), e.control) for e in recalled]
        best = None
        for g, q in candidates:
            candidate = self._residual(g, q, state, start.kinematics, g_f, f_q)
            candidate_merit = self._merit(candidate[0], candidate[1], force_scale)
            if best is None or candidate_merit < best[0]:
                best = (candidate_merit, g, q.copy(), candidate)
        return best

    def _remember(self, key: tuple, solved: Equilibrium, state: ContactState) -> None:
        """Keep ``solved`` (and the wear gap it was solved against) as the cyclic predictor of
        its load step, with the one before it at that step, and as the last equilibrium at its
        load level: 128 keys in all, the oldest dropped first (a load that never repeats, a
        tabulated program or cut-back sub-steps, must not grow the memory)."""
        gap = np.array(state.gap, dtype=float, copy=True)
        for each in (key, _load_step(None, solved.amplitudes)):
            earlier = self._solved_at.pop(each, ((None, None), None))[0]
            self._solved_at[each] = ((solved, gap), earlier)
        while len(self._solved_at) > 128:
            del self._solved_at[next(iter(self._solved_at))]

    def _newton(self, start: Equilibrium, state: ContactState, amplitudes: np.ndarray,
                stats: IncrementStats, key: tuple, window: int) -> tuple[Equilibrium, Response] | None:
        g_f, f_q = self.space.driving(amplitudes)
        force_scale, loaded = self._scales(start, amplitudes, f_q)
        reference = start.kinematics
        merit, g, q, (r_kin, r_ctl, response, forces) = self._predictor(start, state, amplitudes, g_f, f_q,
                                                                         force_scale, key)
        recent, history, stalled = [merit], [merit], False  # merits for the line search
        previous_status = None
        for iteration in range(1, self.settings.max_iterations + 1):
            settled = previous_status is not None and np.array_equal(previous_status, response.status)
            previous_status = response.status
            try:
                delta_g, delta_q, searching = self._newton_step(response, g, state, r_kin, r_ctl, loaded,
                                                                settled)
            except np.linalg.LinAlgError:
                # A singular tangent (e.g. every point sliding under force control) or an
                # iterative solve that gives up: this attempt fails and is cut back.
                break
            # Stalled (points cycling between stick and slip): step only to the first point
            # whose status the step changes, just past it. The linear model is right up to
            # there, so the merit falls; the next linearisation sees the new status.
            step = self._first_kink(g, delta_g, state, reference) if stalled else 1.0
            # A contact-search step (no point closed yet) is taken whole: the merit of the
            # open configuration is no guide to how far the body has to move.
            while not searching:
                trial = self._residual(g + step * delta_g, q + step * delta_q, state, reference, g_f, f_q)
                trial_merit = self._merit(trial[0], trial[1], force_scale)
                if trial_merit <= (1.0 - 1e-4 * step) * max(recent) or step < 1.0 / 64:
                    break
                step *= 0.5
            if searching:
                trial = self._residual(g + delta_g, q + delta_q, state, reference, g_f, f_q)
                trial_merit = self._merit(trial[0], trial[1], force_scale)
            g, q = g + step * delta_g, q + step * delta_q
            r_kin, r_ctl, response, forces = trial
            merit = trial_merit
            recent = (recent + [merit])[-window:]
            history.append(merit)
            # no progress over the window (points cycling): monotone again, kink-limited steps
            stalled = window > 1 and len(history) > window and merit > 0.5 * min(history[:-window])
            if stalled:
                recent = [merit]
            if not np.all(np.isfinite(g)) or not np.all(np.isfinite(q)):
                break
            floating = loaded and not np.any(response.dpressure_dh > 0.0)
            if self._converged(r_kin, r_ctl, force_scale) and not floating:
                stats.iterations += iteration
                stats.max_iterations = max(stats.max_iterations, iteration)
                solved = Equilibrium(g, q, forces, amplitudes.copy())
                self._remember(key, solved, state)
                return solved, response
        stats.iterations += self.settings.max_iterations
        self._last_failure = (response, r_ctl, force_scale, loaded, f_q, state.cof)
        return None

    def _failure_reason(self) -> tuple[str, str]:
        """Why the last attempt failed: (cause, words), the cause "slid_off" for lost tangential
        equilibrium, else "diverged" (see :class:`ConvergenceError`).

        It is said when friction at the failed iterate's pressures could not carry the load
        along the rigid modes even at its full capacity μ·p everywhere (:meth:`_friction_needed`),
        whatever the iterate's statuses. The test used to ask first that every closed point of
        the iterate slide, and measured the capacity by |τ| (μ·p only where a point slides): it
        missed the user joint sliding off at 0.6 mm or at a low COF (QA: 1 to 13 of 33 closed
        points stuck in the failed iterate, friction needing 1.46–1.47 times its capacity, the
        same load whatever the increments, a load proportional to μ), which was told to try more
        increments."""
        generic = ("diverged", "Newton did not converge (the step may be too large for the contact "
                   "status changes; try more increments)")
        response, r_ctl, force_scale, loaded, f_q, cof = self._last_failure
        if loaded and not np.any(response.pressure > 0.0):
            return ("diverged", "no point of the interface stays pressed: the load pulls the body off "
                    "the contact, and a body held only by the contact has no equilibrium then "
                    "(support it, or prescribe the motion of its control DOF instead of a force)")
        closed = response.status != Status.OPEN
        if not self.rigid_modes.size or not np.any(closed):
            return generic
        stuck = response.status == Status.STICK
        if np.linalg.norm(self.rigid_modes.T @ r_ctl) <= self.settings.force_tolerance * force_scale:
            return generic
        capacity = float(np.sum(np.broadcast_to(cof, self.area.shape) * response.pressure * self.area))
        needed = self._friction_needed(response, f_q, cof)
        if needed < 1.0 - 1e-3:
            return ("diverged", f"Newton did not converge: every closed point slid in the failed iterate, "
                    f"but friction at its pressures could carry the load with {100.0 * needed:.3g} % of "
                    f"its capacity ({capacity:.6g} N), so this is no loss of tangential equilibrium "
                    "(the step may be too large for the contact status changes; try more increments)")
        sliding = int(closed.sum() - stuck.sum())
        which = f"all {sliding}" if sliding == int(closed.sum()) else f"{sliding} of the {int(closed.sum())}"
        return ("slid_off", f"tangential equilibrium is lost: {which} closed contact points "
                f"slide at |τ| = μ·p (friction capacity {capacity:.6g} N) and the force-controlled DOFs "
                "cannot be balanced; the applied load exceeds what friction can carry, so no "
                "static solution exists (prescribe a motion instead of a force to drive the "
                "interface into gross slip)")

    def _friction_needed(self, response: Response, f_q: np.ndarray, cof) -> float:
        """The least share of its capacity μ·p·A at which friction balances the load along the
        rigid modes, the pressures being those of ``response`` and μ ``cof`` (the COF of the state):
        below 1, shear forces within the friction limit balance the load, so a static solution
        is not ruled out; infinite where the load needs shear at points with no capacity.

        Only the part of the load that shear forces can act on counts: a failed iterate's
        pressures need not balance the normal load (by 1e-3 to 1e-2 of it in the cases
        measured, a round-off-dependent amount), and what they leave over is no demand on
        friction. The shear is the one of least Σ|A·τ|²/(μ·p·A) (a weighted least-norm
        solution), whose share is exact for a load along one translation (each point then
        carries the same share) and above the least possible one otherwise."""
        closed = response.status != Status.OPEN
        modes = self.rigid_modes
        images = self._mode_images[closed]
        load = modes.T @ f_q
        normal = images[:, 0, :].T @ (self.area[closed] * response.pressure[closed])
        demand = -load - normal  # what the shear forces must carry: E·modes carries λ to the modes
        shear = images[:, 1:, :].reshape(-1, modes.shape[1]).T
        tolerance = 1e-3 * (np.linalg.norm(load) + np.linalg.norm(normal))
        reach = shear @ np.linalg.lstsq(shear, demand, rcond=1e-12)[0]  # the part shear can act on
        capacity = (np.broadcast_to(cof, self.area.shape) * response.pressure * self.area)[closed]
        weights = np.repeat(capacity, self.dim - 1)
        forces = weights * (shear.T @ np.linalg.lstsq((shear * weights) @ shear.T, reach, rcond=1e-12)[0])
        if np.linalg.norm(reach - shear @ forces) > tolerance:  # no capacity where it is needed (μ = 0)
            return np.inf
        with np.errstate(divide="ignore", invalid="ignore"):
            share = np.linalg.norm(forces.reshape(-1, self.dim - 1), axis=1) / capacity
        return float(np.max(np.nan_to_num(share, nan=0.0, posinf=np.inf), initial=0.0))

    def increment(self, start: Equilibrium, state: ContactState, amplitudes: np.ndarray,
                  effects: Effects, position: tuple[int, int] | None = None
                  ) -> tuple[Equilibrium, ContactState, np.ndarray, IncrementStats]:
        """Advance from ``start`` to the load ``amplitudes``, cutting back as needed.
        ``position``: (k, n) when this is the k-th increment of a load cycle of n (the cyclic
        predictors then recall the same point of the last cycles, see :meth:`_predictor`).

        A sub-step that fails (or wears more than the cap) is halved; two in a row that
        succeed let the next grow back by a factor two (growing after every success would
        fail every other attempt where the admissible size is steady), so an increment may
        take many sub-steps (a large cycle jump against the wear cap) while no sub-step is
        smaller than 2^-max_cutbacks of the increment. Returns the converged equilibrium, the advanced state, the point
        status over the increment (the worst of its sub-steps: slip over stick over open) and
        the iteration counters. Raises :class:`ConvergenceError` when a
        sub-step of that smallest size still fails.
        """
        with blas_threads(self.settings.blas_threads):
            return advance_with_cutbacks(self, start, state, amplitudes, effects, position)


def advance_with_cutbacks(solver, start, state: ContactState, amplitudes: np.ndarray, effects: Effects,
                          position: tuple[int, int] | None = None):
    """The sub-stepping of :meth:`ContactSolver.increment`, for any solver with ``law``,
    ``settings``, ``_solve_to(equilibrium, state, target, stats, position)`` (→ (equilibrium,
    response) or None) and ``_failure_reason()``: the condensed solver and the full reference
    model advance through the same sub-steps. ``position`` (the increment's place in its load
    cycle) is handed on only with the whole increment, not with a cut-back sub-step."""
    stats = IncrementStats()
    origin, target = start.amplitudes, np.asarray(amplitudes, dtype=float)
    equilibrium, status = start, None
    done, level = 0.0, 0  # fraction of the increment solved; sub-step size 2^-level
    streak = 0  # sub-steps solved in a row at this size
    while done < 1.0:
        reach = min(1.0, done + 0.5 ** level)
        sub_target = target if reach == 1.0 else origin + reach * (target - origin)
        whole = done == 0.0 and reach == 1.0
        solved = solver._solve_to(equilibrium, state, sub_target, stats, position if whole else None)
        too_much_wear = False
        if solved is not None and effects.wear and np.isfinite(solver.settings.wear_cap):
            wear_now = wear_increment(solved[1], solver.law, effects.cycle_jump).sum(axis=0)
            too_much_wear = float(wear_now.max(initial=0.0)) > solver.settings.wear_cap
        if solved is None or too_much_wear:
            if level >= solver.settings.max_cutbacks:
                cause, reason = (("wear_runaway",
                                  f"the wear increment stays above the cap {solver.settings.wear_cap:g} mm "
                                  f"({float(wear_now.max()):.3g} mm in the smallest sub-step); wear that "
                                  "does not shrink with the step makes the interface slip by itself "
                                  "(explicit wear is unstable at this cycle jump): lower the cycle "
                                  f"jump ({effects.cycle_jump:g}) or the wear coefficients, or raise "
                                  "the cap") if too_much_wear else solver._failure_reason())
                raise ConvergenceError(
                    f"increment to amplitudes {np.round(amplitudes, 6).tolist()} failed with "
                    f"sub-steps of 2^-{level} of it ({stats.cutbacks} cutbacks), the last "
                    f"converged amplitudes being {np.round(equilibrium.amplitudes, 6).tolist()}: "
                    f"{reason}", cause)
            stats.cutbacks += 1
            level += 1
            streak = 0
            continue
        equilibrium, response = solved
        state, substep_status = advance(state, response, solver.law, cof_evolution=effects.cof_evolution,
                                        wear=effects.wear, cycle_jump=effects.cycle_jump,
                                        cof_jump=effects.cycle_jump if effects.cof_jump else 1.0)
        # the increment's status is the worst of its sub-steps, as a cycle's is the worst of its
        # increments: a point that slid in a cut-back sub-step and stuck in the last one slid
        status = substep_status if status is None else np.maximum(status, substep_status)
        stats.substeps += 1
        done = reach
        streak += 1
        if streak == 2:
            level, streak = max(level - 1, 0), 0
    return equilibrium, state, status, stats
