"""Parameters of the generic crankshaft-counterweight model (dataclasses, documented units).

The defaults describe one crank throw of a generic 320 mm-bore medium-speed four-stroke engine:
crank radius 200 mm, 750 rpm, a 79 kg counterweight bolted to each web. Units: mm, N, MPa, t, s.

Crank frame (rotates with the shaft): z along the crank axis, x from the axis towards the crank
pin, y tangential (direction of rotation at the pin). The counterweights sit on the webs opposite
the pin, their contact faces at x = -counterweight_radius.
"""

from __future__ import annotations

import math
import numbers

from dataclasses import dataclass, field

from mbs.counterweight import CounterweightGeometry
from mbs.refusal import Refusal, refuse
from reduction.errors import listed

#: The effects a scene can switch on; code for an effect that is off is not run.
KNOWN_EFFECTS = frozenset({"gas_torque", "gear_mesh", "torsional_vibration", "flexible_crankshaft"})


def _whole(value) -> bool:
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def _positive(value) -> bool:
    return math.isfinite(value) and value > 0


@dataclass(frozen=True)
class CrankThrowParams:
    """One crank throw made of two rigid half-throws (journal + web + half pin) joined at the pin.

    crank_radius: axis to pin centre, mm. journal_radius, pin_radius: mm.
    journal_length: length of each main journal, mm. web_thickness: axial, mm. web_width:
    tangential width of the web, mm. pin_length: axial length of the crank pin between webs, mm.
    counterweight_radius: axis to the CW contact face on the web's far side, mm.
    density: t/mm^3.
    bearing_stiffness: radial stiffness of each main bearing, N/mm; axial_stiffness: thrust
    bearing (journal 1 only), N/mm; bearing_damping: N s/mm (radial and axial).
    pin_stiffness: 6 values for the elastic joint at the crank pin between the half-throws:
    3 translational (N/mm) then 3 rotational (N mm/rad), in the crank frame. They stand for the
    bending and torsion of pin and webs; pin_damping: same layout, N s/mm and N mm s/rad.
    joint_stiffness: None (default) joins each CW interface rigidly to its web; or 6 values
    (3 N/mm, 3 N mm/rad, CW frame) of a stiff spring standing for the bolted joint, so that the
    interface motion relative to the web is the spring's deflection.
    journal_stiffness: 6 values (3 N/mm, 3 N mm/rad, crank frame) of the spring-damper that joins
    neighbouring throws of a multi-throw crankshaft at their shared main journal. Defaults are the
    closed forms of one main journal (length L = journal_length, radius r = journal_radius,
    E = 210 GPa, G = 80.8 GPa): shear 0.9 G pi r^2 / L = 2.9e7 N/mm (x, y), axial
    E pi r^2 / L = 8.2e7 N/mm (z), bending E I / L = 4.6e11 N mm/rad (x, y),
    torsion G J / L = 3.6e11 N mm/rad (z) with I = pi r^4 / 4, J = 2 I. journal_damping: same
    layout, N s/mm and N mm s/rad.
    youngs_modulus (MPa), poisson_ratio: material of the Craig-Bampton throw bodies of the
    "flexible_crankshaft" effect; flexible_modes: fixed-interface normal modes per throw body
    (besides the 18 constraint modes of its three non-frame interfaces).
    Damping is light structural damping (about 1 % at the 400 Hz coupled torsion mode) so that
    resonances stand out; hydrodynamic oil-film damping of the bearings is not modelled.
    """

    crank_radius: float = 200.0
    journal_radius: float = 150.0
    journal_length: float = 180.0
    web_thickness: float = 90.0
    web_width: float = 380.0
    pin_radius: float = 140.0
    pin_length: float = 160.0
    counterweight_radius: float = 230.0
    density: float = 7.85e-9
    bearing_stiffness: float = 2.0e6
    axial_stiffness: float = 1.0e6
    bearing_damping: float = 20.0
    pin_stiffness: tuple[float, ...] = (5.0e6, 5.0e6, 5.0e6, 5.0e11, 5.0e11, 5.0e11)
    pin_damping: tuple[float, ...] = (20.0, 20.0, 20.0, 2.0e6, 2.0e6, 2.0e6)
    joint_stiffness: tuple[float, ...] | None = None
    journal_stiffness: tuple[float, ...] = (2.9e7, 2.9e7, 8.2e7, 4.6e11, 4.6e11, 3.6e11)
    journal_damping: tuple[float, ...] = (20.0, 20.0, 20.0, 2.0e6, 2.0e6, 2.0e6)
    youngs_modulus: float = 210000.0
    poisson_ratio: float = 0.3
    flexible_modes: int = 8

    def validate(self) -> None:
        """Raise :class:`mbs.refusal.Refusal` for a value the model cannot use (only the mode count
        is checked: the throw's sizes are the user's to choose)."""
        if not _whole(self.flexible_modes) or self.flexible_modes < 1:
            # said here, with its key, not by the throw's reduction after the run started
            raise refuse("throw.flexible_modes", self.flexible_modes,
                         "must be a whole number of at least 1 (fixed-interface modes per throw body)")

    @property
    def web_center_z(self) -> float:
        """Axial position of the web mid-planes (+/-), mm."""
        return 0.5 * (self.pin_length + self.web_thickness)

    @property
    def bearing_z(self) -> float:
        """Axial position of the main-bearing centres (+/-), mm."""
        return self.web_center_z + 0.5 * (self.web_thickness + self.journal_length)

    @property
    def throw_pitch(self) -> float:
        """Axial distance of neighbouring throws (main-journal centre to main-journal centre), mm."""
        return 2.0 * self.bearing_z


