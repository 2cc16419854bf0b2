"""One-way coupling of the multibody histories to the counterweight–web contact model.

The multibody run (``mbs``) gives, for one counterweight (CW), the motion of its interface
frame and its Craig–Bampton modal coordinates. The contact model is quasi-static in that
frame: the CW carries the d'Alembert load of its absolute acceleration field

    a(x, t) = a_frame + α × r + ω × (ω × r) + 2 ω × Ψ q̇ + Ψ q̈        (r = x − interface origin)

and the web is held at its far face (the web is the moving reference frame; its own
deformation is not modelled). Each term is one load pattern, condensed once with the CW
(unit frame acceleration per axis, unit angular acceleration per axis, unit ω_z², one
pattern per mode for q̈ and one for ω_z·q̇), and scaled in time by its history. The modes are
the multibody model's, interpolated from its quadratic tetrahedra onto the contact mesh.

The fields are exact for the multibody CW: held at its face, a CW of the same geometry
deforms under them as the multibody CW vibrates (tested: torsion-mode coordinate within 5 %).
The contact CW may differ from the multibody one in details (the generic joint's screw holes
make it 15 % softer in torsion): its response to the same fields differs accordingly.

Only ω_z (the spin) enters the centrifugal and Coriolis terms; ω_x, ω_y of the web tilt are
below 1e-3 of it. Contact does not feed back into the multibody run (one-way coupling).

One contact load cycle is either one period of the dominant wing vibration (``wing_period``,
the default and the paper's choice: constant bolt and centrifugal loads, sinusoidal wing
vibration; every history is reduced to its mean plus its harmonic at that frequency), or one
engine revolution (``revolution``: the last whole revolution of the run, resampled).

Two field sets (``fields``): ``all`` (the default) is the complete acceleration field above;
``wing_mode`` is the paper's CW loading ("bolt forces and centrifugal force constant, the wing
vibration sinusoidal"): the steady centrifugal load plus the elastic load of the wing torsion
mode, normalised so that the CW with its contact face held twists its wings by exactly the
wing torsion history (mm). ``all`` carries the CW's whole rigid-body motion at the vibration
frequency as well (for the generic throw at 375 Hz its radial acceleration loads the joint as
much as the torsion itself), ``wing_mode`` isolates the mode the paper's limit is stated for.

The wing amplitude (half the peak-to-peak wing torsion, mm) can be imposed: the vibrating part
of every history is scaled by amplitude / multibody amplitude, exactly what scaling the
excitation of the linear multibody model would do; the means (centrifugal) are kept. In
``wing_period`` cycles the harmonic is scaled to the whole stated amplitude (conservative when
the wing signal holds other frequencies too).

Units: mm, N, t, s; accelerations mm/s², angular velocities rad/s.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import skfem

from reduction.body_loads import mode_shape_inertia, rigid_body_inertia
from reduction.elasticity import ElasticBody
from reduction.errors import InputError

CYCLES = ("wing_period", "revolution")
_AXES = "xyz"


@dataclass(frozen=True)
class CouplingSettings:
    """The scene's ``[coupling]`` table.

    body: contact body that is the counterweight. counterweight: which CW of the multibody
    model (1 = journal-1 side of throw 1). cycle: "wing_period" or "revolution".
    wing_amplitude: mm, or None for the multibody amplitude at the engine speed.
    """

    body: str
    counterweight: int = 1
    cycle: str = "wing_period"
    wing_amplitude: float | None = None
    fields: str = "all"


FIELDS = ("all", "wing_mode")


@dataclass(frozen=True)
class MultibodyLoading:
    """What the contact model takes from one multibody run, for one CW (CW frame).

    time (n,) s of the steady part (second half of the run); frame_acceleration (n, 3) mm/s²;
    angular_velocity, angular_acceleration (n, 3) rad/s, rad/s²; modal_coordinates,
    modal_velocities, modal_accelerations (n, m); wing_torsion (n,) mm. mesh_points (3, n_v), mesh_cells (4, n_t):
    the CW's linear tetrahedral mesh (P2 elements on it); mode_shapes (3·n_nodes, m),
    node-interleaved in the P2 DOF order of that mesh. speed_rpm: engine speed.
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
    torsion_frequency_hz: float
    torsion_mode: int
    wall_time_s: float

    @property
    def n_modes(self) -> int:
        return int(self.mode_shapes.shape[1])

    @property
    def wing_amplitude(self) -> float:
        """Half the peak-to-peak wing torsion over the steady part, mm."""
        return 0.5 * float(np.ptp(self.wing_torsion))

    @property
    def revolution_period(self) -> float:
        return 60.0 / self.speed_rpm

    def dominant_frequency(self) -> float:
        """Frequency (Hz) of the largest peak of the wing torsion spectrum."""
        from mbs.spectra import peak_frequency

        return peak_frequency(self.time, self.wing_torsion)


