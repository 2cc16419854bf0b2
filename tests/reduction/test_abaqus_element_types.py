"""Abaqus element types: hybrid and reduced-integration variants are read as the element of the
same displacement interpolation; any other type is refused by name, with its file and line."""

import re

import meshio
import numpy as np
import pytest
import skfem

from reduction.errors import InputError
from reduction.mesh.io import read_mesh


def _block(cell_type):
    """A 20 x 10 x 10 mm block of meshio ``cell_type`` cells (file node order, positive volumes)."""
    mesh = skfem.MeshHex.init_tensor(np.linspace(0, 20, 3), np.linspace(0, 10, 2), np.linspace(0, 10, 2))
    if cell_type == "hexahedron":
        return mesh.p.T, mesh.t.T[:, [0, 2, 4, 1, 3, 6, 7, 5]]  # scikit-fem order → Abaqus C3D8 order
    if cell_type == "hexahedron20":
        corners = mesh.t.T[:, [0, 2, 4, 1, 3, 6, 7, 5]]
        edges = np.array([[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4],
                          [0, 4], [1, 5], [2, 6], [3, 7]])
        pairs = np.sort(corners[:, edges].reshape(-1, 2), axis=1)
        unique, inverse = np.unique(pairs, axis=0, return_inverse=True)
        points = np.vstack([mesh.p.T, 0.5 * (mesh.p.T[unique[:, 0]] + mesh.p.T[unique[:, 1]])])
        return points, np.hstack([corners, mesh.p.shape[1] + inverse.reshape(-1, 12)])
    tets = skfem.MeshTet.init_tensor(np.linspace(0, 20, 3), np.linspace(0, 10, 2), np.linspace(0, 10, 2))
    points, cells = tets.p.T, tets.t.T.copy()
    e = points[cells]
    negative = np.linalg.det(np.stack([e[:, 1] - e[:, 0], e[:, 2] - e[:, 0], e[:, 3] - e[:, 0]], axis=1)) < 0
    cells[negative] = cells[negative][:, [0, 2, 1, 3]]
    if cell_type == "tetra":
        return points, cells
    pairs = np.array([[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]])
    edges = np.sort(cells[:, pairs].reshape(-1, 2), axis=1)
    unique, inverse = np.unique(edges, axis=0, return_inverse=True)
    mid = 0.5 * (points[unique[:, 0]] + points[unique[:, 1]])
    return np.vstack([points, mid]), np.hstack([cells, len(points) + inverse.reshape(-1, 6)])


def _written_as(tmp_path, cell_type, element_type):
    """An Abaqus file of the block whose *ELEMENT line says ``element_type``."""
    points, cells = _block(cell_type)
    path = tmp_path / f"{element_type}.inp"
    meshio.write(path, meshio.Mesh(points, [(cell_type, cells)]))
    text = path.read_text()
    path.write_text(re.sub(r"(?im)^(\*ELEMENT\s*,\s*TYPE\s*=\s*)\S+?(?=,|$)", lambda m: m.group(1) + element_type,
                           text))
    assert f"type={element_type}".lower() in path.read_text().lower()
    return path


@pytest.mark.parametrize("cell_type, base, variants", [
    ("tetra", "C3D4", ["C3D4H", "c3d4h"]),
    ("tetra10", "C3D10", ["C3D10H", "C3D10M", "C3D10MH"]),
    ("hexahedron", "C3D8", ["C3D8H", "C3D8R", "C3D8RH"]),
    ("hexahedron20", "C3D20", ["C3D20H", "C3D20R", "C3D20RH"]),
])
def test_hybrid_and_reduced_variants_read_as_their_base_element(tmp_path, cell_type, base, variants):
    expected = read_mesh(_written_as(tmp_path, cell_type, base))
    for variant in variants:
        model = read_mesh(_written_as(tmp_path, cell_type, variant))
        assert type(model.mesh) is type(expected.mesh) and model.quadratic == expected.quadratic
        np.testing.assert_array_equal(model.points, expected.points)
        np.testing.assert_array_equal(model.mesh.t, expected.mesh.t)


@pytest.mark.parametrize("element_type, why", [
    ("C3D27", ""),
    ("C3D8I", "incompatible modes"),
    ("C3D8IH", "incompatible modes"),
])
def test_other_element_types_are_refused_by_name(tmp_path, element_type, why):
    cell_type = "hexahedron20" if element_type == "C3D27" else "hexahedron"
    path = _written_as(tmp_path, cell_type, element_type)
    with pytest.raises(InputError) as refused:
        read_mesh(path, "bodies.cw.mesh")
    message = str(refused.value)
    assert message.startswith(f"'bodies.cw.mesh': {path}: unsupported element type {element_type} (line ")
    assert why in message and "C3D4H" in message and "internal" not in message


def _plate(tmp_path, element_type):
    """A 20 x 10 mm plate of quads written with the *ELEMENT type ``element_type``."""
    mesh = skfem.MeshQuad.init_tensor(np.linspace(0, 20, 5), np.linspace(0, 10, 3))
    path = tmp_path / f"{element_type}.inp"
    meshio.write(path, meshio.Mesh(mesh.p.T, [("quad", mesh.t.T[:, ::-1])]))  # counter-clockwise
    path.write_text(re.sub(r"(?im)^(\*ELEMENT\s*,\s*TYPE\s*=\s*)\S+?(?=,|$)", lambda m: m.group(1) + element_type,
                           path.read_text()))
    return path


@pytest.mark.parametrize("element_type, why", [
    ("CPS4", "plane-stress element type CPS4 (line "),
    ("CPS4R", "plane-stress element type CPS4R (line "),
    ("S4R", "element type S4R (line "),
])
def test_a_2d_mesh_of_other_than_plane_strain_solids_is_refused(tmp_path, element_type, why):
    """fretwork's 2D bodies are plane strain: plane-stress and shell quads (read by meshio as the
    same cells) were analysed as plane-strain ones without a word (QA, 2026-11-28)."""
    with pytest.raises(InputError) as refused:
        read_mesh(_plate(tmp_path, element_type), "bodies.pad.mesh")
    assert why in str(refused.value) and "plane strain (CPE3, CPE4" in str(refused.value)
    for plane_strain in ("CPE4", "CPE4R"):
        assert read_mesh(_plate(tmp_path, plane_strain)).mesh.t.shape == (4, 8)
