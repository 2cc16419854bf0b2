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


def test_a_column_given_twice_is_refused_naming_it_and_its_line(tmp_path):
    header = HEADER.replace("wing_torsion [um]\n", "wing_torsion [um],wing_torsion [um]\n")
    rows = "".join(f"{t:g},1,2,3,0,0,750,0,0,180,5,5\n" for t in np.arange(10) * 0.1)
    with pytest.raises(InputError, match=r"line 4: column 'wing_torsion \[um\]' appears twice \(columns 11 and 12\)"):
        read_interface_histories(_csv(tmp_path, header + rows))


def test_a_byte_order_mark_is_read_past(tmp_path):
    """Excel's "CSV UTF-8" starts the file with a byte-order mark, before '# format'."""
    path = write_interface_histories(tmp_path / "cw.csv", _histories())
    path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    np.testing.assert_array_equal(read_interface_histories(path).wing_torsion, _histories().wing_torsion)


def test_a_time_in_ms_labelled_seconds_is_refused_naming_ms(tmp_path):
    """0.1 ms steps read as 0.1 s: more than 1/8 of a revolution at 750 rpm (0.08 s)."""
    with pytest.raises(InputError, match=r"time step 0.1 s is 1.25 revolutions at speed_rpm = 750 .*"
                                         r"if the time is in ms, label the column 'time \[ms\]'"):
        read_interface_histories(_csv(tmp_path, HEADER.replace("time [ms]", "time [s]") + _rows(np.arange(10) * 0.1)))


def test_a_speed_other_than_the_spin_is_refused_naming_both(tmp_path):
    path = _csv(tmp_path, HEADER + _rows(np.arange(10) * 0.1))
    path.write_text(path.read_text().replace("speed_rpm = 750", "speed_rpm = 1500"))
    with pytest.raises(InputError, match=r"speed_rpm = 1500, but the mean angular velocity .* is 78.5398 rad/s = "
                                         r"750 rpm; they must agree within 5%"):
        read_interface_histories(path)


def _rewrite_hdf5(path, name, values):
    import h5py

    with h5py.File(path, "r+") as root:
        unit = root[name].attrs["unit"]
        del root[name]
        root.create_dataset(name, data=values).attrs["unit"] = unit


@pytest.mark.parametrize("shape", ["column", "row"])
def test_an_hdf5_time_of_one_column_or_row_is_the_time(tmp_path, shape):
    written = _histories()
    path = write_interface_histories(tmp_path / "cw.h5", written)
    _rewrite_hdf5(path, "time", written.time[:, None] if shape == "column" else written.time[None, :])
    np.testing.assert_array_equal(read_interface_histories(path).time, written.time)


def test_an_hdf5_time_of_two_columns_is_refused_naming_its_shape(tmp_path):
    written = _histories()
    path = write_interface_histories(tmp_path / "cw.h5", written)
    _rewrite_hdf5(path, "time", np.column_stack([written.time, written.time]))
    with pytest.raises(InputError, match=r"'time' must hold one value per sample, shape \(samples,\), "
                                         r"got shape \(40, 2\)"):
        read_interface_histories(path)


def test_an_hdf5_float32_time_is_a_fixed_step_to_within_float32(tmp_path):
    """float32 time rounds each 50 us step by up to 6e-8 s near 1 s: 1e-3 of the step, far more
    than the 1e-6 the steps of a float64 file may differ by. Read back: the fixed step it stands for."""
    written = replace(_histories(n=400, step=5e-5), time=0.48 + 5e-5 * np.arange(400))
    path = write_interface_histories(tmp_path / "cw.h5", written)
    _rewrite_hdf5(path, "time", written.time.astype(np.float32))
    read = read_interface_histories(path).time
    spacing = float(np.spacing(np.float32(0.5)))  # of float32 numbers in [0.5, 1)
    steps = np.diff(read)
    assert read.dtype == np.float64 and np.ptp(steps) <= 1e-9 * 5e-5
    np.testing.assert_allclose(steps, 5e-5, rtol=0, atol=2 * spacing / 399)
    np.testing.assert_allclose(read, written.time, rtol=0, atol=spacing)


def test_an_hdf5_float32_time_too_coarse_for_its_step_is_refused_naming_float32(tmp_path):
    written = replace(_histories(n=400, step=5e-5), time=2000.0 + 5e-5 * np.arange(400))
    path = write_interface_histories(tmp_path / "cw.h5", written)
    _rewrite_hdf5(path, "time", written.time.astype(np.float32))
    with pytest.raises(InputError, match=r"'time' is stored in single precision \(float32\).*store it as float64"):
        read_interface_histories(path)


