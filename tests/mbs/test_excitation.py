"""Excitation: order table evaluation and the orders an effect set brings in."""

import numpy as np
import pytest

from mbs.excitation import excitation_orders, gas_torque, gear_mesh_torque
from mbs.parameters import ExcitationParams


def test_gas_torque_is_the_sum_of_its_order_table():
    excitation = ExcitationParams(gas_orders=(0.5, 1.0), gas_torque_amplitudes=(3.0, 2.0), gas_torque_phases=(0.0, np.pi / 2))
    speed = 78.5
    time = np.linspace(0.0, 0.2, 11)
    expected = 3.0 * np.cos(0.5 * speed * time) - 2.0 * np.sin(speed * time)
    assert gas_torque(time, speed, excitation) == pytest.approx(expected)


def test_gear_mesh_runs_at_teeth_times_shaft_frequency():
    excitation = ExcitationParams(gear_teeth=48, gear_torque_amplitude=5.0)
    speed = 2 * np.pi * 12.5
    quarter_period = 0.25 / (48 * 12.5)
    assert gear_mesh_torque(quarter_period, speed, excitation) == pytest.approx(5.0)


def test_only_switched_on_effects_bring_orders():
    excitation = ExcitationParams()
    assert excitation_orders(excitation, {"gear_mesh"}).tolist() == [48.0]
    assert excitation_orders(excitation, set()).size == 0
    assert 0.5 in excitation_orders(excitation, {"gas_torque"})
