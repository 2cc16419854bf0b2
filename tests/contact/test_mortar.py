"""Mortar pairing: the contact patch test on non-matching meshes, Hertz, and the automatic choice.

Two flat 10 × 10 × 4 mm blocks, the upper one pressed (and sheared) through a rigid reference
point on its top face, the lower one fixed at its base, ν = 0. Under the normal load the exact
state is uniform (uniaxial stress, no lateral strain): p = P/A everywhere. Node-to-segment
pairing fails this test on non-matching faces (point pressures scatter by 28-47 %); mortar
pairing passes it to round-off.

With a shear load Q the exact state of a finite block with free sides is not uniform: simple
shear would need shear tractions on the sides, and the two differently meshed bodies warp
differently. It is uniform in the limit of an interface that is compliant in shear against
the bodies, k_t·h/G → 0 (k_t = μ·p/γ_crit): γ_crit = 0.05 mm gives k_t·h/G ≈ 0.4 %, and
Q = 0.1·μ·P keeps the warping of the bodies (a discretisation effect that no pairing removes)
below the tolerance. Node-to-segment then still scatters τ by 13-17 %.
"""

import numpy as np
import pytest

from contact.interface import pair_surfaces
from contact.mortar import mortar_matrices
from contact.solver import ContactSolver, Effects
from contact.structure import ContactSpace
from pipelines import scene as scenes
from pipelines.build import build
from pipelines.jobs.validate import SCENE, check_hertz

PRESS = 1000.0  # N on 100 mm²: p = 10 MPa
COF = 0.56      # the scene's μ


def _blocks(upper, lower, pairing="auto", shear=0.0, critical_slip=1e-3):
    loads = [{"name": "press", "dof": "cylinder.rp.uz", "value": -PRESS, "history": "ramp"}]
    motions = [{"name": "hold_y", "dof": "cylinder.rp.uy", "value": 0.0, "history": "constant"}]
    if shear:
        loads.append({"name": "shear", "dof": "cylinder.rp.ux", "value": shear, "history": "ramp"})
    else:
        motions.append({"name": "hold_x", "dof": "cylinder.rp.ux", "value": 0.0, "history": "constant"})
    overrides = {
        "scene.dimension": 3, "scene.effects": [], "materials.ti64.poisson_ratio": 0.0,
        "bodies.cylinder.mesh": {"generator": "flat_block", "size_x": 10.0, "size_y": 10.0, "height": 4.0,
                                 "n_x": upper[0], "n_y": upper[1], "n_z": 3, "z0": 0.0},
        "bodies.plane.mesh": {"generator": "flat_block", "size_x": 10.0, "size_y": 10.0, "height": 4.0,
                              "n_x": lower[0], "n_y": lower[1], "n_z": 3, "z0": -4.0},
        "bodies.cylinder.reference_points.rp": {"nodes": {"axis": "z", "value": 4.0},
                                                "position": [0.0, 0.0, 4.0]},
        "bodies.plane.fixed": {"nodes": {"axis": "z", "value": -4.0}, "components": ["ux", "uy", "uz"]},
        "contact.slave": {"body": "cylinder", "axis": "z", "value": 0.0},
        "contact.master": {"body": "plane", "axis": "z", "value": 0.0},
        "contact.pairing": pairing, "contact.critical_slip": critical_slip,
        "loads": loads, "motions": motions,
    }
    return build(scenes.load(SCENE, overrides))


def _tractions(model, increments=3):
    """Pressure (n,) and shear traction (n, 3) in global axes, MPa, after the ramp."""
    solver = ContactSolver(ContactSpace(model.assembly.structure), model.law, model.settings)
    equilibrium, state = solver.initial_equilibrium(), model.initial_state()
    for k in range(1, increments + 1):
        equilibrium, state, _, _ = solver.increment(equilibrium, state, model.program.preload(k / increments),
                                                    Effects())
    per_point = equilibrium.forces.reshape(-1, 3) / model.assembly.structure.area[:, None]
    shear = np.einsum("nt,ntd->nd", per_point[:, 1:], model.assembly.pairing.tangents)
    return per_point[:, 0], shear


FACES = [((7, 7), (10, 10)), ((10, 10), (7, 7)), ((7, 7), (13, 11))]


@pytest.mark.parametrize("upper, lower", FACES)
def test_pressure_patch_test_on_non_matching_faces(upper, lower):
    model = _blocks(upper, lower)
    assert model.assembly.pairing.method == "mortar"  # the automatic choice for these faces
    assert model.assembly.structure.area.sum() == pytest.approx(100.0, rel=1e-12)
    pressure, _ = _tractions(model)
    assert np.abs(pressure / (PRESS / 100.0) - 1.0).max() < 0.01


def test_node_to_segment_fails_the_patch_test():
    pressure, _ = _tractions(_blocks((7, 7), (10, 10), pairing="node_to_segment"))
    assert np.abs(pressure / (PRESS / 100.0) - 1.0).max() > 0.2


