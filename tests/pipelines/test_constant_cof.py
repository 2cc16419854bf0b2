"""The constant-COF comparison (``fretwork study constant-cof``): its probes (at least one, of
the scene's dimension, on the contact surface; each read at its nearest contact point, which the
records name with its distance) and what it writes in --out (constant_cof.h5, constant_cof.png)."""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
import pytest
from matplotlib.image import imread

from pipelines.cli.main import main
from pipelines.output.locks import LOCK_NAME, MANIFEST_NAME
from pipelines.studies import constant_cof
from reduction.errors import InputError

SCENE = Path(__file__).parent / "scenes" / "bolted_blocks.toml"  # 3D, cof_evolution, 20 x 20 mm contact
EXAMPLES = Path(__file__).parents[2] / "examples"


def _refuse(*args, **kwargs):
    raise AssertionError("the study went on to build or run a model")


def test_no_probe_is_refused_before_any_model_is_built(monkeypatch, capsys, tmp_path):
    monkeypatch.setattr(constant_cof, "build", _refuse)
    assert main(["study", "constant-cof", str(SCENE), "--out", str(tmp_path / "out")]) == 2
    assert "at least one probe point (--probe x,y[,z] in mm)" in capsys.readouterr().err
    with pytest.raises(InputError, match="at least one probe"):
        constant_cof.constant_cof_comparison(SCENE, {})