def run_multibody(params, counterweight: int) -> MultibodyLoading:
    """Simulate the multibody model (mbs.ModelParams) and keep what CW ``counterweight`` needs."""
    from mbs.counterweight import reduce_counterweight
    from mbs.flexible_throw import reduce_throw
    from mbs.model import simulate

    if not 1 <= counterweight <= params.n_counterweights:
        raise InputError(f"'coupling.counterweight' is {counterweight}, but the multibody model has "
                         f"{params.n_counterweights} counterweights (1 … {params.n_counterweights})")
    reduced = reduce_counterweight(params.counterweight, params.n_modes)
    reduced_throw = reduce_throw(params.throw) if "flexible_crankshaft" in params.effects else None
    histories = simulate(params, reduced=reduced, reduced_throw=reduced_throw)
    steady = slice(len(histories.time) // 2, None)
    c = counterweight - 1
    mesh = reduced.body.mesh
    geometry = params.counterweight
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
        geometry={"width": geometry.width, "height": geometry.height, "thickness": geometry.thickness},
        torsion_frequency_hz=reduced.torsion_frequency,
        torsion_mode=int(reduced.torsion_mode),
        wall_time_s=histories.wall_time,
    )


def interpolate_modes(loading: MultibodyLoading, coordinates: np.ndarray) -> np.ndarray:
    """(n, 3, m) mode shapes at the points ``coordinates`` (n, 3), mm per unit modal coordinate.

    The multibody CW's quadratic-tetrahedron fields are evaluated at the points, which must lie
    in that CW (same geometry and frame)."""
    mesh = skfem.MeshTet1(loading.mesh_points, loading.mesh_cells)
    basis = skfem.Basis(mesh, skfem.ElementVector(skfem.ElementTetP2()))
    if basis.N != loading.mode_shapes.shape[0]:
        raise InputError("the multibody CW modes do not match its mesh (stale cache?): rerun the multibody stage")
    low, high = loading.mesh_points.min(axis=1), loading.mesh_points.max(axis=1)
    tolerance = 1e-6 * float(np.max(high - low))
    outside = np.any((coordinates < low - tolerance) | (coordinates > high + tolerance), axis=1)
    if outside.any():
        raise InputError(f"{int(outside.sum())} node(s) of the counterweight contact mesh lie outside the "
                         f"multibody counterweight (box {low.round(3).tolist()} … {high.round(3).tolist()} mm); "
                         "the contact body must have the multibody CW's geometry and frame")
    # probe slightly inside the box so that points on the outer faces find their element
    centre = 0.5 * (low + high)
    points = coordinates + 1e-9 * (centre - coordinates)
    probes = basis.probes(points.T)  # rows: component-major (all x, all y, all z)
    values = probes @ loading.mode_shapes
    return values.reshape(3, len(coordinates), -1).transpose(1, 0, 2)


