"""What one counterweight's contact model takes from a multibody run, and its load cycle.

:func:`counterweight_loading` reduces the bodies, simulates the model and keeps, for one CW,
the steady part of its frame motion and modal coordinates, its wing torsion and its modes
(:class:`MultibodyLoading`). :func:`cycle_loading` turns those histories into the amplitude
of every inertia pattern over one contact load cycle (:class:`CycleLoading`):

* ``wing_period`` (the paper's choice): one period of the dominant wing vibration; every history
  is reduced to its mean plus its harmonic at that frequency (least squares), the cycle starting
  where the wing torsion harmonic crosses zero upwards;
* ``revolution``: the last whole engine revolution of the run, resampled.

A stated wing amplitude scales the vibrating part of every history by amplitude / multibody
amplitude (what scaling the excitation of the linear multibody model would do); the means
(centrifugal) are kept. In ``wing_period`` cycles the harmonic is scaled to the whole stated
amplitude (conservative when the wing signal holds other frequencies too).

Units: mm, N, t, s; accelerations mm/s², angular velocities rad/s, frequencies Hz.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mbs.counterweight import ReducedCounterweight
from mbs.histories import RunHistories, steady_part, unsettled_message, wing_amplitude
from mbs.model import reduce_bodies, simulate
from mbs.parameters import ModelParams
from reduction.errors import InputError
from reduction.modal_loads import ModeField

CYCLES = ("wing_period", "revolution")
_AXES = "xyz"


@dataclass(frozen=True)
class MultibodyLoading:
    """What the contact model takes from one multibody run, for one CW (CW frame).

    time (n,) s of the steady part (:func:`mbs.histories.steady_part`); frame_acceleration (n, 3)
    mm/s²; angular_velocity, angular_acceleration (n, 3) rad/s, rad/s²; modal_coordinates,
    modal_velocities, modal_accelerations (n, m); wing_torsion (n,) mm. mesh_points (3, n_v),
    mesh_cells (4, n_t): the CW's linear tetrahedral mesh (P2 elements on it); mode_shapes
    (3·n_nodes, m), node-interleaved in the P2 DOF order of that mesh (m = 0, mesh empty: the
    histories carry no modes). speed_rpm: engine speed.
    geometry: the CW's width, height (outer face), thickness (mm); mode_frequencies_hz (m,):
    fixed-interface eigenfrequencies; torsion_mode: index of its wing torsion mode; wall_time_s:
    of the multibody run (0 for histories read from a file, :mod:`mbs.histories_file`).
    unsettled_change: how far the run was from steady (:func:`mbs.histories.unsettled_change`,
    None: too short to tell); revolutions: the run's length. Both None for histories read from
    a file, whose steadiness is the file's author's to ensure.
    """

    speed_rpm: float
    time: np.ndarray
    frame_acceleration: np.ndarray
    angular_velocity: np.ndarray
    angular_acceleration: np.ndarray
    modal_coordinates: np.ndarray
    modal_velocities: np.ndarray
    modal_accelerations: np.ndarray
    wing_torsion: np.ndarray
    mesh_points: np.ndarray
    mesh_cells: np.ndarray
    mode_shapes: np.ndarray
    geometry: dict
    mode_frequencies_hz: np.ndarray
    torsion_mode: int
    wall_time_s: float
    unsettled_change: float | None = None
    revolutions: float | None = None

    @property
    def unsettled(self) -> str | None:
        """Why the wing amplitude of this run cannot be trusted (its response is not steady), or
        None (steady, or histories from a file)."""
        if self.revolutions is None:
            return None
        return unsettled_message(self.unsettled_change, self.revolutions, self.speed_rpm)

    @property
    def n_modes(self) -> int:
        return int(self.mode_shapes.shape[1])

    @property
    def torsion_frequency_hz(self) -> float:
        """Fixed-interface frequency of the wing torsion mode, Hz."""
        return float(self.mode_frequencies_hz[self.torsion_mode])

    @property
    def modes(self) -> ModeField:
        """The CW's mode shapes on its multibody mesh."""
        return ModeField(self.mesh_points, self.mesh_cells, self.mode_shapes)

    @property
    def wing_amplitude(self) -> float:
        """The CW's wing amplitude, mm (:func:`mbs.histories.wing_amplitude`)."""
        return float(wing_amplitude(self.wing_torsion))

    @property
    def revolution_period(self) -> float:
        return 60.0 / self.speed_rpm

    def dominant_frequency(self) -> float:
        """Frequency (Hz) of the largest peak of the wing torsion spectrum."""
        from mbs.spectra import peak_frequency

        return peak_frequency(self.time, self.wing_torsion)


