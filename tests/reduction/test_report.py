"""Accuracy report of Craig-Bampton bodies: figures, records, plot, and a mesh-file entry point."""

import json

import meshio
import numpy as np
import pytest
import skfem
from skfem.io.meshio import to_meshio

from reduction.coupling import rigid_couplings
from reduction.elasticity import assemble_elastic_body
from reduction.report import accuracy_report, accuracy_report_for_mesh, plot_error_vs_modes


@pytest.fixture(scope="module")
def bar():
    mesh = skfem.MeshHex.init_tensor(np.linspace(0, 200, 41), np.linspace(0, 20, 5), np.linspace(0, 10, 3))
    body = assemble_elastic_body(mesh, 210_000.0, 0.3, 7.85e-9)
    x = body.coordinates
    root = np.flatnonzero(np.isclose(x[:, 0], 0))
    tip = np.flatnonzero(np.isclose(x[:, 0], 200))
    return body, root, tip


def _coupled(body, node_sets):
    coupling = rigid_couplings(body.n_dofs, body.node_dofs, body.coordinates,
                               [(nodes, body.coordinates[nodes].mean(axis=0)) for nodes in node_sets], rotations=True)
    return coupling, coupling.reduce_matrix(body.stiffness), coupling.reduce_matrix(body.mass)


def test_clamped_body_report(bar, tmp_path):
    body, root, tip = bar
    coupling, k, m = _coupled(body, [tip])
    fixed = coupling.kept[body.node_dofs[root].ravel()]
    report = accuracy_report(k, m, coupling.reference_dofs.ravel(), 20, fixed=fixed)
    assert report.rigid_modes == 0
    assert report.mode_counts[0] == 0 and report.mode_counts[-1] == 20
    assert np.abs(report.frequency_error[-1]).max() < 0.005
    assert np.all(report.frequency_error >= -1e-9)  # Rayleigh-Ritz: reduced frequencies are upper bounds
    assert report.mac[-1].min() > 0.99
    # the fixed-interface modes are eigenvectors of the interface-fixed model, found independently
    np.testing.assert_allclose(report.interface_fixed_error, 0.0, atol=1e-8)
    # Craig-Bampton statics are exact at the interface
    assert report.static_dofs.size == 6 and report.static_error.max() < 1e-8
    summary = report.summary()
    assert summary["error_never_grows"] and summary["max_frequency_error"] < 0.005
    assert summary["max_static_interface_error"] < 1e-8
    records = report.to_records()
    json.dumps(records)
    json.dumps(summary)
    assert {r["quantity"] for r in records} == {"frequency", "static interface displacement", "time"}
    png = plot_error_vs_modes(report, tmp_path / "error.png")
    assert png.stat().st_size > 5000 and png.read_bytes()[:4] == b"\x89PNG"


def test_free_free_body_report_skips_rigid_modes(bar):
    body, root, tip = bar
    coupling, k, m = _coupled(body, [root, tip])
    report = accuracy_report(k, m, coupling.reference_dofs.ravel(), 20)
    assert report.rigid_modes == 6
    assert report.full_hz[0] > 1000.0  # first free-free bending, well above the clamped 224 Hz
    assert np.abs(report.frequency_error[-1]).max() < 0.005
    assert report.static_dofs.size == 0


def test_report_from_an_abaqus_file(bar, tmp_path):
    body, root, tip = bar
    written = to_meshio(body.mesh)
    written.cell_data = {}
    written.point_sets = {"ROOT": root, "TIP": tip}
    meshio.write(tmp_path / "bar.inp", written)
    report = accuracy_report_for_mesh(tmp_path / "bar.inp", 210_000.0, 0.3, 7.85e-9, 10, clamp_sets=["ROOT"])
    assert report.n_interface == 6
    assert np.abs(report.frequency_error[-1]).max() < 0.01
