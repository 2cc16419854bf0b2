"""The contact law against its own definition: return mapping, tangent, evolution rules."""

import numpy as np
import pytest

from contact.checks import finite_difference_tangent
from contact.law import ContactLaw, ContactState, Status, advance, evaluate, wear_increment

LAW = ContactLaw(normal_stiffness=4e6, critical_slip=1e-3, cof_max=0.7, cof_rate=0.05,
                 wear_coefficients=(0.47e-8, 1.5e-8), wear_form="shear")


def _state(n, n_tangent, cof=0.4, elastic=None, wear=None):
    state = ContactState.initial(n, n_tangent, cof, n_wear_bodies=2)
    from dataclasses import replace
    if elastic is not None:
        state = replace(state, elastic_slip=np.asarray(elastic, float))
    if wear is not None:
        state = replace(state, wear_depth=np.asarray(wear, float))
    return state


@pytest.mark.parametrize("n_tangent", [1, 2])
@pytest.mark.parametrize("case", ["stick", "slip", "slip_with_pressure_change"])
def test_consistent_tangent_matches_finite_differences(n_tangent, case):
    rng = np.random.default_rng(3)
    n = 50
    h = 1e-4 * (1.0 + rng.random(n))  # 0.4-0.8 GPa at kn = 4e6
    direction = rng.normal(size=(n, n_tangent))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    elastic = 0.3e-3 * direction
    if case == "stick":
        ds = 0.2e-3 * rng.normal(size=(n, n_tangent)) / np.sqrt(n_tangent)
        ds = np.clip(ds, -0.3e-3, 0.3e-3)
    else:
        ds = (2e-3 + 1e-3 * rng.random((n, 1))) * direction
        if n_tangent == 2:
            ds += 0.5e-3 * rng.normal(size=(n, n_tangent))
    state = _state(n, n_tangent, cof=0.3 + 0.3 * rng.random(n), elastic=elastic,
                   wear=np.zeros((2, n)) if case != "slip_with_pressure_change"
                   else np.vstack([0.2e-4 * rng.random(n), 0.1e-4 * rng.random(n)]))
    response = evaluate(h, ds, state, LAW)
    expected = Status.STICK if case == "stick" else Status.SLIP
    assert np.all(response.status == expected)
    fd = finite_difference_tangent(h, ds, state, LAW)
    analytic = response.tangent()
    scale = np.abs(analytic).max(axis=(1, 2), keepdims=True)
    assert np.max(np.abs(fd - analytic) / scale) < 1e-6


def test_slip_direction_tangent_is_unsymmetric_normal_coupling():
    """∂τ/∂h ≠ 0 while ∂p/∂Δs = 0: the full tangent is unsymmetric, as the paper says."""
    state = _state(1, 2, elastic=[[0.5e-3, 0.0]])
    response = evaluate(np.array([1e-4]), np.array([[3e-3, 1e-3]]), state, LAW)
    assert np.linalg.norm(response.dshear_dh) > 0


def test_return_mapping_caps_shear_at_critical_and_keeps_slip_additive():
    n = 200
    rng = np.random.default_rng(0)
    h = 1e-4 * rng.random(n) - 0.2e-4
    ds = 3e-3 * rng.normal(size=(n, 2))
    state = _state(n, 2, cof=0.5, elastic=0.5e-3 * rng.normal(size=(n, 2)) / 2)
    response = evaluate(h, ds, state, LAW)
    shear = np.linalg.norm(response.shear, axis=1)
    assert np.all(shear <= 0.5 * response.pressure * (1 + 1e-12) + 1e-15)
    new_state, status = advance(state, response, LAW, cof_evolution=False, wear=False)
    closed = response.pressure > 0
    # γ_tr = γ_el(new) + Δγ_sl·n: elastic plus irreversible slip add up to the trial slip.
    reconstructed = new_state.elastic_slip + (new_state.slip_vector - state.slip_vector)
    trial = (state.elastic_slip + ds)[closed]
    np.testing.assert_allclose(reconstructed[closed], trial, rtol=0, atol=1e-12 * np.abs(trial).max())
    assert np.all(np.linalg.norm(new_state.elastic_slip, axis=1) <= LAW.critical_slip * (1 + 1e-12))
    assert np.all(new_state.elastic_slip[~closed] == 0.0)
    assert np.all(status[~closed] == Status.OPEN)


def test_wear_opens_gap_and_pressure_follows_eq1():
    state = _state(3, 1, wear=[[1e-5, 0, 3e-5], [1e-5, 0, 0]])
    response = evaluate(np.array([5e-5, 5e-5, 2e-5]), np.zeros((3, 1)), state, LAW)
    assert np.allclose(response.pressure, 4e6 * np.array([3e-5, 5e-5, 0.0]))
    assert response.status[2] == Status.OPEN


