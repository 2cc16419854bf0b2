"""Finite sliding and wear on each body's own surface: gross-slip fretting of a cylinder on a flat.

examples/gross_slip_fretting.toml: R = 80 mm, 1066 N/mm (Hertz a = 1.28 mm), element 0.1 mm,
stroke about ±0.5 mm, energy wear with w = 1e-8 (cylinder) and 3e-8 mm²/N (flat). In gross
slip every point of the cylinder's contact slides, so its scar is the contact width 2a; a
point of the flat is rubbed while the contact passes over it, so the flat's scar is 2a + 2δ.
The worn volumes are w_i × the frictional dissipation, whichever body: their ratio is the
ratio of the wear coefficients, and their sum is (w₁ + w₂) × the dissipation measured
globally (external work − stored energy − energy released by removed material).
"""

from pathlib import Path

import h5py
import numpy as np
import pytest

from contact import procedure
from contact.energy import EnergyMeter
from contact.sliding import SlidingSolver, SlidingState, master_wear_at_points, worn_volumes
from contact.solver import Effects
from contact.verdict import Ending
from pipelines import scene as scenes
from pipelines.build import build
from pipelines.output.checkpoint import _read_state, _write_state
from pipelines.jobs.run import run_scene
from pipelines.jobs.validate import (centre_stroke, scar_width, sliding_run, swept_scar,  # as `fretwork validate`
                                     worn_width)
from reduction.threads import single_threaded_blas

SCENE = str(Path(__file__).resolve().parents[2] / "examples" / "gross_slip_fretting.toml")
ELEMENT = 0.1  # mm, the contact element size of the scene


@pytest.fixture(autouse=True, scope="module")
def one_blas_thread():
    """Tiny dense systems: oversubscribed BLAS threads only slow them down."""
    with single_threaded_blas():
        yield


def _run(mode, overrides=None):
    model = build(scenes.load(SCENE, {"contact.sliding": mode, **(overrides or {})}))
    return (model, *sliding_run(model, mode))


@pytest.fixture(scope="module")
def finite():
    return _run("finite")


def test_gross_slip_scar_of_the_flat_is_the_cylinders_swept_by_the_centre_stroke(finite):
    model, solver, result, _ = finite
    pairing = model.assembly.pairing
    x_cylinder, cylinder_depth = pairing.slave.coordinates[:, 0], result.state.wear_depth[0]
    stroke = centre_stroke(model, result)
    assert 0.4 < stroke < 0.6  # comparable to the contact half-width a = 1.28 mm
    # widths where the wear is 10 % of its deepest, each end placed to within half an element:
    # the cylinder's scar has the Hertz shape (every point slides alike), the flat's is it
    # swept by ±stroke (as `fretwork validate` judges them)
    cylinder = scar_width(x_cylinder, cylinder_depth, 0.1)
    assert cylinder == pytest.approx(2 * 1.2833 * np.sqrt(1 - 0.1**2), abs=ELEMENT)
    points = np.linspace(x_cylinder.min() - stroke, x_cylinder.max() + stroke, 4001)
    swept = scar_width(points, swept_scar(x_cylinder, cylinder_depth, stroke, points), 0.1)
    flat = scar_width(pairing.master.coordinates[:, 0], result.state.master_wear, 0.1)
    assert flat == pytest.approx(swept, abs=ELEMENT)
    assert flat > cylinder + stroke  # the fixed pairing's flat scar would be the cylinder's
    assert solver.repairs > 0


def test_small_sliding_cannot_widen_the_flat_scar():
    """With the pairing fixed, the flat's wear stays where the cylinder's points started."""
    model, _, result, _ = _run("small", {"procedure.wear_cycles": 1})
    x = model.assembly.pairing.slave.coordinates[:, 0]
    widths = [worn_width(x, depth) for depth in result.state.wear_depth]
    assert widths[1] == pytest.approx(widths[0], abs=1e-9)
    assert widths[1] < widths[0] + 2 * centre_stroke(model, result) - 5 * ELEMENT


def test_worn_volumes_follow_the_wear_coefficients(finite):
    model, solver, result, _ = finite
    cylinder, flat = worn_volumes(solver.pairing, result.state)
    w_cylinder, w_flat = model.law.wear_coefficients
    assert flat / cylinder == pytest.approx(w_flat / w_cylinder, rel=1e-9)


def test_wear_only_removes_material(finite):
    """No node of the flat's own field, and no point reading it, is worn by a negative depth:
    the dual mortar weights are negative at some partners and put -4.5e-9 mm on the flat's
    field just outside the scar (on the cylinder-on-plane scene, -30 nm on the field and -56 nm
    read at the points) before the transfer and the reading were made positive."""
    _, solver, result, _ = finite
    assert result.state.master_wear.min() >= 0.0 < result.state.master_wear.max()
    assert master_wear_at_points(solver.pairing, result.state.master_wear).min() >= 0.0


