"""Flexible crankshaft (Craig-Bampton throw bodies): mesh mass against the closed form, a run with
per-CW histories, the coupled torsion mode falls with throw flexibility and converges with the
number of throw CB modes."""

from dataclasses import replace

import numpy as np
import pytest

from mbs.flexible_throw import SQUARE_SIDE, reduce_throw
from mbs.model import simulate, torsion_decay_mode
from mbs.parameters import CrankThrowParams, ModelParams, SolverParams
from reduction.errors import InputError

FLEXIBLE = frozenset({"flexible_crankshaft"})


@pytest.fixture(scope="module")
def reduced_throw8():
    return reduce_throw(CrankThrowParams(), 8)


def test_throw_mesh_mass_matches_the_solid_it_stands_for(reduced_throw8):
    t = CrankThrowParams()
    journal_side, pin_half = SQUARE_SIDE * t.journal_radius, 0.5 * SQUARE_SIDE * t.pin_radius
    web_out = 0.5 * t.pin_length + t.web_thickness
    volume = (2.0 * (t.counterweight_radius + t.crank_radius + pin_half) * t.web_width * t.web_thickness
              + 2.0 * pin_half * journal_side * t.pin_length + 2.0 * journal_side ** 2 * (t.bearing_z - web_out))
    mass = reduced_throw8.mass.sum() / 3.0  # consistent mass: each direction sums to the total
    assert mass == pytest.approx(t.density * volume, rel=1e-9)
    assert reduced_throw8.n_modes == 18 + 8  # constraint modes of interfaces 2-4, then normal modes


def test_flexible_two_throw_run_has_centrifugal_load_and_all_cw_histories(reduced_cw4, reduced_throw8):
    params = ModelParams(n_modes=4, throws=2, effects=FLEXIBLE,
                         solver=SolverParams(revolutions=0.1, time_step=1e-4))
    run = simulate(params, reduced=reduced_cw4, reduced_throw=reduced_throw8)
    assert run.cw_modal_coordinates.shape[:2] == (4, len(run.time))
    radial = run.cw_frame_acceleration[:, -20:, 1].mean(axis=1)
    assert radial == pytest.approx([-params.shaft_speed ** 2 * params.throw.counterweight_radius] * 4, rel=1e-2)


def test_a_more_flexible_throw_lowers_the_coupled_torsion_frequency(reduced_cw4):
    frequencies = []
    for youngs_modulus in (1.05e5, 2.1e5, 2.1e7):  # MPa: half steel, steel, near-rigid throw
        throw = replace(CrankThrowParams(), youngs_modulus=youngs_modulus)
        params = ModelParams(n_modes=4, effects=FLEXIBLE, throw=throw)
        frequencies.append(torsion_decay_mode(params, reduced_cw4, reduced_throw=reduce_throw(throw, 4))[0])
    assert frequencies[0] < frequencies[1] < frequencies[2]
    # the CW (fixed-interface torsion 521 Hz) bounds the coupled mode from above as the throw stiffens
    assert frequencies[2] < reduced_cw4.torsion_frequency


def test_coupled_torsion_frequency_converges_with_throw_cb_modes(reduced_cw4):
    params = ModelParams(n_modes=4, effects=FLEXIBLE)
    table = {n: torsion_decay_mode(params, reduced_cw4, reduced_throw=reduce_throw(params.throw, n))[0]
             for n in (2, 4, 16)}
    # Craig-Bampton is a Ritz method: more modes never raise the frequency
    assert table[2] >= table[4] - 1e-6 >= table[16] - 2e-6
    assert abs(table[4] / table[16] - 1.0) < 1e-3
    assert abs(table[2] / table[16] - 1.0) < 3e-3


def test_energy_bookkeeping_refuses_flexible_throws(reduced_cw4, reduced_throw8):
    params = ModelParams(n_modes=4, effects=FLEXIBLE, solver=SolverParams(revolutions=0.01, drive="free"))
    with pytest.raises(InputError, match="rigid throws only"):
        simulate(params, reduced=reduced_cw4, reduced_throw=reduced_throw8, energy=True)



@pytest.mark.bench
def test_free_decay_of_the_flexible_throw_rings_at_the_eigen_analysis_frequency(reduced_cw4, reduced_throw8):
    from mbs.spectra import peak_frequency

    params = ModelParams(n_modes=4, effects=FLEXIBLE, solver=SolverParams(revolutions=1.0, time_step=5e-5, damping=False))
    released = np.zeros(reduced_cw4.n_modes)
    released[reduced_cw4.torsion_mode] = 0.1
    run = simulate(params, reduced=reduced_cw4, reduced_throw=reduced_throw8, initial_modal_coordinates=released)
    measured = peak_frequency(run.time, run.wing_torsion[0], band=(100.0, 2000.0))
    eigen = torsion_decay_mode(params, reduced_cw4, reduced_throw=reduced_throw8)[0]
    print(f"\nflexible throw: decay {measured:.2f} Hz, eigen-analysis {eigen:.2f} Hz, real-time factor "
          f"{run.real_time_factor:.4f}")
    assert abs(measured / eigen - 1.0) < 0.01