def test_cof_evolution_by_dissipation_capped_at_max_and_monotone():
    state = _state(2, 1, cof=0.2)
    p = 100.0
    h = np.full(2, p / LAW.normal_stiffness)
    slip_amount = np.array([1e-2, 1.0])  # small and huge slip
    response = evaluate(h, (LAW.critical_slip + slip_amount)[:, None], state, LAW)
    new_state, status = advance(state, response, LAW, cof_evolution=True, wear=False)
    expected_small = 0.2 + LAW.cof_rate * slip_amount[0] * 0.2 * p
    assert new_state.cof[0] == pytest.approx(expected_small, rel=1e-12)
    assert new_state.cof[1] == LAW.cof_max
    assert new_state.dissipation == pytest.approx(0.2 * p * slip_amount, rel=1e-12)
    # Next increment slides at μ_max: flagged as damage.
    response2 = evaluate(h, np.full((2, 1), -3e-3), new_state, LAW)
    _, status2 = advance(new_state, response2, LAW, cof_evolution=True, wear=False)
    assert status2[1] == Status.SLIP_AT_MAX and status2[0] == Status.SLIP


def test_a_wear_block_scaled_cof_change_stands_for_its_real_cycles():
    """cof_jump J: the COF rises J times a cycle's k·Δγ·|τ| (J cycles of dissipation at the
    block's rate), capped at μ_max; the dissipation record stays one cycle's."""
    state = _state(3, 1, cof=0.2)
    p = 100.0
    h = np.full(3, p / LAW.normal_stiffness)
    slip_amount = np.array([1e-6, 1e-5, 1e-2])  # micro-slip to gross slip, mm
    response = evaluate(h, (LAW.critical_slip + slip_amount)[:, None], state, LAW)
    once, _ = advance(state, response, LAW, cof_evolution=True, wear=False)
    jumped, _ = advance(state, response, LAW, cof_evolution=True, wear=False, cof_jump=500.0)
    rise = LAW.cof_rate * slip_amount * 0.2 * p
    assert once.cof == pytest.approx(0.2 + rise, rel=1e-12)
    assert jumped.cof == pytest.approx(np.minimum(0.2 + 500.0 * rise, LAW.cof_max), rel=1e-12)
    assert jumped.cof[0] < LAW.cof_max == jumped.cof[2]  # micro-slip rises, gross slip saturates
    assert jumped.dissipation == pytest.approx(once.dissipation, rel=1e-15)


@pytest.mark.parametrize("form", ["pressure", "shear"])
def test_archard_wear_per_body_with_cycle_jump_and_pressure_limit(form):
    law = ContactLaw(normal_stiffness=1e5, critical_slip=1e-3, wear_coefficients=(1e-8, 3e-8),
                     pressure_limit=50.0, wear_form=form)
    state = _state(2, 1, cof=0.5)
    h = np.array([100.0, 40.0]) / law.normal_stiffness  # second point below p_lim
    response = evaluate(h, np.full((2, 1), 0.011), state, law)
    increment = wear_increment(response, law, cycle_jump=10.0)
    driver = 100.0 if form == "pressure" else 0.5 * 100.0
    assert increment[:, 0] == pytest.approx(10.0 * 0.010 * driver * np.array([1e-8, 3e-8]), rel=1e-12)
    assert np.all(increment[:, 1] == 0.0)


def test_energy_wear_equals_w_times_dissipation_locally():
    law = ContactLaw(normal_stiffness=1e5, critical_slip=1e-3, wear_coefficients=(1e-8, 2e-8),
                     wear_form="shear")
    rng = np.random.default_rng(1)
    state = _state(20, 1, cof=0.5)
    for _ in range(10):
        response = evaluate(1e-3 * rng.random(20), 5e-3 * rng.normal(size=(20, 1)), state, law)
        state, _ = advance(state, response, law, cof_evolution=False, wear=True)
    assert state.wear_depth.sum(axis=0) == pytest.approx(3e-8 * state.dissipation, rel=1e-12)


def test_no_wear_field_allocated_without_wear_effect():
    state = ContactState.initial(10, 2, 0.2)
    assert state.wear_depth is None and state.gap == 0.0
    response = evaluate(np.full(10, 1e-5), np.full((10, 2), 1e-2), state, LAW)
    with pytest.raises(ValueError, match="wear"):
        advance(state, response, LAW, cof_evolution=True, wear=True)