@dataclass(frozen=True)
class ExcitationParams:
    """Engine excitation (units N mm for torques).

    gas_orders / gas_torque_amplitudes / gas_torque_phases: the order table of the gas torque of
    one cylinder, T(t) = sum_k T_k cos(k * crank_angle + phase_k) (orders in multiples of shaft
    speed; phases rad). Defaults: representative four-stroke medium-speed harmonics, amplitudes as
    multiples of a 6.4 kN m mean torque (about 500 kW per cylinder at 750 rpm). The tangential
    gas force T/crank_radius acts on the crank pin, the drive reacts the torque.
    gear_teeth: teeth of the crank gear, mesh frequency = gear_teeth x shaft frequency.
    gear_torque_amplitude: mesh torque fluctuation on journal 2, N mm.
    torsional_stiffness: shaft stiffness between the drive (flywheel) and journal 1 when the
    torsional-vibration effect is on, N mm/rad; torsional_damping: N mm s/rad;
    flywheel_inertia: t mm^2.
    """

    gas_orders: tuple[float, ...] = (0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 4.5, 5.0, 5.5, 6.0)
    gas_torque_amplitudes: tuple[float, ...] = tuple(
        6.4e6 * c for c in (1.6, 2.0, 1.9, 1.6, 1.3, 1.0, 0.75, 0.55, 0.4, 0.3, 0.22, 0.16))
    gas_torque_phases: tuple[float, ...] = (0.0,) * 12
    gear_teeth: int = 48
    gear_torque_amplitude: float = 2.0e5
    torsional_stiffness: float = 2.0e11
    torsional_damping: float = 2.0e7
    flywheel_inertia: float = 2.0e5

    def validate(self) -> None:
        """Raise :class:`mbs.refusal.Refusal` for the first value the model cannot use."""
        table = ("gas_orders", "gas_torque_amplitudes", "gas_torque_phases")
        lengths = [len(getattr(self, name)) for name in table]
        if len(set(lengths)) > 1:
            raise Refusal(tuple(f"excitation.{name}" for name in table), tuple(getattr(self, name) for name in table),
                          "must have the same length, one row of the order table each (lengths "
                          f"{', '.join(map(str, lengths))})")
        if not all(order > 0 for order in self.gas_orders):
            raise refuse("excitation.gas_orders", self.gas_orders, "must all be positive (multiples of shaft speed)")
        if not _whole(self.gear_teeth) or self.gear_teeth < 1:
            raise refuse("excitation.gear_teeth", self.gear_teeth,
                         "must be a whole number of at least 1 (teeth of the crank gear)")


@dataclass(frozen=True)
class SolverParams:
    """Fixed-step generalized-alpha integration.

    time_step: s (also the output sample period). revolutions: simulated shaft revolutions; the
    wing amplitude is measured over the second half, which must lie past the start-up transient
    (checked: :func:`mbs.histories.unsettled_change`; the shipped model needs about 8 at 900 rpm).
    spectral_radius: numerical damping of generalized-alpha at high frequency (1 = none). With
    exudyn's index-3 joint constraints, 1.0 did not converge in our runs; the default 0.9 keeps
    the energy drift of a free 100-revolution run at 2.5e-6 (mbs/NOTES.md).
    damping: False switches off all physical damping (bearings, pin, CW modes, shaft).
    drive: "constant_speed" holds the drive at engine speed (ideal governor and flywheel);
    "free": no drive, the shaft starts at engine speed and spins freely (energy check).
    newton_tolerance: relative Newton tolerance; exudyn's default 1e-8 is below the round-off
    of the stiff bearing/pin springs and makes Newton fail on stiff throws.
    ramp_revolutions: the excitation fades in over this many revolutions (0: full from t = 0).
    """

    time_step: float = 5.0e-5
    revolutions: float = 12.0
    spectral_radius: float = 0.9
    damping: bool = True
    drive: str = "constant_speed"
    newton_tolerance: float = 1e-6
    ramp_revolutions: float = 0.5

    def validate(self) -> None:
        """Raise :class:`mbs.refusal.Refusal` for the first value the model cannot use."""
        for name, unit in (("time_step", "s"), ("revolutions", "shaft revolutions")):
            if not _positive(getattr(self, name)):
                raise refuse(f"solver.{name}", getattr(self, name), f"must be positive ({unit})")
        if not (math.isfinite(self.ramp_revolutions) and self.ramp_revolutions >= 0):
            raise refuse("solver.ramp_revolutions", self.ramp_revolutions,
                         "must not be negative (shaft revolutions; 0: full excitation from t = 0)")
        if not 0.0 <= self.spectral_radius <= 1.0:
            raise refuse("solver.spectral_radius", self.spectral_radius, "must lie in [0, 1] (1: no numerical damping)")
        if self.drive not in ("constant_speed", "free"):
            raise refuse("solver.drive", self.drive, 'must be "constant_speed" or "free"')


