"""The shipped user-style joint (examples/user_joint.toml, tetrahedral .inp meshes) and bad user
input: each a single message, exit status 2, nothing written."""

from __future__ import annotations

import re
from pathlib import Path

import meshio
import numpy as np
import pytest

from mbs.histories_file import (
    from_loading,
    read_interface_histories,
    to_loading,
    write_interface_histories,
)
from pipelines import scene as scenes
from pipelines.cli.main import main
from pipelines.coupling import multibody_loading

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
SCENE = EXAMPLES / "user_joint.toml"


def _extended(tmp_path, text: str) -> Path:
    """A scene in ``tmp_path`` extending the example: the example's mesh files are found from the
    example's folder, the extending scene's own files from ``tmp_path``."""
    path = tmp_path / "scene.toml"
    path.write_text(f'[scene]\nbase = "{SCENE}"\n{text}\n')
    return path


def test_the_user_cw_mesh_is_the_multibody_cw_and_its_csv_histories_read_back_exactly(tmp_path):
    scene = scenes.load(SCENE, {"mbs.n_modes": 2, "mbs.solver.revolutions": 1.0})
    loading = multibody_loading(scene)
    # the multibody CW is the file's mesh: its vertices are the corner nodes of the file's C3D10
    # tetrahedra (the mid-edge nodes are the quadratic elements' own)
    cw = meshio.read(EXAMPLES / "user_joint" / "cw.inp")
    corners = cw.points[np.unique(cw.cells_dict["tetra10"][:, :4])]
    assert loading.mesh_points.shape[1] == len(corners) < len(cw.points)
    assert np.allclose(np.sort(loading.mesh_points[0]), np.sort(corners[:, 0]))
    # CSV mode shapes carry no cells: the scene's CW mesh gives them, and the loading is the same
    path = write_interface_histories(tmp_path / "cw1.csv", from_loading(loading))
    from pipelines.build import make_mesh

    cw_mesh = make_mesh({"file": str(EXAMPLES / "user_joint" / "cw.inp")}, "cw", None)[0]
    read = to_loading(read_interface_histories(path), cw_mesh)
    for name in ("time", "frame_acceleration", "modal_coordinates", "wing_torsion", "mesh_points", "mesh_cells",
                 "mode_shapes", "mode_frequencies_hz"):
        np.testing.assert_array_equal(getattr(read, name), getattr(loading, name), err_msg=name)
    assert read.torsion_mode == loading.torsion_mode


def _gap_file(tmp_path):
    header = ("time [s],frame_acceleration:x [mm/s^2],frame_acceleration:y [mm/s^2],frame_acceleration:z [mm/s^2],"
              "angular_velocity:x [rad/s],angular_velocity:y [rad/s],angular_velocity:z [rad/s],"
              "angular_acceleration:x [rad/s^2],angular_acceleration:y [rad/s^2],angular_acceleration:z [rad/s^2],"
              "wing_torsion [mm]\n")
    times = np.r_[np.arange(10), np.arange(12, 20)] * 1e-4
    rows = "".join(f"{float(t)!r},0,0,0,0,0,78.5,0,0,0,{float(np.sin(2e3 * t))!r}\n" for t in times)
    (tmp_path / "gap.csv").write_text("# format = fretwork-interface-histories\n# format_version = 1\n"
                                      "# speed_rpm = 750\n" + header + rows)
    return 'effects = ["bolts", "cof_evolution", "wear", "centrifugal"]\n[coupling]\nhistories = "gap.csv"'


def _wedge_file(tmp_path):
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1]], float)
    meshio.write(tmp_path / "wedge.inp", meshio.Mesh(points, [("wedge", np.array([[0, 1, 2, 3, 4, 5]]))]))
    return '[bodies.web]\nmesh = { file = "wedge.inp" }'


@pytest.mark.parametrize("case, message", [
    (lambda tmp: '[contact]\nslave = { body = "counterweight", set = "PADS" }', "no node set 'PADS'"),
    (lambda tmp: '[contact]\nmaster = { body = "web", set = "BASE" }', "touch|pair|no contact"),
    (_wedge_file, "unsupported cell type"),
    (_gap_file, "non-uniform time step"),
])
def test_bad_user_input_is_one_message_exit_2_and_no_output(tmp_path, capsys, case, message):
    scene = _extended(tmp_path, case(tmp_path))
    out = tmp_path / "out"
    assert main(["run", str(scene), "--out", str(out), "--quiet"]) == 2
    error = capsys.readouterr().err.strip()
    assert len(error.splitlines()) == 1, error
    assert re.search(message, error), error
    assert not out.exists()
