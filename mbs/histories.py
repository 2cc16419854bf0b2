"""Histories of one multibody run: the dataclass, its collection from exudyn sensors, energy,
and the one definition of the wing amplitude.

The wing amplitude (:func:`wing_amplitude`) is half the peak-to-peak of the wing torsion
(u_z(+x tip) - u_z(-x tip))/2 over the steady state of a run, in mm. The steady state is the
second half of the run (:func:`steady_part`): the first half is the start-up transient, so a
run must last long enough for the transient to decay (a few times 1 / (damping ratio x 2 pi f)
of the torsion mode). Every command, plot, study and report reads the wing amplitude from here.

Whether it did decay is measured, not assumed (:func:`unsettled_change`): the wing amplitude
over the first engine cycle of the steady half (two revolutions of a four-stroke engine, the
longest period of its excitation) against that over its last. A transient still ringing down
makes the two differ; a steady response repeats every engine cycle. The shipped counterweight
model at 750 rpm, started at full speed, rings from its start-up at 56 µm over the first engine
cycle, 13 µm over revolutions 1-3, 1.15 µm over 2-4 and 0.56 µm from revolution 3 on; at
900 rpm the ring-down lasts more revolutions (it decays in time, not in revolutions): 8
revolutions still left the amplitude 3.8 % high there, 12 (the shipped scene) do not.

Units: mm, N, t, s, rad; energies in mJ (N mm).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mbs.counterweight import ReducedCounterweight

#: Energy is evaluated on at most this many samples: the CW kinetic energy needs the full FE mass.
ENERGY_SAMPLES = 201

#: revolutions of one engine cycle (four-stroke): the longest period of the excitation
ENGINE_CYCLE_REVOLUTIONS = 2.0

#: how much the wing amplitude may change between the first and the last engine cycle of the
#: steady half (:func:`unsettled_change`) for the run to count as steady
SETTLED_CHANGE = 0.05


def steady_part(n_samples: int) -> slice:
    """The samples of a run's steady state: its second half (the first is the start-up transient)."""
    return slice(n_samples // 2, None)


def wing_amplitude(steady_torsion: np.ndarray) -> np.ndarray:
    """The wing amplitude, mm: half the peak-to-peak of the wing torsion over the steady state.

    steady_torsion: wing torsion (mm) over the steady part of a run, samples along the last
    axis ((n,) for one CW, (number of CWs, n) for all); returns a float or one value per CW.
    """
    torsion = np.asarray(steady_torsion, dtype=float)
    return 0.5 * (torsion.max(axis=-1) - torsion.min(axis=-1))


def unsettled_change(crank_angle: np.ndarray, torsion: np.ndarray) -> float | None:
    """How far a run's response is from steady where its wing amplitude is measured: the relative
    change of the wing amplitude between the first and the last engine cycle
    (:data:`ENGINE_CYCLE_REVOLUTIONS`) of the steady half (:func:`steady_part`),
    |A_last - A_first| / max(A_last, A_first), the largest over the CWs.

    crank_angle (n,) rad over the whole run; torsion (n,) or (number of CWs, n) mm, the wing
    torsion over the whole run. None when the steady half is shorter than two engine cycles:
    the first and the last would overlap (they were the same samples at 4 revolutions, and the
    change read 0 for a run still ringing down: QA, 2026-11-28), and the run's steadiness
    cannot be judged. Compare with :data:`SETTLED_CHANGE`.
    """
    revolutions = (np.asarray(crank_angle, dtype=float) - crank_angle[0]) / (2.0 * np.pi)
    torsion = np.atleast_2d(np.asarray(torsion, dtype=float))
    span, slack = ENGINE_CYCLE_REVOLUTIONS, 1e-9 * max(revolutions[-1], 1.0)
    start, end = revolutions[steady_part(revolutions.size)][0], revolutions[-1]
    if end - start < 2.0 * span - slack:
        return None
    first = (revolutions >= start - slack) & (revolutions <= start + span + slack)
    last = revolutions >= end - span - slack
    a_first, a_last = wing_amplitude(torsion[:, first]), wing_amplitude(torsion[:, last])
    larger = np.maximum(a_first, a_last)
    change = np.divide(np.abs(a_last - a_first), larger, out=np.zeros_like(larger), where=larger > 0.0)
    return float(change.max())


def unsettled_message(change: float | None, revolutions: float, speed_rpm: float) -> str | None:
    """What to tell the user about a run's steadiness (:func:`unsettled_change`), or None when it
    is steady. revolutions: the run's length ([mbs.solver] revolutions); speed_rpm: its speed."""
    if change is not None and change <= SETTLED_CHANGE:
        return None
    advice = (f"raise [mbs.solver] revolutions (now {revolutions:g}) so that the start-up transient has "
              "died out before the second half of the run, where the wing amplitude is measured")
    if change is None:
        return (f"the multibody run at {speed_rpm:g} rpm is too short to check that its response is steady "
                f"(its second half must span two engine cycles, {2 * ENGINE_CYCLE_REVOLUTIONS:g} revolutions, to "
                f"compare the first with the last): {advice}")
    return (f"the multibody response at {speed_rpm:g} rpm is not steady: the wing amplitude over the last "
            f"engine cycle differs by {100 * change:.1f} % from that over the first of the run's second half "
            f"(at most {100 * SETTLED_CHANGE:.0f} %): {advice}")


@dataclass(frozen=True)
class SolverStatistics:
    """Counters of one fixed-step generalized-alpha run (exudyn's SolverIterationData).

    newton_iterations: all Newton iterations of the run, the Jacobian-reusing (modified) ones
    included; jacobian_evaluations: Jacobians computed and factorised.
    """

    time_steps: int
    newton_iterations: int
    jacobian_evaluations: int

    @property
    def newton_iterations_per_step(self) -> float:
        return self.newton_iterations / max(self.time_steps, 1)


@dataclass(frozen=True)
class RunHistories:
    """Fixed-step histories of one run (rows = samples at ``time``).

    Per counterweight c (first axis of every cw_* array; throw k carries c = 2k on its journal-1
    side and c = 2k + 1 on its journal-2 side; "2" below is the number of CWs), all vectors in the CW local frame (x tangential, y radial out, z crank axis):
    cw_interface_displacement (2, n, 3) mm and cw_interface_rotation (2, n, 3) rad: CW
    interface relative to the web; cw_interface_force (2, n, 3) N and cw_interface_moment
    (2, n, 3) N mm: load the web applies to the CW at its interface (exudyn's joint reaction,
    negated); cw_modal_coordinates,
    cw_modal_velocities, cw_modal_accelerations (2, n, m); cw_frame_acceleration (2, n, 3) mm/s^2
    (interface origin, absolute); cw_angular_velocity (2, n, 3) rad/s;
    cw_angular_acceleration (2, n, 3) rad/s^2; cw_wing_tip_axial (2, n, 2) mm: axial deformation
    of the two wing tips relative to the interface. crank_angle (n,) rad, crank_speed (n,) rad/s.
    energy_time (n_e,) s and energy (n_e,) mJ: total mechanical energy at up to ENERGY_SAMPLES
    evenly spaced samples when requested, else None. wall_time: s spent in the solver.
    solver: exudyn's iteration counters of the run (time steps, Newton iterations, Jacobian
    evaluations); None for histories read back from a file.
    """

    time: np.ndarray
    crank_angle: np.ndarray
    crank_speed: np.ndarray
    cw_interface_displacement: np.ndarray
    cw_interface_rotation: np.ndarray
    cw_interface_force: np.ndarray
    cw_interface_moment: np.ndarray
    cw_modal_coordinates: np.ndarray
    cw_modal_velocities: np.ndarray
    cw_modal_accelerations: np.ndarray
    cw_frame_acceleration: np.ndarray
    cw_angular_velocity: np.ndarray
    cw_angular_acceleration: np.ndarray
    cw_wing_tip_axial: np.ndarray
    energy_time: np.ndarray | None
    energy: np.ndarray | None
    wall_time: float
    solver: SolverStatistics | None = None

    @property
    def wing_torsion(self) -> np.ndarray:
        """(2, n) mm: opposite-phase (torsion) part of the wing-tip axial motion, (u_+x - u_-x)/2."""
        return 0.5 * (self.cw_wing_tip_axial[:, :, 1] - self.cw_wing_tip_axial[:, :, 0])

    @property
    def wing_amplitude(self) -> np.ndarray:
        """(number of CWs,) mm: the wing amplitude of each CW (:func:`wing_amplitude`)."""
        return wing_amplitude(self.wing_torsion[:, steady_part(len(self.time))])

    @property
    def unsettled_change(self) -> float | None:
        """How far the response is from steady (:func:`unsettled_change`), None if the run is too short to tell."""
        return unsettled_change(self.crank_angle, self.wing_torsion)

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall-clock second."""
        return float((self.time[-1] - self.time[0]) / self.wall_time)


def counterweight_energy(reduced: ReducedCounterweight, rotation, velocity, omega, q, q_t) -> np.ndarray:
    """Kinetic + strain energy (mJ) of one CW from its frame motion and modal coordinates.

    Nodal velocities in the CW frame: A^T v + omega x (x_ref + Psi q) + Psi q_t; kinetic energy
    1/2 V^T M V with the full FE mass matrix, strain energy 1/2 q^T K_red q.
    """
    n_samples = q.shape[0]
    psi = reduced.mode_shapes
    positions = reduced.node_coordinates.ravel()[:, None] + psi @ q.T
    local_velocity = np.einsum("sji,sj->si", rotation.reshape(n_samples, 3, 3), velocity)
    pos = positions.reshape(-1, 3, n_samples)
    omega_t = omega.T[None, :, :]
    cross = np.cross(omega_t, pos, axis=1)
    nodal = (cross + local_velocity.T[None, :, :]).reshape(-1, n_samples) + psi @ q_t.T
    kinetic = 0.5 * np.einsum("is,is->s", nodal, reduced.mass @ nodal)
    modal_stiffness = psi.T @ (reduced.stiffness @ psi)
    strain = 0.5 * np.einsum("si,ij,sj->s", q, modal_stiffness, q)
    return kinetic + strain


def _stored(mbs, sensor) -> np.ndarray:
    return np.asarray(mbs.GetSensorStoredData(sensor))


def solver_statistics(mbs) -> SolverStatistics:
    """Iteration counters of the last SolveDynamic of ``mbs`` (it stores its solver in mbs.sys)."""
    counters = mbs.sys["dynamicSolver"].it
    return SolverStatistics(time_steps=int(counters.numberOfSteps), newton_iterations=int(counters.newtonStepsCount),
                            jacobian_evaluations=int(counters.newtonJacobiCount))


def collect_histories(mbs, sensors, reduced: ReducedCounterweight, energy: bool, wall_time: float) -> RunHistories:
    """RunHistories from the stored sensors of a finished exudyn run (sensor keys as mbs.model adds them)."""
    spin = _stored(mbs, sensors["spin"])
    # Sensors write when t reaches the next write time; round-off can store one instant twice.
    keep = np.concatenate([[True], np.diff(spin[:, 0]) > 0.5 * np.median(np.diff(spin[:, 0]))])
    spin = spin[keep]
    time = spin[:, 0]
    n_cw = sum(1 for key in sensors if isinstance(key, tuple) and key[0] == "q")
    data = {key: np.stack([_stored(mbs, sensors[(key, c)])[keep, 1:] for c in range(n_cw)])
            for key in ("q", "q_t", "q_tt", "rotation", "acceleration", "omega", "alpha", "velocity",
                        "joint_displacement", "joint_rotation", "joint_force", "joint_moment")}
    rotation = data["rotation"].reshape(n_cw, -1, 3, 3)
    to_local = lambda vectors: np.einsum("csji,csj->csi", rotation, vectors)  # A^T v per sample
    tip_shapes = reduced.wing_tip_axial_shapes()
    energy_time = total_energy = None
    if energy:
        picked = np.unique(np.linspace(0, len(time) - 1, ENERGY_SAMPLES).astype(int))
        energy_time = time[picked]
        total_energy = sum(_stored(mbs, s)[keep][picked, 1] for s in sensors["kinetic"] + sensors["potential"])
        for c in range(n_cw):
            total_energy = total_energy + counterweight_energy(
                reduced, *(data[key][c][picked] for key in ("rotation", "velocity", "omega", "q", "q_t")))
    return RunHistories(
        time=time,
        crank_angle=_stored(mbs, sensors["angle"])[keep, 6],
        crank_speed=spin[:, 6],
        cw_interface_displacement=data["joint_displacement"],
        cw_interface_rotation=data["joint_rotation"],
        cw_interface_force=-data["joint_force"],
        cw_interface_moment=-data["joint_moment"],
        cw_modal_coordinates=data["q"],
        cw_modal_velocities=data["q_t"],
        cw_modal_accelerations=data["q_tt"],
        cw_frame_acceleration=to_local(data["acceleration"]),
        cw_angular_velocity=data["omega"],
        cw_angular_acceleration=to_local(data["alpha"]),
        cw_wing_tip_axial=np.einsum("tm,csm->cst", tip_shapes, data["q"]),
        energy_time=energy_time,
        energy=total_energy,
        wall_time=wall_time,
        solver=solver_statistics(mbs),
    )
