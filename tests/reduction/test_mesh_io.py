"""Reading meshes with sets (Abaqus .inp, Gmsh .msh, scikit-fem) and geometric selection."""

import meshio
import numpy as np
import pytest
import skfem
from skfem.io.meshio import to_meshio

from reduction.condensation import condense
from reduction.elasticity import assemble_elastic_body
from reduction.errors import InputError
from reduction.mesh.io import from_skfem, read_mesh
from reduction.mesh.selection import (nodes_at_points, nodes_in_box, nodes_on_cylinder, nodes_on_plane,
                                      select_body_nodes)

LENGTH, WIDTH, HEIGHT = 60.0, 10.0, 10.0


def _bar_tets():
    """Tet4 connectivity of a 60 x 10 x 10 mm bar, every element positively oriented (file convention)."""
    mesh = skfem.MeshTet.init_tensor(np.linspace(0, LENGTH, 7), np.linspace(0, WIDTH, 3), np.linspace(0, HEIGHT, 3))
    points, cells = mesh.p.T, mesh.t.T.copy()
    e = points[cells]
    negative = np.linalg.det(np.stack([e[:, 1] - e[:, 0], e[:, 2] - e[:, 0], e[:, 3] - e[:, 0]], axis=1)) < 0
    cells[negative] = cells[negative][:, [0, 2, 1, 3]]
    return points, cells


def _tet10(points, cells):
    """Add mid-edge nodes in meshio/Abaqus C3D10 order: edges 01, 12, 20, 03, 13, 23."""
    pairs = np.array([[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]])
    edges = np.sort(cells[:, pairs].reshape(-1, 2), axis=1)
    unique, inverse = np.unique(edges, axis=0, return_inverse=True)
    mid = 0.5 * (points[unique[:, 0]] + points[unique[:, 1]])
    return np.vstack([points, mid]), np.hstack([cells, len(points) + inverse.reshape(-1, 6)])


def _sets(points):
    return {
        "ROOT": np.flatnonzero(np.isclose(points[:, 0], 0)),
        "TIP": np.flatnonzero(np.isclose(points[:, 0], LENGTH)),
    }


def _tip_deflection(body, model):
    root = model.body_nodes(body, "ROOT")
    tip = model.body_nodes(body, "TIP")
    load = np.zeros(body.n_dofs)
    load[body.node_dofs[tip, 2]] = -100.0 / tip.size
    condensed = condense(body.stiffness, body.node_dofs[tip, 2], fixed=body.node_dofs[root].ravel(),
                         loads={"tip": load})
    return np.linalg.solve(condensed.stiffness, condensed.loads["tip"]).mean()