def test_energy_identity_holds_with_finite_sliding(finite):
    model, solver, result, dissipation = finite
    worn = sum(worn_volumes(solver.pairing, result.state))
    assert worn == pytest.approx(sum(model.law.wear_coefficients) * dissipation, rel=0.01)


def test_auto_stays_small_while_slip_is_below_an_element():
    """A ±20 µm stroke (a fifth of an element): auto never re-pairs and gives small sliding's
    answer exactly."""
    small = _run("small", {"motions": [{"name": "tangential", "dof": "cylinder.rp.ux", "value": 0.05,
                                         "history": "cyclic"}], "procedure.wear_cycles": 1})
    auto = _run("auto", {"motions": [{"name": "tangential", "dof": "cylinder.rp.ux", "value": 0.05,
                                       "history": "cyclic"}], "procedure.wear_cycles": 1})
    assert auto[1].summary()["sliding"] == "small" and auto[1].repairs == 0
    assert np.array_equal(auto[2].state.wear_depth, small[2].state.wear_depth)


def _pressed_by_motions(mode, stroke):
    """One cycle of the scene pressed (0.01 mm approach) and slid (±``stroke`` mm) by prescribed
    reference-point motions, no load: re-paired wherever a pressed point has slid at all."""
    model = build(scenes.load(SCENE, {
        "contact.sliding": mode, "scene.effects": [], "loads": [],
        "motions": [{"name": "normal", "dof": "cylinder.rp.uy", "value": -0.01, "history": "ramp"},
                    {"name": "tangential", "dof": "cylinder.rp.ux", "value": stroke, "history": "cyclic"}],
        "procedure.preload_increments": 2, "procedure.increments_per_cycle": 8,
        "procedure.cof_cycles": 1, "procedure.wear_cycles": 0}))
    solver = SlidingSolver(model.assembly, model.law, model.settings, mode=mode, repair_fraction=0.0)
    result = procedure.run(solver, model.initial_state(), model.program, model.procedure,
                           cof_evolution=False, wear=False)
    return solver, result


def test_finite_sliding_with_every_reference_point_dof_prescribed_agrees_with_small_sliding():
    """With every reference-point DOF prescribed, a re-pairing (which eliminates every
    surface DOF) leaves no control DOF; the Newton solve once failed there. Strokes well
    below an element keep every point's partner, and the finite run then differs from the
    small one only because each re-pairing, made at the deformed positions, shifts the
    mortar weights by the slid fraction of an element: to first order in the stroke
    (measured: 8e-5 of the peak pressure at ±0.5 µm, 8e-4 at ±5 µm; element 100 µm)."""
    def partners(pairing):
        return pairing.master_nodes[np.arange(pairing.n_points), np.argmax(pairing.weights, axis=1)]

    differences = []
    for stroke in (5e-4, 5e-3):
        (small, small_run), (finite, finite_run) = (_pressed_by_motions(mode, stroke) for mode in ("small", "finite"))
        assert finite.repairs > 0 and finite.space.n_control == 0 < small.space.n_control
        assert finite_run.ending == small_run.ending == Ending.COMPLETED
        assert np.array_equal(partners(finite.pairing), partners(small.pairing))
        expected = small_run.equilibrium.forces.reshape(-1, 2)
        difference = np.abs(finite_run.equilibrium.forces.reshape(-1, 2) - expected).max(axis=0)
        peak = expected[:, 0].max()
        assert np.all(difference <= 0.05 * stroke / ELEMENT * peak)
        differences.append(difference[0] / peak)
    assert 5.0 < differences[1] / differences[0] < 20.0


def test_run_summary_says_auto_chose_finite_sliding(tmp_path):
    scene = scenes.load(SCENE, {"contact.sliding": "auto", "procedure.wear_cycles": 1})
    outcome = run_scene(scene, tmp_path, progress=False, plots=False)
    assert outcome.summary["sliding"] == "finite"
    assert outcome.summary["sliding_mode"] == "auto"
    assert outcome.summary["repairings"] > 0


def test_checkpoint_keeps_the_master_wear_and_the_pairing(finite, tmp_path):
    state = finite[2].state
    assert isinstance(state, SlidingState) and state.paired_at is not None
    with h5py.File(tmp_path / "state.h5", "w") as file:
        _write_state(file.create_group("state"), state)
    with h5py.File(tmp_path / "state.h5", "r") as file:
        back = _read_state(file["state"])
    assert isinstance(back, SlidingState)
    assert np.array_equal(back.master_wear, state.master_wear)
    assert np.array_equal(back.paired_at, state.paired_at)