def counterweight_loading(params: ModelParams, counterweight: int) -> MultibodyLoading:
    """Reduce the bodies, simulate ``params`` and keep what CW ``counterweight`` (1 = first) needs."""
    if not 1 <= counterweight <= params.n_counterweights:
        raise InputError(f"'coupling.counterweight' is {counterweight}, but the multibody model has "
                         f"{params.n_counterweights} counterweights (1 … {params.n_counterweights})")
    reduced, reduced_throw = reduce_bodies(params)
    histories = simulate(params, reduced=reduced, reduced_throw=reduced_throw)
    return run_loading(params, reduced, histories, counterweight)


def run_loading(params: ModelParams, reduced: ReducedCounterweight, histories: RunHistories,
                counterweight: int) -> MultibodyLoading:
    """What CW ``counterweight`` (1 = first) of a finished run gives the contact model: the steady
    part of its histories, its mesh and modes."""
    steady = steady_part(len(histories.time))
    c = counterweight - 1
    mesh = reduced.body.mesh
    low, high = reduced.node_coordinates.min(axis=0), reduced.node_coordinates.max(axis=0)
    geometry = params.counterweight
    size = ({"width": geometry.width, "height": geometry.height, "thickness": geometry.thickness}
            if geometry.mesh_file is None else
            {"width": float(high[0] - low[0]), "height": float(high[1]), "thickness": float(high[2] - low[2])})
    return MultibodyLoading(
        speed_rpm=params.speed_rpm,
        time=histories.time[steady].copy(),
        frame_acceleration=histories.cw_frame_acceleration[c, steady].copy(),
        angular_velocity=histories.cw_angular_velocity[c, steady].copy(),
        angular_acceleration=histories.cw_angular_acceleration[c, steady].copy(),
        modal_coordinates=histories.cw_modal_coordinates[c, steady].copy(),
        modal_velocities=histories.cw_modal_velocities[c, steady].copy(),
        modal_accelerations=histories.cw_modal_accelerations[c, steady].copy(),
        wing_torsion=histories.wing_torsion[c, steady].copy(),
        mesh_points=np.asarray(mesh.p).copy(),
        mesh_cells=np.asarray(mesh.t).copy(),
        mode_shapes=np.asarray(reduced.mode_shapes).copy(),
        geometry=size,
        mode_frequencies_hz=np.asarray(reduced.eigenfrequencies, dtype=float).copy(),
        torsion_mode=int(reduced.torsion_mode),
        wall_time_s=histories.wall_time,
        unsettled_change=histories.unsettled_change,
        revolutions=float(params.solver.revolutions),
    )


def _signals(loading: MultibodyLoading) -> dict[str, np.ndarray]:
    """The history of every pattern's amplitude (before the products), name → (n,)."""
    signals = {}
    for k, axis in enumerate(_AXES):
        signals[f"frame_a{axis}"] = loading.frame_acceleration[:, k]
        signals[f"alpha_{axis}"] = loading.angular_acceleration[:, k]
    signals["spin"] = loading.angular_velocity[:, 2]
    for k in range(loading.n_modes):
        signals[f"mode_{k + 1}"] = loading.modal_accelerations[:, k]
        signals[f"velocity_{k + 1}"] = loading.modal_velocities[:, k]
    signals["wing_torsion"] = loading.wing_torsion
    return signals


@dataclass(frozen=True)
class CycleLoading:
    """Pattern histories over one contact load cycle.

    tables: pattern → (n_samples,) amplitude at phases k/n_samples, k = 1 … n (periodic).
    wing_torsion: (n_samples,) mm, the multibody wing torsion over the cycle after scaling.
    frequency_hz: the cycle's frequency; wing_amplitude: mm; scale: factor on the vibrating parts;
    multibody_wing_amplitude: mm, before scaling; cycle: "wing_period" or "revolution".
    """

    tables: dict
    wing_torsion: np.ndarray
    frequency_hz: float
    wing_amplitude: float
    scale: float
    multibody_wing_amplitude: float
    cycle: str


def harmonic_fit(time, signal, frequency):
    """Mean and the cosine and sine amplitudes of ``signal`` at ``frequency`` (Hz), by least
    squares over ``time`` (s)."""
    phase = 2.0 * np.pi * frequency * (time - time[0])
    basis = np.column_stack([np.ones_like(time), np.cos(phase), np.sin(phase)])
    (mean, cosine, sine), *_ = np.linalg.lstsq(basis, signal, rcond=None)
    return mean, cosine, sine