def test_abaqus_tet4_with_node_and_element_sets(tmp_path):
    points, cells = _bar_tets()
    half = np.arange(len(cells) // 2)
    # a stray reference node (as Abaqus reference points are) must not become an unconnected DOF
    stray = np.vstack([points, [[200.0, 0.0, 0.0]]])
    meshio.write(tmp_path / "bar.inp", meshio.Mesh(stray, [("tetra", cells)], point_sets=_sets(points),
                                                    cell_sets={"LEFT": [half], "ALL": [np.arange(len(cells))]}))
    model = read_mesh(tmp_path / "bar.inp")
    assert isinstance(model.mesh, skfem.MeshTet1)
    assert model.points.shape == points.shape
    np.testing.assert_array_equal(model.element_set("LEFT"), half)
    young = model.per_element({"ALL": 210_000.0}, "Young's modulus")
    body = assemble_elastic_body(model.mesh, young, 0.3)
    assert body.n_dofs == 3 * len(points)
    assert model.body_nodes(body, "TIP").size == 9
    with pytest.raises(InputError, match="no node set 'BOLT'; available: \\['ROOT', 'TIP'\\]"):
        model.node_set("BOLT")
    with pytest.raises(InputError, match="have no Young's modulus"):
        model.per_element({"LEFT": 1.0}, "Young's modulus")


def test_materials_per_element_set_change_the_stiffness(tmp_path):
    points, cells = _bar_tets()
    centre_x = points[cells].mean(axis=1)[:, 0]
    sets = {"STEEL": [np.flatnonzero(centre_x < LENGTH / 2)], "ALU": [np.flatnonzero(centre_x >= LENGTH / 2)]}
    meshio.write(tmp_path / "bar.inp",
                 meshio.Mesh(points, [("tetra", cells)], point_sets=_sets(points), cell_sets=sets))
    model = read_mesh(tmp_path / "bar.inp")
    uniform = assemble_elastic_body(model.mesh, 210_000.0, 0.3)
    mixed = assemble_elastic_body(model.mesh, model.per_element({"STEEL": 210_000.0, "ALU": 70_000.0}, "E"), 0.3)
    # Euler-Bernoulli: tip deflection ~ integral of (L - x)^2 / E over the length; the root half
    # carries 7/8 of it, so aluminium (E/3) on the tip half gives (7 + 3) / 8 = 1.25 times steel
    ratio = _tip_deflection(mixed, model) / _tip_deflection(uniform, model)
    assert ratio == pytest.approx(1.25, rel=0.05)


def test_abaqus_hex8_matches_the_same_scikit_fem_mesh(tmp_path):
    mesh = skfem.MeshHex.init_tensor(np.linspace(0, LENGTH, 7), np.linspace(0, WIDTH, 3), np.linspace(0, HEIGHT, 3))
    written = to_meshio(mesh)
    written.cell_data = {}
    written.point_sets = _sets(mesh.p.T)
    meshio.write(tmp_path / "bar.inp", written)
    model = read_mesh(tmp_path / "bar.inp")
    direct = from_skfem(mesh.with_boundaries({"ROOT": lambda x: np.isclose(x[0], 0),
                                              "TIP": lambda x: np.isclose(x[0], LENGTH)}))
    deflection_file = _tip_deflection(assemble_elastic_body(model.mesh, 210_000.0, 0.3), model)
    deflection_direct = _tip_deflection(assemble_elastic_body(direct.mesh, 210_000.0, 0.3), direct)
    assert deflection_file == pytest.approx(deflection_direct, rel=1e-10)
    # Euler-Bernoulli: w = F L^3 / (3 E I) for a sanity bound on the coarse hex bar (stiff in bending)
    beam = -100.0 * LENGTH**3 / (3 * 210_000.0 * WIDTH * HEIGHT**3 / 12)
    assert 0.5 < deflection_file / beam < 1.0


def test_tet10_file_equals_quadratic_elements_on_the_linear_mesh(tmp_path):
    points, cells = _bar_tets()
    points10, cells10 = _tet10(points, cells)
    meshio.write(tmp_path / "bar10.inp", meshio.Mesh(points10, [("tetra10", cells10)], point_sets=_sets(points10)))
    model = read_mesh(tmp_path / "bar10.inp")
    assert isinstance(model.mesh, skfem.MeshTet2)
    body = assemble_elastic_body(model.mesh, 210_000.0, 0.3)
    assert body.n_dofs == 3 * len(points10)
    assert model.body_nodes(body, "TIP").size == 25
    linear = from_skfem(skfem.MeshTet1(points.T, cells.T).with_boundaries(
        {"ROOT": lambda x: np.isclose(x[0], 0), "TIP": lambda x: np.isclose(x[0], LENGTH)}))
    reference = assemble_elastic_body(linear.mesh, 210_000.0, 0.3, quadratic=True)
    reference_root = nodes_on_plane(reference.coordinates, [0, 0, 0], [1, 0, 0])
    reference_tip = nodes_on_plane(reference.coordinates, [LENGTH, 0, 0], [1, 0, 0])
    load = np.zeros(reference.n_dofs)
    load[reference.node_dofs[reference_tip, 2]] = -100.0 / reference_tip.size
    condensed = condense(reference.stiffness, reference.node_dofs[reference_tip, 2],
                         fixed=reference.node_dofs[reference_root].ravel(), loads={"tip": load})
    expected = np.linalg.solve(condensed.stiffness, condensed.loads["tip"]).mean()
    assert _tip_deflection(body, model) == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize("file_format", ["gmsh22", "gmsh"])
def test_gmsh_physical_groups_become_sets(tmp_path, file_format):
    points, cells = _bar_tets()
    mesh = skfem.MeshTet1(points.T, cells.T)
    boundary = mesh.facets[:, mesh.boundary_facets()].T
    at_tip = np.all(np.isclose(points[boundary, 0], LENGTH), axis=1)
    triangles = boundary[at_tip]
    raw = meshio.Mesh(
        points, [("triangle", triangles), ("tetra", cells)],
        cell_data={"gmsh:physical": [np.full(len(triangles), 2), np.full(len(cells), 1)],
                   "gmsh:geometrical": [np.full(len(triangles), 2), np.full(len(cells), 1)]},
        field_data={"SOLID": np.array([1, 3]), "TIP": np.array([2, 2])},
        # each node belongs to one Gmsh entity, the lowest-dimensional one containing it
        point_data={"gmsh:dim_tags": np.where(np.isclose(points[:, :1], LENGTH), [2, 2], [3, 1])},
    )
    meshio.write(tmp_path / "bar.msh", raw, file_format=file_format, binary=False)
    model = read_mesh(tmp_path / "bar.msh")
    np.testing.assert_array_equal(np.sort(model.element_set("SOLID")), np.arange(len(cells)))
    tip = model.node_set("TIP")
    assert tip.size == 9 and np.allclose(model.points[tip, 0], LENGTH)


def test_inverted_element_is_named(tmp_path):
    points, cells = _bar_tets()
    cells[5] = cells[5][[0, 2, 1, 3]]
    meshio.write(tmp_path / "bad.inp", meshio.Mesh(points, [("tetra", cells)]))
    with pytest.raises(InputError, match="1 of 144 tetra elements are inverted .* first element index 5"):
        read_mesh(tmp_path / "bad.inp")


def test_unsupported_cells_and_missing_files_are_named(tmp_path):
    wedge = meshio.Mesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1]], float),
                        [("wedge", np.array([[0, 1, 2, 3, 4, 5]]))])
    meshio.write(tmp_path / "wedge.vtu", wedge)
    with pytest.raises(InputError, match="unsupported cell type\\(s\\) wedge"):
        read_mesh(tmp_path / "wedge.vtu")
    with pytest.raises(InputError, match="does not exist"):
        read_mesh(tmp_path / "missing.inp")


