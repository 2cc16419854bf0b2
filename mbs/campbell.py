"""Campbell diagram of the reduced counterweight: eigenfrequencies versus engine speed.

In the frame that spins with the shaft (angular speed Omega about the crank axis, the CW's local
z), the modal coordinates q of a CW whose interface is held by the web obey

    M q'' + 2 Omega G q' + (K - Omega^2 S) q = 0,

with M, K the reduced mass and stiffness, G = Psi^T M (I x Z) Psi the gyroscopic and
S = Psi^T M (I x P) Psi the spin-softening matrix (Z: cross product with the unit crank axis,
P: projection onto the plane normal to it). These are the terms exudyn's floating-frame body
carries, so the diagram shows the frequencies the multibody run resonates at. Frequencies in Hz,
speeds in rpm.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
import scipy.sparse as sp

from mbs.counterweight import ReducedCounterweight, reduced_matrices

_AXIS_CROSS = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
_PLANE = np.diag([1.0, 1.0, 0.0])


@dataclass(frozen=True)
class Campbell:
    """speeds_rpm (n_s,); frequencies (n_s, n_modes) Hz of the reduced CW sorted per speed;
    orders (n_o,) engine orders drawn as lines f = order * rpm / 60; crossings: list of dicts
    with keys order, mode, speed_rpm, frequency_hz where an order line meets a CW mode line.
    system_frequencies (n_s, k) Hz: eigenfrequencies of the coupled multibody model (crank throw
    + both CWs) or None; system_crossings: the order crossings of those modes, where a run may
    resonate (a resonance only where the swept amplitude peaks)."""

    speeds_rpm: np.ndarray
    frequencies: np.ndarray
    orders: np.ndarray
    crossings: list
    system_frequencies: np.ndarray | None = None
    system_crossings: list = field(default_factory=list)


def _spin_matrices(reduced: ReducedCounterweight) -> tuple[np.ndarray, np.ndarray]:
    psi = reduced.mode_shapes
    n_nodes = reduced.node_coordinates.shape[0]
    rotate = sp.kron(sp.identity(n_nodes), _AXIS_CROSS, format="csr")
    project = sp.kron(sp.identity(n_nodes), _PLANE, format="csr")
    mass_psi = reduced.mass @ psi
    return psi.T @ (rotate.T @ mass_psi), psi.T @ (project @ mass_psi)


def rotating_eigenfrequencies(reduced: ReducedCounterweight, speeds_rpm) -> np.ndarray:
    """(n_s, n_modes) eigenfrequencies (Hz) of the reduced CW spinning at each speed."""
    stiffness, mass = reduced_matrices(reduced)
    gyroscopic, softening = _spin_matrices(reduced)
    n = stiffness.shape[0]
    rows = []
    for rpm in np.atleast_1d(np.asarray(speeds_rpm, dtype=float)):
        omega = rpm * 2.0 * np.pi / 60.0
        mass_inverse = np.linalg.inv(mass)
        companion = np.block([
            [np.zeros((n, n)), np.eye(n)],
            [-mass_inverse @ (stiffness - omega ** 2 * softening), -2.0 * omega * mass_inverse @ gyroscopic],
        ])
        eigenvalues = scipy.linalg.eigvals(companion)
        rows.append(np.sort(np.abs(eigenvalues.imag[eigenvalues.imag > 0]))[:n] / (2.0 * np.pi))
    return np.asarray(rows)


def order_crossings(speeds_rpm, frequencies, orders) -> list:
    """Speeds where an engine-order line f = order * rpm / 60 crosses a mode line (linear
    interpolation between the given speeds). Each crossing names the mode by its column
    (``mode``, 0 the lowest) and as an engineer counts it (``mode_number``, 1 the lowest)."""
    speeds = np.asarray(speeds_rpm, dtype=float)
    crossings = []
    for order in np.asarray(orders, dtype=float):
        excitation = order * speeds / 60.0
        for mode in range(frequencies.shape[1]):
            gap = frequencies[:, mode] - excitation
            for i in np.nonzero(np.sign(gap[:-1]) * np.sign(gap[1:]) <= 0)[0]:
                if gap[i] == gap[i + 1]:
                    continue
                fraction = gap[i] / (gap[i] - gap[i + 1])
                speed = speeds[i] + fraction * (speeds[i + 1] - speeds[i])
                crossings.append({"order": float(order), "mode": int(mode), "mode_number": int(mode) + 1,
                                  "speed_rpm": float(speed),
                                  "frequency_hz": float(order * speed / 60.0)})
    return sorted(crossings, key=lambda c: c["speed_rpm"])


def campbell_diagram(reduced: ReducedCounterweight, speeds_rpm, orders, system_frequencies=None) -> Campbell:
    """Reduced-CW eigenfrequencies over speeds_rpm with the engine-order lines and crossings.

    system_frequencies: optional (n_s, k) coupled-model eigenfrequencies at the same speeds
    (mbs.model.system_eigenfrequencies), whose order crossings are added as system_crossings.
    """
    speeds = np.asarray(speeds_rpm, dtype=float)
    frequencies = rotating_eigenfrequencies(reduced, speeds)
    system = None if system_frequencies is None else np.asarray(system_frequencies, dtype=float)
    return Campbell(speeds_rpm=speeds, frequencies=frequencies, orders=np.asarray(orders, dtype=float),
                    crossings=order_crossings(speeds, frequencies, orders),
                    system_frequencies=system,
                    system_crossings=[] if system is None else order_crossings(speeds, system, orders))
