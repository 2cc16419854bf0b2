"""RBE2 and RBE3 couplings of node sets to reference points."""

import numpy as np
import pytest
import scipy.sparse.linalg as spla
import skfem

from reduction.condensation import condense
from reduction.coupling import distributing_coupling, rigid_body_matrix, rigid_coupling, rigid_couplings
from reduction.elasticity import assemble_elastic_body
from reduction.errors import InputError


def _block(dim):
    if dim == 2:
        mesh = skfem.MeshQuad.init_tensor(np.linspace(0, 20, 9), np.linspace(0, 30, 13))
    else:
        mesh = skfem.MeshHex.init_tensor(np.linspace(0, 20, 5), np.linspace(0, 10, 3), np.linspace(0, 30, 7))
    body = assemble_elastic_body(mesh, 70_000.0, 0.33)
    x = body.coordinates
    height = x[:, -1]
    bottom = np.flatnonzero(np.isclose(height, 0))
    top = np.flatnonzero(np.isclose(height, height.max()))
    reference = x[top].mean(axis=0)
    reference[-1] += 5.0  # reference point above the face, as for a load introduction point
    return body, bottom, top, reference


@pytest.mark.parametrize("dim", [2, 3])
def test_rbe2_reference_motion_reproduces_prescribed_rigid_face(dim):
    """Full model with the top face driven rigidly (Dirichlet) vs RBE2 + condensation onto the
    reference point loaded by the full model's reaction: same reference motion."""
    body, bottom, top, reference = _block(dim)
    fixed = body.node_dofs[bottom].ravel()
    n_ref = 3 if dim == 2 else 6
    motion = np.array([0.01, -0.02, 1e-4]) if dim == 2 else np.array([0.01, -0.02, 0.005, 1e-4, -2e-4, 3e-4])

    # full model: top face prescribed as a rigid motion of the reference point
    face = body.node_dofs[top].ravel()
    rigid = rigid_body_matrix(body.coordinates[top] - reference, rotations=True)
    u = np.zeros(body.n_dofs)
    u[face] = rigid @ motion
    free = np.setdiff1d(np.arange(body.n_dofs), np.concatenate([fixed, face]))
    k = body.stiffness
    u[free] = spla.spsolve(k[free][:, free].tocsc(), -k[free][:, face] @ u[face])
    reaction = rigid.T @ (k @ u)[face]  # resultant force (N) and moment (N mm) at the reference

    coupling = rigid_coupling(body.n_dofs, body.node_dofs, body.coordinates, top, reference, rotations=True)
    assert coupling.reference_dofs.size == n_ref
    k_reduced = coupling.reduce_matrix(k)
    condensed = condense(k_reduced, coupling.reference_dofs, fixed=coupling.kept[fixed])
    q = np.linalg.solve(condensed.stiffness, reaction)
    np.testing.assert_allclose(q, motion, rtol=1e-8, atol=1e-10 * np.abs(motion).max())
    np.testing.assert_allclose(coupling.expand(condensed.expand(q)), u, rtol=1e-8, atol=1e-10 * np.abs(u).max())


def test_rbe2_loaded_reference_equals_full_model_with_stiff_face():
    """Translations-only RBE2 on a free top face: the reference force spreads so that all face
    nodes move together; checked against the full model with face DOFs tied by the transformation."""
    body, bottom, top, reference = _block(3)
    coupling = rigid_coupling(body.n_dofs, body.node_dofs, body.coordinates, top, reference, rotations=False)
    fixed = coupling.kept[body.node_dofs[bottom].ravel()]
    force = np.array([100.0, 0.0, -400.0])
    condensed = condense(coupling.reduce_matrix(body.stiffness), coupling.reference_dofs, fixed=fixed)
    q = np.linalg.solve(condensed.stiffness, force)
    u = coupling.expand(condensed.expand(q))
    face = u[body.node_dofs[top]]
    np.testing.assert_allclose(face, np.tile(q, (top.size, 1)), rtol=1e-12, atol=1e-12 * np.abs(q).max())
    # equilibrium: bottom reactions balance the applied force
    reaction = (body.stiffness @ u)[body.node_dofs[bottom]].sum(axis=0)
    np.testing.assert_allclose(reaction, -force, rtol=1e-8, atol=1e-8 * np.abs(force).max())


def test_two_rigid_couplings_order_reference_dofs_last():
    body, bottom, top, reference = _block(3)
    coupling = rigid_couplings(body.n_dofs, body.node_dofs, body.coordinates,
                               [(top, reference), (bottom, np.zeros(3))], rotations=True)
    n_kept = body.n_dofs - 3 * (top.size + bottom.size)
    np.testing.assert_array_equal(coupling.reference_dofs, np.arange(n_kept, n_kept + 12).reshape(2, 6))
    assert coupling.kept.max() == n_kept - 1
    with pytest.raises(InputError, match="more than one"):
        rigid_couplings(body.n_dofs, body.node_dofs, body.coordinates,
                        [(top, reference), (top, reference)], rotations=True)


@pytest.mark.parametrize("dim", [2, 3])
def test_rbe3_distributes_force_and_moment_and_averages_motion(dim):
    body, _, top, reference = _block(dim)
    rbe3 = distributing_coupling(body.n_dofs, body.node_dofs, body.coordinates, top, reference,
                                 rotations=True, weights=np.linspace(1, 2, top.size))
    n_ref = 3 if dim == 2 else 6
    load = np.arange(1.0, n_ref + 1)
    nodal = rbe3.distribute(load)
    # statically equivalent: the rigid-body work of the nodal forces equals that of the reference load
    rigid = rigid_body_matrix(body.coordinates[top] - reference, rotations=True)
    np.testing.assert_allclose(rigid.T @ nodal[body.node_dofs[top].ravel()], load, rtol=1e-12,
                               atol=1e-12 * np.abs(load).max())
    # a rigid motion of the face is read back exactly at the reference point
    motion = np.linspace(-1, 1, n_ref) * 1e-3
    u = np.zeros(body.n_dofs)
    u[body.node_dofs[top].ravel()] = rigid @ motion
    np.testing.assert_allclose(rbe3.reference_motion(u), motion, rtol=1e-10, atol=1e-10 * np.abs(motion).max())


def test_rbe3_on_collinear_nodes_cannot_carry_moment():
    body, _, top, reference = _block(3)
    line = top[np.isclose(body.coordinates[top, 1], 0)]
    line = line[np.isclose(body.coordinates[line, 0], 0)]
    with pytest.raises(InputError, match="moment"):
        distributing_coupling(body.n_dofs, body.node_dofs, body.coordinates, line, reference, rotations=True)
