"""Craig-Bampton reduction against the full sparse model."""

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse.linalg as spla
import skfem

from reduction.coupling import rigid_coupling
from reduction.craig_bampton import craig_bampton
from reduction.elasticity import assemble_elastic_body
from reduction.errors import InputError
from reduction.factorization import SOLVERS, solver_available

# optional factorisations are tested where installed; scipy SuperLU always is
INSTALLED_SOLVERS = [name for name in SOLVERS if solver_available(name)]


@pytest.fixture(scope="module")
def cantilever():
    """Steel bar 200 x 20 x 10 mm clamped at x = 0, tip face RBE2-coupled to a reference point."""
    mesh = skfem.MeshHex.init_tensor(np.linspace(0, 200, 41), np.linspace(0, 20, 5), np.linspace(0, 10, 3))
    body = assemble_elastic_body(mesh, 210_000.0, 0.3, 7.85e-9)
    x = body.coordinates
    tip = np.flatnonzero(np.isclose(x[:, 0], 200))
    root = np.flatnonzero(np.isclose(x[:, 0], 0))
    coupling = rigid_coupling(body.n_dofs, body.node_dofs, x, tip, [200.0, 10.0, 5.0], rotations=True)
    k = coupling.reduce_matrix(body.stiffness)
    m = coupling.reduce_matrix(body.mass)
    fixed = coupling.kept[body.node_dofs[root].ravel()]
    free = np.setdiff1d(np.arange(k.shape[0]), fixed)
    eigenvalues = spla.eigsh(k[free][:, free].tocsc(), k=6, M=m[free][:, free].tocsc(), sigma=0,
                             return_eigenvectors=False)
    full_hz = np.sqrt(np.sort(eigenvalues)) / (2 * np.pi)
    return k, m, coupling.reference_dofs, fixed, full_hz


def _frequencies_hz(cb, count):
    return np.sqrt(sla.eigh(cb.stiffness, cb.mass, eigvals_only=True)[:count]) / (2 * np.pi)


def test_first_six_frequencies_within_half_percent_with_20_modes(cantilever):
    k, m, interface, fixed, full_hz = cantilever
    # sanity check of the full model against Euler-Bernoulli (first bending about the thin axis);
    # two linear hexes through the thickness are too stiff in bending, hence the loose bound
    inertia, area, length = 20 * 10**3 / 12, 200.0, 200.0
    beam_hz = 1.875104**2 / (2 * np.pi) * np.sqrt(210_000.0 * inertia / (7.85e-9 * area * length**4))
    assert 1.0 < full_hz[0] / beam_hz < 1.1
    cb = craig_bampton(k, m, interface, n_modes=20, fixed=fixed)
    errors = np.abs(_frequencies_hz(cb, 6) / full_hz - 1)
    assert errors.max() < 0.005


def test_frequency_error_never_grows_with_more_modes(cantilever):
    k, m, interface, fixed, full_hz = cantilever
    largest = craig_bampton(k, m, interface, n_modes=20, fixed=fixed)
    counts = [0, 2, 4, 6, 8, 10, 15, 20]
    errors = [np.abs(_frequencies_hz(largest.truncated(n), 6) / full_hz - 1).max() for n in counts]
    assert all(later <= earlier * (1 + 1e-9) for earlier, later in zip(errors, errors[1:]))
    assert errors[-1] < 0.01 * errors[0]
    # the reduced frequencies bound the full ones from above (Rayleigh-Ritz)
    assert np.all(_frequencies_hz(largest, 6) >= full_hz * (1 - 1e-9))


def test_statics_at_interface_are_exact_without_any_modes(cantilever):
    k, m, interface, fixed, _ = cantilever
    cb = craig_bampton(k, m, interface, n_modes=4, fixed=fixed)
    load = np.zeros(k.shape[0])
    load[interface] = [0.0, 0.0, -100.0, 0.0, 500.0, 0.0]
    free = np.setdiff1d(np.arange(k.shape[0]), fixed)
    full = np.zeros(k.shape[0])
    full[free] = spla.spsolve(k[free][:, free].tocsc(), load[free])
    q = np.linalg.solve(cb.stiffness, cb.basis.T @ load)
    # Components that vanish in exact arithmetic (here -1.5e-12 against -3.4e-12 mm beside
    # 0.69 mm) are judged against the interface motion's size, not against round-off.
    interface_scale = np.abs(full[interface]).max()
    np.testing.assert_allclose(q[: cb.n_interface], full[interface], rtol=1e-8, atol=1e-10 * interface_scale)
    np.testing.assert_allclose(q[cb.n_interface:], 0.0, atol=1e-12 * np.abs(q).max())
    np.testing.assert_allclose(cb.expand(q), full, rtol=1e-8, atol=1e-10 * np.abs(full).max())


def test_normal_modes_are_mass_normalised_and_vanish_at_interface(cantilever):
    k, m, interface, fixed, _ = cantilever
    cb = craig_bampton(k, m, interface, n_modes=5, fixed=fixed)
    np.testing.assert_allclose(cb.mass[6:, 6:], np.eye(5), atol=1e-9)
    eigenvalues = cb.fixed_interface_eigenvalues
    np.testing.assert_allclose(cb.stiffness[6:, 6:], np.diag(eigenvalues), rtol=1e-9, atol=1e-10 * eigenvalues.max())
    assert np.abs(cb.normal_modes[interface]).max() == 0.0
    assert np.all(np.diff(cb.fixed_interface_frequencies_hz) >= 0)


def test_bad_requests_are_named(cantilever):
    k, m, interface, fixed, _ = cantilever
    with pytest.raises(InputError, match="both an interface DOF and fixed"):
        craig_bampton(k, m, interface, 2, fixed=np.concatenate([fixed, interface[:1]]))
    with pytest.raises(InputError, match="must be >= 0"):
        craig_bampton(k, m, interface, -1, fixed=fixed)


@pytest.mark.parametrize("solver", INSTALLED_SOLVERS)
def test_no_interface_gives_clamped_normal_modes_only(cantilever, solver):
    k, m, interface, fixed, _ = cantilever
    cb = craig_bampton(k, m, [], 3, fixed=np.concatenate([fixed, interface]), solver=solver)
    assert cb.basis.shape == (k.shape[0], 3)
    assert cb.fixed_interface_frequencies_hz[0] > 1000.0  # bar clamped at both ends
