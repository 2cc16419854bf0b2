"""Counterweight block: mass properties against closed forms, the wing torsion mode, CB consistency."""

import numpy as np
import pytest

from mbs.counterweight import CounterweightGeometry, reduce_counterweight, reduced_eigenfrequencies
from reduction.errors import InputError


def test_mass_and_centre_of_mass_match_the_block_geometry(reduced_cw4):
    g = reduced_cw4.geometry
    hub_volume = g.hub_width * g.hub_height * g.thickness
    plate_volume = g.width * (g.height - g.hub_height) * g.thickness
    mass = g.density * (hub_volume + plate_volume)
    centroid_y = (hub_volume * 0.5 * g.hub_height + plate_volume * 0.5 * (g.height + g.hub_height)) / (hub_volume + plate_volume)
    assert reduced_cw4.total_mass == pytest.approx(mass, rel=1e-10)
    assert reduced_cw4.center_of_mass == pytest.approx([0.0, centroid_y, 0.0], abs=1e-8 * g.height)


def test_torsion_mode_moves_the_wing_tips_axially_in_opposite_phase(reduced_cw4):
    tips = reduced_cw4.wing_tip_axial_shapes()[:, reduced_cw4.torsion_mode]
    assert tips[0] * tips[1] < 0
    assert abs(tips[0] + tips[1]) < 0.1 * abs(tips[0] - tips[1])
    shape = reduced_cw4.mode_shapes[:, reduced_cw4.torsion_mode].reshape(-1, 3)
    assert np.abs(shape[reduced_cw4.interface_nodes]).max() == 0.0  # interface held: fixed-interface mode


def test_reduced_body_reproduces_the_fixed_interface_eigenfrequencies(reduced_cw4):
    assert reduced_eigenfrequencies(reduced_cw4) == pytest.approx(reduced_cw4.eigenfrequencies, rel=1e-8)


def test_torsion_frequency_converges_under_mesh_refinement():
    coarse = reduce_counterweight(CounterweightGeometry(), n_modes=2).torsion_frequency
    fine = reduce_counterweight(CounterweightGeometry(elements_x=20, elements_y=6, elements_z=2), n_modes=2).torsion_frequency
    assert fine < coarse  # conforming displacement FE converges from above
    assert (coarse - fine) / fine < 0.05


def test_bad_geometry_is_reported_by_name():
    with pytest.raises(InputError, match="hub_width"):
        CounterweightGeometry(hub_width=800.0).validate()
