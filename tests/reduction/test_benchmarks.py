"""Benchmarks of the reduction (run by `make bench`; printed figures go into the closing note)."""

import time

import numpy as np
import pytest
import skfem

from reduction.condensation import condense
from reduction.elasticity import assemble_elastic_body
from reduction.factorization import resolve_solver


def _plate(n_side):
    """Tet block 40 x 40 x 10 mm, face z = 10 retained, face z = 0 clamped."""
    mesh = skfem.MeshTet.init_tensor(np.linspace(0, 40, n_side), np.linspace(0, 40, n_side), np.linspace(0, 10, 11))
    body = assemble_elastic_body(mesh, 210_000.0, 0.3)
    z = body.coordinates[:, 2]
    return body, body.node_dofs[np.isclose(z, 10)].ravel(), body.node_dofs[np.isclose(z, 0)].ravel()


@pytest.mark.bench
def test_condensing_50k_dofs_onto_4800_face_dofs_takes_at_most_10_s():
    body, retained, clamped = _plate(40)
    assert resolve_solver("auto") == "pardiso", "install pypardiso for the fast Schur complement"
    start = time.perf_counter()
    condensed = condense(body.stiffness, retained, fixed=clamped)
    elapsed = time.perf_counter() - start
    print(f"\ncondense {body.n_dofs} DOFs ({body.n_dofs - clamped.size} free) onto {retained.size} "
          f"face DOFs with {condensed.solver}: {elapsed:.2f} s")
    assert elapsed <= 10.0
    # exactness spot check on one load case against the interior solve
    load = np.zeros(retained.size)
    load[2::3] = -1.0
    u_r = np.linalg.solve(condensed.stiffness, load)
    u = condensed.expand(u_r)
    residual = body.stiffness @ u
    assert np.abs(residual[condensed.interior]).max() < 1e-8
    np.testing.assert_allclose(residual[retained], load, atol=1e-8)
