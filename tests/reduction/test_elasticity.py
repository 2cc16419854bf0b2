"""Assembly of elastic bodies: the simplex fast path equals scikit-fem's forms; DOF layout; errors."""

import numpy as np
import pytest
import skfem
from skfem.helpers import dot
from skfem.models.elasticity import lame_parameters, linear_elasticity

from reduction.elasticity import assemble_elastic_body
from reduction.errors import InputError


@pytest.mark.parametrize("mesh", [
    skfem.MeshTri.init_tensor(np.linspace(0, 3, 4), np.linspace(0, 2, 5)),
    skfem.MeshTet.init_tensor(np.linspace(0, 3, 4), np.linspace(0, 2, 3), np.linspace(0, 1, 3)),
], ids=["tri", "tet"])
def test_simplex_fast_path_equals_scikit_fem_forms(mesh):
    n_elements = mesh.t.shape[1]
    young = np.linspace(1000.0, 2000.0, n_elements)
    density = np.linspace(1.0, 3.0, n_elements)
    body = assemble_elastic_body(mesh, young, 0.3, density)
    element = skfem.ElementTriP1() if mesh.dim() == 2 else skfem.ElementTetP1()
    basis = skfem.Basis(mesh, skfem.ElementVector(element))
    lam, mu = lame_parameters(young[:, None], 0.3)

    @skfem.BilinearForm
    def stiffness_form(u, v, w):
        return linear_elasticity(1.0, 0.0).form(u, v, w) * w["lam"] + \
            linear_elasticity(0.0, 1.0).form(u, v, w) * w["mu"]

    reference_k = stiffness_form.assemble(basis, lam=lam, mu=mu)
    reference_m = skfem.BilinearForm(lambda u, v, w: w["rho"] * dot(u, v)).assemble(basis, rho=density[:, None])
    assert abs(body.stiffness - reference_k).max() < 1e-12 * abs(reference_k).max()
    assert abs(body.mass - reference_m).max() < 1e-12 * abs(reference_m).max()


@pytest.mark.parametrize("mesh,quadratic,nodes", [
    (skfem.MeshHex.init_tensor(np.linspace(0, 1, 3), np.linspace(0, 1, 2), np.linspace(0, 1, 2)), False, 12),
    (skfem.MeshTet.init_tensor(np.linspace(0, 1, 2), np.linspace(0, 1, 2), np.linspace(0, 1, 2)), True, 8 + 19),
    (skfem.MeshQuad.init_tensor(np.linspace(0, 1, 3), np.linspace(0, 1, 3)), False, 9),
])
def test_node_dofs_cover_every_dof_once_and_mass_is_total_mass(mesh, quadratic, nodes):
    body = assemble_elastic_body(mesh, 1000.0, 0.25, 2.0, quadratic=quadratic)
    assert body.node_dofs.shape == (nodes, mesh.dim())
    np.testing.assert_array_equal(np.sort(body.node_dofs.ravel()), np.arange(body.n_dofs))
    translation = np.zeros(body.n_dofs)
    translation[body.node_dofs[:, 0]] = 1.0
    assert translation @ body.mass @ translation == pytest.approx(2.0 * 1.0, rel=1e-12)  # unit volume (area)
    assert np.abs(body.stiffness @ translation).max() < 1e-9 * abs(body.stiffness).max()


def test_bad_materials_are_named():
    mesh = skfem.MeshTri()
    with pytest.raises(InputError, match="poisson_ratio must lie in"):
        assemble_elastic_body(mesh, 1000.0, 0.5)
    with pytest.raises(InputError, match="one value per element \\(2\\)"):
        assemble_elastic_body(mesh, [1.0, 2.0, 3.0], 0.3)
    with pytest.raises(InputError, match="not supported"):
        assemble_elastic_body(skfem.MeshLine(), 1000.0, 0.3)