@pytest.mark.parametrize("upper, lower", FACES)
def test_shear_patch_test_on_non_matching_faces(upper, lower):
    shear_load = 0.1 * COF * PRESS
    pressure, shear = _tractions(_blocks(upper, lower, shear=shear_load, critical_slip=0.05))
    mean = shear_load / 100.0
    assert np.abs(pressure / (PRESS / 100.0) - 1.0).max() < 0.01
    assert np.abs(shear[:, 0] / mean - 1.0).max() < 0.01
    assert np.abs(shear[:, 1:]).max() < 0.01 * mean


def test_node_to_segment_fails_the_shear_patch_test():
    shear_load = 0.1 * COF * PRESS
    _, shear = _tractions(_blocks((7, 7), (10, 10), pairing="node_to_segment", shear=shear_load,
                                  critical_slip=0.05))
    assert np.abs(shear[:, 0] / (shear_load / 100.0) - 1.0).max() > 0.1


def test_matching_faces_pair_node_to_node():
    """Auto keeps node-to-segment on matching faces, and mortar there reduces to node-to-node:
    with dual test functions D is diagonal and M = D."""
    model = _blocks((7, 7), (7, 7))
    assert model.assembly.pairing.method == "node_to_segment"
    pairing = model.assembly.pairing
    D, M, _ = mortar_matrices(pairing.slave, pairing.master)
    assert np.abs(D - D.multiply(np.eye(D.shape[0]) > 0)).max() < 1e-12 * D.max()
    same_place = np.linalg.norm(pairing.slave.coordinates[:, None, :2]
                                - pairing.master.coordinates[None, :, :2], axis=2) < 1e-9
    assert np.abs(M.toarray() - D.diagonal()[:, None] * same_place).max() < 1e-12 * D.max()


def _strips(upper_size, lower_size):
    """The 2D counterpart of :func:`_blocks`: 10 × 10 mm strips (the scene's cylinder block
    with an infinite radius on its plane block), contact elements of ``upper_size`` and
    ``lower_size`` mm, pressed by 1000 N/mm (p = 100 MPa), ν = 0, pairing "auto"."""
    def block(generator, size):
        return {"generator": generator, "half_width": 5.0, "contact_half_width": 5.0 - size, "contact_size": size,
                **({"radius": 1e12, "height": 10.0} if generator == "cylinder_block" else {"depth": 10.0})}

    return build(scenes.load(SCENE, {
        "scene.effects": [], "materials.ti64.poisson_ratio": 0.0,
        "bodies.cylinder.mesh": block("cylinder_block", upper_size),
        "bodies.plane.mesh": block("plane_block", lower_size),
        "bodies.cylinder.reference_points.rp": {"nodes": {"axis": "y", "value": 10.0}, "position": [0.0, 10.0]},
        "bodies.plane.fixed": {"nodes": {"axis": "y", "value": -10.0}, "components": ["ux", "uy"]},
        "contact.slave": {"body": "cylinder", "box": [[-5.01, -0.01], [5.01, 0.01]]},
        "contact.master": {"body": "plane", "box": [[-5.01, -0.01], [5.01, 0.01]]},
        "contact.pairing": "auto",
        "loads": [{"name": "press", "dof": "cylinder.rp.uy", "value": -1000.0, "history": "ramp"}],
        "motions": [{"name": "hold_x", "dof": "cylinder.rp.ux", "value": 0.0, "history": "constant"}]}))


@pytest.mark.parametrize("build_model, method", [
    (lambda: _blocks((5, 5), (10, 10)), "mortar"),  # every slave node on every other master node
    (lambda: _blocks((4, 4), (20, 20)), "mortar"),  # ... on every fifth
    (lambda: _strips(0.5, 0.1), "mortar"),
    (lambda: _strips(0.5, 0.5), "node_to_segment"),
], ids=["3d_every_other_master_node", "3d_every_fifth", "2d_every_fifth", "2d_matching"])
def test_auto_pairs_node_to_node_only_where_the_meshes_match_both_ways(build_model, method):
    """Nested faces (a finer master, each slave node on a master node) are not node-to-node:
    the master nodes in between would carry no force and the pressure scatter by 8-10 %.
    Auto pairs them by mortar, which passes the pressure patch test to round-off; truly
    matching faces stay node-to-node, exact too."""
    model = build_model()
    assert model.assembly.pairing.method == method
    dim = model.scene.dimension
    solver = ContactSolver(ContactSpace(model.assembly.structure), model.law, model.settings)
    equilibrium, state = solver.initial_equilibrium(), model.initial_state()
    for k in (1, 2, 3):
        equilibrium, state, _, _ = solver.increment(equilibrium, state, model.program.preload(k / 3), Effects())
    pressure = equilibrium.forces.reshape(-1, dim)[:, 0] / model.assembly.structure.area
    exact = PRESS / 100.0 if dim == 3 else 100.0  # MPa
    assert np.abs(pressure / exact - 1.0).max() < 1e-9


