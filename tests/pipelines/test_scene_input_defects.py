"""Scene inputs that passed validation and failed later with misleading errors, or flipped a
verdict without a word (QA of the scene input): each is now refused at load time with a sentence
naming its key and value, or warned of as a likely unit slip or a key that does nothing."""

from pathlib import Path

import pytest

from pipelines import scene as scenes
from pipelines.build import make_mesh
from pipelines.cli.accuracy import set_overrides
from pipelines.cli.main import main
from pipelines.scene.checks import plausibility
from reduction.errors import InputError

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
CYLINDER = EXAMPLES / "cylinder_on_plane.toml"
TEXT = CYLINDER.read_text()


def edited(*replacements) -> str:
    text = TEXT
    for old, new in replacements:
        assert old in text, old
        text = text.replace(old, new, 1)
    return text


def refusal(text: str) -> str:
    with pytest.raises(InputError) as caught:
        scenes.parse(text)
    return str(caught.value)


def warnings_of(text: str) -> list[str]:
    return plausibility(scenes.parse(text).data)


@pytest.mark.parametrize("old, new, said", [
    ("normal_stiffness = 4.0e6", "normal_stiffness = inf",
     "'contact.normal_stiffness' must be a finite number > 0 (kn, N/mm³), got inf"),
    ("youngs_modulus = 120000.0", "youngs_modulus = inf",
     "'materials.ti64.youngs_modulus' must be a finite number > 0 (Young's modulus E, MPa), got inf"),
    ("radius = 80.0", "radius = inf", "'bodies.cylinder.mesh.radius' must be a finite number > 0 (mm or count), got inf"),
    ("cycle_jump = 1000.0", "cycle_jump = inf", "'procedure.cycle_jump' must be a finite number >= 1"),
    ("value = -1066.0", "value = -inf", "'loads[0].value' must be a finite number (full amplitude, N or mm), got -inf"),
    ("value = 0.107", "value = nan", "'motions[0].value' must be a finite number (full amplitude, N or mm), got nan"),
    ("wear_coefficients = [0.47e-8, 1.5e-8]", "wear_coefficients = [inf, 1.5e-8]",
     "'contact.wear_coefficients' must be two finite numbers >= 0 [slave, master], mm²/N, got [inf, 1.5e-08]"),
    ("position = [0.0, 20.0]", "position = [0.0, inf]",
     "'bodies.cylinder.reference_points.rp.position' must be 2 coordinates in mm (finite numbers), got [0.0, inf]"),
    ("box = [[-2.6, -0.01], [2.6, 0.3]]", "box = [[-2.6, -0.01], [2.6, nan]]",
     "'contact.slave.box' must be [[min x, y], [max ...]]: finite numbers in mm, got [[-2.6, -0.01], [2.6, nan]]"),
])
def test_an_infinite_or_nan_value_is_refused_naming_its_key(old, new, said):
    message = refusal(edited((old, new)))
    assert said in message, message
    assert message.count("\n") == 0, message  # the one problem, not a consequence of it too


def test_inf_stays_allowed_where_it_means_no_limit():
    scene = scenes.parse(edited(("wear_cap = 2.0e-4", "wear_cap = 2.0e-4\nmax_cycle_jump = inf\nlife_cycles = inf")))
    assert scene.data["procedure"]["life_cycles"] == float("inf")
    assert "'procedure.life_cycles' must be a finite number > 0" in refusal(edited(("wear_cap = 2.0e-4",
                                                                   "wear_cap = 2.0e-4\nlife_cycles = -inf")))


def test_a_modulus_below_a_gpa_is_said_whatever_the_material_is_named():
    found = warnings_of(edited(("youngs_modulus = 120000.0", "youngs_modulus = 120.0")))
    assert found == ["'materials.ti64.youngs_modulus' = 120 MPa is below 1,000 MPa, softer than any metal or "
                     "engineering solid of a bolted joint: looks like GPa (MPa expected: 120 GPa is 120000 MPa)"]
    assert warnings_of(TEXT) == []


def test_a_critical_slip_in_um_typed_as_mm_is_said():
    found = warnings_of(edited(("critical_slip = 1.0e-3", "critical_slip = 1.0")))
    assert len(found) == 1 and found[0].startswith("'contact.critical_slip' = 1 mm is above 0.05 mm")
    assert "probably µm (mm expected: 1 µm is 0.001 mm)" in found[0]
    assert warnings_of(edited(("critical_slip = 1.0e-3", "critical_slip = 0.01"))) == []  # 10 µm: plausible


