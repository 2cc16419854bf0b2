"""The dense and the sparse contact solvers on one small bolted 3D scene (issue 14).

``scenes/bolted_blocks.toml``: two flat blocks on non-matching meshes (mortar pairing), the
fixed end of the lower block holding an edge of the master surface (held contact DOFs), a
bolt locked after the preload, a cyclic motion of the upper block's end and a cyclic body load
on it; COF evolution, wear and the adaptive cycle jump. Run whole (``run_scene``, as
``fretwork run``) with ``[contact] solver = "dense"`` and ``"sparse"``: every per-point field
and figure of every cycle, the dissipation and the energy columns of every increment, the bolt
force and the verdict agree to 1e-8 of each quantity's largest magnitude (measured: ≤ 5.4e-9
for wear, dissipation and energies, 2e-11 for the pressure); the fretting damage fields,
recovered from displacement gradients, to E·δ/h of the largest surface stress (δ Newton's
displacement tolerance, h the element size; measured 2.7e-7).

With a body load, the stored energy and the external work differ between the paths by the
body load's self-energy in the condensed bodies' interior, ½·aᵀ·(f_iᵀ·K_ii⁻¹·f_i)·a (the
condensed model counts the strain energy of its retained DOFs only, the sparse one of all),
and so does the force reported at a reference point (the body load's share there: condensed
or the coupled nodes' own); their difference, the energy balance, agrees. Without the body
load every column agrees.
"""

from pathlib import Path

import h5py
import numpy as np
import pytest

import contact.sparse
from contact.solver import NewtonSettings
from pipelines import scene as scenes
from pipelines.build import build
from pipelines.cli.main import _human_summary
from pipelines.jobs.run import run_scene
from pipelines.output.results import ResultsWriter
from reduction import pardiso
from reduction.errors import InputError

pytest.importorskip("pypardiso")

SCENE = Path(__file__).parent / "scenes" / "bolted_blocks.toml"
#: per-path quantities: solver work and the forces the paths share out differently (see the module)
SOLVER_COUNTS = {"increments/iterations", "increments/cutbacks"}
BODY_LOAD_DEPENDENT = {"increments/stored_energy", "increments/external_work", "increments/control/force"}


def _datasets(path: Path) -> dict:
    out = {}
    with h5py.File(path, "r") as file:
        file.visititems(lambda name, item: out.__setitem__(name, item[()]) if isinstance(item, h5py.Dataset)
                        else None)
        out["verdict"] = file["summary"].attrs["verdict"]
    return out


def _run(tmp_path: Path, solver: str, body_load: bool = True, **overrides):
    values = {"contact.solver": solver, **overrides}
    scene = scenes.load(SCENE, values)
    if not body_load:
        scene.data.pop("body_loads")
    outcome = run_scene(scene, tmp_path / f"{solver}_{body_load}", progress=False, plots=False)
    return outcome, _datasets(outcome.results_path)


def _relative(expected: np.ndarray, got: np.ndarray) -> float:
    scale = float(np.max(np.abs(expected), initial=0.0))
    return float(np.max(np.abs(got - expected), initial=0.0)) / (scale or 1.0)


def _compare(dense: dict, sparse: dict, skip: set) -> dict:
    assert dense.keys() == sparse.keys()
    assert dense.pop("verdict") == sparse.pop("verdict")
    worst = {}
    for name, expected in dense.items():
        if name in skip or np.asarray(expected).dtype.kind not in "fiu":
            continue
        if name.rsplit("/", 1)[-1] in ("status", "cycle", "phase"):
            assert np.array_equal(expected, sparse[name]), name
        worst[name] = _relative(np.asarray(expected, float), np.asarray(sparse[name], float))
    return worst


