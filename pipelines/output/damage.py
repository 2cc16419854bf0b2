"""Fretting damage fields of a run (FDP, FFDP, surface tangential stress) as the procedure goes.

:class:`DamageObserver` stands between the procedure and the results writer: after every
increment it recovers the slave surface's displacements from the condensed model and keeps
the most tensile surface stress σ_t of each point (:class:`contact.damage.DamageTracker`);
after every cycle it puts FDP, FFDP and σ_t into the cycle's fields and their maxima and
locations into its figures, then hands the cycle on. The physics is in :mod:`contact.damage`.
Units: mm, MPa; FDP MPa·mm, FFDP MPa²·mm.
"""

from __future__ import annotations

import numpy as np

from contact.damage import DamageTracker
from contact.procedure import CycleSummary, IncrementRecord, Observer
from contact.structure import ContactSpace


class DamageObserver(Observer):
    """Tracks σ_t over each cycle and adds the damage fields before ``inner`` sees the cycle.

    model: the built model (its assembly and scene give the slave surface and its material);
    space: the contact space the solver starts in (:meth:`follow` a finite-sliding solver's new
    ones).
    """

    def __init__(self, inner: Observer, model, space: ContactSpace):
        self.inner, self.space = inner, space
        assembly = model.assembly
        pairing, body = assembly.pairing, assembly.bodies[assembly.slave_body]
        self.dim = assembly.structure.dim
        self.surface_dofs = body.offset + np.arange(pairing.slave.nodes.size * self.dim)
        material = model.scene.data["materials"][model.scene.data["bodies"][assembly.slave_body]["material"]]
        self.tracker = DamageTracker(pairing.slave.coordinates, pairing.slave.facets, pairing.tangents,
                                     material["youngs_modulus"], material["poisson_ratio"])
        self.area = assembly.structure.area

    def follow(self, space: ContactSpace) -> None:
        self.space = space

    def phase(self, name, n_cycles):
        self.inner.phase(name, n_cycles)

    def increment(self, record: IncrementRecord) -> None:
        if record.phase != "preload":
            eq = record.equilibrium
            displacement = self.space.displacements(eq.control, eq.forces, eq.amplitudes, self.surface_dofs)
            per_point = eq.forces.reshape(len(self.area), -1) / self.area[:, None]
            self.tracker.record(displacement.reshape(-1, self.dim), per_point[:, 0], per_point[:, 1:])
        self.inner.increment(record)

    def cycle(self, summary: CycleSummary) -> None:
        summary.damage = self.tracker.cycle(summary.max_shear, summary.slip_range)
        summary.figures.update(self.tracker.figures(summary.damage))
        self.inner.cycle(summary)
