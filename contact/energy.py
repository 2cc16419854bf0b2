"""Global energy bookkeeping of a contact run, independent of the local dissipation sums.

External work is integrated with the trapezoidal rule from the forces the surroundings
apply (loads and reactions at prescribed DOFs) and the displacements of their DOFs. Stored
energy is the strain energy of the condensed bodies plus the energy in the contact springs
(normal penalty ½·p²/kn and elastic stick ½·τ·γ_el per unit area). Their difference is the
frictional dissipation measured *globally*, plus the small energy p·Δr that material
removal releases, which is tracked separately.

Neither needs the displacement field: with the contact DOFs c eliminated,
u_c = K_cc⁻¹·(B·s − G_cᵀ·λ), B = [L_c, K_cp, K_cq], s = [a, −u_p, −q] (a the pattern
amplitudes, L the load patterns), so every product of u_c with a load or a coupling block is
a product of precomputed compliances K_cc⁻¹·B with s and λ, and the only product of size
n² left is λᵀ·W·λ (with sparse bodies, :mod:`contact.sparse`, one solve). The per-increment cost is then that of one multiplication by W instead
of a solve with the bodies' contact stiffness and a product with their full condensed
stiffness (10 % of a counterweight run's time before).

The elastic stick is not a potential: its stiffness μ·p/γ_crit changes with the pressure
and the COF, so ψ = ½·μ·p·|γ_el|²/γ_crit grows by ½·|γ_el|²/γ_crit·Δ(μ·p) at fixed elastic
slip without any work being done. That source (at most ½·μ·p·γ_crit per point and load
change; visible when the clamping force varies or μ jumps, and for large γ_crit) is
integrated separately, so that external work + stick source = stored + dissipated +
released by wear. Units: mJ = N·mm.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field

import numpy as np

from contact.law import ContactLaw, ContactState
from contact.procedure import IncrementRecord, Observer
from contact.solver import Equilibrium
from contact.structure import ContactSpace, dense_block


class WorkOperators:
    """The blocks of the condensed stiffness and the load patterns that energies need.

    With r = n_patterns + n_prescribed + n_control columns: ``BtY`` = Bᵀ·K_cc⁻¹·B (r, r),
    ``GY`` = G_c·K_cc⁻¹·B (n_rows, r); the control and prescribed stiffness blocks; the load
    patterns on control and on prescribed DOFs (body loads have a share there: the support's
    reaction is the internal force less it).
    """

    def __init__(self, space: ContactSpace):
        structure = space.structure
        K = structure.stiffness
        c, q, p = space.contact_dofs, space.control_dofs, space.prescribed
        patterns = structure.patterns
        loads = np.zeros((K.shape[0], len(patterns)))
        for k, name in enumerate(patterns):
            if name in structure.loads:
                loads[:, k] = structure.loads[name]
        B = np.hstack([loads[c], dense_block(K, c, p), dense_block(K, c, q)])
        self._Y = Y = space.solve_contact_block(B)
        self.n_patterns, self.n_prescribed = len(patterns), p.size
        self.BtY = 0.5 * (B.T @ Y + Y.T @ B)
        self.load_q, self.load_p = loads[q], loads[p]
        self.Kqq, self.Kqp, self.Kpp = dense_block(K, q, q), dense_block(K, q, p), dense_block(K, p, p)
        self.motion = space.pattern_motion
        self._pair(space)

    def _pair(self, space: ContactSpace) -> None:
        """The terms that depend on the pairing: G_c·K_cc⁻¹·B, G on the prescribed DOFs, W·λ."""
        self._space = space
        self.GY = np.asarray(space.Gc @ self._Y)
        contact_p = space.structure.contact_operator[:, space.prescribed]
        self.Gp = contact_p.T.tocsr() if contact_p.nnz else None
        self.compliance = space.compliance  # W·λ (dense or sparse space)

    def repaired(self, space: ContactSpace) -> WorkOperators:
        """The operators of ``space``, a new pairing of the same bodies: only the pairing's
        terms are formed again when it eliminates the same DOFs (else all are)."""
        old = self._space
        same = (space.structure.stiffness is old.structure.stiffness
                and all(np.array_equal(getattr(space, name), getattr(old, name))
                        for name in ("contact_dofs", "control_dofs", "prescribed")))
        if not same:
            return WorkOperators(space)
        operators = copy.copy(self)
        operators._pair(space)
        return operators

    def work_terms(self, control: np.ndarray, forces: np.ndarray, amplitudes: np.ndarray):
        """(ℓ = Lᵀ·u per pattern (mm·N per unit amplitude), reaction forces of the supports at
        the prescribed DOFs (N), u_p (mm), strain energy ½·uᵀ·K·u (mJ)) of an equilibrium."""
        u_p = self.motion @ amplitudes
        s = np.concatenate([amplitudes, -u_p, -control])
        Bt_u = self.BtY @ s - self.GY.T @ forces  # [L_cᵀ·u_c, K_pc·u_c, K_qc·u_c]
        k, n_p = self.n_patterns, self.n_prescribed
        load_u, Kpc_u, Kqc_u = Bt_u[:k], Bt_u[k:k + n_p], Bt_u[k + n_p:]
        G_u = self.GY @ s - self.compliance(forces)  # G_c·u_c
        strain = (Bt_u @ s - G_u @ forces + 2.0 * (Kqc_u @ control + Kpc_u @ u_p)
                  + control @ self.Kqq @ control + 2.0 * control @ self.Kqp @ u_p + u_p @ self.Kpp @ u_p)
        reaction = Kpc_u + self.Kqp.T @ control + self.Kpp @ u_p - self.load_p @ amplitudes
        if self.Gp is not None:
            reaction = reaction + self.Gp @ forces
        return load_u + self.load_q.T @ control + self.load_p.T @ u_p, reaction, u_p, 0.5 * float(strain)


@dataclass
class EnergyMeter:
    """Accumulates external work and wear release; evaluates stored energy on demand.

    Work is counted from the unloaded configuration, the solver's initial equilibrium.
    stick_source: energy the elastic stick gains from changes of μ·p (see the module).
    """

    space: ContactSpace
    law: ContactLaw
    external_work: float = 0.0
    wear_release: float = 0.0
    stick_source: float = 0.0
    stored: float = 0.0  # stored energy after the last increment, mJ
    operators: WorkOperators | None = field(default=None, repr=False)
    _last: tuple | None = None  # amplitudes, ℓ, reactions, u_p of the last increment
    _gap: np.ndarray | None = None
    _control: np.ndarray | None = None
    _stick: tuple | None = None  # per point: μ for the next increment, μ·p in ψ, p, |γ_el|²

    def __post_init__(self):
        if self.operators is None:
            self.operators = WorkOperators(self.space)

    def follow(self, space: ContactSpace) -> None:
        """Go on in ``space``, the contact space of a new pairing of the same bodies (finite
        sliding): the work operators are rebuilt for it; the sums and the work terms of the
        last increment (per pattern and prescribed DOF) carry over."""
        self.space, self.operators = space, self.operators.repaired(space)

    _MEMORY = ("amplitudes", "load_work", "reaction", "prescribed_motion")

    def memory(self) -> dict:
        """The arrays the meter carries from one increment to the next (for checkpoints)."""
        out = dict(zip(self._MEMORY, self._last or ()))
        if self._control is not None:
            out["control"] = self._control
        if self._gap is not None:
            out["gap"] = self._gap
        out.update({f"stick{k}": value for k, value in enumerate(self._stick or ())})
        return out

    def recall(self, memory: dict) -> None:
        """Restore what :meth:`memory` returned (the accumulated sums are set separately)."""
        self._last = tuple(memory[name] for name in self._MEMORY) if self._MEMORY[0] in memory else None
        self._control, self._gap = memory.get("control"), memory.get("gap")
        stick = [memory[f"stick{k}"] for k in range(4) if f"stick{k}" in memory]
        self._stick = tuple(stick) if stick else None

    def control_values(self, dofs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Displacement (mm) and external force (N: load, or reaction where prescribed) of the
        last increment at ``dofs``, global indices of control or prescribed DOFs."""
        space = self.space
        amplitudes, _, reaction, u_p = self._last
        n = space.structure.n_dofs
        displacement, force = np.full(n, np.nan), np.full(n, np.nan)
        displacement[space.control_dofs] = self._control
        displacement[space.prescribed] = u_p
        force[space.control_dofs] = self.operators.load_q @ amplitudes
        force[space.prescribed] = reaction
        if np.isnan(displacement[dofs]).any():
            raise ValueError("control_values: a DOF lies on the contact surface")
        return displacement[dofs], force[dofs]

    def _spring_energy(self, equilibrium: Equilibrium, state: ContactState) -> float:
        structure = self.space.structure
        per_point = equilibrium.forces.reshape(structure.n_points, -1) / structure.area[:, None]
        pressure, shear = per_point[:, 0], per_point[:, 1:]
        kn = np.broadcast_to(self.law.normal_stiffness, pressure.shape)
        normal = 0.5 * pressure ** 2 / kn
        tangential = 0.5 * np.einsum("ij,ij->i", shear, state.elastic_slip)
        return float(np.sum(structure.area * (normal + tangential)))

    def _bolt_energy(self, equilibrium: Equilibrium, locked_elongation) -> float:
        """Energy the locked bolts' springs gained since they were locked, mJ.

        A locked bolt is the pair of forces F − k_b·ε_lock, whose work the external work counts,
        and a spring k_b·ε of zero rest length in the control block (:mod:`contact.bolts`):
        since the lock it stores ½·k_b·(ε² − ε_lock²). The locked space is the solver's, not the
        meter's: the lock is read from the increment (``locked_elongation`` ε_lock, mm, None
        before the lock or without bolts)."""
        bolts = self.space.structure.bolts
        if locked_elongation is None or bolts is None:
            return 0.0
        elongation = bolts.elongation(self.space, equilibrium.control)
        return float(np.sum(0.5 * bolts.stiffness * (elongation ** 2 - np.asarray(locked_elongation) ** 2)))

    def update(self, equilibrium: Equilibrium, state: ContactState, locked_elongation=None) -> tuple[float, float]:
        """Advance by one converged increment; returns (external work, stored energy), mJ.
        locked_elongation: ε_lock (mm) of the bolts once locked (the record's; their springs'
        energy), None before the lock or without bolts."""
        loads_u, reaction, u_p, strain = self.operators.work_terms(
            equilibrium.control, equilibrium.forces, equilibrium.amplitudes)
        amplitudes = equilibrium.amplitudes
        # The first increment starts from the unloaded configuration (u = 0, no forces),
        # where the solver's initial equilibrium is: its work counts like any other.
        last_a, last_loads_u, last_reaction, last_u_p = self._last or (
            np.zeros_like(amplitudes), np.zeros_like(loads_u), np.zeros_like(reaction), np.zeros_like(u_p))
        bolts = self.space.structure.bolts
        if locked_elongation is not None and bolts is not None:
            # Locking sets each pretension amplitude to 1 − k_b·ε_lock/F at fixed displacements
            # (and holds it): the increment after the lock is loaded by that, not by the mean of
            # it and the pretension (which put 87 mJ, 0.3 % of the work, into the counterweight's
            # balance at its 5-increment preload, 22 mJ at 20)
            held = [self.space.structure.patterns.index(name) for name in bolts.patterns]
            last_a = last_a.copy()
            last_a[held] = amplitudes[held]
        # ½(F₁ + F₀)·(u₁ − u₀) with F = Σ a_k·L_k, plus the supports' reactions on the prescribed DOFs.
        self.external_work += 0.5 * float((amplitudes + last_a) @ (loads_u - last_loads_u)
                                          + (reaction + last_reaction) @ (u_p - last_u_p))
        gap = np.asarray(state.gap, dtype=float)
        if self._gap is not None and gap.ndim:
            pressure = equilibrium.forces.reshape(self.space.structure.n_points, -1)[:, 0]
            self.wear_release += float(np.sum(pressure * (gap - self._gap)))
        self._last, self._gap = (amplitudes.copy(), loads_u, reaction, u_p), gap
        self._control = equilibrium.control
        self._update_stick_source(equilibrium, state)
        self.stored = strain + self._spring_energy(equilibrium, state) + self._bolt_energy(equilibrium, locked_elongation)
        return self.external_work, self.stored

    @property
    def global_dissipation(self) -> float:
        """Frictional dissipation measured globally after the last increment (mJ): external
        work plus the stick source, less the stored energy and the energy wear released."""
        return self.external_work + self.stick_source - self.stored - self.wear_release
    def _update_stick_source(self, equilibrium: Equilibrium, state: ContactState) -> None:
        """Add ∫ ½·|γ_el|²/γ_crit·d(μ·p) over the increment: first the COF update of the last
        increment at fixed γ_el and p, then the pressure change (trapezoidal in |γ_el|²)."""
        structure = self.space.structure
        pressure = equilibrium.forces.reshape(structure.n_points, -1)[:, 0] / structure.area
        slip_squared = np.einsum("ij,ij->i", state.elastic_slip, state.elastic_slip)
        zero = np.zeros_like(pressure)
        previous = self._stick or (state.cof, zero, zero, zero)
        cof_used, cof_p_before, pressure_before, slip_squared_before = previous
        cof_p_start = cof_used * pressure_before
        cof_p_end = cof_used * pressure
        source = (0.5 * (cof_p_start - cof_p_before) * slip_squared_before
                  + 0.25 * (cof_p_end - cof_p_start) * (slip_squared_before + slip_squared))
        gamma_crit = np.broadcast_to(self.law.critical_slip, pressure.shape)
        self.stick_source += float(np.sum(structure.area * source / gamma_crit))
        self._stick = (state.cof.copy(), cof_p_end, pressure, slip_squared)


class MeterObserver(Observer):
    """Keeps an :class:`EnergyMeter` up with every converged increment of a procedure run."""

    def __init__(self, meter: EnergyMeter):
        self.meter = meter

    def increment(self, record: IncrementRecord) -> None:
        self.meter.update(record.equilibrium, record.state, record.locked_elongation)