def inertia_patterns(body: ElasticBody, loading: MultibodyLoading) -> dict[str, np.ndarray]:
    """Unit load patterns (N per unit history value) of the CW's acceleration field.

    frame_a{x,y,z}: per mm/s² of interface acceleration; alpha_{x,y,z}: per rad/s² of angular
    acceleration; spin_squared: per (rad/s)² of ω_z²; mode_k: per unit q̈_k; coriolis_k: per unit
    ω_z·q̇_k. The CW frame origin is the centre of the contact face (the coordinate origin).
    """
    if body.dim != 3:
        raise InputError("the counterweight coupling needs a 3D contact model")
    patterns = {}
    for k, axis in enumerate(_AXES):
        unit = np.eye(3)[k]
        patterns[f"frame_a{axis}"] = rigid_body_inertia(body, unit)
        patterns[f"alpha_{axis}"] = rigid_body_inertia(body, np.zeros(3), unit)
    patterns["spin_squared"] = rigid_body_inertia(body, np.zeros(3), None, np.array([0.0, 0.0, 1.0]))
    shapes = interpolate_modes(loading, body.coordinates)  # (n_nodes, 3, m)
    n_dofs = body.n_dofs
    modes = np.zeros((n_dofs, loading.n_modes))
    modes[body.node_dofs.ravel()] = shapes.reshape(-1, loading.n_modes)
    inertia = mode_shape_inertia(body, modes)
    spin_cross = np.zeros_like(modes)  # e_z × Ψ_k, per node: (-ψ_y, ψ_x, 0)
    spin_cross[body.node_dofs[:, 0]] = -modes[body.node_dofs[:, 1]]
    spin_cross[body.node_dofs[:, 1]] = modes[body.node_dofs[:, 0]]
    coriolis = -2.0 * (body.mass @ spin_cross)
    for k in range(loading.n_modes):
        patterns[f"mode_{k + 1}"] = inertia[:, k]
        patterns[f"coriolis_{k + 1}"] = coriolis[:, k]
    return patterns


def centrifugal_pattern(body: ElasticBody, loading: MultibodyLoading) -> np.ndarray:
    """Load (N) of the steady rotation: the mean interface acceleration and the mean ω_z² field."""
    load = np.zeros(body.n_dofs)
    for k in range(3):
        load += loading.frame_acceleration[:, k].mean() * rigid_body_inertia(body, np.eye(3)[k])
    spin_squared = float(np.mean(loading.angular_velocity[:, 2] ** 2))
    return load + spin_squared * rigid_body_inertia(body, np.zeros(3), None, np.array([0.0, 0.0, 1.0]))


