"""The verdict of a procedure run and the figures it rests on (paper §3; SPEC §5).

:func:`cycle_figures` gives the global figures of one load cycle (area fractions over the
nominal contact area, stick margin, wear, dissipation); :func:`wear_figures` the worn volume
and the deepest wear, with each body's own field in finite sliding; :func:`active_slip_area_fraction` the
area that still slides in the sense of the verdict; :func:`loosening_evident` whether the clamp
force keeps falling while the stick area shrinks; :func:`verdict` the engineer's answer
(``stick``, ``partial_slip``, ``damage`` or ``loosening``; :data:`VERDICT_MEANINGS`). :class:`Ending` is why a run stopped. Pure functions of
arrays: no I/O. Units: area mm², pressure MPa, dissipation mJ/mm², slip mm, force N.
"""

from __future__ import annotations

from enum import Enum

import numpy as np

from contact.law import ContactState, Status


VERDICT_MEANINGS = {
    "stick": "shakedown to stick: at most the area tolerance still slides; the joint is safe at this load",
    "partial_slip": "a stick zone holds and loosening is not evident, but the contact edges keep sliding at a "
                    "COF that never had to rise (constant COF, or mu_0 = mu_max): fretting at the edges, no "
                    "friction-driven surface damage; judge crack risk by FFDP",
    "damage": "points keep sliding after their COF rose there, at mu_max or still rising towards it when the run "
              "ended (or the whole contact slides): fretting scars expected, loosening not evident",
    "loosening": "the clamp force keeps falling while the stick area shrinks, or half of it is lost: the joint "
                 "loosens",
}


class Ending(str, Enum):
    """Why a procedure run ended.

    completed: every cycle of every phase ran; shakedown: the contact became stationary (stuck)
    and the run stopped early; loosening: the wear phase stopped because loosening was evident;
    slid_off: an increment failed because tangential equilibrium was lost (the load exceeds what
    friction can carry); wear_runaway: an increment failed because the wear increment did not
    shrink with the step; separated: the contact surfaces, re-paired where the bodies had moved
    (finite sliding), no longer face each other: they slid or wore apart during the run;
    diverged: an increment failed for another reason.
    """

    COMPLETED = "completed"
    SHAKEDOWN = "shakedown"
    LOOSENING = "loosening"
    SLID_OFF = "slid_off"
    WEAR_RUNAWAY = "wear_runaway"
    SEPARATED = "separated"
    DIVERGED = "diverged"


def _fractions(area, nominal, mask):
    return float(area[mask].sum() / nominal) if nominal > 0 else 0.0


#: A point's COF has evolved once it has risen by more than this share of its range μ_max − μ0
#: (numerical micro-slips of equilibrium iterations raise μ by round-off amounts that are not fretting).
COF_EVOLVED_SHARE = 0.01
#: The clamp force's loss rate holds up (loosening, :func:`loosening_evident`) while the second half
#: of the window loses at least this share of the first half's rate per real cycle.
RATE_HOLDS = 0.8


def cycle_figures(area: np.ndarray, nominal_area: float, status: np.ndarray,
                  max_utilised: np.ndarray, state: ContactState, cof_initial: np.ndarray,
                  cof_max, area_tolerance: float, master_wear: np.ndarray | None = None,
                  master_area: np.ndarray | None = None) -> dict:
    """Global figures of a cycle: area fractions, margin, wear, dissipation.

    Fractions refer to the nominal contact area (closed after the preload). The stick margin
    is 1 − max utilised COF / μ_max over points that stayed stuck. The wear figures are
    :func:`wear_figures`: ``master_wear`` (mm) and ``master_area`` (mm², mm in 2D) are the
    master body's own wear field and its nodes' areas in finite sliding, None while the
    pairing is fixed.
    """
    stuck = status == Status.STICK
    slipped = status >= Status.SLIP
    damaged = status == Status.SLIP_AT_MAX
    wear = state.gap if state.wear_depth is not None else np.zeros_like(area)
    margins = 1.0 - max_utilised[stuck] / np.broadcast_to(cof_max, area.shape)[stuck]
    return {
        "stick_area_fraction": _fractions(area, nominal_area, stuck),
        "slip_area_fraction": _fractions(area, nominal_area, slipped),
        "damaged_area_fraction": _fractions(area, nominal_area, damaged),
        "worn_area_fraction": _fractions(area, nominal_area, np.asarray(wear) > 1e-9),
        "cof_evolved_area_fraction": _fractions(area, nominal_area, state.cof > cof_initial + COF_EVOLVED_SHARE * (
            np.broadcast_to(cof_max, area.shape) - cof_initial)),
        **wear_figures(area, state, master_wear, master_area),
        "dissipated_energy_mJ": float(np.sum(state.dissipation * area)),
        "min_stick_margin": float(margins.min()) if margins.size else None,
    }


