"""The flat-on-flat benchmark's graded block: conforming, the uniform block's contact face, and
nearly its compliance (fine at the contact, coarsening 3:1 in plane with depth)."""

import numpy as np
import pytest
import scipy.sparse.linalg as spla
import skfem

from reduction.elasticity import assemble_elastic_body
from reduction.mesh.generators import flat_block, graded_flat_block
from tests.reduction.patch import interior_residual

SIZE, HEIGHT, CELLS = 10.0, 5.0, 14  # mm; 15 × 15 contact points
#: the graded block's static compliance against the fine tensor grid's, by traction direction.
#: Measured at 15 × 15 points: the graded block is stiffer by 0.14 % (normal) and 1.0 %
#: (tangential); at 40 × 40 by 0.48 % and 2.4 % (the benchmark's 6-layer uniform block: −0.8 %
#: and −1.3 %). The coarse trilinear cells far from the contact are stiffer in shear (the free
#: sides make the far field bend); the fine face and the two layers under it, which resolve the
#: edges' stress peaks, are the tensor grid's.
COMPLIANCE_TOLERANCE = {2: 5e-3, 0: 2e-2}


def _facet_counts(mesh) -> np.ndarray:
    """How many cells hold each distinct facet (node set) of a hexahedral mesh."""
    faces = np.array([[0, 1, 4, 2], [0, 1, 5, 3], [0, 2, 6, 3], [1, 4, 7, 5], [2, 4, 7, 6], [3, 5, 7, 6]])
    keys = np.sort(mesh.t[faces].transpose(2, 0, 1).reshape(-1, 4), axis=1)
    return np.unique(keys, axis=0, return_counts=True)[1]


def _face(mesh, z: float) -> np.ndarray:
    """The nodes (x, y) of the plane z, sorted."""
    p = mesh.p[:2, mesh.p[2] == z].T
    return p[np.lexsort((p[:, 1], p[:, 0]))]


@pytest.mark.parametrize("top_fine", [False, True])
def test_graded_flat_block_is_conforming_with_the_uniform_contact_face(top_fine):
    z0 = -HEIGHT if top_fine else 0.0
    contact, far = (0.0, -HEIGHT) if top_fine else (0.0, HEIGHT)
    graded = graded_flat_block(SIZE, SIZE, HEIGHT, CELLS, CELLS, z0=z0, top_fine=top_fine)
    uniform = flat_block(SIZE, SIZE, HEIGHT, CELLS, CELLS, 6, z0=z0, z_growth=1.4, top_fine=top_fine)
    # conforming: every facet inside the box is held by exactly two cells, the others lie on
    # its six faces (a hanging node would leave unmatched facets inside)
    counts = _facet_counts(graded)
    assert counts.max() == 2 and graded.boundary_facets().size == np.sum(counts == 1)
    centre = graded.p[:, graded.facets[:, graded.boundary_facets()]].mean(axis=1)
    on_box = (np.isclose(np.abs(centre[0]), 0.5 * SIZE) | np.isclose(np.abs(centre[1]), 0.5 * SIZE)
              | np.isclose(centre[2], contact) | np.isclose(centre[2], far))
    assert np.all(on_box)
    # the same orientation as the tensor grid's cells (skfem's hexahedra: det J < 0), volume exact
    det = graded.mapping().detDF(np.full((3, 1), 0.5))
    assert np.all(det < 0)
    assert float(-det.sum()) == pytest.approx(SIZE * SIZE * HEIGHT, rel=1e-12)
    # the contact face: the uniform block's nodes, bit for bit; the far face: a few coarse cells
    np.testing.assert_array_equal(_face(graded, contact), _face(uniform, contact))
    assert np.unique(_face(graded, far)[:, 0]).size < 0.5 * (CELLS + 1)
    assert graded.p.shape[1] < 0.75 * uniform.p.shape[1]


def _compliance(mesh, direction: int) -> float:
    """Mean displacement (mm) of the face z = 0 along ``direction`` under a uniform traction of
    1 MPa on it along ``direction``, the face z = HEIGHT clamped (210 GPa, ν 0.3): work-conjugate,
    f·u / F."""
    body = assemble_elastic_body(mesh, 210e3, 0.3)
    force = np.zeros(body.n_dofs)
    facets = mesh.facets[:, mesh.facets_satisfying(lambda x: np.isclose(x[2], 0.0), boundaries_only=True)]
    corners = mesh.p[:2, facets]  # (2, 4, n): rectangles on the uniform grid
    area = np.ptp(corners[0], axis=0) * np.ptp(corners[1], axis=0)
    np.add.at(force, body.node_dofs[facets.ravel(), direction], np.tile(0.25 * area, 4))
    fixed = body.node_dofs[np.isclose(mesh.p[2], HEIGHT)].ravel()
    free = np.setdiff1d(np.arange(body.n_dofs), fixed)
    u = np.zeros(body.n_dofs)
    u[free] = spla.spsolve(body.stiffness[free][:, free].tocsc(), force[free])
    return float(force @ u / force.sum())


@pytest.mark.parametrize("direction", [2, 0], ids=["normal", "tangential"])
def test_graded_flat_block_has_the_compliance_of_the_fine_tensor_grid(direction):
    graded = graded_flat_block(SIZE, SIZE, HEIGHT, CELLS, CELLS)
    lines = np.linspace(-0.5 * SIZE, 0.5 * SIZE, CELLS + 1)
    # the fine reference: the contact face's lines through the whole depth, the graded block's layers
    fine = skfem.MeshHex.init_tensor(lines, lines, np.unique(graded.p[2]))
    assert _compliance(graded, direction) == pytest.approx(_compliance(fine, direction), rel=COMPLIANCE_TOLERANCE[direction])


def test_graded_flat_block_passes_the_patch_test():
    """A linear displacement field is in equilibrium at every interior node (the 3:1 transitions
    included); a hanging node would carry an unbalanced force."""
    mesh = graded_flat_block(SIZE, SIZE, HEIGHT, CELLS, CELLS)
    assert interior_residual(mesh) < 1e-9