def test_geometric_selections():
    x = np.array([[0, 0, 0], [10, 0, 0], [0, 5, 0], [3, 4, 7], [5, 0, 2]], dtype=float)
    np.testing.assert_array_equal(nodes_on_plane(x, [0, 0, 0], [0, 0, 1]), [0, 1, 2])
    np.testing.assert_array_equal(nodes_in_box(x, [0, 0, 0], [5, 5, 5]), [0, 2, 4])
    np.testing.assert_array_equal(nodes_on_cylinder(x, [0, 0, 0], [0, 0, 1], 5.0), [2, 3, 4])
    np.testing.assert_array_equal(nodes_on_cylinder(x, [0, 0, 0], [0, 0, 1], 5.0, axial_range=(0, 3)), [2, 4])
    np.testing.assert_array_equal(nodes_at_points(x, [[3, 4, 7], [0, 0, 0]]), [3, 0])
    with pytest.raises(InputError, match="no mesh node found in the box"):
        nodes_in_box(x, [20, 20, 20], [30, 30, 30])
    with pytest.raises(InputError, match="have no mesh node"):
        nodes_at_points(x, [[1, 1, 1]])


def _hex20(mesh):
    """meshio hexahedron20 points and cells of a scikit-fem hex mesh (mid-edge nodes at the midpoints)."""
    written = to_meshio(mesh)
    points, hexes = written.points, written.cells_dict["hexahedron"]
    edges = np.array([[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4], [0, 4], [1, 5], [2, 6], [3, 7]])
    pairs = np.sort(hexes[:, edges].reshape(-1, 2), axis=1)
    unique, inverse = np.unique(pairs, axis=0, return_inverse=True)
    mid = 0.5 * (points[unique[:, 0]] + points[unique[:, 1]])
    return np.vstack([points, mid]), np.hstack([hexes, len(points) + inverse.reshape(-1, 12)])


def _clamped_tip_deflection(body, root, tip):
    """Tip deflection (mm) under 100 N in -z spread over the ``tip`` nodes, ``root`` nodes clamped."""
    load = np.zeros(body.n_dofs)
    load[body.node_dofs[tip, 2]] = -100.0 / tip.size
    condensed = condense(body.stiffness, body.node_dofs[tip, 2], fixed=body.node_dofs[root].ravel(),
                         loads={"tip": load})
    return np.linalg.solve(condensed.stiffness, condensed.loads["tip"]).mean()


