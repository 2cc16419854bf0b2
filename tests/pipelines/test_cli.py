"""The command line as a user meets it: JSON figures, exit status 2 on bad input, no partial files."""

import json

import h5py
import meshio
import numpy as np
import pytest

from pipelines.cli.main import main
from pipelines.output import paraview

FIGURES = {"verdict", "stick_area_fraction", "slip_area_fraction", "damaged_area_fraction",
           "worn_area_fraction", "max_wear_depth_mm", "wear_volume_mm3", "dissipated_energy_mJ",
           "min_stick_margin", "cycles_run", "wall_time_s"}


def test_run_prints_json_figures_and_writes_results(coarse_cylinder, tmp_path, capsys, monkeypatch):
    out = tmp_path / "out"
    assert main(["run", str(coarse_cylinder), "--out", str(out), "--json", "--quiet"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert FIGURES <= set(summary)
    assert summary["verdict"] == "damage"  # gross slip at constant μ = μ_max: fretting scar
    assert summary["cycles_run"] == 2 and summary["max_wear_depth_mm"] > 0
    with h5py.File(out / "results.h5") as file:
        assert file.attrs["complete"] and file.attrs["format_version"] == 1
        wear = file["final/wear_depth"][()]
        area = file["points/area"][()]
        assert np.sum(wear.sum(axis=0) * area) == pytest.approx(summary["wear_volume_mm3"], rel=1e-9)
        assert file["final/pressure"].attrs["units"] == "MPa"
        figures = file["cycles/figures"]
        assert figures["clamp_force_N"].attrs["units"] == "N" and figures["fdp_max_MPa_mm"].attrs["units"] == "MPa*mm"
        assert figures["stick_area_fraction"].attrs["units"].startswith("1 ")
        assert figures["wear_volume_mm3"].attrs["units"] == "mm^3"
        assert all(figures[name].attrs["units"] for name in figures)
    assert (out / "plots" / "fields.png").stat().st_size > 10_000
    monkeypatch.chdir(out)  # meshio's reader resolves the XDMF's heavy-data file from the cwd
    with meshio.xdmf.TimeSeriesReader("interface.xdmf") as reader:
        points, cells = reader.read_points_cells()
        assert len(points) == len(area) and cells[0].type == "line"
        assert reader.num_steps == 2
        _, point_data, _ = reader.read_data(reader.num_steps - 1)
        total = wear.sum(axis=0)
        np.testing.assert_allclose(point_data["wear_depth_total"], total, rtol=1e-12, atol=1e-12 * total.max())
    # a results file too large to read whole is read row by row, to the same series
    monkeypatch.setattr(paraview, "_READ_WHOLE", 0)
    paraview.write_interface_series(out / "results.h5", out / "by_row.xdmf")
    with meshio.xdmf.TimeSeriesReader("by_row.xdmf") as reader:
        reader.read_points_cells()
        _, by_row, _ = reader.read_data(reader.num_steps - 1)
    assert by_row.keys() == point_data.keys()
    for name, value in point_data.items():
        np.testing.assert_array_equal(by_row[name], value)


def test_bad_scene_exits_2_with_message_and_writes_nothing(coarse_cylinder, tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(coarse_cylinder.read_text().replace("critical_slip", "critcal_slip"))
    out = tmp_path / "never"
    assert main(["run", str(bad), "--out", str(out)]) == 2
    error = capsys.readouterr().err
    assert "critcal_slip" in error and "Traceback" not in error
    assert not out.exists()


def test_missing_scene_file_exits_2(tmp_path, capsys):
    assert main(["run", str(tmp_path / "nope.toml"), "--out", str(tmp_path / "o")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_reduce_reports_frequency_errors_that_shrink_with_modes(tmp_path, capsys):
    import skfem

    mesh = skfem.MeshHex.init_tensor(np.linspace(0, 100, 21), np.linspace(0, 10, 3), np.linspace(0, 10, 3))
    points = mesh.p.T
    hexes = mesh.t.T[:, [0, 2, 4, 1, 3, 6, 7, 5]]  # scikit-fem order → Abaqus C3D8 order
    path = tmp_path / "bar.inp"
    meshio.Mesh(points, [("hexahedron", hexes)],
                point_sets={"clamp": np.flatnonzero(points[:, 0] == 0.0),
                            "tip": np.flatnonzero(points[:, 0] == 100.0)}).write(path)
    assert main(["reduce", str(path), "--modes", "12", "--clamp-sets", "clamp", "--interface-sets", "tip",
                 "--out", str(tmp_path / "red"), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    errors = {}
    for r in report["records"]:
        if r["quantity"] == "frequency" and r["case"] == "interfaces free":
            errors.setdefault(r["modes"], []).append(abs(r["relative_error"]))
    counts = sorted(errors)
    assert max(errors[counts[-1]]) < 5e-3
    assert max(errors[counts[-1]]) <= max(errors[counts[0]])
    assert (tmp_path / "red" / "reduction_error_vs_modes.png").exists()


def test_a_failing_run_says_why_and_exits_1(coarse_cylinder, tmp_path, capsys):
    # Pulling the cylinder off the plane under force control: no equilibrium exists.
    bad = tmp_path / "pull.toml"
    bad.write_text(coarse_cylinder.read_text().replace("value = -1066.0", "value = 1066.0"))
    assert main(["run", str(bad), "--out", str(tmp_path / "out"), "--quiet"]) == 1
    error = capsys.readouterr().err
    assert "the simulation stopped" in error and "Traceback" not in error
