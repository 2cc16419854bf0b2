"""Campbell diagram of the reduced CW: standstill limit, weak speed dependence, crossings."""

import numpy as np
import pytest

from mbs.campbell import campbell_diagram, order_crossings, rotating_eigenfrequencies


def test_standstill_frequencies_are_the_fixed_interface_eigenfrequencies(reduced_cw4):
    assert rotating_eigenfrequencies(reduced_cw4, [0.0])[0] == pytest.approx(reduced_cw4.eigenfrequencies, rel=1e-9)


def test_spin_changes_the_torsion_frequency_only_by_order_speed_squared(reduced_cw4):
    frequencies = rotating_eigenfrequencies(reduced_cw4, [0.0, 750.0])
    torsion = reduced_cw4.torsion_mode
    ratio = (750.0 * 2 * np.pi / 60.0) / (2 * np.pi * reduced_cw4.torsion_frequency)
    assert abs(frequencies[1, torsion] / frequencies[0, torsion] - 1.0) < 2.0 * ratio ** 2


def test_order_line_crosses_a_constant_mode_at_sixty_f_over_order():
    speeds = np.linspace(400.0, 800.0, 9)
    crossings = order_crossings(speeds, np.full((9, 1), 500.0), [48.0])
    assert len(crossings) == 1
    assert crossings[0]["speed_rpm"] == pytest.approx(60.0 * 500.0 / 48.0)


def test_diagram_flags_the_gear_mesh_crossing_of_the_torsion_mode(reduced_cw4):
    campbell = campbell_diagram(reduced_cw4, np.linspace(500.0, 800.0, 31), [48.0])
    torsion = [c for c in campbell.crossings if c["mode"] == reduced_cw4.torsion_mode]
    assert torsion[0]["speed_rpm"] == pytest.approx(60.0 * reduced_cw4.torsion_frequency / 48.0, rel=1e-3)


def test_a_crossing_names_its_mode_as_the_text_output_counts_it():
    """`--json` said mode 1/2/3 (the column) where the text said mode 2/3/4 (QA): each crossing
    also carries the count from 1, mode_number."""
    speeds = np.array([600.0, 900.0])
    frequencies = np.array([[5.0, 12.0], [5.0, 12.0]])  # Hz, two modes; order 1 crosses the second at 720 rpm
    (crossing,) = order_crossings(speeds, frequencies, [1.0])
    assert crossing["mode"] == 1 and crossing["mode_number"] == 2
    assert crossing["speed_rpm"] == pytest.approx(720.0)
