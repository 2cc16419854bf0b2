"""Scenes that cannot run are refused before anything is built or written, each refusal naming
its key (and file) and the way out; through the command line, exit status 2."""

from pathlib import Path

import pytest

from pipelines import scene as scenes
from pipelines.cli.main import main
from reduction.errors import InputError
from reduction.mesh.generators import MAX_GENERATED_NODES

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _extending(tmp_path, base: str, text: str) -> Path:
    path = tmp_path / "scene.toml"
    path.write_text(f'[scene]\nbase = "{EXAMPLES / base}"\n\n{text}')
    return path


def _refused_by_the_cli(scene: Path, tmp_path, capsys) -> str:
    out = tmp_path / "out"
    assert main(["run", str(scene), "--out", str(out), "--quiet"]) == 2
    captured = capsys.readouterr()
    assert not out.exists() and "Traceback" not in captured.err
    return captured.err


def test_a_procedure_without_load_cycles_is_refused(coarse_cylinder, tmp_path, capsys):
    scene = tmp_path / "no_cycles.toml"
    scene.write_text(coarse_cylinder.read_text().replace("wear_cycles = 2 ", "wear_cycles = 0 "))
    error = _refused_by_the_cli(scene, tmp_path, capsys)
    assert str(scene) in error and "'procedure.cof_cycles' and 'procedure.wear_cycles' are both 0" in error
    assert "to at least 1" in error


def test_a_contact_size_in_metres_is_refused_before_meshing(tmp_path, capsys):
    scene = _extending(tmp_path, "counterweight.toml", "[bodies.web.mesh]\ncontact_size = 0.01\n")
    error = _refused_by_the_cli(scene, tmp_path, capsys)
    assert "'bodies.web.mesh.contact_size' = 0.01 would generate a mesh of at least" in error
    assert f"more than the {MAX_GENERATED_NODES:,}" in error and "meant in metres, write 10" in error
    nodes = int(error.split("at least ")[1].split(" nodes")[0].replace(",", ""))
    assert nodes > 100 * MAX_GENERATED_NODES


def test_a_fine_mesh_in_mm_is_not_refused():
    """1 mm on the counterweight joint (some 10⁵ nodes a body) is far below the bound."""
    scenes.load(EXAMPLES / "counterweight.toml", {"bodies.counterweight.mesh.contact_size": 1.0,
                                                  "bodies.web.mesh.contact_size": 1.0})


def test_an_engine_speed_of_zero_names_its_key_and_file(tmp_path, capsys):
    scene = _extending(tmp_path, "user_joint.toml", "[mbs]\nspeed_rpm = 0.0\n")
    error = _refused_by_the_cli(scene, tmp_path, capsys)
    assert f"{scene}: [mbs] speed_rpm = 0.0: must be positive (engine speed, rpm)" in error


def test_bodies_without_support_are_named(coarse_cylinder, tmp_path, capsys):
    scene = tmp_path / "floating.toml"
    scene.write_text("\n".join(line for line in coarse_cylinder.read_text().splitlines()
                               if not line.startswith("fixed")))
    error = _refused_by_the_cli(scene, tmp_path, capsys)
    assert "bodies 'cylinder' and 'plane' (joined by the contact or bolts) have no support" in error
    assert "add a fixed selection, e.g. bodies.plane.fixed" in error
    with pytest.raises(InputError, match="bodies 'counterweight' and 'web' .* have no support: no "
                                         "'bodies.NAME.fixed' selection"):
        scenes.load(EXAMPLES / "user_joint.toml", {"bodies.web.fixed": []})


def _with_plane_mesh_file(coarse_cylinder, tmp_path, file: str) -> Path:
    text = coarse_cylinder.read_text()
    line = next(line for line in text.splitlines() if "plane_block" in line)
    scene = tmp_path / f"plane_from_{file.strip('.') or 'folder'}.toml"
    scene.write_text(text.replace(line, f'mesh = {{ file = "{file}" }}'))
    return scene


def test_a_mesh_file_meshio_cannot_read_names_the_key_and_exits_2(coarse_cylinder, tmp_path, capsys):
    (tmp_path / "bad.msh").write_text("garbage\n")
    scene = _with_plane_mesh_file(coarse_cylinder, tmp_path, "bad.msh")
    assert main(["run", str(scene), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and "Couldn't read" not in captured.err
    assert f"'bodies.plane.mesh.file': {tmp_path / 'bad.msh'} is not a Gmsh file" in captured.err
    folder = _with_plane_mesh_file(coarse_cylinder, tmp_path, ".")
    assert main(["run", str(folder), "--out", str(tmp_path / "out2"), "--quiet"]) == 2
    error = capsys.readouterr().err
    assert f"'bodies.plane.mesh.file': {tmp_path}" in error and "is a folder, not a mesh file" in error