def test_mortar_integrals_conserve_area_and_rigid_motion():
    """Rows of M sum to the slave's D (a rigid translation opens no gap), and the areas the
    points carry add up to the slave surface on both meshes' sides."""
    pairing = _blocks((7, 7), (13, 11)).assembly.pairing
    D, M, _ = mortar_matrices(pairing.slave, pairing.master)
    row_d, row_m = np.asarray(D.sum(axis=1)).ravel(), np.asarray(M.sum(axis=1)).ravel()
    assert row_m == pytest.approx(row_d, rel=1e-12)
    assert np.asarray(M.sum(axis=0)).ravel() == pytest.approx(pairing.master.area, rel=1e-12)
    assert row_d == pytest.approx(pairing.slave.area, rel=1e-12)


def test_mortar_integrals_are_the_same_summed_dense_or_sparse(monkeypatch):
    """Small interfaces sum the integrals in a dense array, large ones through scipy's COO
    form (contact/mortar.py, ``_summed``): the same entries either way, to round-off, and the
    same sparsity once round-off is dropped (a quadrilateral's own dual coefficients leave
    D's off-diagonals as round-off)."""
    import contact.mortar as mortar

    pairing = _blocks((7, 7), (13, 11)).assembly.pairing
    dense_sum = mortar_matrices(pairing.slave, pairing.master)
    monkeypatch.setattr(mortar, "_DENSE_SUM", 0)
    coo_sum = mortar_matrices(pairing.slave, pairing.master)
    for dense, coo in zip(dense_sum[:2], coo_sum[:2]):
        assert dense.nnz == coo.nnz
        assert np.array_equal(dense.indptr, coo.indptr) and np.array_equal(dense.indices, coo.sorted_indices().indices)
        assert np.abs((dense - coo).toarray()).max() <= 1e-13 * np.abs(coo.data).max()


def test_hertz_on_non_matching_meshes_with_mortar():
    model = build(scenes.load(SCENE, {"bodies.plane.mesh.contact_size": 0.043}))
    assert model.assembly.pairing.method == "mortar"
    for record in check_hertz(model):
        assert record["rel_error"] < 0.02, record


def test_unknown_pairing_method_is_an_input_error():
    pairing = _blocks((7, 7), (7, 7)).assembly.pairing
    with pytest.raises(Exception, match="pairing must be one of"):
        pair_surfaces(pairing.slave, pairing.master, method="surface_to_surface")


@pytest.mark.parametrize("shift", [0.0, 4.0])
def test_the_projection_is_formed_only_for_slave_nodes_the_master_does_not_cover(shift):
    """A finite-sliding re-pairing forms the node-to-segment projection only when some slave
    node needs it (contact/interface.py, ``pair_surfaces``): the pairing is that of the
    projection formed first, with the master in place (every node covered) and slid 4 mm off
    (the overhanging nodes keep the projection's weights and their own tributary area)."""
    from dataclasses import fields, replace

    from contact.interface import pair_node_to_segment
    from contact.mortar import mortar_pairing

    pairing = _blocks((7, 7), (13, 11)).assembly.pairing
    master = replace(pairing.master, coordinates=pairing.master.coordinates + [shift, 0.0, 0.0])
    lazy = pair_surfaces(pairing.slave, master, method="mortar")
    projection = pair_node_to_segment(pairing.slave, master)
    eager = mortar_pairing(pairing.slave, master, lambda: projection)
    for field in fields(lazy):
        a, b = getattr(lazy, field.name), getattr(eager, field.name)
        assert a is b or np.array_equal(a, b) if isinstance(a, np.ndarray) else a == b, field.name
    D, _, _ = mortar_matrices(pairing.slave, master)
    overhanging = np.asarray(D.sum(axis=1)).ravel() <= 1e-9 * pairing.slave.area
    assert overhanging.any() == (shift > 0.0)
    assert np.array_equal(lazy.point_area[overhanging], pairing.slave.area[overhanging])


@pytest.mark.parametrize("method", ["mortar", "node_to_segment", "auto"])
def test_surfaces_of_different_dimensions_are_an_input_error(method):
    """A 2D slave and a 3D master are refused with one message whichever pairing is asked for
    (the mortar pairing forms no projection, which would have said it)."""
    from dataclasses import replace

    from reduction.errors import InputError

    pairing = _blocks((7, 7), (7, 7)).assembly.pairing
    flat = replace(pairing.slave, coordinates=pairing.slave.coordinates[:, :2])
    with pytest.raises(InputError, match="slave surface is 2D but master surface is 3D"):
        pair_surfaces(flat, pairing.master, method=method)
