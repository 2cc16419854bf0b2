"""Mesh convergence of a scene: its verdict and figures at several contact element sizes.

Each level runs the whole scene with every body mesh's ``contact_size`` set to one size (mm):
verdict, stick / sliding / worn areas, maximum wear depth, clamp-force loss, minimum stick
margin and, when asked, the wing-amplitude limit. Where three or more levels halve the size
and a figure converges monotonically, Richardson extrapolation estimates its limit h → 0 and
the observed order. A scene is converged at a size when its verdict equals that of the next
finer level and its limit is within ``limit_tolerance`` of the finest level's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from itertools import pairwise

FIGURES = ("stick_area_fraction", "active_slip_area_fraction", "cof_evolved_area_fraction",
           "worn_area_fraction", "max_wear_depth_mm", "clamp_force_loss_fraction", "min_stick_margin",
           "equivalent_cycles")


@dataclass
class Level:
    """One element size (mm) and what the scene gave there; limit_mm None when not searched."""

    size_mm: float
    verdict: str
    figures: dict
    limit_mm: float | None = None
    monotone: bool | None = None
    points: int | None = None
    wall_time_s: float | None = None
    extra: dict = field(default_factory=dict)


def size_overrides(data: dict, size_mm: float) -> dict:
    """Dotted overrides that set every body mesh's ``contact_size`` (mm) to ``size_mm``."""
    overrides = {f"bodies.{name}.mesh.contact_size": float(size_mm)
                 for name, body in data.get("bodies", {}).items()
                 if isinstance(body.get("mesh"), dict) and "contact_size" in body["mesh"]}
    if not overrides:
        raise ValueError("no body mesh of the scene has a contact_size to refine (mesh files are fixed)")
    return overrides


def richardson(sizes, values) -> dict | None:
    """Richardson estimate of the h → 0 value from the three finest levels.

    sizes: element sizes (mm), any order; values: the figure at each. Needs a constant
    refinement ratio r > 1 and monotone convergence (differences of one sign, shrinking).
    Returns {"estimate", "order", "error_finest"} or None where the sequence does not allow it.
    """
    pairs = sorted((s, v) for s, v in zip(sizes, values) if v is not None and math.isfinite(v))
    if len(pairs) < 3:
        return None
    (h1, f1), (h2, f2), (h3, f3) = pairs[:3]  # finest first
    ratio = h2 / h1
    if not (ratio > 1.0 and math.isclose(h3 / h2, ratio, rel_tol=1e-6)):
        return None
    near, far = f2 - f1, f3 - f2
    if near == 0.0:
        return {"estimate": f1, "order": math.inf, "error_finest": 0.0}
    if far == 0.0 or near * far < 0.0 or abs(near) >= abs(far):
        return None  # oscillating or not yet converging: no estimate
    order = math.log(abs(far) / abs(near)) / math.log(ratio)
    estimate = f1 - near / (ratio ** order - 1.0)
    return {"estimate": estimate, "order": order, "error_finest": f1 - estimate}


def converged_size(levels: list[Level], limit_tolerance: float = 0.05) -> float | None:
    """The coarsest size whose verdict equals the next finer level's and whose limit is within
    ``limit_tolerance`` (relative) of the finest level's; None if no level qualifies."""
    ordered = sorted(levels, key=lambda level: level.size_mm, reverse=True)  # coarse first
    finest = ordered[-1]
    for level, finer in pairwise(ordered):
        if level.verdict != finer.verdict:
            continue
        if finest.limit_mm is not None or level.limit_mm is not None:
            if level.limit_mm is None or finest.limit_mm is None:
                continue
            if abs(level.limit_mm - finest.limit_mm) > limit_tolerance * finest.limit_mm:
                continue
        return level.size_mm
    return None


def extrapolations(levels: list[Level]) -> dict:
    """Richardson estimates of every figure (and the limit) that the levels allow."""
    sizes = [level.size_mm for level in levels]
    out = {}
    for name in FIGURES:
        found = richardson(sizes, [level.figures.get(name) for level in levels])
        if found is not None:
            out[name] = found
    found = richardson(sizes, [level.limit_mm for level in levels])
    if found is not None:
        out["limit_mm"] = found
    return out
