"""Engine excitation as functions of time at constant engine speed (pure functions).

Torques in N mm, speed in rad/s, time in s. The crank angle is speed * t (constant speed: the
drive holds the mean speed, torsional vibration is a small deviation from it).
"""

from __future__ import annotations

import numpy as np

from mbs.parameters import ExcitationParams


def gas_torque_table(shaft_speed: float, excitation: ExcitationParams) -> list[tuple[float, float, float]]:
    """Rows (angular frequency rad/s, amplitude N mm, phase rad) of the gas-torque order table."""
    return [(order * shaft_speed, amplitude, phase) for order, amplitude, phase in
            zip(excitation.gas_orders, excitation.gas_torque_amplitudes, excitation.gas_torque_phases)]


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