def _constant_loading(tmp_path, wing_torsion):
    """A static check's file: the centrifugal frame acceleration of 230 mm at 750 rpm, constant,
    over a little more than one revolution (the revolution cycle takes the last one)."""
    from mbs.histories_file import to_loading

    n = 1700
    time = 0.48 + 5e-5 * np.arange(n)
    spin = 750.0 * np.pi / 30.0
    frame = np.tile([0.0, -230.0 * spin ** 2, 0.0], (n, 1))
    histories = InterfaceHistories(750.0, time, frame, np.tile([0.0, 0.0, spin], (n, 1)), np.zeros((n, 3)),
                                   wing_torsion(time), np.zeros((n, 0)), np.zeros((n, 0)), np.zeros((n, 0)), None)
    return to_loading(read_interface_histories(write_interface_histories(tmp_path / "const.csv", histories)))


@pytest.mark.parametrize("cycle", ["wing_period", "revolution"])
@pytest.mark.parametrize("torsion", [0.0, 3e-3], ids=["zero", "constant"])
def test_histories_without_vibration_give_the_static_cycle(tmp_path, cycle, torsion):
    from mbs.loading import cycle_loading

    loading = _constant_loading(tmp_path, lambda time: np.full(len(time), torsion))
    static = cycle_loading(loading, cycle, None, 8)
    assert static.scale == 0.0 and static.wing_amplitude == 0.0 and static.frequency_hz == 750.0 / 60.0
    np.testing.assert_allclose(static.tables["frame_ay"], np.full(8, loading.frame_acceleration[0, 1]), rtol=1e-15)
    np.testing.assert_allclose(static.tables["spin_squared"], np.full(8, loading.angular_velocity[0, 2] ** 2),
                               rtol=1e-15)
    np.testing.assert_allclose(static.wing_torsion, np.full(8, torsion), rtol=1e-15)


def test_a_stated_amplitude_for_histories_without_vibration_is_refused_naming_the_static_check(tmp_path):
    from mbs.loading import cycle_loading

    loading = _constant_loading(tmp_path, np.zeros_like)
    with pytest.raises(InputError, match=r"cannot be scaled to the stated 'coupling.wing_amplitude' = 0.1 mm; "
                                         r"leave 'coupling.wing_amplitude' out for a static check"):
        cycle_loading(loading, "wing_period", 0.1, 8)
    in_process = replace(loading, revolutions=12.0)  # what the exudyn run gives: its excitation is off
    for amplitude in (None, 0.1):
        with pytest.raises(InputError, match=r"switch on an excitation in \[mbs\] effects"):
            cycle_loading(in_process, "wing_period", amplitude, 8)


def test_a_revolution_cycle_on_a_file_shorter_than_a_revolution_names_the_file_not_the_solver(tmp_path):
    from mbs.loading import cycle_loading

    loading = _constant_loading(tmp_path, lambda time: 1e-3 * np.sin(2 * np.pi * 375.0 * time))  # 0.085 s, > 0.08 s
    cycle_loading(loading, "revolution", None, 8)
    short = replace(loading, time=loading.time[:800], wing_torsion=loading.wing_torsion[:800])  # 0.04 s
    with pytest.raises(InputError, match=r"needs one whole revolution of history \(0.08 s at 750 rpm\); the "
                                         r"interface-histories file spans 0.03995 s"):
        cycle_loading(short, "revolution", None, 8)
    with pytest.raises(InputError, match=r"raise \[mbs.solver\] revolutions"):  # a multibody run's advice
        cycle_loading(replace(short, revolutions=1.0), "revolution", None, 8)


def test_a_frame_acceleration_in_the_wrong_unit_is_refused_by_the_radius_it_implies(tmp_path):
    """ω²·r at 750 rpm and r = 230 mm is 1.42e6 mm/s²: written as 1.42e6 but labelled m/s² it is read
    as 1.42e9 mm/s², a frame 230 m from the axis (it ended in a Newton failure; QA, 2026-11-28)."""
    centripetal = (750 * 2 * np.pi / 60) ** 2 * 230.0  # mm/s²
    rows = "".join(f"{t:g},0,{-centripetal:.6g},0,0,0,750,0,0,0,5\n" for t in np.arange(10) * 0.1)
    with pytest.raises(InputError, match=r"puts the CW frame 230 m from the spin axis: check the unit of "
                                         r"frame_acceleration"):
        read_interface_histories(_csv(tmp_path, HEADER + rows))
    right = HEADER.replace("[m/s^2]", "[mm/s^2]")
    read = read_interface_histories(_csv(tmp_path, right + rows))  # in its own unit: 230 mm, accepted
    assert read.frame_acceleration[0, 1] == pytest.approx(-centripetal, rel=1e-5)  # 6 digits written
