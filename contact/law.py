"""The paper's contact law (Mäntylä et al., eqs. 1-8), vectorised over contact points.

Pure functions: arrays in, arrays out. One call of :func:`evaluate` is the UINTER of the
paper for every point at once; :func:`advance` turns a converged increment into the new
history state (elastic slip, COF, wear, accumulated slip and dissipation).

Conventions (per point i, ``n_tangent`` = 1 in plane strain, 2 in 3D):

* ``overclosure`` h (mm): > 0 where the unworn surfaces interpenetrate.
* ``slip_increment`` Δs (mm): tangential relative displacement since the last converged
  increment, in the point's tangent frame.
* normal pressure p (MPa) and shear traction τ (MPa) act against the overclosure and the
  relative slip respectively; the equilibrium residual adds ``Gᵀ·A·[p, τ]``.

Units: mm, N, MPa, mJ. ``cof_rate`` k in mm/N, wear coefficients w in mm²/N.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from enum import IntEnum

import numpy as np

WEAR_FORMS = ("pressure", "shear")


class Status(IntEnum):
    """Contact status of a point after an increment."""

    OPEN = 0
    STICK = 1
    SLIP = 2
    SLIP_AT_MAX = 3  # sliding with the COF at μ_max: fretting damage expected


@dataclass(frozen=True)
class ContactLaw:
    """Material parameters of the interface; scalars or per-point arrays.

    normal_stiffness: kn, N/mm³ (pressure per mm of overclosure).
    critical_slip: γ_crit, mm (reversible elastic slip at the onset of sliding).
    cof_max: μ_max, the stable COF limit; μ never exceeds it.
    cof_rate: k, mm/N; dμ = k·Δγ_sl·|τ| (eq. 7). Used only with COF evolution on.
    wear_coefficients: w per body, mm²/N (Archard, eq. 8). Their sum opens the gap.
    pressure_limit: p_lim, MPa; no wear where p < p_lim.
    wear_form: "pressure" (Archard, w·Δγ·p) or "shear" (energy wear, w·Δγ·|τ|).
    """

    normal_stiffness: float | np.ndarray
    critical_slip: float | np.ndarray
    cof_max: float | np.ndarray = np.inf
    cof_rate: float | np.ndarray = 0.0
    wear_coefficients: tuple[float, ...] = (0.0, 0.0)
    pressure_limit: float = 0.0
    wear_form: str = "pressure"


@dataclass(frozen=True)
class ContactState:
    """History variables of every point, as converged at the end of an increment.

    elastic_slip: γ_el, (n, n_tangent) mm.
    cof: μ, (n,). Never decreases.
    wear_depth: (n_bodies, n) mm, one field per body; the gap is their sum. ``None`` when
        the scene does not ask for wear (nothing allocated).
    accumulated_slip: Σ Δγ_sl, (n,) mm.
    dissipation: frictional energy density Σ |τ|·Δγ_sl, (n,) mJ/mm².
    slip_vector: Σ Δγ_sl·n, (n, n_tangent) mm: the irreversible slip path, for slip ranges.
    """

    elastic_slip: np.ndarray
    cof: np.ndarray
    wear_depth: np.ndarray | None
    accumulated_slip: np.ndarray
    dissipation: np.ndarray
    slip_vector: np.ndarray = field(repr=False)

    @classmethod
    def initial(cls, n_points: int, n_tangent: int, cof: float | np.ndarray,
                n_wear_bodies: int | None = None) -> "ContactState":
        """Fresh state: no slip, COF at μ_0, zero wear (allocated only if ``n_wear_bodies``)."""
        cof_field = np.broadcast_to(np.asarray(cof, dtype=float), (n_points,)).copy()
        wear = None if n_wear_bodies is None else np.zeros((n_wear_bodies, n_points))
        return cls(
            elastic_slip=np.zeros((n_points, n_tangent)),
            cof=cof_field,
            wear_depth=wear,
            accumulated_slip=np.zeros(n_points),
            dissipation=np.zeros(n_points),
            slip_vector=np.zeros((n_points, n_tangent)),
        )

    @property
    def gap(self) -> np.ndarray | float:
        """Total wear depth r (mm) that acts as a gap, or 0 without wear."""
        return 0.0 if self.wear_depth is None else self.wear_depth.sum(axis=0)


@dataclass(frozen=True)
class Response:
    """Tractions, trial quantities and the consistent tangent of one evaluation.

    pressure: p, (n,) MPa.  shear: τ, (n, n_tangent) MPa.
    trial_slip: γ_tr = γ_el + Δs, (n, n_tangent) mm.
    slip: Δγ_sl, (n,) mm, irreversible slip of this increment.
    status: (n,) :class:`Status` codes (SLIP_AT_MAX is set by :func:`advance`).
    dpressure_dh: ∂p/∂h (n,), N/mm³.  dshear_dh: ∂τ/∂h (n, n_tangent).
    dshear_ds: ∂τ/∂Δs (n, n_tangent, n_tangent), N/mm³. Unsymmetric overall through ∂τ/∂h.
    """

    pressure: np.ndarray
    shear: np.ndarray
    trial_slip: np.ndarray
    slip: np.ndarray
    status: np.ndarray
    dpressure_dh: np.ndarray
    dshear_dh: np.ndarray
    dshear_ds: np.ndarray

    def tangent(self) -> np.ndarray:
        """The consistent tangent ∂[p, τ]/∂[h, Δs] per point, (n, dim, dim) in N/mm³."""
        n, n_tangent = self.shear.shape
        matrix = np.zeros((n, 1 + n_tangent, 1 + n_tangent))
        matrix[:, 0, 0] = self.dpressure_dh
        matrix[:, 1:, 0] = self.dshear_dh
        matrix[:, 1:, 1:] = self.dshear_ds
        return matrix


def evaluate(overclosure: np.ndarray, slip_increment: np.ndarray, state: ContactState,
             law: ContactLaw) -> Response:
    """Tractions and consistent tangent for trial kinematics (eqs. 1-6).

    overclosure: h, (n,) mm.  slip_increment: Δs, (n, n_tangent) mm since ``state``.
    The COF is the converged μ of ``state``: it changes only in :func:`advance`.
    """
    n_points, n_tangent = slip_increment.shape
    # Scalars broadcast in the arithmetic below; per-point arrays are used as they are.
    kn, gamma_crit, cof = law.normal_stiffness, law.critical_slip, state.cof

    penetration = overclosure - state.gap
    closed = penetration > 0.0
    pressure = np.where(closed, kn * penetration, 0.0)
    # One-sided derivative at exactly zero penetration: a body that just touches (a cylinder
    # on a plane under force control) then has a nonsingular tangent in its first iteration.
    dpressure_dh = np.where(penetration >= 0.0, kn, 0.0)

    trial = np.where(closed[:, None], state.elastic_slip + slip_increment, 0.0)
    trial_norm = np.sqrt(np.add.reduce(trial * trial, axis=1))
    sliding = closed & (trial_norm > gamma_crit)
    sticking = closed & ~sliding

    critical_shear = cof * pressure
    safe_norm = np.where(sliding, trial_norm, 1.0)
    direction = trial / safe_norm[:, None]

    # Open points have p = 0 and γ_tr = 0, so every branch below gives them zero.
    stick_stiffness = critical_shear / gamma_crit
    slide = sliding[:, None]
    shear = np.where(slide, critical_shear[:, None] * direction, stick_stiffness[:, None] * trial)

    identity = np.eye(n_tangent)
    slip_ds = (critical_shear / safe_norm)[:, None, None] * (
        identity - direction[:, :, None] * direction[:, None, :])
    dshear_ds = np.where(slide[:, :, None], slip_ds,
                         np.where(sticking, stick_stiffness, 0.0)[:, None, None] * identity)
    ratio = cof * kn
    dshear_dh = np.where(slide, ratio[:, None] * direction,
                         np.where(sticking, ratio / gamma_crit, 0.0)[:, None] * trial)

    status = closed.astype(np.int8)  # Status.OPEN 0, STICK 1
    status[sliding] = Status.SLIP
    return Response(
        pressure=pressure,
        shear=shear,
        trial_slip=trial,
        slip=np.where(sliding, trial_norm - gamma_crit, 0.0),
        status=status,
        dpressure_dh=dpressure_dh,
        dshear_dh=dshear_dh,
        dshear_ds=dshear_ds,
    )


def wear_increment(response: Response, law: ContactLaw, cycle_jump: float = 1.0) -> np.ndarray:
    """Archard wear depth increment of each body (eq. 8), (n_bodies, n) mm.

    Pressure form: w·Δγ_sl·p; shear (energy) form: w·Δγ_sl·|τ|. No wear where p < p_lim.
    ``cycle_jump`` J: one simulated cycle stands for J real ones.
    """
    if law.wear_form not in WEAR_FORMS:
        raise ValueError(f"wear_form must be one of {WEAR_FORMS}, got {law.wear_form!r}")
    driver = response.pressure if law.wear_form == "pressure" else np.linalg.norm(
        response.shear, axis=1)
    active = (response.pressure >= law.pressure_limit) & (response.slip > 0.0)
    depth = np.where(active, cycle_jump * response.slip * driver, 0.0)
    return np.asarray(law.wear_coefficients, dtype=float)[:, None] * depth[None, :]


def advance(state: ContactState, response: Response, law: ContactLaw, *,
            cof_evolution: bool, wear: bool, cycle_jump: float = 1.0,
            cof_jump: float = 1.0) -> tuple[ContactState, np.ndarray]:
    """History update from a converged increment; returns the new state and final status.

    Elastic slip is γ_tr in stick, γ_crit·n in slip and reset to 0 where open. With
    ``cof_evolution`` μ ← min(μ + J_μ·k·Δγ_sl·|τ|, μ_max) (eq. 7, J_μ = ``cof_jump``: the real
    cycles the increment's COF change stands for, 1 unless a wear block scales it like its
    wear); with ``wear`` each body's depth grows by :func:`wear_increment` (``cycle_jump`` J).
    A point sliding with μ at μ_max is flagged :attr:`Status.SLIP_AT_MAX`.
    """
    slip = response.slip
    shear_norm = np.linalg.norm(response.shear, axis=1)
    trial_norm = np.linalg.norm(response.trial_slip, axis=1)
    sliding = slip > 0.0
    direction = response.trial_slip / np.where(sliding, trial_norm, 1.0)[:, None]
    elastic_slip = np.where(sliding[:, None], response.trial_slip - slip[:, None] * direction,
                            response.trial_slip)
    dissipation_increment = shear_norm * slip

    cof = state.cof
    if cof_evolution:
        cof = np.minimum(cof + cof_jump * np.asarray(law.cof_rate) * dissipation_increment, law.cof_max)
    wear_depth = state.wear_depth
    if wear:
        if wear_depth is None:
            raise ValueError("wear requested but the state has no wear field; "
                             "create it with ContactState.initial(..., n_wear_bodies=...)")
        wear_depth = wear_depth + wear_increment(response, law, cycle_jump)

    status = response.status.copy()
    at_max = sliding & (state.cof >= np.asarray(law.cof_max) * (1.0 - 1e-12))
    status[at_max] = Status.SLIP_AT_MAX
    new_state = replace(
        state,
        elastic_slip=elastic_slip,
        cof=cof,
        wear_depth=wear_depth,
        accumulated_slip=state.accumulated_slip + slip,
        dissipation=state.dissipation + dissipation_increment,
        slip_vector=state.slip_vector + slip[:, None] * direction,
    )
    return new_state, status


def utilised_cof(pressure: np.ndarray, shear: np.ndarray) -> np.ndarray:
    """|τ|/p where closed, 0 where open: how much of the available friction is in use.

    pressure (n,) and shear (n, n_tangent) in MPa (or both as nodal forces: the ratio is the same).
    """
    shear_norm = np.linalg.norm(shear, axis=1)
    return np.divide(shear_norm, pressure, out=np.zeros_like(shear_norm), where=pressure > 0.0)
