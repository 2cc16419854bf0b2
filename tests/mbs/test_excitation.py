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


def test_pressure_curve_with_a_long_conrod_gives_the_closed_form_first_order():
    from mbs.excitation import gas_torque_from_pressure

    angles = np.linspace(0.0, 720.0, 73)[:-1]
    pressure = np.full_like(angles, 2.0)  # MPa, constant
    bore, radius = 320.0, 200.0
    mean, orders, amplitudes, phases = gas_torque_from_pressure(angles, pressure, bore=bore, crank_radius=radius,
                                                                conrod_length=1e9, max_order=3.0)
    # T = p A r sin(theta) = p A r cos(theta - pi/2): only order 1, phase -pi/2, no mean
    first = list(orders).index(1.0)
    assert amplitudes[first] == pytest.approx(2.0 * np.pi * bore ** 2 / 4 * radius, rel=1e-6)
    assert phases[first] == pytest.approx(-np.pi / 2, abs=1e-6)
    assert np.delete(amplitudes, first).max() < 1e-6 * amplitudes[first]
    assert abs(mean) < 1e-6 * amplitudes[first]


def test_firing_pressure_peak_gives_half_orders():
    from mbs.excitation import gas_torque_from_pressure

    angles = np.linspace(0.0, 720.0, 721)
    pressure = 0.2 + 18.0 * np.exp(-0.5 * ((angles - 370.0) / 25.0) ** 2)  # firing just after TDC at 360 deg
    mean, orders, amplitudes, _ = gas_torque_from_pressure(angles, pressure, bore=320.0, crank_radius=200.0,
                                                           conrod_length=800.0)
    assert mean > 0  # the expansion stroke does net work
    assert amplitudes[list(orders).index(0.5)] > 0.1 * amplitudes.max()


def test_a_later_firing_cylinder_delays_the_gas_torque_by_its_firing_angle():
    from mbs.excitation import cylinder_gas_torque_table

    speed = 750.0 * np.pi / 30.0
    excitation = ExcitationParams()
    firing = np.radians(480.0)
    time = np.linspace(0.0, 0.16, 97)
    table = np.asarray(cylinder_gas_torque_table(speed, excitation, firing))
    delayed = (table[:, 1] * np.cos(np.multiply.outer(time, table[:, 0]) + table[:, 2])).sum(axis=1)
    assert delayed == pytest.approx(gas_torque(time - firing / speed, speed, excitation), abs=1e-6 * 6.4e6)
    # two cylinders 360 deg apart: the half orders cancel in the sum, the integer orders double
    pair = np.asarray(cylinder_gas_torque_table(speed, excitation, 0.0) + cylinder_gas_torque_table(speed, excitation, 2 * np.pi))
    total = (pair[:, 1] * np.cos(np.multiply.outer(time, pair[:, 0]) + pair[:, 2])).sum(axis=1)
    base = np.asarray(cylinder_gas_torque_table(speed, excitation, 0.0))
    integer = np.isclose(base[:, 0] / speed % 1.0, 0.0)
    doubled = 2.0 * (base[integer, 1] * np.cos(np.multiply.outer(time, base[integer, 0]) + base[integer, 2])).sum(axis=1)
    assert total == pytest.approx(doubled, abs=1e-6 * 6.4e6)
