"""Load programs whose patterns follow tabulated histories over a load cycle.

A :class:`TabulatedProgram` is a :class:`contact.procedure.LoadProgram` in which some patterns
(shape ``"history"``) follow sampled values over one cycle instead of sin 2πt: the inertia
loads of a counterweight driven by multibody histories, for instance. They are zero in the
preload (the bolts are tightened at standstill and locked) and take their tabulated values,
mean included, from the first cycle on.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from contact.procedure import LoadProgram


@dataclass(frozen=True)
class TabulatedProgram(LoadProgram):
    """tables: pattern → (n,) amplitudes at the cycle phases k/n, k = 1 … n (periodic; the value
    at phase 0 is the one at phase 1). Between samples the amplitude is interpolated linearly."""

    tables: dict = field(default_factory=dict)

    def cycle(self, phase: float) -> np.ndarray:
        amplitudes = super().cycle(phase)
        for name, samples in self.tables.items():
            n = len(samples)
            periodic = np.concatenate([[samples[-1]], samples])
            amplitudes[self.patterns.index(name)] = np.interp(phase % 1.0 if phase != 1.0 else 1.0,
                                                              np.arange(n + 1) / n, periodic)
        return amplitudes
