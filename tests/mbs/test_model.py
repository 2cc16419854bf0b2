"""Crankshaft-counterweight model: closed-form centrifugal loads, torsion-mode frequency against
the reduced body, CB-mode convergence, energy conservation, real-time factor."""

from dataclasses import replace

import numpy as np
import pytest

from mbs.counterweight import reduce_counterweight, reduced_eigenfrequencies
from mbs.model import reduce_bodies, simulate, system_eigenfrequencies
from mbs.parameters import CrankThrowParams, ModelParams, SolverParams
from mbs.spectra import peak_frequency
from reduction.errors import InputError

QUIET = frozenset()


def stiff_throw(factor=100.0):
    """A crank throw so stiff that the web holds the CW interface like a clamp ("joint fixed")."""
    throw = CrankThrowParams()
    return replace(throw, bearing_stiffness=throw.bearing_stiffness * factor,
                   axial_stiffness=throw.axial_stiffness * factor,
                   pin_stiffness=tuple(np.asarray(throw.pin_stiffness) * factor))


def torsion_decay_frequency(params, reduced):
    """Release the torsion mode of both CWs and read the wing-torsion frequency of the run."""
    initial = np.zeros(reduced.n_modes)
    initial[reduced.torsion_mode] = 0.1
    run = simulate(params, reduced=reduced, initial_modal_coordinates=initial)
    return peak_frequency(run.time, run.wing_torsion[0], band=(100.0, 2000.0))


def test_centrifugal_interface_load_matches_closed_form(reduced_cw4):
    params = ModelParams(n_modes=4, effects=QUIET, solver=SolverParams(revolutions=1.0, time_step=1e-4))
    run = simulate(params, reduced=reduced_cw4)
    omega = params.shaft_speed
    radius = params.throw.counterweight_radius
    radial_acceleration = run.cw_frame_acceleration[:, :, 1].mean(axis=1)
    assert radial_acceleration == pytest.approx([-omega ** 2 * radius] * 2, rel=2e-3)
    centripetal_force = -reduced_cw4.total_mass * omega ** 2 * (radius + reduced_cw4.center_of_mass[1])
    assert run.cw_interface_force[:, :, 1].mean(axis=1) == pytest.approx([centripetal_force] * 2, rel=1e-2)
    assert np.abs(run.cw_interface_displacement).max() < 1e-6  # rigid joint holds


def test_torsion_frequency_of_the_run_matches_the_reduced_body_within_one_percent(reduced_cw4):
    params = ModelParams(n_modes=4, effects=QUIET, throw=stiff_throw(),
                         solver=SolverParams(revolutions=2.0, time_step=5e-5, damping=False))
    measured = torsion_decay_frequency(params, reduced_cw4)
    direct = reduced_eigenfrequencies(reduced_cw4)[reduced_cw4.torsion_mode]
    assert abs(measured / direct - 1.0) < 0.01


def test_coupled_torsion_frequency_converges_with_cb_modes_and_matches_system_eigenvalues():
    solver = SolverParams(revolutions=2.0, time_step=5e-5, damping=False)
    table = {}
    for n_modes in (2, 4, 8):
        params = ModelParams(n_modes=n_modes, effects=QUIET, solver=solver)
        reduced = reduce_counterweight(params.counterweight, n_modes)
        table[n_modes] = torsion_decay_frequency(params, reduced)
    assert abs(table[4] / table[8] - 1.0) < 2e-3
    assert abs(table[2] / table[8] - 1.0) < 5e-3
    eigen = system_eigenfrequencies(params, reduced)
    assert np.min(np.abs(eigen / table[8] - 1.0)) < 0.01


def test_energy_is_conserved_without_excitation_and_damping(reduced_cw4):
    params = ModelParams(n_modes=4, effects=QUIET,
                         solver=SolverParams(revolutions=5.0, time_step=5e-5, damping=False, drive="free"))
    run = simulate(params, reduced=reduced_cw4, energy=True)
    drift = np.abs(run.energy - run.energy[0]).max() / run.energy[0]
    assert drift < 1e-3


@pytest.mark.bench
def test_energy_drift_over_100_revolutions(reduced_cw4):
    params = ModelParams(n_modes=4, effects=QUIET,
                         solver=SolverParams(revolutions=100.0, time_step=5e-5, damping=False, drive="free"))
    run = simulate(params, reduced=reduced_cw4, energy=True)
    drift = np.abs(run.energy - run.energy[0]).max() / run.energy[0]
    print(f"\nenergy drift over 100 revolutions (dt 5e-5 s, rho_inf 0.9): {drift:.2e}; "
          f"real-time factor {run.real_time_factor:.3f}")
    assert drift < 1e-3


@pytest.mark.bench
def test_real_time_factor_of_the_default_model():
    params = ModelParams()
    reduced, reduced_throw = reduce_bodies(params)
    run = simulate(params, reduced=reduced, reduced_throw=reduced_throw)
    print(f"\nreal-time factor {run.real_time_factor:.3f} (CB modes {params.n_modes}, time step "
          f"{params.solver.time_step} s, {len(run.time)} samples, effects {sorted(params.effects)}); "
          f"wing amplitude {1e3 * run.wing_amplitude.max():.2f} um")
    assert run.real_time_factor > 0


def test_unknown_effect_is_rejected():
    with pytest.raises(InputError, match="may name only .*gas_torque.*, not earthquake"):
        ModelParams(effects=frozenset({"gas_torque", "earthquake"})).validate()


def test_a_failing_time_integration_raises_simulation_error_without_printing(capsys):
    from mbs.model import SimulationError

    throw = replace(CrankThrowParams(), bearing_stiffness=2e10,
                    pin_stiffness=tuple(np.asarray(CrankThrowParams().pin_stiffness) * 1e4))
    params = ModelParams(n_modes=2, throw=throw, solver=SolverParams(revolutions=0.2, newton_tolerance=1e-10))
    reduced, _ = reduce_bodies(params)
    with pytest.raises(SimulationError, match="did not converge at 750.0 rpm"):
        simulate(params, reduced=reduced)
    assert capsys.readouterr().out == ""


def test_stiff_joint_deflects_by_the_centrifugal_force_over_its_stiffness(reduced_cw4):
    stiffness = 1.0e7
    throw = replace(CrankThrowParams(), joint_stiffness=(stiffness,) * 3 + (1.0e12,) * 3)
    params = ModelParams(n_modes=4, effects=QUIET, throw=throw, solver=SolverParams(revolutions=1.0, time_step=1e-4))
    run = simulate(params, reduced=reduced_cw4)
    radius = params.throw.counterweight_radius + reduced_cw4.center_of_mass[1]
    force = reduced_cw4.total_mass * params.shaft_speed ** 2 * radius
    assert run.cw_interface_displacement[:, :, 1].mean(axis=1) == pytest.approx([force / stiffness] * 2, rel=1e-2)
    assert run.cw_interface_force[:, :, 1].mean(axis=1) == pytest.approx([-force] * 2, rel=1e-2)
