"""Global energy bookkeeping of a contact run, independent of the local dissipation sums.

External work is integrated with the trapezoidal rule from the forces the surroundings
apply (loads and reactions at prescribed DOFs) and the displacements of their DOFs. Stored
energy is the strain energy of the condensed bodies plus the energy in the contact springs
(normal penalty ½·p²/kn and elastic stick ½·τ·γ_el per unit area). Their difference is the
frictional dissipation measured *globally*, plus the small energy p·Δr that material
removal releases, which is tracked separately.

The elastic stick is not a potential: its stiffness μ·p/γ_crit changes with the pressure
and the COF, so ψ = ½·μ·p·|γ_el|²/γ_crit grows by ½·|γ_el|²/γ_crit·Δ(μ·p) at fixed elastic
slip without any work being done. That source (at most ½·μ·p·γ_crit per point and load
change; visible when the clamping force varies or μ jumps, and for large γ_crit) is
integrated separately, so that external work + stick source = stored + dissipated +
released by wear. Units: mJ = N·mm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from contact.law import ContactLaw, ContactState
from contact.solver import Equilibrium
from contact.structure import ContactSpace


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
    _displacement: np.ndarray | None = None
    _forces: np.ndarray | None = None
    _gap: np.ndarray | None = None
    _stick: tuple | None = None  # per point: μ for the next increment, μ·p in ψ, p, |γ_el|²

    def stored(self, equilibrium: Equilibrium, state: ContactState, displacement: np.ndarray) -> float:
        structure = self.space.structure
        strain = 0.5 * float(displacement @ (structure.stiffness @ displacement))
        per_point = equilibrium.forces.reshape(structure.n_points, -1) / structure.area[:, None]
        pressure, shear = per_point[:, 0], per_point[:, 1:]
        kn = np.broadcast_to(self.law.normal_stiffness, pressure.shape)
        normal = 0.5 * pressure ** 2 / kn
        tangential = 0.5 * np.einsum("ij,ij->i", shear, state.elastic_slip)
        return strain + float(np.sum(structure.area * (normal + tangential)))

    def update(self, equilibrium: Equilibrium, state: ContactState) -> tuple[float, float]:
        """Advance by one converged increment; returns (external work, stored energy), mJ."""
        displacement = self.space.displacements(equilibrium.control, equilibrium.forces,
                                                equilibrium.amplitudes)
        forces = self.space.external_forces(displacement, equilibrium.forces, equilibrium.amplitudes)
        if self._displacement is None:
            # The first increment starts from the unloaded configuration (u = 0, no forces),
            # where the solver's initial equilibrium is: its work counts like any other.
            self._displacement, self._forces = np.zeros_like(displacement), np.zeros_like(forces)
        self.external_work += 0.5 * float((forces + self._forces) @ (displacement - self._displacement))
        gap = np.asarray(state.gap, dtype=float)
        if self._gap is not None and gap.ndim:
            pressure = equilibrium.forces.reshape(self.space.structure.n_points, -1)[:, 0]
            self.wear_release += float(np.sum(pressure * (gap - self._gap)))
        self._displacement, self._forces, self._gap = displacement, forces, gap
        self._update_stick_source(equilibrium, state)
        return self.external_work, self.stored(equilibrium, state, displacement)

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
