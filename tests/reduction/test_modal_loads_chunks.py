"""Mode shapes are interpolated onto a contact mesh in chunks of points: scikit-fem's element
finder maps every point of one call into every candidate element of all of them, and a refined
C3D10 counterweight (11,889 nodes) took 3.8 GB at once (QA). Chunked, the values are the same to
round-off (a node on a face shared by two elements may be probed in either)."""

import numpy as np
import skfem

from reduction import modal_loads
from reduction.modal_loads import ModeField, interpolate_modes


def test_chunked_probes_give_the_modes_of_one_call(monkeypatch):
    mesh = skfem.MeshTet1.init_tensor(np.linspace(0, 40, 6), np.linspace(0, 20, 4), np.linspace(0, 10, 3))
    basis = skfem.Basis(mesh, skfem.ElementVector(skfem.ElementTetP2()))
    x, y, z = basis.doflocs
    shapes = np.column_stack([np.sin(x / 13.0) * y, z * x / 40.0 + y ** 2 / 100.0, np.cos(z / 5.0) + x * z / 400.0])
    modes = ModeField(points=mesh.p, cells=mesh.t, shapes=shapes)
    points = np.random.default_rng(1).uniform([0, 0, 0], [40, 20, 10], size=(1234, 3))
    monkeypatch.setattr(modal_loads, "PROBE_CHUNK", 10**9)
    whole = interpolate_modes(modes, points)
    monkeypatch.setattr(modal_loads, "PROBE_CHUNK", 100)
    chunked = interpolate_modes(modes, points)
    assert chunked.shape == (1234, 3, 3)
    np.testing.assert_allclose(chunked, whole, rtol=0, atol=1e-13 * np.abs(whole).max())
