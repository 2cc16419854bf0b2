"""Multi-throw crankshaft: per-CW histories, throw angles, the torsional mode of a throw on its
journal spring against the closed form, energy conservation, scene keys."""

import math
from dataclasses import replace

import numpy as np
import pytest

from mbs.items import COUNTERWEIGHT_ROTATION, half_throw_inertia
from mbs.model import simulate, system_eigenfrequencies
from mbs.parameters import CrankThrowParams, ModelParams, SolverParams
from mbs.results import read_histories, write_run
from mbs.scene import load_model_params
from reduction.errors import InputError

QUIET = frozenset()


def test_two_throw_run_writes_histories_of_all_four_counterweights(reduced_cw4, tmp_path):
    params = ModelParams(n_modes=4, throws=2, solver=SolverParams(revolutions=1.0, time_step=1e-4))
    run = simulate(params, reduced=reduced_cw4)
    assert run.cw_modal_coordinates.shape[0] == 4
    # every CW sits at the contact-face radius of its throw, whatever the throw's crank angle
    radial = run.cw_frame_acceleration[:, len(run.time) // 2:, 1].mean(axis=1)
    assert radial == pytest.approx([-params.shaft_speed ** 2 * params.throw.counterweight_radius] * 4, rel=5e-3)
    assert np.all(np.abs(run.wing_torsion).max(axis=1) > 0)  # gas torque and gear mesh reach every CW
    signals = read_histories(write_run(tmp_path / "run.h5", params, reduced_cw4, run))
    for c in range(1, 5):
        assert signals[f"cw{c}_wing_torsion"].shape == run.time.shape
    assert "cw5_wing_torsion" not in signals


def throw_polar_inertia(params, reduced, journal_fractions):
    """Polar moment of inertia (t mm^2) of one throw with its two CWs about the crank axis."""
    throw = params.throw
    polar = 0.0
    for side, fraction in zip((-1.0, 1.0), journal_fractions):
        inertia = half_throw_inertia(throw, side, fraction)
        com = np.asarray(inertia.COM())
        polar += inertia.InertiaCOM()[2][2] + inertia.Mass() * (com[0] ** 2 + com[1] ** 2)
    nodes = reduced.node_coordinates @ COUNTERWEIGHT_ROTATION.T + [-throw.counterweight_radius, 0.0, 0.0]
    spin_field = (np.cross([0.0, 0.0, 1.0], nodes) @ COUNTERWEIGHT_ROTATION).ravel()  # rigid spin, CW frame
    return polar + 2.0 * spin_field @ (reduced.mass @ spin_field)


def test_second_throw_twists_on_the_journal_spring_at_the_closed_form_frequency(reduced_cw4):
    """Drive holds throw 1; throw 2 spins against the journal torsion spring k_t alone (bearings
    act on the axis, the pin spring is 500 x stiffer): f = sqrt(k_t / J_2) / 2 pi. Slow speed:
    the eigen-analysis linearises the spinning system without gyroscopic terms."""
    torsion = 3.6e8
    base = CrankThrowParams()
    throw = replace(base, journal_stiffness=base.journal_stiffness[:5] + (torsion,))
    params = ModelParams(speed_rpm=1.0, n_modes=4, effects=QUIET, throws=2, throw=throw)
    lowest = system_eigenfrequencies(params, reduced_cw4)[0]
    expected = math.sqrt(torsion / throw_polar_inertia(params, reduced_cw4, (0.5, 1.0))) / (2.0 * math.pi)
    assert lowest == pytest.approx(expected, rel=5e-3)


def test_stiffer_journals_raise_the_throw_torsion_frequency(reduced_cw4):
    base = CrankThrowParams()
    frequencies = []
    for torsion in (3.6e8, 3.6e9):
        throw = replace(base, journal_stiffness=base.journal_stiffness[:5] + (torsion,))
        params = ModelParams(speed_rpm=1.0, n_modes=4, effects=QUIET, throws=2, throw=throw)
        frequencies.append(system_eigenfrequencies(params, reduced_cw4)[0])
    assert frequencies[1] / frequencies[0] == pytest.approx(math.sqrt(10.0), rel=1e-2)


def test_energy_of_a_three_throw_shaft_is_conserved_without_excitation_and_damping(reduced_cw4):
    params = ModelParams(n_modes=4, effects=QUIET, throws=3,
                         solver=SolverParams(revolutions=3.0, time_step=5e-5, damping=False, drive="free"))
    run = simulate(params, reduced=reduced_cw4, energy=True)
    drift = np.abs(run.energy - run.energy[0]).max() / run.energy[0]
    assert drift < 1e-3


def test_scene_sets_throws_and_their_angle_tables(tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text("[mbs]\nthrows = 3\ncrank_angles_deg = [0, 120, 240]\nfiring_angles_deg = [0, 480, 240]\n"
                     "[mbs.throw]\njournal_stiffness = [1e7, 1e7, 1e7, 1e11, 1e11, 1e11]\n")
    params = load_model_params(scene)
    assert params.throws == 3 and params.n_counterweights == 6
    assert params.throw_angles == pytest.approx(np.radians([0.0, 120.0, 240.0]))
    assert params.firing_angles == pytest.approx(np.radians([0.0, 480.0, 240.0]))
    assert params.throw.journal_stiffness[0] == 1e7


def test_evenly_spaced_throws_by_default_and_angle_tables_must_match_the_throw_count():
    assert ModelParams(throws=4).throw_angles == pytest.approx(np.radians([0.0, 90.0, 180.0, 270.0]))
    with pytest.raises(InputError, match="crank_angles_deg must give one angle per throw"):
        ModelParams(throws=2, crank_angles_deg=(0.0,)).validate()
    with pytest.raises(InputError, match="throws = 0: must be a whole number"):
        ModelParams(throws=0).validate()


def test_sweep_of_a_two_throw_shaft_reports_every_counterweight():
    from pipelines.jobs.sweep import speed_sweep

    params = ModelParams(n_modes=2, throws=2, effects=frozenset({"gear_mesh"}),
                         solver=SolverParams(revolutions=0.25, time_step=1e-4))
    result = speed_sweep(params, [700.0, 750.0])
    assert result.wing_amplitude.shape == (2, 4)
    assert np.all(result.wing_amplitude > 0)


@pytest.mark.bench
def test_energy_drift_of_a_three_throw_shaft_over_100_revolutions(reduced_cw4):
    params = ModelParams(n_modes=4, effects=QUIET, throws=3,
                         solver=SolverParams(revolutions=100.0, time_step=5e-5, damping=False, drive="free"))
    run = simulate(params, reduced=reduced_cw4, energy=True)
    drift = np.abs(run.energy - run.energy[0]).max() / run.energy[0]
    print(f"\nthree throws: energy drift over 100 revolutions {drift:.2e}; real-time factor {run.real_time_factor:.3f}")
    assert drift < 1e-3


def test_scene_switches_on_the_flexible_crankshaft(tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text('[mbs]\nthrows = 2\neffects = ["flexible_crankshaft", "gas_torque"]\n'
                     "[mbs.throw]\nyoungs_modulus = 200000.0\nflexible_modes = 12\n")
    params = load_model_params(scene)
    assert "flexible_crankshaft" in params.effects
    assert params.throw.youngs_modulus == 200000.0 and params.throw.flexible_modes == 12