def wear_figures(area: np.ndarray, state: ContactState, master_wear: np.ndarray | None = None,
                 master_area: np.ndarray | None = None) -> dict:
    """``wear_volume_mm3``, the volume both bodies have lost, mm³ (mm² per mm in 2D), and
    ``max_wear_depth_mm``, mm.

    Pairing fixed (small sliding; ``master_wear`` None): each point's two depths lie on top of
    each other, so the volume is Σ gap·A over the points and the depth is the deepest gap, the
    two bodies' depths at one point added. Finite sliding: each body's depth lives on its own
    surface (SPEC §4), and the master's scar reaches beyond the points' current partners. The
    volume is then the slave's depth × the points' areas plus the master's own field ×
    ``master_area`` (its nodes' areas). The depth is the deepest material removed at one
    place: the deepest gap (where the two scars lie on top of each other, at the points'
    current partners, their depths add) or the deepest of either body's own field, whichever
    is deeper. A short stroke gives small sliding's figure; a stroke longer than the contact
    leaves the master's scar deepest where the slave no longer is.
    """
    if state.wear_depth is None:
        return {"max_wear_depth_mm": 0.0, "wear_volume_mm3": 0.0}
    gap = state.gap
    if master_wear is None:
        return {"max_wear_depth_mm": float(np.max(gap, initial=0.0)),
                "wear_volume_mm3": float(np.sum(np.asarray(gap) * area))}
    slave = state.wear_depth[0]
    deepest = max(np.max(gap, initial=0.0), np.max(slave, initial=0.0), np.max(master_wear, initial=0.0))
    return {"max_wear_depth_mm": float(deepest),
            "wear_volume_mm3": float(np.sum(slave * area) + np.sum(master_wear * master_area))}


def active_slip_area_fraction(area: np.ndarray, nominal_area: float, pressure: np.ndarray,
                              dissipation_in_cycle: np.ndarray, cof: np.ndarray,
                              critical_slip, slip_tolerance: float) -> float:
    """Fraction of the nominal area that still slides in a cycle, in the sense of the verdict.

    A point slides when its pressure-weighted irreversible slip over the cycle,
    Σ p·Δγ_sl / p̄ (Σ p·Δγ_sl = dissipation / μ, the Archard wear driver; p̄ the mean pressure
    over the nominal area at the end of the cycle), exceeds ``slip_tolerance``·γ_crit.
    Two kinds of point fail that test although their status says slip: points worn out of
    contact, whose pressure Archard wear drives towards zero only asymptotically (w·Δγ·p
    vanishes with p), and points at the stick limit whose irreversible slip is a tiny
    fraction of the elastic slip γ_crit the law already treats as stick. Neither carries
    friction load nor wears or evolves its COF any more. Units: area mm², pressure MPa,
    dissipation mJ/mm², critical_slip mm.
    """
    mean_pressure = float(np.sum(pressure * area) / nominal_area) if nominal_area > 0 else 0.0
    if mean_pressure <= 0.0:
        return 0.0
    weighted_slip = np.divide(dissipation_in_cycle, cof, out=np.zeros_like(dissipation_in_cycle),
                              where=cof > 0.0) / mean_pressure
    sliding = weighted_slip > slip_tolerance * np.broadcast_to(critical_slip, area.shape)
    return _fractions(area, nominal_area, sliding)


def clamp_lost(clamp_force: float | None, initial_clamp: float | None, procedure) -> bool:
    """Whether a bolted joint has lost ``procedure.clamp_loss_limit`` of its clamp force (N, the
    bolts' summed force against ``initial_clamp``, that after the preload): it has loosened,
    whatever the trend. A joint whose clamp is gone presses nothing, so nothing slides with any
    pressure and the sliding measures read as stick."""
    if clamp_force is None or initial_clamp is None or initial_clamp <= 0.0:
        return False
    return clamp_force <= (1.0 - procedure.clamp_loss_limit) * initial_clamp


def verdict(history: list, procedure, stationary: bool, loosened_before: bool = False,
            lost_clamp: bool = False) -> str:
    """``loosening`` when the joint lost its clamp (``lost_clamp``, :func:`clamp_lost`), or when
    loosening is evident (:func:`loosening_evident`; also when it was evident earlier in the run,
    ``loosened_before``, and the joint has not shaken down since: a run going on to its life
    horizon may see the loss rate slow over its last window without being any safer), else
    ``stick`` when at most ``area_tolerance`` of the area still slid in the last cycle (:func:`active_slip_area_fraction`; histories
    without it fall back to the status-based slip area), else ``partial_slip`` when a stick
    zone holds and no COF evolved (the status "slip at μ_max" of a contact with μ_0 = μ_max
    says nothing about damage), else ``damage``. See :data:`VERDICT_MEANINGS`."""
    last = history[-1].figures
    if lost_clamp or (loosened_before and not stationary) or loosening_evident(history, procedure):
        return "loosening"
    sliding = last.get("active_slip_area_fraction", last["slip_area_fraction"])
    if sliding <= procedure.area_tolerance:
        return "stick"
    if (last["stick_area_fraction"] > procedure.area_tolerance
            and last.get("cof_evolved_area_fraction", 1.0) <= procedure.area_tolerance):
        return "partial_slip"
    return "damage"


