"""Field output within a cycle (``[procedure] field_output``): the chosen increments of the
recorded cycles in results.h5 and in ParaView, equal at the cycle's end to the per-cycle fields."""

from pathlib import Path

import h5py
import meshio
import numpy as np
import pytest

from contact.law import Status
from pipelines import scene as scenes
from pipelines.jobs.run import run_scene
from pipelines.output.results import output_increments
from reduction.errors import InputError

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
# The double beam under low slip is in partial slip: its pad edges slide at the peak load.
LOW_SLIP = {"bodies.upper.mesh.contact_size": 3.0, "bodies.lower.mesh.contact_size": 3.0,
            "procedure.increments_per_cycle": 8, "procedure.cof_cycles": 3, "procedure.wear_cycles": 0,
            "procedure.record_every": 2, "procedure.field_output": [0.25, 0.5, 0.75, 1.0],
            "scene.effects": ["bolts", "cof_evolution"]}
# The cylinder in gross slip with wear and finite sliding, every increment.
CYLINDER = {"bodies.cylinder.mesh.contact_size": 0.2, "bodies.plane.mesh.contact_size": 0.2,
            "procedure.wear_cycles": 2, "procedure.increments_per_cycle": 12, "procedure.field_output": "increment"}
AT_THE_END = ("pressure", "shear", "cof", "accumulated_slip", "dissipation", "wear_depth")


@pytest.fixture(scope="module")
def low_slip(tmp_path_factory):
    out = tmp_path_factory.mktemp("low_slip")
    run_scene(scenes.load(EXAMPLES / "double_beam_low_slip.toml", LOW_SLIP), out, progress=False, plots=False)
    return out


@pytest.fixture(scope="module")
def cylinder(tmp_path_factory):
    out = tmp_path_factory.mktemp("cylinder")
    run_scene(scenes.load(EXAMPLES / "cylinder_on_plane.toml", CYLINDER), out, progress=False, plots=False)
    return out


def test_the_chosen_fractions_of_the_recorded_cycles_are_written(low_slip):
    with h5py.File(low_slip / "results.h5") as file:
        group = file["increment_fields"]
        assert file["cycles/fields/cycle"][()].tolist() == [1, 2]  # record_every = 2 of 3 cycles
        assert group["cycle"][()].tolist() == [1, 1, 1, 1, 2, 2, 2, 2]
        assert group["fraction"][()].tolist() == [0.25, 0.5, 0.75, 1.0] * 2
        assert group["time"][()].tolist() == [0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 1.75, 2.0]
        assert group["time"].attrs["units"] == "cycles"
        assert group["fields/pressure"].shape == (8, file["points/area"].shape[0])
        assert group["fields/pressure"].attrs["units"] == "MPa"
        assert "wear_depth" not in group["fields"]  # the scene has no wear


def test_every_increment_of_the_recorded_cycles_is_written(cylinder):
    with h5py.File(cylinder / "results.h5") as file:
        group = file["increment_fields"]
        assert group["cycle"][()].tolist() == [1] * 12 + [2] * 12
        assert np.array_equal(group["fraction"][()], np.tile(np.arange(1, 13) / 12, 2))
        assert np.array_equal(group["time"][()], file["increments/time"][()][file["increments/phase"][()] > 0])
        assert group["fields/wear_depth"].shape == (24, 2, file["points/area"].shape[0])


@pytest.mark.parametrize("run", ["low_slip", "cylinder"])
def test_the_field_at_the_end_of_a_cycle_is_the_cycle_field_bit_for_bit(run, request):
    with h5py.File(request.getfixturevalue(run) / "results.h5") as file:
        increments, cycles = file["increment_fields"], file["cycles/fields"]
        for row, cycle in enumerate(cycles["cycle"][()]):
            end = np.flatnonzero((increments["cycle"][()] == cycle) & (increments["fraction"][()] == 1.0))
            assert end.size == 1
            for name in AT_THE_END:
                if name in cycles:
                    assert np.array_equal(increments[f"fields/{name}"][end[0]], cycles[name][row]), name
                    assert increments[f"fields/{name}"][end[0]].any(), name  # not two empty fields


def test_the_stick_zone_at_the_peak_load_differs_from_the_one_at_zero_load(low_slip):
    with h5py.File(low_slip / "results.h5") as file:
        status = file["increment_fields/fields/status"][()]
        assert file["increment_fields/fields/status"].attrs["codes"].startswith("0 open, 1 stick")
    peak, unloaded = status[4], status[5]  # cycle 2 at fractions 0.25 (peak) and 0.5 (zero load)
    # Mindlin: at the peak the pad's edges slide around a stick zone; on the way back to zero
    # load the whole pad sticks first, so at zero load nothing slides.
    assert np.sum(peak == Status.SLIP) > 0 and np.sum(peak == Status.STICK) > 0
    assert np.sum(unloaded >= Status.SLIP) == 0
    assert np.sum(unloaded == Status.STICK) > np.sum(peak == Status.STICK)


def test_paraview_gets_one_time_step_per_written_increment(low_slip):
    with h5py.File(low_slip / "results.h5") as file:
        status = file["increment_fields/fields/status"][()]
    reader = meshio.xdmf.TimeSeriesReader(str(low_slip / "interface_increments.xdmf"))
    with reader:
        points, cells = reader.read_points_cells()
        times, data = zip(*(reader.read_data(k)[:2] for k in range(reader.num_steps)))
    assert list(times) == [0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 1.75, 2.0]
    assert np.array_equal(data[4]["status"], status[4])
    assert cells[0].type == "quad" and len(points) == status.shape[1]


def test_a_run_without_field_output_writes_no_increment_fields(coarse_cylinder, tmp_path):
    run_scene(scenes.load(coarse_cylinder), tmp_path, progress=False, plots=False)
    with h5py.File(tmp_path / "results.h5") as file:
        assert "increment_fields" not in file
    assert not (tmp_path / "interface_increments.xdmf").exists()


def test_fractions_pick_the_nearest_increment():
    assert output_increments([0.25, 0.5, 0.75, 1.0], 8) == {2, 4, 6, 8}
    assert output_increments([0.3, 0.01], 8) == {2, 1}  # round(2.4), and never increment 0
    assert output_increments("increment", 5) == {1, 2, 3, 4, 5}
    assert output_increments("cycle", 5) == output_increments(None, 5) == frozenset()


@pytest.mark.parametrize("value, message", [
    ("[0.0, 0.5]", r"cycle fractions in \(0, 1\].*not \[0.0\]"),
    ("[0.5, 1.5]", r"not \[1.5\]"),
    ("[]", "at least one cycle fraction"),
    ('"peak"', '"cycle", "increment" or a list of cycle fractions'),
    ("0.25", '"cycle", "increment" or a list of cycle fractions'),
    ('["a"]', r"not \['a'\]"),
])
def test_bad_field_output_is_one_message_naming_the_key(cylinder_text, value, message):
    text = cylinder_text.replace("[procedure]\n", f"[procedure]\nfield_output = {value}\n")
    with pytest.raises(InputError, match="procedure.field_output") as error:
        scenes.parse(text)
    assert len(str(error.value).splitlines()) == 1
    assert error.match(message)