@dataclass(frozen=True)
class ModelParams:
    """Everything that defines one run of the crankshaft-counterweight model.

    speed_rpm: engine speed. n_modes: Craig-Bampton (fixed-interface) modes per CW.
    modal_damping_ratio: damping ratio of every CW mode (-). effects: subset of KNOWN_EFFECTS.
    throws: number of crank throws chained along the crank axis (1 = the single-throw model);
    throw k sits at z = k x throw_pitch (journal centre to journal centre), throws share main
    journals and carry two CWs each (cw1, cw2 on throw 1, cw3, cw4 on throw 2, ...).
    crank_angles_deg: angle of each throw's pin about the crank axis (deg, direction of rotation);
    default evenly spaced, 360 k / throws. firing_angles_deg: crank angle at which each cylinder
    fires within the 720 deg four-stroke cycle (its gas-torque phase table: order n of cylinder k
    is shifted by -n x firing angle); default: the crank angles.
    """

    speed_rpm: float = 750.0
    counterweight: CounterweightGeometry = field(default_factory=CounterweightGeometry)
    n_modes: int = 6
    modal_damping_ratio: float = 0.02
    throw: CrankThrowParams = field(default_factory=CrankThrowParams)
    excitation: ExcitationParams = field(default_factory=ExcitationParams)
    solver: SolverParams = field(default_factory=SolverParams)
    effects: frozenset = frozenset({"gas_torque", "gear_mesh"})
    throws: int = 1
    crank_angles_deg: tuple[float, ...] | None = None
    firing_angles_deg: tuple[float, ...] | None = None

    @property
    def throw_angles(self) -> tuple[float, ...]:
        """Crank angle of each throw's pin, rad."""
        angles = self.crank_angles_deg if self.crank_angles_deg is not None \
            else tuple(360.0 * k / self.throws for k in range(self.throws))
        return tuple(math.radians(a) for a in angles)

    @property
    def firing_angles(self) -> tuple[float, ...]:
        """Firing angle of each cylinder in the 720 deg cycle, rad."""
        if self.firing_angles_deg is None:
            return self.throw_angles
        return tuple(math.radians(a) for a in self.firing_angles_deg)

    @property
    def n_counterweights(self) -> int:
        return 2 * self.throws

    def validate(self) -> None:
        """Raise :class:`mbs.refusal.Refusal` for the first value the model cannot use, naming
        its field ('n_modes', 'solver.time_step'), its value and what is allowed."""
        if not _whole(self.throws) or self.throws < 1:
            raise refuse("throws", self.throws, "must be a whole number of at least 1 (crank throws)")
        for name in ("crank_angles_deg", "firing_angles_deg"):
            table = getattr(self, name)
            if table is not None and len(table) != self.throws:
                raise Refusal((name, "throws"), (table, self.throws),
                              f"{name} must give one angle per throw: {self.throws} angles, not {len(table)}")
        if not _positive(self.speed_rpm):
            raise refuse("speed_rpm", self.speed_rpm, "must be positive (engine speed, rpm)")
        if not _whole(self.n_modes) or self.n_modes < 1:
            # said here, with its key, not by the Craig-Bampton reduction after the run started
            raise refuse("n_modes", self.n_modes,
                         "must be a whole number of at least 1 (Craig-Bampton modes per counterweight)")
        unknown = set(self.effects) - KNOWN_EFFECTS
        if unknown:
            raise refuse("effects", self.effects, f"may name only {listed(sorted(KNOWN_EFFECTS))}, not "
                         f"{listed(sorted(unknown))}")
        if not (math.isfinite(self.modal_damping_ratio) and self.modal_damping_ratio >= 0):
            raise refuse("modal_damping_ratio", self.modal_damping_ratio,
                         "must not be negative (damping ratio of every CW mode, a fraction of critical: 0.02 is 2 %)")
        self.counterweight.validate()
        self.throw.validate()
        self.excitation.validate()
        self.solver.validate()

    @property
    def shaft_speed(self) -> float:
        """Engine speed in rad/s."""
        return self.speed_rpm * 2.0 * math.pi / 60.0