def loosening_window_blocks(history: list, procedure) -> int:
    """How many of the last cycles of ``history`` the loosening window spans: the last
    ``loosening_window`` blocks, or with ``loosening_window_cycles`` the blocks of the last that
    many real cycles (at least ``loosening_window`` of them), one block before the window
    included so that it spans the whole span (a history shorter than the window: all of it)."""
    span = procedure.loosening_window_cycles
    least = max(procedure.loosening_window, 1)
    if span is None or not history:
        return least
    reach = history[-1].equivalent_cycles - span
    count = 1
    while count < len(history) and history[-count].equivalent_cycles > reach:
        count += 1
    return max(count, least)


def _clamp_window(history: list, procedure):
    """The wear cycles of the loosening window (:func:`loosening_window_blocks`) with their clamp
    forces (N), real cycles and the loss rates (N per real cycle) over its two halves of equal
    real duration; None while the wear phase does not fill the window."""
    wear_cycles = [c for c in history if c.phase == "wear" and c.clamp_force is not None]
    if len(wear_cycles) < max(procedure.loosening_window, 2):
        return None
    span = procedure.loosening_window_cycles
    if span is not None and wear_cycles[-1].equivalent_cycles - wear_cycles[0].equivalent_cycles < span:
        return None  # the wear phase does not span the window yet
    recent = wear_cycles[-loosening_window_blocks(wear_cycles, procedure):]
    force = np.array([c.clamp_force for c in recent])
    real = np.array([c.equivalent_cycles for c in recent])  # blocks of an adaptive jump differ in length
    if real[-1] <= real[0]:
        return None
    middle = int(np.searchsorted(real, 0.5 * (real[0] + real[-1])))  # halves of equal real duration
    middle = min(max(middle, 1), len(real) - 2) if len(real) > 2 else 1
    first_rate = (force[0] - force[middle]) / (real[middle] - real[0])
    second_rate = (force[middle] - force[-1]) / (real[-1] - real[middle]) if middle < len(real) - 1 else first_rate
    return recent, force, real, first_rate, second_rate


def loosening_evident(history: list, procedure) -> bool:
    """Loosening is evident when, over the loosening window (:func:`loosening_window_blocks`:
    the last ``loosening_window`` wear cycles, or those of the last ``loosening_window_cycles``
    real cycles), the clamp
    force keeps falling without its rate per real cycle decaying (second half at least 0.8 of
    the first; blocks of an adaptive cycle jump stand for different numbers of cycles),
    by a visible amount (0.5 % of the clamp force), while the stick area shrinks or the
    whole contact slides. The shrinking is the least-squares trend of the stick area over
    the window, not its first and last values: points at the stick limit flicker between
    stick and slip from cycle to cycle by a few per cent of the area, and an endpoint
    comparison called a contact loosening whose stick area was steady or regrowing."""
    window = _clamp_window(history, procedure)
    if window is None or len(window[0]) < procedure.loosening_window:
        return False
    recent, force, real, first_rate, second_rate = window
    stick = np.array([c.figures["stick_area_fraction"] for c in recent])
    falling = second_rate > 0.0 and second_rate >= RATE_HOLDS * first_rate
    visible = force[0] - force[-1] > 5e-3 * abs(force[0])
    stick_change = np.polyfit(real - real[0], stick, 1)[0] * (real[-1] - real[0])
    stick_shrinks = stick_change < -procedure.area_tolerance or stick[-1] <= procedure.area_tolerance
    return bool(falling and visible and stick_shrinks)


def clamp_loss_pace(rate_ratio: float | None) -> str:
    """How the clamp force was falling, in words, from ``clamp_loss_rate_ratio`` (the window's
    second half's loss rate over its first's): slowing below :data:`RATE_HOLDS`."""
    return "at a slowing rate" if rate_ratio is not None and rate_ratio < RATE_HOLDS else "at an undiminished rate"


def clamp_still_falling(history: list, procedure, initial_clamp: float | None) -> dict:
    """How much clamp force (N) the joint lost over the loosening window when it is still losing
    it visibly at the end (more than 0.5 % of ``initial_clamp`` over the window, and in its
    second half too): ``clamp_loss_recent_fraction`` (of the initial clamp force),
    ``clamp_loss_recent_cycles`` (the window's real cycles) and ``clamp_loss_rate_ratio`` (the
    second half's rate over the first's: below 1 the loss is slowing). Empty when the clamp
    force has settled, or the window is not filled. A joint judged stuck, partial_slip or
    damage while this is not empty has not settled: its clamp force may level off or go on
    falling (QA: a double beam at constant COF lost 6.3 % in 1e5 cycles, still falling at a
    slowing rate, and was called partial_slip, whose meaning then said "clamp force stable")."""
    window = _clamp_window(history, procedure)
    if window is None or initial_clamp is None or initial_clamp <= 0.0:
        return {}
    recent, force, real, first_rate, second_rate = window
    lost = force[0] - force[-1]
    if lost <= 5e-3 * initial_clamp or second_rate <= 0.0:
        return {}
    return {"clamp_loss_recent_fraction": float(lost / initial_clamp),
            "clamp_loss_recent_cycles": float(real[-1] - real[0]),
            "clamp_loss_rate_ratio": float(second_rate / first_rate) if first_rate > 0.0 else None}