@pytest.mark.parametrize("stiffness, said", [("4.0", "'contact.normal_stiffness' = 4 N/mm³ is below 100 N/mm³"),
                                             ("4.0e15", "probably N/m³ (N/mm³ expected: 4e+15 N/m³ is 4e+06 N/mm³)")])
def test_a_normal_stiffness_far_outside_metal_joints_is_said(stiffness, said):
    found = warnings_of(edited(("normal_stiffness = 4.0e6", f"normal_stiffness = {stiffness}")))
    assert len(found) == 1 and said in found[0], found


def test_a_base_that_is_no_path_is_an_input_error(tmp_path):
    (tmp_path / "s.toml").write_text('[scene]\nbase = 5\nname = "x"\n')
    with pytest.raises(InputError, match=r"'scene.base' must be a string.*got 5"):
        scenes.load(tmp_path / "s.toml")


def test_a_procedure_without_cycles_for_its_effects_is_refused_at_load():
    message = refusal(edited(('effects = ["wear"]', "effects = []")))
    assert "'procedure.cof_cycles' is 0" in message and "'procedure.wear_cycles' = 20" in message
    assert 'add "wear" to \'scene.effects\'' in message


def test_keys_of_an_effect_not_listed_are_said():
    found = warnings_of(edited(("cof_max = 0.56", "cof_max = 0.9\ncof_rate = 0.1")))
    assert found == ["'contact.cof_max' = 0.9 and 'contact.cof_rate' = 0.1 act only with the effect "
                     "\"cof_evolution\", which 'scene.effects' does not list (['wear']): the COF stays at "
                     "'contact.cof_initial', and they do nothing; add \"cof_evolution\" to 'scene.effects', or "
                     "remove them"]
    no_wear = warnings_of(edited(('effects = ["wear"]', "effects = []"), ("cof_cycles = 0", "cof_cycles = 5"),
                                 ("wear_cap = 2.0e-4", "wear_cap = 2.0e-4\nloosening_window = 5")))
    assert len(no_wear) == 2, no_wear
    assert all(key in no_wear[0] for key in ("'contact.wear_coefficients'", "'contact.wear_form' = 'shear'",
                                             "'procedure.wear_cycles' = 20", "'procedure.cycle_jump' = 1000.0",
                                             "'procedure.wear_cap' = 0.0002", 'the effect "wear"'))
    assert "'contact.pressure_limit'" not in no_wear[0]  # 0.0: its default, which does nothing either way
    assert no_wear[1].startswith("'procedure.loosening_window' = 5 acts only with the effect \"bolts\"")


@pytest.mark.parametrize("name", sorted(p.name for p in EXAMPLES.glob("*.toml")))
def test_the_shipped_scenes_resolved_raise_no_warning(name):
    assert plausibility(scenes.load(EXAMPLES / name).data) == []


@pytest.mark.parametrize("old, new, said", [
    ("contact_half_width = 2.0, contact_size = 0.05 }\n", "contact_half_width = 2.0, contact_size = 50.0 }\n",
     "'bodies.cylinder.mesh' (mesh generator cylinder_block: radius = 80.0, half_width = 20.0, height = 20.0, "
     "contact_half_width = 2.0, contact_size = 50.0): contact_size (50 mm) must not exceed contact_half_width (2 mm)"),
    ("depth = 20.0, contact_half_width = 2.0", "depth = 20.0, contact_half_width = 30.0",
     "'bodies.plane.mesh' (mesh generator plane_block: half_width = 20.0, depth = 20.0, contact_half_width = 30.0, "
     "contact_size = 0.05): contact_half_width (30 mm) must be smaller than half_width (20 mm)"),
    ("radius = 80.0", "radius = 0.08",
     "'bodies.cylinder.mesh' (mesh generator cylinder_block: radius = 0.08, half_width = 20.0, height = 20.0, "
     "contact_half_width = 2.0, contact_size = 0.05): half_width (20 mm) must be smaller than radius (0.08 mm): the "
     "block is the lower part of the cylinder, narrower than it; if the radius was meant in metres, write 80"),
])
def test_a_generated_block_that_cannot_be_meshed_is_said_with_its_body_keys_and_values(old, new, said):
    """Said when the mesh is made (by `build`, and by a convergence study before any level runs,
    there with the --sizes level at fault), not by the scene's validation."""
    bodies = scenes.parse(edited((old, new))).data["bodies"]
    body = said.split("'")[1].split(".")[1]
    with pytest.raises(InputError) as caught:
        make_mesh(bodies[body]["mesh"], f"bodies.{body}.mesh", None)
    assert str(caught.value).startswith(said), str(caught.value)


