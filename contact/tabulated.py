"""Load programs whose patterns follow tabulated histories over a load cycle.

A :class:`TabulatedProgram` is a :class:`contact.procedure.LoadProgram` in which some patterns
(shape ``"history"``) follow sampled values over one cycle instead of sin 2πt: the inertia
loads of a counterweight driven by multibody histories, for instance. They are zero while the
bolts are tightened (at standstill) and locked, come on with their mean values in the run-up
that follows (:meth:`TabulatedProgram.run_up`, no COF evolution or wear there), and follow
their tabulated values from the first cycle on.
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

    def run_up(self, fraction: float) -> np.ndarray:
        """Amplitudes while the tabulated means come on after the preload (engine run-up):
        ``fraction`` of each table's mean, every other pattern as between cycles."""
        amplitudes = super().cycle(0.0)
        for name, samples in self.tables.items():
            amplitudes[self.patterns.index(name)] = fraction * float(np.mean(samples))
        return amplitudes

    def cycle(self, phase: float, vibration: float = 1.0) -> np.ndarray:
        amplitudes = super().cycle(phase, vibration)
        for name, samples in self.tables.items():
            n = len(samples)
            periodic = np.concatenate([[samples[-1]], samples])
            value = np.interp(phase % 1.0 if phase != 1.0 else 1.0, np.arange(n + 1) / n, periodic)
            mean = float(np.mean(samples))
            amplitudes[self.patterns.index(name)] = value if vibration == 1.0 else mean + vibration * (value - mean)
        return amplitudes