def test_hex20_file_equals_serendipity_elements_on_the_corner_mesh(tmp_path):
    mesh = skfem.MeshHex.init_tensor(np.linspace(0, LENGTH, 7), np.linspace(0, WIDTH, 3), np.linspace(0, HEIGHT, 3))
    points, cells = _hex20(mesh)
    meshio.write(tmp_path / "bar20.inp", meshio.Mesh(points, [("hexahedron20", cells)], point_sets=_sets(points)))
    model = read_mesh(tmp_path / "bar20.inp")
    assert model.quadratic and isinstance(model.mesh, skfem.MeshHex1) and model.mesh.p.shape[1] == mesh.p.shape[1]
    body = assemble_elastic_body(model.mesh, 210_000.0, 0.3, quadratic=True)
    assert body.n_dofs == 3 * len(points)  # corners and mid-edge nodes of the file
    # the sets keep the file's mid-edge nodes, numbered as the body's nodes: 9 corners + 12 mid-edge at the tip
    np.testing.assert_array_equal(model.node_set("TIP"), model.body_nodes(body, "TIP"))
    assert model.node_set("TIP").size == 21
    reference = assemble_elastic_body(mesh, 210_000.0, 0.3, quadratic=True)
    on_plane = [nodes_on_plane(reference.coordinates, [x, 0, 0], [1, 0, 0]) for x in (0.0, LENGTH)]
    assert _tip_deflection(body, model) == pytest.approx(_clamped_tip_deflection(reference, *on_plane), rel=1e-9)


@pytest.mark.parametrize("cell_type", ["hexahedron20", "tetra10"])
def test_a_clamped_quadratic_cantilever_from_a_file_bends_as_timoshenko(tmp_path, cell_type):
    """60 x 10 x 10 mm steel bar in 6 x 2 x 2 quadratic cells, its root set listing corner nodes
    only: the scene's selection adds the mid-edge nodes of the clamped face, so the clamp holds
    the whole face (before, Hex20 clamps left them free: 1.13 x Euler-Bernoulli)."""
    if cell_type == "hexahedron20":
        points, cells = _hex20(skfem.MeshHex.init_tensor(np.linspace(0, LENGTH, 7), np.linspace(0, WIDTH, 3),
                                                         np.linspace(0, HEIGHT, 3)))
        corners = np.unique(cells[:, :8])
    else:
        points, cells = _tet10(*_bar_tets())
        corners = np.unique(cells[:, :4])
    root = np.intersect1d(np.flatnonzero(np.isclose(points[:, 0], 0.0)), corners)
    tip = np.flatnonzero(np.isclose(points[:, 0], LENGTH))
    meshio.write(tmp_path / "bar.inp", meshio.Mesh(points, [(cell_type, cells)],
                                                   point_sets={"ROOT": root, "TIP": tip}))
    model = read_mesh(tmp_path / "bar.inp")
    body = assemble_elastic_body(model.mesh, 210_000.0, 0.3, quadratic=model.quadratic)
    clamped = select_body_nodes(body.coordinates, model.mesh, {"set": "ROOT"}, "fixed.nodes", model)
    np.testing.assert_array_equal(clamped, nodes_on_plane(body.coordinates, [0, 0, 0], [1, 0, 0]))
    deflection = -_clamped_tip_deflection(body, clamped, model.body_nodes(body, "TIP"))
    # Timoshenko: F L^3 / (3 E I) + F L / (k G A), k = 10 (1 + nu) / (12 + 11 nu) for a rectangle
    young, poisson, force, inertia, area = 210_000.0, 0.3, 100.0, WIDTH * HEIGHT**3 / 12, WIDTH * HEIGHT
    shear = 10 * (1 + poisson) / (12 + 11 * poisson) * young / (2 * (1 + poisson))
    timoshenko = force * LENGTH**3 / (3 * young * inertia) + force * LENGTH / (shear * area)
    # two quadratic cells over the height: 2.5 % stiff (1.5 % with four), of which about 1 % is
    # the clamp holding the root's Poisson contraction; both errors only ever stiffen the bar
    assert 0.96 < deflection / timoshenko < 1.0


