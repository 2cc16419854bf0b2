"""HDF5 cache of reductions: keys change with what the reduction depends on, round trips are exact."""

import h5py
import numpy as np
import pytest
import skfem

from reduction.cache import (cached_condensation, cached_craig_bampton, load_condensation, reduction_key,
                             save_condensation)
from reduction.condensation import condense
from reduction.craig_bampton import craig_bampton
from reduction.elasticity import assemble_elastic_body
from reduction.errors import InputError


@pytest.fixture(scope="module")
def plate():
    mesh = skfem.MeshQuad.init_tensor(np.linspace(0, 40, 9), np.linspace(0, 10, 4))
    body = assemble_elastic_body(mesh, 70_000.0, 0.33, 2.7e-9)
    x = body.coordinates
    clamp = body.node_dofs[np.isclose(x[:, 0], 0)].ravel()
    face = body.node_dofs[np.isclose(x[:, 0], 40)].ravel()
    return mesh, body, clamp, face


def test_key_depends_on_mesh_material_sets_and_modes(plate):
    mesh, _, clamp, face = plate
    base = dict(materials={"E": 70_000.0, "nu": 0.33}, retained={"face": face, "clamp": clamp}, n_modes=10)
    key = reduction_key(mesh, **base)
    assert key == reduction_key(mesh, **base)
    moved = skfem.MeshQuad(mesh.p * 1.001, mesh.t)
    assert reduction_key(moved, **base) != key
    assert reduction_key(mesh, **{**base, "materials": {"E": 70_001.0, "nu": 0.33}}) != key
    assert reduction_key(mesh, **{**base, "retained": {"face": face[:-1], "clamp": clamp}}) != key
    assert reduction_key(mesh, **{**base, "n_modes": 11}) != key


def test_craig_bampton_is_computed_once(plate, tmp_path):
    mesh, body, clamp, face = plate
    key = reduction_key(mesh, {"E": 70_000.0}, {"face": face}, 5)
    calls = []

    def compute():
        calls.append(1)
        return craig_bampton(body.stiffness, body.mass, face, 5, fixed=clamp)

    first, hit_first = cached_craig_bampton(tmp_path, key, compute)
    second, hit_second = cached_craig_bampton(tmp_path, key, compute)
    assert (hit_first, hit_second, len(calls)) == (False, True, 1)
    np.testing.assert_array_equal(second.basis, first.basis)
    np.testing.assert_array_equal(second.mass, first.mass)
    np.testing.assert_array_equal(second.fixed_interface_eigenvalues, first.fixed_interface_eigenvalues)
    with h5py.File(tmp_path / f"{key}.h5") as handle:
        assert handle.attrs["fretwork_format"] == "fretwork-reduction"
        assert handle["stiffness"].attrs["units"] == "N/mm"


def test_condensation_round_trip_expands_like_the_original(plate, tmp_path):
    _, body, clamp, face = plate
    load = np.zeros(body.n_dofs)
    load[1::2] = -1.0
    original = condense(body.stiffness, face, fixed=clamp, loads={"weight": load})
    save_condensation(tmp_path, "k1", original)
    restored = load_condensation(tmp_path, "k1", body.stiffness)
    np.testing.assert_array_equal(restored.stiffness, original.stiffness)
    np.testing.assert_array_equal(restored.loads["weight"], original.loads["weight"])
    u_r = np.linalg.solve(restored.stiffness, restored.loads["weight"])
    # exact on purpose: the restored matrices are bit-equal to the originals (asserted above),
    # so the same expansion of them must give the same bits
    np.testing.assert_array_equal(restored.expand(u_r, {"weight": 1.0}), original.expand(u_r, {"weight": 1.0}))
    assert load_condensation(tmp_path, "missing") is None
    without_matrix = load_condensation(tmp_path, "k1")
    with pytest.raises(InputError, match="without the stiffness"):
        without_matrix.expand(u_r)
    (tmp_path / "bad.h5").write_bytes(b"")
    with h5py.File(tmp_path / "bad.h5", "w") as handle:
        handle.attrs["fretwork_format"] = "something else"
    with pytest.raises(InputError, match="not a fretwork condensation cache file"):
        load_condensation(tmp_path, "bad")


def test_cached_condensation_skips_the_second_schur_complement(plate, tmp_path):
    mesh, body, clamp, face = plate
    key = reduction_key(mesh, {"E": 70_000.0}, {"face": face, "clamp": clamp})
    calls = []

    def compute():
        calls.append(1)
        return condense(body.stiffness, face, fixed=clamp)

    first, hit_first = cached_condensation(tmp_path, key, body.stiffness, compute)
    second, hit_second = cached_condensation(tmp_path, key, body.stiffness, compute)
    assert (hit_first, hit_second, len(calls)) == (False, True, 1)
    u_r = np.linspace(0, 1e-3, face.size)
    # exact on purpose: a cache hit must give back what was computed, bit for bit
    np.testing.assert_array_equal(second.expand(u_r), first.expand(u_r))
