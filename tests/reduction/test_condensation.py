"""Exact static condensation: condensed statics against the full sparse model."""

import numpy as np
import pytest
import scipy.sparse.linalg as spla
import skfem

from reduction.condensation import condense
from reduction.elasticity import assemble_elastic_body
from reduction.errors import InputError
from reduction.factorization import cholmod_available
from reduction import pardiso

# Optional factorisations are tested where installed; scipy's SuperLU always is.
SOLVERS = [
    pytest.param("pardiso", marks=pytest.mark.skipif(not pardiso.available(), reason="pypardiso not installed")),
    pytest.param("cholmod", marks=pytest.mark.skipif(not cholmod_available(), reason="sksparse-minimal not installed")),
    "splu",
]

STEEL = dict(youngs_modulus=210_000.0, poisson_ratio=0.3, density=7.85e-9)


def _full_solution(stiffness, load, fixed):
    free = np.setdiff1d(np.arange(stiffness.shape[0]), fixed)
    u = np.zeros(stiffness.shape[0])
    u[free] = spla.spsolve(stiffness[free][:, free].tocsc(), load[free])
    return u


def _relative(a, b):
    return np.linalg.norm(a - b) / np.linalg.norm(b)


def _body_and_sets(mesh):
    body = assemble_elastic_body(mesh, **STEEL)
    x = body.coordinates
    clamped = body.node_dofs[np.isclose(x[:, 0], x[:, 0].min())].ravel()
    face_nodes = np.flatnonzero(np.isclose(x[:, 0], x[:, 0].max()))
    # retained: the loaded end face plus one interior node, in a scrambled order
    retained = np.random.default_rng(0).permutation(
        np.concatenate([body.node_dofs[face_nodes].ravel(), body.node_dofs[len(x) // 2]])
    )
    return body, clamped, retained


@pytest.mark.parametrize(
    "mesh",
    [
        skfem.MeshTri.init_tensor(np.linspace(0, 100, 21), np.linspace(0, 20, 6)),
        skfem.MeshQuad.init_tensor(np.linspace(0, 100, 21), np.linspace(0, 20, 6)),
        skfem.MeshTet.init_tensor(np.linspace(0, 100, 11), np.linspace(0, 20, 4), np.linspace(0, 10, 3)),
        skfem.MeshHex.init_tensor(np.linspace(0, 100, 11), np.linspace(0, 20, 4), np.linspace(0, 10, 3)),
    ],
    ids=["tri-plane-strain", "quad-plane-strain", "tet", "hex"],
)
@pytest.mark.parametrize("solver", SOLVERS)
def test_condensed_statics_equal_full_model(mesh, solver):
    body, clamped, retained = _body_and_sets(mesh)
    rng = np.random.default_rng(1)
    traction = np.zeros(body.n_dofs)
    traction[retained] = rng.normal(size=retained.size)
    gravity = np.zeros(body.n_dofs)
    gravity[body.node_dofs[:, 1]] = -9810.0
    gravity = body.mass @ gravity

    condensed = condense(body.stiffness, retained, fixed=clamped,
                         loads={"traction": traction, "gravity": gravity}, solver=solver)
    assert condensed.solver == solver
    for factors in ({"traction": 1.0}, {"traction": 0.5, "gravity": 3.0}):
        total = sum(f * {"traction": traction, "gravity": gravity}[n] for n, f in factors.items())
        full = _full_solution(body.stiffness, total, clamped)
        load_r = sum(f * condensed.loads[n] for n, f in factors.items())
        u_r = np.linalg.solve(condensed.stiffness, load_r)
        assert _relative(u_r, full[retained]) < 1e-8
        assert _relative(condensed.expand(u_r, factors), full) < 1e-8


def test_plane_strain_uniaxial_stress_matches_closed_form():
    """Square pulled in x, free in y, plane strain: eps_xx = sigma (1 - nu^2) / E."""
    mesh = skfem.MeshQuad.init_tensor(np.linspace(0, 10, 6), np.linspace(0, 10, 6))
    body = assemble_elastic_body(mesh, 1000.0, 0.3)
    x = body.coordinates
    left = np.isclose(x[:, 0], 0)
    right = np.flatnonzero(np.isclose(x[:, 0], 10))
    fixed = np.concatenate([body.node_dofs[left, 0], body.node_dofs[np.flatnonzero(left)[:1], 1]])
    stress = 5.0  # MPa on a 10 mm x 1 mm (unit thickness) face
    load = np.zeros(body.n_dofs)
    edge_nodes = np.isclose(x[right, 1], 0) | np.isclose(x[right, 1], 10)
    load[body.node_dofs[right, 0]] = np.where(edge_nodes, 1.0, 2.0) * stress * 10 / 10
    condensed = condense(body.stiffness, body.node_dofs[right, 0], fixed=fixed, loads={"pull": load})
    u_r = np.linalg.solve(condensed.stiffness, condensed.loads["pull"])
    np.testing.assert_allclose(u_r / 10, stress * (1 - 0.3**2) / 1000.0, rtol=1e-10)


def test_expand_handles_many_cases_at_once():
    body, clamped, retained = _body_and_sets(skfem.MeshTri.init_tensor(np.linspace(0, 50, 11), np.linspace(0, 10, 4)))
    condensed = condense(body.stiffness, retained, fixed=clamped)
    cases = np.random.default_rng(2).normal(size=(retained.size, 3))
    together = condensed.expand(cases)
    one_by_one = np.stack([condensed.expand(c) for c in cases.T], axis=1)
    np.testing.assert_allclose(together, one_by_one, rtol=1e-12, atol=1e-12 * np.abs(one_by_one).max())
    # expanded field is in equilibrium at every interior DOF
    residual = body.stiffness @ together
    assert np.abs(residual[condensed.interior]).max() < 1e-8 * np.abs(residual).max()


@pytest.mark.parametrize("solver", SOLVERS)
def test_interior_with_rigid_motion_is_rejected(solver):
    body = assemble_elastic_body(skfem.MeshTri().refined(2), **STEEL)
    # a mechanism of the interior does not change the Schur complement (it is decoupled from the
    # retained DOFs), so PARDISO may only notice it when the interior is solved for
    with pytest.raises(InputError, match="rigid-body motion"):
        condense(body.stiffness, retained=body.node_dofs[0], solver=solver).expand(np.zeros(2))


def test_bad_dof_sets_are_named():
    body = assemble_elastic_body(skfem.MeshTri().refined(1), **STEEL)
    with pytest.raises(InputError, match="both retained and fixed"):
        condense(body.stiffness, retained=[0, 1], fixed=[1, 2])
    with pytest.raises(InputError, match="retained DOFs contain duplicates"):
        condense(body.stiffness, retained=[0, 0])
    with pytest.raises(InputError, match="out of range"):
        condense(body.stiffness, retained=[10**6])


@pytest.mark.parametrize("solver", SOLVERS)
def test_free_body_condenses_to_singular_stiffness_with_rigid_modes(solver):
    """No fixed DOFs: the condensed stiffness must not resist rigid translations and rotation."""
    body = assemble_elastic_body(skfem.MeshQuad.init_tensor(np.linspace(0, 40, 9), np.linspace(0, 10, 4)),
                                 **STEEL)
    x = body.coordinates
    ends = np.flatnonzero(np.isclose(x[:, 0], 0) | np.isclose(x[:, 0], 40))
    retained = body.node_dofs[ends].ravel()
    condensed = condense(body.stiffness, retained, solver=solver)
    rigid = np.zeros((retained.size, 3))
    rigid[0::2, 0] = 1.0
    rigid[1::2, 1] = 1.0
    rigid[0::2, 2] = -x[ends, 1]
    rigid[1::2, 2] = x[ends, 0]
    scale = np.abs(condensed.stiffness).max() * np.abs(rigid).max()
    assert np.abs(condensed.stiffness @ rigid).max() < 1e-9 * scale
    assert np.linalg.matrix_rank(condensed.stiffness, tol=1e-9 * np.abs(condensed.stiffness).max()) == retained.size - 3


def _small_counterweight():
    """A small CW (mm): the shipped joint's layout scaled down, screw heads coupled (RBE2) to two
    reference points on the top face, a wing load that twists it (a torsion-like inertia field)."""
    from reduction.coupling import rigid_couplings
    from reduction.mesh.generators import counterweight_block

    mesh = counterweight_block(300.0, 80.0, 30.0, 140.0, 15.0, 50.0, 8.0, 10.0, coarse_size=20.0,
                               relief_half_width=30.0)
    body = assemble_elastic_body(mesh, **STEEL)
    x, y = body.coordinates[:, 0], body.coordinates[:, 1]
    face = np.flatnonzero(np.abs(y) < 1e-9)
    pads = face[np.abs(x[face]) >= 30.0 - 1e-9]
    heads = [np.flatnonzero((np.abs(y - 80.0) < 1e-9) & (s * x >= 30.0 - 1e-9) & (s * x <= 70.0 + 1e-9))
             for s in (-1, 1)]
    coupling = rigid_couplings(body.n_dofs, body.node_dofs, body.coordinates,
                               [(h, np.array([s * 50.0, 80.0, 0.0])) for h, s in zip(heads, (-1, 1))],
                               rotations=True)
    field = np.zeros(body.n_dofs)
    field[body.node_dofs[:, 2]] = x * y / 80.0
    wing = 1e6 * (body.mass @ field)  # ω² M Ψ with a torsion-like Ψ, N
    spin = np.zeros(body.n_dofs)
    spin[body.node_dofs[:, 1]] = 1e7 * (y + 230.0)
    return body, face, pads, heads, coupling, {"wing": wing, "spin": body.mass @ spin}


@pytest.mark.parametrize("solver", SOLVERS)
def test_shared_factor_equals_the_two_factor_path(solver):
    """The wing-mode normalisation (face clamped, heads free) and the condensation of the coupled
    body onto its pads and reference points, both from ONE factorisation of the body, equal the
    previous path (a factor of the clamped body, then the condensation's own) to 1e-10."""
    from reduction.condensation import boundary_schur, condense_from_boundary
    from reduction.factorization import factorize
    from reduction.modal_loads import wing_tip_dofs, wing_torsion

    body, face, pads, heads, coupling, loads = _small_counterweight()
    minus, plus = wing_tip_dofs(body)
    # previous path: the clamped body's own factor for the torsion, then condense(Tᵀ K T)
    held = body.node_dofs[face].ravel()
    free = np.setdiff1d(np.arange(body.n_dofs), held)
    u = np.zeros(body.n_dofs)
    u[free] = factorize(body.stiffness[free][:, free], solver=solver).solve(loads["wing"][free])
    torsion = wing_torsion(u[minus], u[plus])
    reduced = coupling.reduce_matrix(body.stiffness)
    retained = np.concatenate([coupling.kept[body.node_dofs[pads].ravel()], coupling.reference_dofs.ravel()])
    reduced_loads = {name: coupling.reduce_vector(v) for name, v in loads.items()}
    before = condense(reduced, retained, loads=reduced_loads, solver=solver)
    # shared path: one condensation onto face, heads and tips answers both
    boundary = np.concatenate([held, minus, plus] + [body.node_dofs[h].ravel() for h in heads])
    schur = boundary_schur(body.stiffness, boundary, loads=loads, solver=solver)
    shared_u = schur.clamped_response(held, "wing")
    index = np.searchsorted(schur.boundary, np.concatenate([minus, plus]))
    assert wing_torsion(shared_u[index[:minus.size]], shared_u[index[minus.size:]]) == pytest.approx(torsion, rel=1e-10)
    after = condense_from_boundary(schur, reduced, coupling.transformation, retained, loads=reduced_loads)
    assert _relative(after.stiffness, before.stiffness) < 1e-10
    for name in loads:
        assert _relative(after.loads[name], before.loads[name]) < 1e-10
    np.testing.assert_array_equal(after.interior, before.interior)
    # the expanded field of the shared condensation is the full model's
    u_r = np.linalg.lstsq(after.stiffness, after.loads["spin"], rcond=None)[0]
    np.testing.assert_allclose(after.expand(u_r, {"spin": 1.0}), before.expand(u_r, {"spin": 1.0}),
                               rtol=0, atol=1e-10 * np.abs(before.expand(u_r, {"spin": 1.0})).max())


def test_shared_factor_needs_the_coupled_nodes_on_its_boundary():
    from reduction.condensation import boundary_schur, condense_from_boundary

    body, face, pads, _, coupling, _ = _small_counterweight()
    schur = boundary_schur(body.stiffness, body.node_dofs[face].ravel(), solver="splu")
    retained = coupling.kept[body.node_dofs[pads].ravel()]
    with pytest.raises(InputError, match="coupled node"):
        condense_from_boundary(schur, coupling.reduce_matrix(body.stiffness), coupling.transformation, retained)
