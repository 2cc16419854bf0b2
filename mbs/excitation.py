"""Engine excitation as functions of time at constant engine speed (pure functions).

Torques in N mm, speed in rad/s, time in s. The crank angle is speed * t (constant speed: the
drive holds the mean speed, torsional vibration is a small deviation from it).
"""

from __future__ import annotations

import numpy as np

from mbs.parameters import ExcitationParams
from reduction.errors import InputError


def gas_torque_table(shaft_speed: float, excitation: ExcitationParams) -> list[tuple[float, float, float]]:
    """Rows (angular frequency rad/s, amplitude N mm, phase rad) of the gas-torque order table."""
    return [(order * shaft_speed, amplitude, phase) for order, amplitude, phase in
            zip(excitation.gas_orders, excitation.gas_torque_amplitudes, excitation.gas_torque_phases)]


def cylinder_gas_torque_table(shaft_speed: float, excitation: ExcitationParams,
                              firing_angle: float) -> list[tuple[float, float, float]]:
    """Order table of a cylinder that fires firing_angle (rad, within the 720 deg cycle) after
    cylinder 1: its torque is cylinder 1's delayed by firing_angle / shaft_speed, so order n
    gets the phase -n x firing_angle."""
    return [(w, amplitude, phase - (w / shaft_speed) * firing_angle)
            for w, amplitude, phase in gas_torque_table(shaft_speed, excitation)]


def gas_torque(time, shaft_speed: float, excitation: ExcitationParams):
    """Fluctuating gas torque of one cylinder, sum_k T_k cos(order_k * angle + phase_k), N mm."""
    table = np.asarray(gas_torque_table(shaft_speed, excitation))
    angle = np.multiply.outer(np.asarray(time, dtype=float), table[:, 0])
    return (table[:, 1] * np.cos(angle + table[:, 2])).sum(axis=-1)


def gear_mesh_torque(time, shaft_speed: float, excitation: ExcitationParams):
    """Gear-mesh torque fluctuation at teeth x shaft frequency, N mm."""
    return excitation.gear_torque_amplitude * np.sin(excitation.gear_teeth * shaft_speed * np.asarray(time, dtype=float))


def excitation_orders(excitation: ExcitationParams, effects) -> np.ndarray:
    """Engine orders present in the excitation of the switched-on effects (sorted)."""
    orders = []
    if "gas_torque" in effects:
        orders.extend(excitation.gas_orders)
    if "gear_mesh" in effects:
        orders.append(float(excitation.gear_teeth))
    return np.unique(np.asarray(orders, dtype=float))


def gas_torque_from_pressure(crank_angle_deg, pressure, *, bore: float, crank_radius: float,
                             conrod_length: float, max_order: float = 12.0, samples: int = 1440):
    """Gas-torque order table of one cylinder from its pressure curve over a four-stroke cycle.

    crank_angle_deg: angles of the pressure samples over 0..720 deg (any spacing, periodic);
    pressure: gauge cylinder pressure, MPa; bore, crank_radius, conrod_length: mm.
    Piston force p * pi bore^2 / 4 acts through the slider crank (conrod angle beta,
    sin beta = (r/l) sin theta): torque T = F r sin(theta + beta) / cos(beta), mass forces left out.
    Returns (mean torque N mm, orders, amplitudes N mm, phases rad) with
    T(theta) = mean + sum_k amplitude_k cos(order_k theta + phase_k), orders 0.5 .. max_order.
    """
    angles = np.asarray(crank_angle_deg, dtype=float)
    pressure = np.asarray(pressure, dtype=float)
    if angles.shape != pressure.shape or angles.size < 8:
        raise InputError("gas pressure curve needs matching crank-angle and pressure columns (at least 8 rows)")
    if conrod_length <= crank_radius:
        raise InputError("conrod_length must be longer than crank_radius (slider crank)")
    theta = np.arange(samples) * (4.0 * np.pi / samples)
    p = np.interp(np.degrees(theta), angles, pressure, period=720.0)
    sin_beta = (crank_radius / conrod_length) * np.sin(theta)
    beta = np.arcsin(sin_beta)
    torque = p * (np.pi * bore ** 2 / 4.0) * crank_radius * np.sin(theta + beta) / np.cos(beta)
    coefficients = np.fft.rfft(torque) / samples
    n_harmonics = int(round(2 * max_order))
    harmonics = np.arange(1, n_harmonics + 1)
    return (float(coefficients[0].real), harmonics / 2.0, 2.0 * np.abs(coefficients[harmonics]),
            np.angle(coefficients[harmonics]))
