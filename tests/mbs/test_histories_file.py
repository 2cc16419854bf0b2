"""Interface-histories files: round trips and the checks of units, columns and sampling."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import skfem

from mbs.histories_file import (
    InterfaceHistories,
    read_interface_histories,
    write_interface_histories,
)
from reduction.errors import InputError


def _histories(n=40, step=1e-4):
    time = 0.1 + step * np.arange(n)
    wave = np.sin(2 * np.pi * 350.0 * time)
    vector = np.column_stack([wave, 2 * wave, -wave])
    return InterfaceHistories(750.0, time, 1e5 * vector, 78.5 + vector, 1e3 * vector, 0.01 * wave,
                              np.zeros((n, 0)), np.zeros((n, 0)), np.zeros((n, 0)), None)


@pytest.mark.parametrize("suffix", ["h5", "csv"])
def test_histories_written_and_read_back_are_the_same_numbers(tmp_path, suffix):
    written = _histories()
    read = read_interface_histories(write_interface_histories(tmp_path / f"cw.{suffix}", written))
    for name in ("time", "frame_acceleration", "angular_velocity", "angular_acceleration", "wing_torsion"):
        np.testing.assert_array_equal(getattr(read, name), getattr(written, name))
    assert read.speed_rpm == 750.0 and read.modes is None


def _csv(tmp_path, text):
    path = tmp_path / "other_code.csv"
    path.write_text("# format = fretwork-interface-histories\n# format_version = 1\n# speed_rpm = 750\n" + text)
    return path


HEADER = ("time [ms],frame_acceleration:x [m/s^2],frame_acceleration:y [m/s^2],frame_acceleration:z [m/s^2],"
          "angular_velocity:x [rpm],angular_velocity:y [rpm],angular_velocity:z [rpm],"
          "angular_acceleration:x [deg/s^2],angular_acceleration:y [deg/s^2],angular_acceleration:z [deg/s^2],"
          "wing_torsion [um]\n")


def _rows(times):
    return "".join(f"{t:g},1,2,3,0,0,750,0,0,180,5\n" for t in times)


def test_units_of_another_code_are_converted(tmp_path):
    read = read_interface_histories(_csv(tmp_path, HEADER + _rows(np.arange(10) * 0.1)))
    np.testing.assert_allclose(read.time[1], 1e-4)
    np.testing.assert_allclose(read.frame_acceleration[0], [1e3, 2e3, 3e3])
    np.testing.assert_allclose(read.angular_velocity[0, 2], 750 * 2 * np.pi / 60)
    np.testing.assert_allclose(read.angular_acceleration[0, 2], np.pi)
    np.testing.assert_allclose(read.wing_torsion[0], 5e-3)


@pytest.mark.parametrize("header, times, message", [
    (HEADER.replace(",wing_torsion [um]", "").replace("angular_velocity:z [rpm],", ""), None,
     "missing column|components x, y, z"),
    (HEADER.replace("[m/s^2]", "[furlongs]"), None, "unknown unit 'furlongs' of 'frame_acceleration'"),
    (HEADER, np.r_[np.arange(5), np.arange(6, 11)] * 0.1, "non-uniform time step.*between samples 5 and 6"),
])
def test_bad_files_are_one_clear_error(tmp_path, header, times, message):
    times = np.arange(10) * 0.1 if times is None else times
    columns = header.count(",") + 1
    rows = "".join(",".join([f"{t:g}"] + ["1"] * (columns - 1)) + "\n" for t in times)
    with pytest.raises(InputError, match=message):
        read_interface_histories(_csv(tmp_path, header + rows))


def test_a_file_without_wing_torsion_or_modes_is_refused(tmp_path):
    from mbs.histories_file import to_loading

    header = HEADER.replace(",wing_torsion [um]", "")
    rows = "".join(f"{t:g},1,2,3,0,0,750,0,0,180\n" for t in np.arange(10) * 0.1)
    with pytest.raises(InputError, match="needs a 'wing_torsion' column or modal coordinates"):
        to_loading(read_interface_histories(_csv(tmp_path, header + rows)))


def _hexahedral_cw(serendipity: bool):
    """A 120 x 40 x 30 mm block of 3 x 2 x 1 hexahedra: its nodes and meshio/Abaqus cells (with
    mid-edge nodes for Hex20), and the corner mesh (scikit-fem)."""
    from skfem.io.meshio import HEX_MAPPING

    from reduction.mesh.io import HEX20_EDGES

    mesh = skfem.MeshHex.init_tensor(np.linspace(-60, 60, 4), np.linspace(0, 40, 3), np.linspace(-15, 15, 2))
    points, cells = mesh.p.T, mesh.t.T[:, HEX_MAPPING[:8]]
    if serendipity:
        pairs = np.sort(cells[:, HEX20_EDGES].reshape(-1, 2), axis=1)
        unique, inverse = np.unique(pairs, axis=0, return_inverse=True)
        points = np.vstack([points, 0.5 * (points[unique[:, 0]] + points[unique[:, 1]])])
        cells = np.hstack([cells, len(mesh.p.T) + inverse.reshape(-1, 12)])
    return points, cells, mesh


def _spanned_field(points: np.ndarray, serendipity: bool) -> np.ndarray:
    """(n, 3, 2) two mode shapes (mm per unit coordinate) the element reproduces exactly: complete
    quadratics for Hex20, trilinear fields (with xyz) for Hex8."""
    x, y, z = (points / 60.0).T
    first = (np.column_stack([x * x + y * z, x * y - z * z, y * y + x * z]) if serendipity
             else np.column_stack([x * y * z + x, y * z, x * z - y]))
    return np.stack([first, 2.0 * first[:, ::-1]], axis=2)


@pytest.mark.parametrize("serendipity", [False, True], ids=["hexahedron", "hexahedron20"])
@pytest.mark.parametrize("cells_in_file", [True, False], ids=["file cells", "CW mesh cells"])
def test_mode_shapes_on_hexahedra_reach_the_p2_field_as_the_hexahedra_carry_them(tmp_path, serendipity,
                                                                                 cells_in_file):
    """Hexahedral mode meshes are split into tetrahedra for the contact model's P2 field; the P2
    nodes the file has no values at (the split's diagonals, Hex8 edge midpoints) take the
    hexahedron's own interpolation, so a field the hexahedron spans arrives unchanged (the edge
    mean, used for tetrahedra, would miss x² by a quarter of the squared diagonal)."""
    from mbs.histories_file import ModeShapes, to_loading

    points, cells, corner_mesh = _hexahedral_cw(serendipity)
    shapes = _spanned_field(points, serendipity)
    n = 40
    modal = np.column_stack([np.linspace(0.0, 1.0, n), np.linspace(1.0, 0.0, n)])
    histories = replace(_histories(n), modal_coordinates=modal, modal_velocities=0 * modal,
                        modal_accelerations=0 * modal,
                        modes=ModeShapes(points, shapes, np.array([150.0, 300.0]), 0,
                                         cells if cells_in_file else None))
    read = read_interface_histories(write_interface_histories(tmp_path / "cw.h5", histories))
    loading = to_loading(read, None if cells_in_file else corner_mesh)
    tetrahedra = skfem.MeshTet1(loading.mesh_points, loading.mesh_cells)
    nodes = skfem.Basis(tetrahedra, skfem.ElementVector(skfem.ElementTetP2()), intorder=1).doflocs[:, 0::3].T
    assert len(nodes) > len(points)  # P2 nodes that the file does not hold
    expected = _spanned_field(nodes, serendipity).reshape(-1, 2)
    np.testing.assert_allclose(loading.mode_shapes, expected, rtol=0, atol=1e-12 * np.abs(expected).max())


def test_hexahedron_shape_functions_are_a_partition_of_unity_with_nodal_values():
    from mbs.histories_file import _HEX_REFERENCE, hexahedron_shape_functions

    for n_nodes in (8, 20):
        at_nodes = hexahedron_shape_functions(_HEX_REFERENCE[:n_nodes], n_nodes)
        np.testing.assert_allclose(at_nodes, np.eye(n_nodes), atol=1e-15)
        inside = np.random.default_rng(3).uniform(-1, 1, (20, 3))
        np.testing.assert_allclose(hexahedron_shape_functions(inside, n_nodes).sum(axis=1), 1.0, atol=1e-14)


def test_unknown_mode_shape_cells_are_refused(tmp_path):
    from mbs.histories_file import ModeShapes

    points, cells, _ = _hexahedral_cw(False)
    histories = replace(_histories(), modal_coordinates=np.zeros((40, 2)), modal_velocities=np.zeros((40, 2)),
                        modal_accelerations=np.zeros((40, 2)),
                        modes=ModeShapes(points, _spanned_field(points, False), np.array([1.0, 2.0]), 0, cells))
    path = write_interface_histories(tmp_path / "cw.h5", histories)
    import h5py

    with h5py.File(path, "a") as root:
        root["modes/cells"].attrs["cell_type"] = "wedge"
    with pytest.raises(InputError, match="mode-shape cells must be tetra .* hexahedron20 \\(n, 20\\), got 'wedge'"):
        read_interface_histories(path)