@pytest.mark.parametrize("body_load", [True, False])
def test_sparse_run_equals_the_dense_run(tmp_path, body_load):
    dense_outcome, dense = _run(tmp_path, "dense", body_load)
    sparse_outcome, sparse = _run(tmp_path, "sparse", body_load)
    assert dense_outcome.summary["contact_solver"] == "dense (asked for, 49 points)"
    assert sparse_outcome.summary["contact_solver"] == "sparse (asked for, 49 points)"
    assert "sparse bodies" in sparse_outcome.summary["linear_solver"]
    assert "contact solver: sparse (asked for, 49 points); sparse bodies" in _human_summary(sparse_outcome)
    assert sparse_outcome.summary["pairing"] == "mortar" and dense["increments/bolt_forces"].size
    # the run exercised what it should: wear, an evolved COF, a jump that grew
    assert dense["final/wear_depth"].max() > 0.0 and dense["final/cof"].max() > 0.2
    assert dense["cycles/equivalent_cycles"][-1] > dense["cycles/cycle"][-1]
    skip = SOLVER_COUNTS | (BODY_LOAD_DEPENDENT if body_load else set())
    worst = _compare(dict(dense), dict(sparse), skip)
    # The fretting damage fields (surface stress, FDP, FFDP) are recovered from displacement
    # gradients (contact.damage): where Newton stopped inside its tolerance δ (1e-10 mm), the
    # surface stress may differ by about E·δ/h (h the element size, 20/6 mm on the slave block),
    # here relative to the largest surface stress of the run; where their maximum lies is an
    # argmax over near ties.
    damage = {name: worst.pop(name) for name in list(worst) if any(
        key in name for key in ("surface_tangential_stress", "fdp", "ffdp"))}
    stress_floor = (210000.0 * NewtonSettings().displacement_tolerance / (20.0 / 6.0)
                    / float(np.max(np.abs(dense["cycles/fields/surface_tangential_stress"]))))
    assert max(value for name, value in damage.items() if not name.endswith("location_mm")) < stress_floor, \
        (damage, stress_floor)
    # Both paths stop Newton inside the same tolerance (1e-10 mm on the kinematics), from
    # different iterates (another linear solver, the same predictors): a stuck point's shear
    # may differ by the stick stiffness μ·p/γ_crit times that tolerance, 1e-10 mm / γ_crit =
    # 1e-7 of the largest shear μ·p. That is the floor of any comparison of two converged
    # runs; every field agrees within it (most to 1e-9).
    floor = NewtonSettings().displacement_tolerance / 1.0e-3  # γ_crit of the scene, mm
    assert max(worst.values()) < floor, sorted(worst.items(), key=lambda item: -item[1])[:5]
    balance = [data["increments/external_work"] - data["increments/stored_energy"] for data in (dense, sparse)]
    assert _relative(*balance) < 1e-8 * max(1.0, np.max(np.abs(dense["increments/external_work"]))
                                            / np.max(np.abs(balance[0])))
    for name in ("max_wear_depth_mm", "dissipated_energy_mJ", "clamp_force_loss_fraction"):
        assert sparse_outcome.summary[name] == pytest.approx(dense_outcome.summary[name], rel=floor, abs=1e-300)


def test_a_sparse_run_resumes_bit_for_bit(tmp_path, monkeypatch):
    overrides = {"procedure.checkpoint_every": 3}
    _, reference = _run(tmp_path / "reference", "sparse", **overrides)
    original = ResultsWriter.checkpoint

    def checkpoint_then_stop(self, snapshot):
        original(self, snapshot)
        raise KeyboardInterrupt

    monkeypatch.setattr(ResultsWriter, "checkpoint", checkpoint_then_stop)
    with pytest.raises(KeyboardInterrupt):
        _run(tmp_path / "interrupted", "sparse", **overrides)
    monkeypatch.setattr(ResultsWriter, "checkpoint", original)
    scene = scenes.load(SCENE, {"contact.solver": "sparse", **overrides})
    outcome = run_scene(scene, tmp_path / "interrupted" / "sparse_True", progress=False, plots=False, resume=True)
    assert outcome.summary["resumed_from_cycle"] >= 3
    resumed = _datasets(outcome.results_path)
    for name, value in reference.items():
        assert np.array_equal(value, resumed[name], equal_nan=np.asarray(value).dtype.kind == "f"), name


@pytest.mark.parametrize(("threshold", "path"), [(40, "sparse"), (50, "dense")])
def test_auto_picks_the_path_by_the_point_count(monkeypatch, threshold, path):
    monkeypatch.setattr(contact.sparse, "SPARSE_FROM_POINTS", threshold)
    model = build(scenes.load(SCENE))
    sign = "≥" if path == "sparse" else "<"
    assert (model.contact_path, model.contact_path_reason) == (path, f"49 points {sign} {threshold}")
    assert isinstance(model.contact_space(), contact.sparse.SparseContactSpace) == (path == "sparse")


@pytest.mark.filterwarnings("ignore:pypardiso")  # the dense build's fallback says so
def test_a_bad_or_unavailable_solver_is_an_input_error(monkeypatch):
    with pytest.raises(InputError, match="contact.solver"):
        scenes.load(SCENE, {"contact.solver": "fast"})
    monkeypatch.setattr(pardiso, "available", lambda: False)
    with pytest.raises(InputError, match="needs MKL PARDISO"):
        build(scenes.load(SCENE, {"contact.solver": "sparse"}))
    assert build(scenes.load(SCENE)).contact_path == "dense"  # auto stays dense here
