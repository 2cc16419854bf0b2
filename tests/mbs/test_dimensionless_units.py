"""Dimensionless quantities carry the units attribute '1' (the SI convention), as the contact
results do; the sweep file wrote '-' for three of them (QA)."""

import h5py
import numpy as np

from mbs.campbell import Campbell
from mbs.sweep import SweepResult, write_sweep


def test_the_sweep_file_writes_dimensionless_quantities_in_units_of_1(tmp_path):
    speeds = np.array([600.0, 700.0])
    result = SweepResult(
        speeds_rpm=speeds, wing_amplitude=np.full((2, 2), 1e-3), dominant_frequencies=np.ones((2, 3)),
        dominant_orders=np.ones((2, 3)), real_time_factor=np.array([0.5, 0.6]),
        system_frequencies=np.ones((2, 4)), crossings=[], resonance=np.array([False, True]), failures={},
        campbell=Campbell(speeds, np.ones((2, 2)), np.array([1.0, 2.0]), []),
        unsettled_change=np.array([0.01, np.nan]), unsettled={})
    write_sweep(tmp_path / "sweep.h5", result)
    with h5py.File(tmp_path / "sweep.h5") as root:
        units = {name: dataset.attrs["units"] for name, dataset in root["sweep"].items()}
    assert units["real_time_factor"] == units["resonance"] == units["unsettled_change"] == "1"
    assert "-" not in units.values()