@pytest.mark.parametrize("old, new, said", [
    ('dof = "cylinder.rp.ux"', 'dof = "cylinder.rp.uy"',
     "'loads[0]' ('normal') acts on 'cylinder.rp.uy', a DOF whose motion 'motions[0]' ('tangential') prescribes"),
    ("radius = 80.0,", "radius = 80.0, raduis = 3.0,",
     "unknown key 'bodies.cylinder.mesh.raduis' (did you mean 'radius'?): the mesh generator cylinder_block of body "
     "'cylinder' takes radius, half_width, height, contact_half_width, contact_size and growth"),
    ('master = { body = "plane"', 'master = { body = "cylinder"',
     "'contact.slave.body' and 'contact.master.body' select the same body 'cylinder'"),
])
def test_a_refusal_names_the_keys_and_values_at_fault(old, new, said):
    message = refusal(edited((old, new)))
    assert said in message, message
    assert "no support" not in message and "graded mesh" not in message


def test_a_scene_with_a_byte_order_mark_reads_as_without(tmp_path):
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + TEXT.encode())
    assert scenes.load(path).data == scenes.load(CYLINDER).data
    assert scenes.parse("\ufeff" + TEXT).data == scenes.parse(TEXT).data


def test_a_device_or_an_empty_file_is_said_as_such(tmp_path, capsys):
    assert main(["run", "/dev/null", "--out", str(tmp_path / "x")]) == 2
    assert capsys.readouterr().err == ("fretwork: error: scene file /dev/null is not a regular file (a device, pipe "
                                       "or socket): give a scene file (.toml)\n")
    (tmp_path / "empty.toml").write_text("# nothing yet\n")
    with pytest.raises(InputError, match=r"empty\.toml is empty \(comments only\)"):
        scenes.load(tmp_path / "empty.toml")


def test_an_override_of_no_key_is_said_as_the_overrides_not_the_files():
    with pytest.raises(InputError) as caught:
        set_overrides(["procedure.cof_cylces=2"])
    assert str(caught.value) == ("--set procedure.cof_cylces: 'procedure' has no key 'cof_cylces' "
                                 "(did you mean 'cof_cycles'?)")
    assert set_overrides(["procedure.cof_cycles=2", "motions.tangential.value=0.05",
                          "bodies.plane.mesh.contact_size=0.1"]) == {
        "procedure.cof_cycles": 2, "motions.tangential.value": 0.05, "bodies.plane.mesh.contact_size": 0.1}
    with pytest.raises(InputError, match=r"^override procedure\.cof_cylces \(set on top of .*cylinder_on_plane\.toml\)"):
        scenes.load(CYLINDER, {"procedure.cof_cylces": 2})


def test_a_generators_refusal_names_the_body_and_its_values():
    web = dict(generator="web_block", width=300.0, depth=100.0, thickness=80.0, hub_width=400.0, screw_x=95.0,
               hole_half_size=17.5, hole_depth=70.0, contact_size=10.0)
    with pytest.raises(InputError) as caught:
        make_mesh(web, "bodies.web.mesh", None)
    assert str(caught.value).startswith("'bodies.web.mesh' (mesh generator web_block: width = 300.0,")
    assert "needs hub_width <= width (400, 300 mm)" in str(caught.value)


def test_a_caller_that_sets_the_effects_builds_a_model_of_its_own(tmp_path):
    """The validation job's patch tests set 'scene.effects' = [] on the wear scene to build (not run)
    its bodies: no refusal for the wear cycles it does not run; a file that says so is refused."""
    assert scenes.load(CYLINDER, {"scene.effects": []}).effects == frozenset()
    (tmp_path / "idle.toml").write_text(edited(('effects = ["wear"]', "effects = []")))
    with pytest.raises(InputError, match=r"'procedure.wear_cycles' = 20\) runs only with \"wear\""):
        scenes.load(tmp_path / "idle.toml", {"procedure.increments_per_cycle": 8})
    assert scenes.load(tmp_path / "idle.toml", {"procedure.cof_cycles": 1}).data["procedure"]["cof_cycles"] == 1