def test_3d_block_slid_off_its_partner_is_carried_by_the_overlap():
    """A 7×7 face slid by about 1.5 mm over a 10×10 face (10 × 10 mm each): with finite
    sliding the part that has left the lower face opens and the overlap carries the load;
    with the pairing fixed every point would still be pressed."""
    overrides = {
        "scene.dimension": 3, "scene.effects": [], "materials.ti64.poisson_ratio": 0.0,
        "bodies.cylinder.mesh": {"generator": "flat_block", "size_x": 10.0, "size_y": 10.0, "height": 4.0,
                                 "n_x": 7, "n_y": 7, "n_z": 3, "z0": 0.0},
        "bodies.plane.mesh": {"generator": "flat_block", "size_x": 10.0, "size_y": 10.0, "height": 4.0,
                              "n_x": 10, "n_y": 10, "n_z": 3, "z0": -4.0},
        "bodies.cylinder.reference_points.rp": {"nodes": {"axis": "z", "value": 4.0}, "position": [0.0, 0.0, 4.0]},
        "bodies.plane.fixed": {"nodes": {"axis": "z", "value": -4.0}, "components": ["ux", "uy", "uz"]},
        "contact.slave": {"body": "cylinder", "axis": "z", "value": 0.0},
        "contact.master": {"body": "plane", "axis": "z", "value": 0.0},
        "loads": [{"name": "press", "dof": "cylinder.rp.uz", "value": -1000.0, "history": "ramp"}],
        "motions": [{"name": "slide", "dof": "cylinder.rp.ux", "value": 1.5, "history": "cyclic"},
                    {"name": "hold_y", "dof": "cylinder.rp.uy", "value": 0.0, "history": "constant"}],
    }
    from pipelines.jobs.validate import SCENE as CYLINDER

    model = build(scenes.load(CYLINDER, overrides))
    solver = SlidingSolver(model.assembly, model.law, model.settings, mode="finite")
    equilibrium, state = solver.initial_equilibrium(), model.initial_state()
    for k in range(1, 4):
        equilibrium, state, _, _ = solver.increment(equilibrium, state, model.program.preload(k / 3), Effects())
    for k in range(1, 6):  # a quarter cycle: out to the full 1.5 mm
        equilibrium, state, _, _ = solver.increment(equilibrium, state, model.program.cycle(k / 20), Effects())
    normal = equilibrium.forces.reshape(-1, 3)[:, 0]
    x = model.assembly.pairing.slave.coordinates[:, 0]
    overlap_edge = 5.0 - 1.5
    row = 10.0 / 7  # mm, one slave element
    assert normal.sum() == pytest.approx(1000.0, rel=1e-9)
    assert solver.repairs > 0
    assert x[normal > 0].max() == pytest.approx(overlap_edge, abs=row)
    assert solver.area[normal > 0].sum() == pytest.approx(10.0 * (10.0 - 1.5), abs=10.0 * row)


def test_re_paired_space_shares_the_bodies_and_equals_one_built_anew():
    """Re-pairing forms only the pairing's operators again: G_c, W, E and g_f of the re-paired
    space, and the energy meter's work operators, equal those of a space built from scratch for
    the same pairing (to round-off of W's scale), while K_cc's factor, S_q and the load images
    are shared."""
    from dataclasses import replace as replaced

    from contact.energy import WorkOperators
    from contact.sliding import sliding_state
    from contact.structure import ContactSpace

    model = build(scenes.load(SCENE, {"contact.sliding": "finite"}))
    solver = SlidingSolver(model.assembly, model.law, model.settings, mode="finite")
    meter = EnergyMeter(solver.space, model.law)
    solver.listeners.append(meter.follow)
    state = sliding_state(model.initial_state())
    slide = np.zeros(model.assembly.structure.n_dofs)
    slide[solver._dofs["slave"][:, 0]] = 1.0  # the cylinder's surface moved along the flat, mm
    spaces = []
    for stroke in (0.3, 0.45):  # mm, 3 and 4.5 elements
        solver._repair(stroke * slide, solver.initial_equilibrium(), state)
        spaces.append(solver.space)
    first, second = spaces
    assert second._Kcc is first._Kcc and second.Sq is first.Sq
    assert abs(second.Gc - first.Gc).max() > 0.1  # paired with other master nodes
    fresh = ContactSpace(second.structure)
    scale = np.abs(fresh.W).max()
    np.testing.assert_allclose(second.W, fresh.W, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(second.E, fresh.E, rtol=0, atol=1e-12)
    np.testing.assert_allclose(second.pattern_gf, fresh.pattern_gf, rtol=0, atol=1e-12 * np.abs(fresh.pattern_gf).max())
    # the same pairing with the unpaired surface nodes left as control DOFs is another exact
    # elimination: the pairing's columns differ, the body factor is built for it
    plain = first.repaired(replaced(second.structure, surface_dofs=None))
    assert plain._Kcc is not first._Kcc and plain.n_control > second.n_control
    operators = WorkOperators(second)
    for name in ("BtY", "GY", "Kqq", "load_p"):
        np.testing.assert_allclose(getattr(meter.operators, name), getattr(operators, name), rtol=0,
                                   atol=1e-12 * max(np.abs(getattr(operators, name)).max(), 1e-300))
