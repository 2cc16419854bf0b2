"""Global energy bookkeeping of a contact run, independent of the local dissipation sums.

External work is integrated with the trapezoidal rule from the forces the surroundings
apply (loads and reactions at prescribed DOFs) and the displacements of their DOFs. Stored
energy is the strain energy of the condensed bodies plus the energy in the contact springs
(normal penalty ½·p²/kn and elastic stick ½·τ·γ_el per unit area). Their difference is the
frictional dissipation measured *globally*, plus the small energy p·Δr that material
removal releases, which is tracked separately. Units: mJ = N·mm.
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
    """

    space: ContactSpace
    law: ContactLaw
    external_work: float = 0.0
    wear_release: float = 0.0
    _displacement: np.ndarray | None = None
    _forces: np.ndarray | None = None
    _gap: np.ndarray | None = None

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
        return self.external_work, self.stored(equilibrium, state, displacement)
