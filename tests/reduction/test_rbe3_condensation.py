"""Condensation onto RBE3 reference points against the full model (u_ref = R u, load R^T F)."""

import numpy as np
import pytest
import scipy.sparse.linalg as spla
import skfem

from reduction.condensation import condense
from reduction.coupling import distributing_coupling, rigid_coupling
from reduction.elasticity import assemble_elastic_body
from reduction.errors import InputError
from reduction.rbe3_condensation import attach_rbe3


@pytest.fixture(scope="module")
def block():
    """Hex block 30 x 30 x 20 mm clamped at z = 0; a 10 x 10 mm bearing patch on the top face."""
    mesh = skfem.MeshHex.init_tensor(np.linspace(0, 30, 7), np.linspace(0, 30, 7), np.linspace(0, 20, 5))
    body = assemble_elastic_body(mesh, 210_000.0, 0.3)
    x = body.coordinates
    clamp = body.node_dofs[np.isclose(x[:, 2], 0)].ravel()
    top = np.isclose(x[:, 2], 20)
    patch = np.flatnonzero(top & (np.abs(x[:, 0] - 15) <= 5) & (np.abs(x[:, 1] - 15) <= 5))
    other = np.flatnonzero(top & (x[:, 0] >= 25))
    return body, clamp, patch, other


@pytest.mark.parametrize("rotations", [True, False])
def test_rbe3_reference_motion_and_kept_dofs_equal_full_model(block, rotations):
    body, clamp, patch, other = block
    rbe3 = distributing_coupling(body.n_dofs, body.node_dofs, body.coordinates, patch, [15.0, 15.0, 25.0],
                                 rotations=rotations)
    kept = body.node_dofs[other].ravel()
    surface_load = np.zeros(body.n_dofs)
    surface_load[body.node_dofs[other, 2]] = -10.0
    condensed = condense(body.stiffness, np.concatenate([kept, rbe3.coupled_dofs]), fixed=clamp,
                         loads={"surface": surface_load})
    referenced = attach_rbe3(condensed, [rbe3])
    n_ref = 6 if rotations else 3
    np.testing.assert_array_equal(referenced.reference_dofs, [np.arange(kept.size, kept.size + n_ref)])
    force = np.array([200.0, -100.0, -5000.0, 3000.0, -1000.0, 500.0])[:n_ref]  # N and N mm

    rhs = referenced.loads["surface"].copy()
    rhs[referenced.reference_dofs[0]] += force
    x = np.linalg.solve(referenced.stiffness, rhs)

    free = np.setdiff1d(np.arange(body.n_dofs), clamp)
    full = np.zeros(body.n_dofs)
    total = surface_load + rbe3.distribute(force)
    full[free] = spla.spsolve(body.stiffness[free][:, free].tocsc(), total[free])
    scale = np.abs(full).max()  # mm; near-zero components are judged against it, not round-off
    np.testing.assert_allclose(x[: kept.size], full[kept], rtol=1e-8, atol=1e-10 * scale)
    motion = rbe3.reference_motion(full)
    np.testing.assert_allclose(x[kept.size:], motion, rtol=1e-8, atol=1e-10 * np.abs(motion).max())
    np.testing.assert_allclose(referenced.expand(x, {"surface": 1.0}), full, rtol=1e-8, atol=1e-10 * scale)


def test_rbe3_is_softer_than_rbe2_on_the_same_patch(block):
    """RBE2 stiffens the bearing area, RBE3 does not: the vertical reference stiffness is lower."""
    body, clamp, patch, _ = block
    point = [15.0, 15.0, 20.0]
    rbe3 = distributing_coupling(body.n_dofs, body.node_dofs, body.coordinates, patch, point, rotations=False)
    soft = attach_rbe3(condense(body.stiffness, rbe3.coupled_dofs, fixed=clamp), [rbe3]).stiffness[2, 2]
    rbe2 = rigid_coupling(body.n_dofs, body.node_dofs, body.coordinates, patch, point, rotations=False)
    stiff = condense(rbe2.reduce_matrix(body.stiffness), rbe2.reference_dofs, fixed=rbe2.kept[clamp]).stiffness[2, 2]
    assert 0.5 * stiff < soft < stiff


def test_unretained_bearing_area_is_named(block):
    body, clamp, patch, other = block
    rbe3 = distributing_coupling(body.n_dofs, body.node_dofs, body.coordinates, patch, [15, 15, 20], rotations=False)
    with pytest.raises(InputError, match="not retained"):
        attach_rbe3(condense(body.stiffness, body.node_dofs[other].ravel(), fixed=clamp), [rbe3])


def test_free_bearing_area_that_can_rotate_without_strain_is_refused(block):
    body, _, patch, _ = block
    rbe3 = distributing_coupling(body.n_dofs, body.node_dofs, body.coordinates, patch, [15, 15, 20], rotations=False)
    free_body = condense(body.stiffness, rbe3.coupled_dofs)
    with pytest.raises(InputError, match="move without strain"):
        attach_rbe3(free_body, [rbe3])