def test_curved_hex20_edges_are_refused(tmp_path):
    mesh = skfem.MeshHex.init_tensor(np.linspace(0, 10, 2), np.linspace(0, 10, 2), np.linspace(0, 10, 2))
    points, cells = _hex20(mesh)
    points[cells[0, 8]] += [0.0, 1.0, 0.0]
    meshio.write(tmp_path / "curved.inp", meshio.Mesh(points, [("hexahedron20", cells)]))
    with pytest.raises(InputError, match="curved edges"):
        read_mesh(tmp_path / "curved.inp")


def test_abaqus_surfaces_by_element_faces_and_by_nodes(tmp_path):
    points, cells = _bar_tets()
    path = tmp_path / "bar.inp"
    meshio.write(path, meshio.Mesh(points, [("tetra", cells)], point_sets=_sets(points)))
    # the faces of the tip: every tetrahedron face with its three corners at x = LENGTH
    faces = {"S1": (0, 1, 2), "S2": (0, 3, 1), "S3": (1, 3, 2), "S4": (2, 3, 0)}
    lines = [f"{k + 1}, {name}" for k, cell in enumerate(cells) for name, corners in faces.items()
             if np.allclose(points[cell[list(corners)], 0], LENGTH)]
    root = [str(k + 1) for k in np.flatnonzero(np.isclose(points[:, 0], 0.0))]
    with path.open("a") as stream:
        stream.write("** surfaces meshio drops\n*SURFACE, NAME=TIP_FACES, TYPE=ELEMENT\n" + "\n".join(lines) + "\n")
        stream.write("*NSET, NSET=ROOT_NODES\n" + ",".join(root) + "\n*SURFACE, NAME=ROOT_SURF, TYPE=NODE\nROOT_NODES\n")
        stream.write("*ELSET, ELSET=FIRST, GENERATE\n1, 3, 1\n*SURFACE, NAME=FIRST_S1\nFIRST, S1\n")
    model = read_mesh(path)
    np.testing.assert_array_equal(model.node_set("TIP_FACES"), model.node_set("TIP"))
    np.testing.assert_array_equal(model.node_set("ROOT_SURF"), model.node_set("ROOT"))
    first = model.node_set("FIRST_S1")
    assert 3 <= first.size <= 9 and np.all(np.isin(first, np.unique(cells[:3])))
    with path.open("a") as stream:
        stream.write("*SURFACE, NAME=BAD\nNOSUCHSET, S2\n")
    with pytest.raises(InputError, match="BAD names element set 'NOSUCHSET'"):
        read_mesh(path)


def test_a_file_meshio_cannot_read_names_the_key_and_the_file(tmp_path, capsys):
    """meshio prints and ends the process (SystemExit) when no reader accepts a file: here an
    InputError naming the scene key and the file, with nothing printed."""
    garbage = tmp_path / "bad.msh"
    garbage.write_text("garbage\n")
    with pytest.raises(InputError) as error:
        read_mesh(garbage, "bodies.web.mesh.file")
    message = str(error.value)
    assert "'bodies.web.mesh.file'" in message and str(garbage) in message and "not a Gmsh file" in message
    assert capsys.readouterr() == ("", "")


def test_an_element_on_an_undefined_node_and_a_folder_are_said_as_such(tmp_path):
    points, cells = _bar_tets()
    meshio.write(tmp_path / "bar.inp", meshio.Mesh(points, [("tetra", cells)]))
    lines = (tmp_path / "bar.inp").read_text().splitlines()
    first = lines.index(next(line for line in lines if line.upper().startswith("*ELEMENT"))) + 1
    number, nodes = lines[first].split(",", 1)
    lines[first] = f"{number}, 99999," + nodes.split(",", 1)[1]
    (tmp_path / "bad.inp").write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match="'bodies.cw.mesh.file': .*bad.inp: an element .*refers to node 99999, "
                                         "which the file does not define"):
        read_mesh(tmp_path / "bad.inp", "bodies.cw.mesh.file")
    with pytest.raises(InputError, match="'bodies.cw.mesh.file': .* is a folder, not a mesh file"):
        read_mesh(tmp_path, "bodies.cw.mesh.file")
