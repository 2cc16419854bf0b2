"""results.h5 and ParaView keep the master's own wear field in finite sliding.

examples/gross_slip_fretting.toml driven by ±1.5 mm, one wear cycle: the cylinder's contact
(2a = 2.57 mm) travels 3 mm over the flat, whose scar is wider than the cylinder's by about
the stroke. /final/wear_depth holds the flat's depth only at the cylinder's current partners;
/final/master_wear_depth on the nodes of /master_surface/ holds all of it, and the run's
wear_volume_mm3 is the two bodies' own volumes (w_i × the dissipation each).
"""

from pathlib import Path

import h5py
import meshio
import numpy as np
import pytest

from pipelines import scene as scenes
from pipelines.jobs.run import run_scene
from pipelines.output import plots
from pipelines.output.paraview import write_master_final_vtu
from pipelines.jobs.validate import worn_width
from reduction.threads import single_threaded_blas

SCENE = str(Path(__file__).resolve().parents[2] / "examples" / "gross_slip_fretting.toml")
LONG_STROKE = [{"name": "tangential", "dof": "cylinder.rp.ux", "value": 1.5, "history": "cyclic"}]


def _run(folder, sliding):
    scene = scenes.load(SCENE, {"contact.sliding": sliding, "motions": LONG_STROKE, "procedure.wear_cycles": 1})
    with single_threaded_blas():
        return run_scene(scene, folder, progress=False, plots=False)


@pytest.fixture(scope="module")
def finite(tmp_path_factory):
    folder = tmp_path_factory.mktemp("finite")
    return folder, _run(folder, "finite")


def test_results_file_holds_the_master_wear_on_its_own_surface(finite):
    folder, outcome = finite
    with h5py.File(outcome.results_path, "r") as file:
        depth = file["final/master_wear_depth"]
        assert depth.attrs["units"] == "mm"
        coordinates, area = file["master_surface/coordinates"][()], file["master_surface/area"][()]
        assert file["master_surface/coordinates"].attrs["units"] == "mm"
        assert depth.shape == area.shape == coordinates[:, 0].shape
        assert file["master_surface/facets"][()].max() == len(area) - 1
        slave, points = file["final/wear_depth"][0], file["points/coordinates"][()]
        cylinder = float(np.sum(slave * file["points/area"][()]))
        flat = float(np.sum(depth[()] * area))
        figures = outcome.summary
        assert figures["wear_volume_mm3"] == pytest.approx(cylinder + flat, rel=1e-12)
        gap = file["final/wear_depth"][()].sum(axis=0)
        assert figures["max_wear_depth_mm"] == max(gap.max(), slave.max(), depth[()].max())
        assert flat / cylinder == pytest.approx(3.0, rel=1e-9)  # w_flat / w_cylinder
        # the flat's scar is wider than the cylinder's by about the 3 mm stroke
        assert worn_width(coordinates[:, 0], depth[()]) - worn_width(points[:, 0], slave) > 2.5


def test_paraview_writes_the_master_wear_on_the_master_surface(finite, tmp_path):
    folder, outcome = finite
    final = meshio.read(folder / "interface_final.vtu")  # the points' fields, as before
    assert "master_wear_depth" not in final.point_data
    path = write_master_final_vtu(outcome.results_path, tmp_path / "master_final.vtu")
    mesh = meshio.read(path)
    with h5py.File(outcome.results_path, "r") as file:
        assert np.array_equal(mesh.point_data["master_wear_depth"], file["final/master_wear_depth"][()])
        assert np.array_equal(mesh.points[:, :2], file["master_surface/coordinates"][()])


def test_small_sliding_writes_no_master_surface(tmp_path):
    outcome = _run(tmp_path, "small")
    with h5py.File(outcome.results_path, "r") as file:
        assert "master_surface" not in file and "master_wear_depth" not in file["final"]
        gap = file["final/wear_depth"][()].sum(axis=0)
        assert outcome.summary["wear_volume_mm3"] == float(np.sum(gap * file["points/area"][()]))
    assert write_master_final_vtu(outcome.results_path, tmp_path / "master_final.vtu") is None
    assert not (tmp_path / "master_final.vtu").exists()


def test_profile_plot_draws_the_master_wear_along_its_own_surface(finite, tmp_path, monkeypatch):
    folder, outcome = finite
    drawn = {}
    monkeypatch.setattr(plots, "_save", lambda fig, target: drawn.setdefault(target.name, fig) and target)
    plots.plot_results(outcome.results_path, tmp_path)
    wear = next(ax for ax in drawn["fields.png"].axes if ax.get_ylabel().startswith("wear depth"))
    master = next(line for line in wear.lines if line.get_label().startswith("master's own surface"))
    with h5py.File(outcome.results_path, "r") as file:
        depth = file["final/master_wear_depth"][()]
        x = file["master_surface/coordinates"][()][:, 0]
    assert np.array_equal(master.get_xdata(), np.sort(x))
    assert np.max(master.get_ydata()) == 1e3 * depth.max()  # drawn in µm
