"""Scan and refine: every change of verdict over a range of amplitudes, not only the first.

A bisection for "the" stick limit assumes that a larger amplitude never gives a safer verdict.
Measured on the counterweight, that is not so (a mesh at which 300 µm shook down to stick
while 256 µm loosened), and a bisection then reports whichever change it happens to land on.
This search first runs a coarse grid over the whole range, then refines, in rounds, every
interval whose two ends disagree, until each is no wider than the tolerance. The limit is the
lowest amplitude whose verdict is not ``stick``; every change is listed, and a verdict that
comes back to ``stick`` above the limit is reported as non-monotone.

A change of verdict and back again between two neighbouring grid points is not seen: the
grid's spacing is the resolution of the scan, the tolerance that of each change it finds.
Pure logic: ``evaluate(amplitudes)`` runs the cases (in parallel where it can).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from itertools import pairwise

import numpy as np

SAFE = "stick"


@dataclass(frozen=True)
class Change:
    """Neighbouring amplitudes (mm) with different verdicts, at most the tolerance apart."""

    below_mm: float
    above_mm: float
    verdict_below: str
    verdict_above: str

    @property
    def to_unsafe(self) -> bool:
        return self.verdict_below == SAFE and self.verdict_above != SAFE


@dataclass
class Scan:
    """Verdicts by amplitude (mm) and what they say.

    limit_mm: the lowest amplitude whose verdict is not ``stick`` (None: all stuck);
    stuck_below_mm: the largest stuck amplitude below it (None: the lowest was not stuck);
    monotone: once not stuck, never stuck again at a larger amplitude.
    """

    verdicts: dict = field(default_factory=dict)

    def sorted(self) -> list[tuple[float, str]]:
        return sorted(self.verdicts.items())

    @property
    def changes(self) -> list[Change]:
        runs = self.sorted()
        return [Change(a, b, va, vb) for (a, va), (b, vb) in pairwise(runs) if va != vb]

    @property
    def limit_mm(self) -> float | None:
        return next((a for a, v in self.sorted() if v != SAFE), None)

    @property
    def stuck_below_mm(self) -> float | None:
        limit = self.limit_mm
        stuck = [a for a, v in self.sorted() if v == SAFE and (limit is None or a < limit)]
        return stuck[-1] if stuck else None

    @property
    def monotone(self) -> bool:
        limit = self.limit_mm
        return limit is None or all(v != SAFE for a, v in self.sorted() if a > limit)


def decimal_mm(amplitude_mm) -> float:
    """An amplitude (mm) rounded to 1e-9 mm: the value its decimal digits say, as a scene would
    state it (the grid's and the bisection's arithmetic left 238.74999999999997 µm, shown as
    238.7, and a run at it differed from a run at 238.75 µm in its last digits)."""
    return round(float(amplitude_mm), 9)


def scan(evaluate: Callable[[Sequence[float]], dict], low_mm: float, high_mm: float, *,
         tolerance_mm: float, grid: int = 7, parallel: int = 1) -> Scan:
    """Scan ``grid`` amplitudes over [low_mm, high_mm], then refine every change of verdict.

    evaluate: amplitudes (mm) → {amplitude: verdict} for those amplitudes.
    parallel: amplitudes to run per round; each interval that still has to narrow gets an
    equal share of them, at least one. Give a number that does not depend on the machine (not
    the workers): the amplitudes run, and so what is found, depend on it.
    """
    if grid < 2:
        raise ValueError("the scan needs a grid of at least 2 amplitudes")
    result = Scan()
    result.verdicts.update(evaluate([decimal_mm(a) for a in np.linspace(low_mm, high_mm, grid)]))
    while True:
        wide = [c for c in result.changes if c.above_mm - c.below_mm > tolerance_mm]
        if not wide:
            return result
        share = max(1, parallel // len(wide))
        points = [decimal_mm(c.below_mm + (c.above_mm - c.below_mm) * k / (share + 1))
                  for c in wide for k in range(1, share + 1)]
        result.verdicts.update(evaluate(points))
