"""A complete run: HDF5 follows the shared /histories contract, the acceleration field balances the
interface force (Newton's second law), effects switch items on and off."""

from types import SimpleNamespace

import h5py
import numpy as np
import pytest

import mbs.plots
import mbs.run
from mbs.counterweight import reduce_counterweight
from mbs.model import simulate
from mbs.parameters import ModelParams, SolverParams
from mbs.results import acceleration_field
from mbs.run import calibration, run_model


@pytest.fixture(scope="module")
def reduced_cw2():
    return reduce_counterweight(ModelParams().counterweight, n_modes=2)


def test_run_writes_the_shared_history_layout_and_plots(tmp_path, reduced_cw2, monkeypatch):
    drawn = []
    monkeypatch.setattr(mbs.run, "plot_time_history",
                        lambda *args, **kwargs: drawn.append(kwargs) or mbs.plots.plot_time_history(*args, **kwargs))
    params = ModelParams(n_modes=2, solver=SolverParams(revolutions=2.0, time_step=1e-4))
    outputs = run_model(params, tmp_path, bodies=(reduced_cw2, None), scene="engine", stated_wing_amplitude_mm=0.1,
                        counterweight=2)
    # drawn once, named and calibrated as the scene states: 0.1 mm over this run's CW2 amplitude
    assert drawn == [{"scene": "engine", "calibration": pytest.approx(0.1 / outputs.histories.wing_amplitude[1])}]
    with h5py.File(outputs.results_file) as root:
        assert root.attrs["fretwork_format"] == "fretwork-results" and root.attrs["format_version"] == 1
        histories = root["histories"]
        n = histories["time"].shape[0]
        assert histories["time"].attrs["units"] == "s"
        assert np.allclose(np.diff(histories["time"][()]), 1e-4)
        for name, dataset in histories.items():
            assert dataset.shape[0] == n, name
            assert dataset.attrs["units"] and dataset.attrs["description"], name
            if dataset.ndim == 2:
                assert len(dataset.attrs["components"]) == dataset.shape[1], name
        assert histories["cw1_modal_coordinates"].shape == (n, 2)
        assert histories["cw2_wing_tip_displacement"].shape == (n, 2)
        assert "wing_torsion_orders" in root["spectra"] and "frequency" in root["campbell"]
    assert all(path.exists() and path.stat().st_size > 0 for path in outputs.plots.values())


def test_acceleration_field_balances_the_interface_force(reduced_cw2):
    params = ModelParams(n_modes=2, solver=SolverParams(revolutions=0.5, time_step=1e-4))
    run = simulate(params, reduced=reduced_cw2)
    sample = len(run.time) - 1
    for c in range(2):
        field = acceleration_field(run, reduced_cw2, c, sample)
        inertia_force = (reduced_cw2.mass @ field.ravel()).reshape(-1, 3).sum(axis=0)
        assert inertia_force == pytest.approx(run.cw_interface_force[c, sample], rel=1e-2, abs=1e-3 * np.abs(inertia_force).max())


def test_torsional_vibration_effect_lets_the_shaft_speed_fluctuate(reduced_cw2):
    solver = SolverParams(revolutions=1.0, time_step=1e-4)
    held = simulate(ModelParams(n_modes=2, effects=frozenset({"gas_torque"}), solver=solver), reduced=reduced_cw2)
    elastic = simulate(ModelParams(n_modes=2, effects=frozenset({"gas_torque", "torsional_vibration"}), solver=solver),
                       reduced=reduced_cw2)
    speed = ModelParams().shaft_speed
    assert np.abs(held.crank_speed - speed).max() < 1e-9 * speed
    assert np.abs(elastic.crank_speed - speed).max() > 1e-4 * speed


def test_the_calibration_is_the_stated_amplitude_over_the_runs_own():
    histories = SimpleNamespace(wing_amplitude=np.array([2e-4, 5e-5]))
    assert calibration(histories, 0.1, 1) == pytest.approx(500.0)
    assert calibration(histories, 0.1, 2) == pytest.approx(2000.0)
    assert calibration(histories, None, 1) is None  # the scene states none: raw amplitudes are its own
    assert calibration(histories, 0.1, 3) is None  # no such CW
    assert calibration(SimpleNamespace(wing_amplitude=np.array([0.0])), 0.1, 1) is None  # nothing to scale