def test_a_probe_of_the_wrong_dimension_is_refused_before_any_model_is_built(monkeypatch, capsys, tmp_path):
    monkeypatch.setattr(constant_cof, "build", _refuse)
    assert main(["study", "constant-cof", str(SCENE), "--probe", "1,2,0", "--probe", "0,0",
                 "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert "probe P2 (0,0) has 2 coordinates, the scene is 3D: give x,y,z in mm" in error and "P1" not in error


def test_a_probe_far_from_the_contact_surface_is_refused_naming_the_nearest_point():
    grid = np.array([[x, y] for x in range(5) for y in range(5)], dtype=float)  # 1 mm apart
    with pytest.raises(InputError) as refused:
        constant_cof.probe_points({"P1": (5000.0, 0.0), "P2": (1.2, 1.1), "P3": (6.1, 2.0)}, grid)
    message = str(refused.value)
    assert "probe P1 (5000,0) is 4996 mm from the nearest contact point (4,0)" in message
    assert "probe P3 (6.1,2) is 2.1 mm from the nearest contact point (4,2), farther than 2 times the " \
           "contact points' spacing there (2 mm)" in message
    assert "P2" not in message
    inside, edge = constant_cof.probe_points({"P2": (1.2, 1.1), "P4": (5.5, 2.0)}, grid)
    assert inside.position_mm == (1.0, 1.0) and inside.distance_mm == pytest.approx(np.hypot(0.2, 0.1))
    assert edge.position_mm == (4.0, 2.0) and edge.distance_mm == pytest.approx(1.5)  # just off the edge: read there


def test_a_far_probe_is_refused_before_either_run(monkeypatch, capsys, tmp_path):
    monkeypatch.setattr(constant_cof, "_last_cycle", _refuse)
    assert main(["study", "constant-cof", str(SCENE), "--probe", "5000,0,0", "--out", str(tmp_path / "out")]) == 2
    assert "probe P1 (5000,0,0) is 4990 mm from the nearest contact point (10,0,0)" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()  # a refused input leaves nothing behind


def test_records_give_the_probe_the_point_used_and_their_distance():
    records = constant_cof.constant_cof_comparison(SCENE, {"P1": (-4.0, 1.0, 0.0)}).records()
    assert [r["model"] for r in records] == ["variable COF", "constant COF 0.6"]
    for record in records:
        assert record["probe_mm"] == [-4.0, 1.0, 0.0]
        used = np.array(record["position_mm"])
        assert record["distance_mm"] == pytest.approx(np.linalg.norm(used - [-4.0, 1.0, 0.0]))
        assert record["distance_mm"] < 20.0 / 6  # within an element of the upper block's contact face
        assert record["max_shear_MPa"] > 0.0


def _png(path: Path) -> np.ndarray:
    """The pixels of a PNG file, checked to be one of a drawn figure."""
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert path.stat().st_size > 30_000  # axes, maps and labels, not an empty canvas
    pixels = imread(path)
    assert pixels.shape[0] > 400 and pixels.shape[1] > 800
    return pixels


def _study(capsys, scene, out: Path, *options: str) -> dict:
    assert main(["study", "constant-cof", str(scene), "--out", str(out), "--json", *options]) == 0
    return json.loads(capsys.readouterr().out)


def test_out_holds_the_plot_and_the_fields_of_both_models(tmp_path, capsys):
    out = tmp_path / "out"
    printed = _study(capsys, SCENE, out, "--probe=-4,1,0", "--probe", "6,-6,0")
    assert printed["plot"] == str(out / "constant_cof.png") and printed["file"] == str(out / "constant_cof.h5")
    assert printed["scene"] == "bolted_blocks" and not (out / LOCK_NAME).exists()
    # recorded as fretwork's, so that a rerun clears them and a user's file of the name is refused
    assert {"constant_cof.png", "constant_cof.h5"} <= set((out / MANIFEST_NAME).read_text().split())
    _png(out / "constant_cof.png")
    with h5py.File(out / "constant_cof.h5", "r") as file:
        assert file.attrs["fretwork_format"] == "fretwork-constant-cof" and file.attrs["format_version"] == 1
        assert list(file.attrs["models"]) == ["variable", "constant"] and file.attrs["dimension"] == 3
        cof_initial, cof_max = file.attrs["cof_initial"], file.attrs["cof_max"]
        assert (cof_initial, cof_max) == (0.2, 0.6)
        datasets = []
        file.visititems(lambda name, item: datasets.append(name) if isinstance(item, h5py.Dataset) else None)
        units = {name: file[name].attrs.get("units") for name in datasets}
        assert None not in units.values(), units  # every dataset says its units
        assert units["points/coordinates"] == "mm" and units["probes/max_shear"] == "MPa"
        coordinates = file["points/coordinates"][()]
        n = len(coordinates)
        assert coordinates.shape == (n, 3) and np.all(coordinates[:, 2] == 0.0)  # the blocks touch at z = 0
        fields = {}
        for key in ("variable", "constant"):
            group = file["models"][key]
            assert group.attrs["cycle"] == 3 and units[f"models/{key}/max_shear"] == "MPa"
            fields[key] = {name: group[name][()] for name in constant_cof.MODEL_FIELDS}
            assert all(value.shape == (n,) for value in fields[key].values())
        assert file["models/variable"].attrs["cof_evolution"] and not file["models/constant"].attrs["cof_evolution"]
        probes = {name: file["probes"][name][()] for name in ("name", "given", "position", "index", "distance",
                                                               "max_shear")}
    # the probe rows: the contact point each is read at, both models' max shear there, as printed
    assert [name.decode() for name in probes["name"]] == ["P1", "P2"]
    assert np.array_equal(probes["position"], coordinates[probes["index"]])
    assert np.allclose(probes["distance"], np.linalg.norm(probes["position"] - probes["given"], axis=1))
    assert np.array_equal(probes["max_shear"], np.column_stack([fields["variable"]["max_shear"][probes["index"]],
                                                                fields["constant"]["max_shear"][probes["index"]]]))
    printed_shear = {(r["model"], r["probe"]): r["max_shear_MPa"] for r in printed["records"]}
    for row, name in enumerate(("P1", "P2")):
        assert printed_shear[("variable COF", name)] == probes["max_shear"][row, 0]
        assert printed_shear[("constant COF 0.6", name)] == probes["max_shear"][row, 1]
    # Coulomb's law in each model: the constant one at μ_max everywhere, never beyond it; the
    # evolving COF between μ0 and μ_max, and a point's shear never beyond its COF of the cycle's
    # end (the COF only rises)
    variable, constant = fields["variable"], fields["constant"]
    assert np.all(constant["cof"] == cof_max) and np.max(constant["max_utilised_cof"]) <= cof_max * (1 + 1e-9)
    assert np.all((variable["cof"] >= cof_initial) & (variable["cof"] <= cof_max))
    assert np.all(variable["max_utilised_cof"] <= variable["cof"] * (1 + 1e-9))
    # partial slip: the contact carries shear in both models, and they differ
    assert np.max(variable["max_shear"]) > 1.0 and np.max(constant["max_shear"]) > 1.0
    assert np.max(np.abs(variable["max_shear"] - constant["max_shear"])) > 0.1


def test_a_plane_strain_interface_is_drawn_along_the_contact(tmp_path, capsys):
    out = tmp_path / "plane"
    coarse = ['scene.effects=["cof_evolution"]', "contact.cof_initial=0.3", "contact.cof_rate=0.5",
              "procedure.preload_increments=3", "procedure.increments_per_cycle=12", "procedure.cof_cycles=3",
              "motions.0.value=0.01", "bodies.cylinder.mesh.contact_size=0.2", "bodies.plane.mesh.contact_size=0.2"]
    printed = _study(capsys, EXAMPLES / "cylinder_on_plane.toml", out, "--probe=-0.5,0", "--probe", "0.8,0",
                     *(f"--set={item}" for item in coarse))
    assert [r["model"] for r in printed["records"]] == ["variable COF"] * 2 + ["constant COF 0.56"] * 2
    _png(out / "constant_cof.png")
    with h5py.File(out / "constant_cof.h5", "r") as file:
        assert file.attrs["dimension"] == 2 and file["points/coordinates"].shape[1] == 2
        assert file["points/area"].attrs["units"] == "mm^2 (mm per unit thickness in 2D)"
        assert file["models/constant"].attrs["name"] == "constant COF 0.56"