def _wing_period_synthesis(loading, signals, phases):
    """(synthesise(name, scale), reference amplitude, frequency) over one wing period."""
    frequency = loading.dominant_frequency()
    fits = {name: harmonic_fit(loading.time, values, frequency) for name, values in signals.items()}
    _, wc, ws = fits["wing_torsion"]
    # start the cycle where the wing torsion harmonic crosses zero upwards: it reads sin(2πθ)
    angle = 2.0 * np.pi * phases - np.arctan2(wc, ws)

    def synthesise(name, scale):
        mean, cosine, sine = fits[name]
        return mean + scale * (cosine * np.cos(angle) + sine * np.sin(angle))
    return synthesise, float(np.hypot(wc, ws)), frequency


def _revolution_synthesis(loading, signals, phases):
    """(synthesise(name, scale), reference amplitude, frequency) over the last whole revolution."""
    start = loading.time[-1] - loading.revolution_period
    if start < loading.time[0] - 1e-12:
        if loading.revolutions is None:  # histories read from a file
            raise InputError(f"'coupling.cycle' = 'revolution' needs one whole revolution of history "
                             f"({loading.revolution_period:.4g} s at {loading.speed_rpm:g} rpm); the interface-"
                             f"histories file spans {loading.time[-1] - loading.time[0]:.4g} s: give a longer "
                             "file, or use 'coupling.cycle' = 'wing_period'")
        raise InputError("'coupling.cycle' = 'revolution' needs the steady half of the multibody run to "
                         "last one revolution: raise [mbs.solver] revolutions to at least 2")
    window = loading.time >= start
    means = {name: float(np.mean(values[window])) for name, values in signals.items()}
    sample_times = start + phases * loading.revolution_period

    def synthesise(name, scale):
        values = np.interp(sample_times, loading.time, signals[name])
        return means[name] + scale * (values - means[name])
    return synthesise, loading.wing_amplitude, 1.0 / loading.revolution_period


def cycle_loading(loading: MultibodyLoading, cycle: str, wing_amplitude_mm: float | None,
                  n_samples: int) -> CycleLoading:
    """The histories of every inertia pattern over one contact load cycle (module doc).

    cycle: "wing_period" or "revolution"; wing_amplitude_mm: the stated wing amplitude (mm), or
    None for the multibody one; n_samples: samples of the cycle (the increments per cycle).

    Histories from a file whose wing torsion does not vibrate (a static check: constant loads)
    give, without a stated amplitude, the static cycle: every history its mean (scale 0), one
    cycle per revolution.
    """
    if cycle not in CYCLES:
        raise InputError(f"'coupling.cycle' must be one of {CYCLES}, got {cycle!r}")
    phases = np.arange(1, n_samples + 1) / n_samples
    signals = _signals(loading)
    synthesis = _wing_period_synthesis if cycle == "wing_period" else _revolution_synthesis
    synthesise, reference, frequency = synthesis(loading, signals, phases)
    amplitude = loading.wing_amplitude if wing_amplitude_mm is None else wing_amplitude_mm
    # a constant wing torsion fits a harmonic of round-off size, not a vibration to scale
    if reference <= 1e-12 * float(np.max(np.abs(loading.wing_torsion))):
        if loading.revolutions is not None:  # the in-process multibody model, not a file
            raise InputError("the multibody run shows no wing vibration to scale (zero wing torsion): "
                             "switch on an excitation in [mbs] effects")
        if wing_amplitude_mm is not None:
            raise InputError(f"the wing torsion of the interface histories does not vibrate, and a signal without "
                             f"vibration cannot be scaled to the stated 'coupling.wing_amplitude' = "
                             f"{wing_amplitude_mm:g} mm; leave 'coupling.wing_amplitude' out for a static check "
                             "(every history its mean)")
        means = {name: float(np.mean(values)) for name, values in signals.items()}

        def synthesise(name, scale):
            return np.full(n_samples, means[name])
        amplitude, scale, frequency = 0.0, 0.0, 1.0 / loading.revolution_period
    else:
        scale = amplitude / reference
    tables = {}
    for axis in _AXES:
        tables[f"frame_a{axis}"] = synthesise(f"frame_a{axis}", scale)
        tables[f"alpha_{axis}"] = synthesise(f"alpha_{axis}", scale)
    spin = synthesise("spin", scale)
    tables["spin_squared"] = spin ** 2
    for k in range(1, loading.n_modes + 1):
        tables[f"mode_{k}"] = synthesise(f"mode_{k}", scale)
        tables[f"coriolis_{k}"] = spin * synthesise(f"velocity_{k}", scale)
    tables["wing_mode"] = synthesise("wing_torsion", scale)
    tables["centrifugal"] = np.ones(n_samples)
    return CycleLoading(tables, synthesise("wing_torsion", scale), frequency, float(amplitude), float(scale),
                        loading.wing_amplitude, cycle)