def wing_mode_pattern(body: ElasticBody, loading: MultibodyLoading, clamped_nodes: np.ndarray) -> np.ndarray:
    """Load (N) of the wing "torsion" mode per mm of wing torsion (the paper's wing vibration).

    The elastic force ω_t² M Ψ_t of the multibody CW's torsion mode (interpolated), scaled so that
    the CW with its contact face ``clamped_nodes`` held deflects by a wing torsion
    (u_z(+x tip) − u_z(−x tip))/2 of exactly 1 mm under it.
    """
    from reduction.factorization import factorize

    shapes = interpolate_modes(loading, body.coordinates)[:, :, loading.torsion_mode]
    mode = np.zeros(body.n_dofs)
    mode[body.node_dofs.ravel()] = shapes.ravel()
    omega = 2.0 * np.pi * loading.torsion_frequency_hz
    load = omega ** 2 * (body.mass @ mode)
    fixed = np.zeros(body.n_dofs, dtype=bool)
    fixed[body.node_dofs[clamped_nodes].ravel()] = True
    free = np.flatnonzero(~fixed)
    displacement = np.zeros(body.n_dofs)
    factor = factorize(body.stiffness[free][:, free].tocsc(), label="clamped counterweight")
    displacement[free] = factor.solve(load[free])
    coordinates = body.coordinates
    tips = [np.flatnonzero((np.abs(coordinates[:, 0] - sign * coordinates[:, 0].max()) < 1e-6)
                           & (np.abs(coordinates[:, 1] - coordinates[:, 1].max()) < 1e-6)) for sign in (-1, 1)]
    if any(t.size == 0 for t in tips):
        raise InputError("the counterweight contact mesh has no wing-tip edge (outer face at the x extremes)")
    torsion = 0.5 * (displacement[body.node_dofs[tips[1], 2]].mean() - displacement[body.node_dofs[tips[0], 2]].mean())
    if abs(torsion) < 1e-12:
        raise InputError("the interpolated torsion mode does not twist the counterweight's wings")
    return load / torsion


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
    multibody_wing_amplitude: mm, before scaling.
    """

    tables: dict
    wing_torsion: np.ndarray
    frequency_hz: float
    wing_amplitude: float
    scale: float
    multibody_wing_amplitude: float
    cycle: str


def _harmonic(time, signal, frequency):
    """Mean and complex amplitude of ``signal`` at ``frequency`` (least squares on time)."""
    phase = 2.0 * np.pi * frequency * (time - time[0])
    basis = np.column_stack([np.ones_like(time), np.cos(phase), np.sin(phase)])
    (mean, cosine, sine), *_ = np.linalg.lstsq(basis, signal, rcond=None)
    return mean, cosine, sine


def cycle_loading(loading: MultibodyLoading, settings: CouplingSettings, n_samples: int) -> CycleLoading:
    """The histories of every inertia pattern over one contact load cycle (see the module doc)."""
    if settings.cycle not in CYCLES:
        raise InputError(f"'coupling.cycle' must be one of {CYCLES}, got {settings.cycle!r}")
    if settings.fields not in FIELDS:
        raise InputError(f"'coupling.fields' must be one of {FIELDS}, got {settings.fields!r}")
    phases = np.arange(1, n_samples + 1) / n_samples
    signals = _signals(loading)
    if settings.cycle == "wing_period":
        frequency = loading.dominant_frequency()
        fits = {name: _harmonic(loading.time, values, frequency) for name, values in signals.items()}
        _, wc, ws = fits["wing_torsion"]
        reference = float(np.hypot(wc, ws))
        # start the cycle where the wing torsion harmonic crosses zero upwards: it reads sin(2πθ)
        offset = np.arctan2(wc, ws)
        angle = 2.0 * np.pi * phases - offset

        def synthesise(name, scale):
            mean, cosine, sine = fits[name]
            return mean + scale * (cosine * np.cos(angle) + sine * np.sin(angle))
    else:
        frequency = 1.0 / loading.revolution_period
        start = loading.time[-1] - loading.revolution_period
        if start < loading.time[0] - 1e-12:
            raise InputError("'coupling.cycle' = 'revolution' needs the steady half of the multibody run to "
                             "last one revolution: raise [mbs.solver] revolutions to at least 2")
        window = loading.time >= start
        reference = loading.wing_amplitude
        means = {name: float(np.mean(values[window])) for name, values in signals.items()}
        sample_times = start + phases * loading.revolution_period

        def synthesise(name, scale):
            values = np.interp(sample_times, loading.time, signals[name])
            return means[name] + scale * (values - means[name])
    if reference <= 0.0:
        raise InputError("the multibody run shows no wing vibration to scale (zero wing torsion): "
                         "switch on an excitation in [mbs] effects")
    amplitude = loading.wing_amplitude if settings.wing_amplitude is None else settings.wing_amplitude
    scale = amplitude / reference
    tables = {}
    for k, axis in enumerate(_AXES):
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
                        loading.wing_amplitude, settings.cycle)


def with_amplitude(settings: CouplingSettings, wing_amplitude: float | None) -> CouplingSettings:
    return replace(settings, wing_amplitude=wing_amplitude)
