"""The counterweight pipeline: multibody → inertia fields → contact model; limit; stages; effects."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mbs.loading import cycle_loading
from pipelines import coupling, scene as scenes, stages
from reduction import modal_loads
from pipelines.jobs import limit as limits
from pipelines.build import build
from pipelines.coupling import multibody_loading
from pipelines.cli.main import main
from reduction.mesh.generators import counterweight_block, web_block
from reduction.elasticity import assemble_elastic_body
from reduction.errors import InputError
from reduction.factorization import factorize

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
SCENE = EXAMPLES / "counterweight.toml"
COARSE = {"bodies.counterweight.mesh.contact_size": 20.0, "bodies.web.mesh.contact_size": 20.0,
          "mbs.n_modes": 4, "mbs.solver.revolutions": 2.0}


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return stages.StageCache(tmp_path_factory.mktemp("stage-cache"))


@pytest.fixture(scope="module")
def coarse_scene():
    return scenes.load(SCENE, COARSE)


@pytest.fixture(scope="module")
def loading(coarse_scene, cache):
    return multibody_loading(coarse_scene, cache)


def clamped_solver(mesh, elastic):
    face = np.flatnonzero(np.abs(mesh.p[1]) < 1e-9)
    fixed = np.zeros(elastic.n_dofs, dtype=bool)
    fixed[elastic.node_dofs[face].ravel()] = True
    free = np.flatnonzero(~fixed)
    factor = factorize(elastic.stiffness[free][:, free].tocsc())

    def solve(load):
        displacement = np.zeros(elastic.n_dofs)
        displacement[free] = factor.solve(load[free])
        return displacement
    return solve


def wing_torsion(elastic, displacement):
    x = elastic.coordinates
    tips = [np.flatnonzero((np.abs(x[:, 0] - s * x[:, 0].max()) < 1e-6) & (np.abs(x[:, 1] - x[:, 1].max()) < 1e-6))
            for s in (-1, 1)]
    uz = displacement[elastic.node_dofs[:, 2]]
    return 0.5 * (uz[tips[1]].mean() - uz[tips[0]].mean())


def test_counterweight_and_web_meshes_match_on_the_hub_face():
    cw = counterweight_block(700.0, 200.0, 80.0, 220.0, 30.0, 65.0, 22.0, 10.0)
    web = web_block(260.0, 100.0, 80.0, 220.0, 65.0, 22.0, 70.0, 10.0)
    face_cw = cw.p[:, np.abs(cw.p[1]) < 1e-9]
    face_web = web.p[:, (np.abs(web.p[1]) < 1e-9) & (np.abs(web.p[0]) <= 110.0 + 1e-9)]
    assert face_cw.shape == face_web.shape
    assert np.allclose(np.lexsort(face_cw[[2, 0]]).size, face_cw.shape[1])
    assert np.allclose(face_cw[:, np.lexsort(face_cw[[2, 0]])], face_web[:, np.lexsort(face_web[[2, 0]])])
    # volume: hub + wing plate − two square through holes
    volume = 220 * 30 * 80 + 700 * 170 * 80 - 2 * 44 * 44 * 200
    elastic = assemble_elastic_body(cw, 210000.0, 0.3, 7.85e-9)
    mass = elastic.mass.sum() / 3.0
    assert mass == pytest.approx(7.85e-9 * volume, rel=1e-9)


def test_quasi_static_response_to_the_acceleration_field_reproduces_the_multibody_modes(loading):
    """d'Alembert: the CW held at its face and loaded by −M·a(x, t) deforms as the multibody CW
    vibrates. Projected on the multibody modes (Ψᵀ M u; the static response also holds the
    residual flexibility of the modes the multibody model leaves out), the modal coordinates
    are the multibody ones up to the damping term of the modal equation, 2ζ q̇/ω (2 % damping)
    and the hexahedral vs quadratic-tetrahedral discretisation: torsion-mode coordinate within
    10 % at every sample, relative to its amplitude (measured 4.6 %). The multibody CW has no
    screw holes, so the hexahedral CW gets 2.5 mm ones here; with the scene's 44 mm holes it
    is 15 % softer in torsion and its static response 15 % larger."""
    g = loading.geometry
    mesh = counterweight_block(g["width"], g["height"], g["thickness"], 260.0, 30.0, 95.0, 2.5, 10.0)
    elastic = assemble_elastic_body(mesh, 210000.0, 0.3, 7.85e-9)
    patterns = modal_loads.inertia_patterns(elastic, loading.modes)
    solve = clamped_solver(mesh, elastic)
    shapes = modal_loads.interpolate_modes(loading.modes, elastic.coordinates)
    torsion = np.zeros(elastic.n_dofs)
    torsion[elastic.node_dofs.ravel()] = shapes[:, :, loading.torsion_mode].ravel()
    projector = elastic.mass @ torsion / (torsion @ (elastic.mass @ torsion))
    samples = np.arange(0, len(loading.time), 7)
    quasi_static = []
    for i in samples:
        load = patterns["spin_squared"] * loading.angular_velocity[i, 2] ** 2
        for k, axis in enumerate("xyz"):
            load = load + patterns[f"frame_a{axis}"] * loading.frame_acceleration[i, k]
            load = load + patterns[f"alpha_{axis}"] * loading.angular_acceleration[i, k]
        for k in range(loading.n_modes):
            load = load + patterns[f"mode_{k + 1}"] * loading.modal_accelerations[i, k]
            load = load + patterns[f"coriolis_{k + 1}"] * loading.angular_velocity[i, 2] * loading.modal_velocities[i, k]
        quasi_static.append(projector @ solve(load))
    multibody = loading.modal_coordinates[samples, loading.torsion_mode]
    scale = np.ptp(multibody) / 2
    assert np.max(np.abs(np.array(quasi_static) - multibody)) < 0.10 * scale


def test_centrifugal_pattern_carries_the_mass_times_spin_squared_times_radius(loading):
    g = loading.geometry
    mesh = counterweight_block(g["width"], g["height"], g["thickness"], 260.0, 30.0, 95.0, 22.0, 20.0)
    elastic = assemble_elastic_body(mesh, 210000.0, 0.3, 7.85e-9)
    load = modal_loads.centrifugal_pattern(
        elastic, loading.frame_acceleration.mean(axis=0), float(np.mean(loading.angular_velocity[:, 2] ** 2)))
    radial = load[elastic.node_dofs[:, 1]].sum()
    mass = elastic.mass.sum() / 3.0
    centre_y = (elastic.mass @ np.where(np.arange(elastic.n_dofs) % 3 == 1, np.repeat(elastic.coordinates[:, 1], 3), 0.0)).sum() / mass
    spin = float(np.mean(loading.angular_velocity[:, 2]))
    axis_distance = -np.mean(loading.frame_acceleration[:, 1]) / np.mean(loading.angular_velocity[:, 2] ** 2)
    assert axis_distance == pytest.approx(230.0, rel=0.01)  # contact face 230 mm from the crank axis
    assert radial == pytest.approx(mass * spin ** 2 * (axis_distance + centre_y), rel=0.01)


def test_wing_mode_pattern_twists_the_held_counterweight_by_one_millimetre_in_the_mode_shape(loading):
    g = loading.geometry
    mesh = counterweight_block(g["width"], g["height"], g["thickness"], 260.0, 30.0, 95.0, 22.0, 20.0)
    elastic = assemble_elastic_body(mesh, 210000.0, 0.3, 7.85e-9)
    face = np.flatnonzero(np.abs(mesh.p[1]) < 1e-9)
    load = modal_loads.wing_mode_pattern(elastic, loading.modes, loading.torsion_mode, loading.torsion_frequency_hz, face)
    displacement = clamped_solver(mesh, elastic)(load)
    assert wing_torsion(elastic, displacement) == pytest.approx(1.0, rel=1e-9)
    mode = modal_loads.interpolate_modes(loading.modes, elastic.coordinates)[:, :, loading.torsion_mode].ravel()
    response = displacement[elastic.node_dofs].ravel()
    mac = (mode @ response) ** 2 / ((mode @ mode) * (response @ response))
    assert mac > 0.97  # the static response to the mode's elastic load is the mode (hex vs tet10 meshes)


def test_cycle_loading_scales_the_vibration_and_keeps_the_means(loading):
    cycle = cycle_loading(loading, "wing_period", 0.2, 24)
    half_range = 0.5 * np.ptp(cycle.tables["wing_mode"])
    assert half_range == pytest.approx(0.2, rel=0.02)  # the sampled sine of amplitude 0.2 mm
    doubled = cycle_loading(loading, "wing_period", 0.4, 24)
    for name in ("frame_ax", "mode_1", "alpha_y"):
        mean = cycle.tables[name].mean()
        assert doubled.tables[name].mean() == pytest.approx(mean, rel=1e-9, abs=1e-9 * np.abs(cycle.tables[name]).max())
        assert np.ptp(doubled.tables[name]) == pytest.approx(2 * np.ptp(cycle.tables[name]), rel=1e-9)
    assert cycle.tables["spin_squared"].mean() == pytest.approx(np.mean(loading.angular_velocity[:, 2]) ** 2, rel=1e-3)


def test_the_contact_body_must_have_the_multibody_counterweight_geometry(cache):
    scene = scenes.load(SCENE, dict(COARSE, **{"bodies.counterweight.mesh.width": 800.0}))
    with pytest.raises(InputError, match="multibody counterweight spans"):
        build(scene, cache=cache)


def test_a_scene_without_wear_never_allocates_wear_state(cache):
    effects = ["bolts", "cof_evolution", "centrifugal", "flexible_counterweight", "gas_torque", "gear_mesh"]
    scene = scenes.load(SCENE, dict(COARSE, **{"scene.effects": effects}))
    model = build(scene, cache=cache)
    assert model.initial_state().wear_depth is None
    assert "wear_mode" not in model.program.patterns


def test_effects_select_the_inertia_patterns(cache):
    scene = scenes.load(SCENE, dict(COARSE, **{"scene.effects": ["bolts", "flexible_counterweight", "gear_mesh"]}))
    model = build(scene, cache=cache)
    assert "wing_mode" in model.program.patterns and "centrifugal" not in model.program.patterns
    table = scenes.load(SCENE, COARSE).data
    table["coupling"]["fields"] = "all"
    table["scene"]["effects"] = ["bolts", "centrifugal", "gear_mesh"]
    model = build(scenes.Scene(table, SCENE), cache=cache)
    assert "spin_squared" in model.program.patterns
    assert not any(p.startswith(("mode_", "coriolis_")) for p in model.program.patterns)


def test_multibody_effect_without_coupling_is_reported():
    text = (EXAMPLES / "cylinder_on_plane.toml").read_text().replace('effects = [', 'effects = ["gear_mesh", ', 1)
    with pytest.raises(InputError, match="gear_mesh.*needs a \\[coupling\\] table"):
        scenes.parse(text)


def _fake_run(scene_path, overrides, amplitude_mm, cache_dir, out_dir=None, models=None):
    """Stand-in for a contact run: stuck below 0.2637 mm (counts its calls in a file)."""
    with open(Path(cache_dir) / "calls.txt", "a") as stream:
        stream.write(f"{amplitude_mm}\n")
    verdict = "stick" if amplitude_mm < 0.2637 else ("damage" if amplitude_mm < 0.3 else "loosening")
    return limits.AmplitudeRun(amplitude_mm, verdict, {"clamp_force_loss_fraction": 0.0})


def test_limit_search_brackets_the_limit_to_the_tolerance(tmp_path, monkeypatch):
    monkeypatch.setattr(limits, "run_amplitude", _fake_run)
    result = limits.find_limit(SCENE, 0.1, 0.4, tolerance_mm=0.005, cache_dir=str(tmp_path), workers=0,
                               progress=False)
    stuck, limit = result.bracket_mm
    assert stuck < 0.2637 <= limit and limit - stuck <= 0.005
    assert result.limit_mm == limit and result.monotone
    assert [(c.verdict_below, c.verdict_above) for c in result.changes] == [("stick", "damage"), ("damage", "loosening")]
    calls = (tmp_path / "calls.txt").read_text().split()
    assert len(calls) == len(set(calls)) == len(result.runs)  # every amplitude runs once
    assert limits.find_limit(SCENE, 0.3, 0.4, tolerance_mm=0.01, cache_dir=str(tmp_path), workers=0,
                             progress=False).bracket_mm == (None, 0.3)  # not stuck even at the lowest


def _non_monotone_run(scene_path, overrides, amplitude_mm, cache_dir, out_dir=None, models=None):
    """Stand-in for the measured case: loosening from 256 µm, stuck again from 290 to 350 µm."""
    verdict = "loosening" if 0.256 <= amplitude_mm < 0.29 or amplitude_mm >= 0.35 else "stick"
    return limits.AmplitudeRun(amplitude_mm, verdict, {"clamp_force_loss_fraction": 0.0})


def test_limit_search_says_when_the_verdict_is_not_monotone(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(limits, "run_amplitude", _non_monotone_run)
    assert main(["limit", str(SCENE), "--amplitude", "100:400", "--tolerance", "5", "--grid", "13",
                 "--workers", "0", "--cache", str(tmp_path), "--out", str(tmp_path / "limit"), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert not summary["monotone"] and 256 <= summary["limit_um"] <= 261
    assert [(c["verdict_below"], c["verdict_above"]) for c in summary["changes"]] == [
        ("stick", "loosening"), ("loosening", "stick"), ("stick", "loosening")]
    assert main(["limit", str(SCENE), "--amplitude", "100:400", "--tolerance", "5", "--grid", "13",
                 "--workers", "0", "--cache", str(tmp_path), "--out", str(tmp_path / "limit")]) == 0
    assert "NOT MONOTONE" in capsys.readouterr().out


def test_limit_command_reports_bad_ranges(capsys):
    assert main(["limit", str(SCENE), "--amplitude", "400:100"]) == 2
    assert "LOW < HIGH" in capsys.readouterr().err


def test_sweep_without_margins_never_builds_the_contact_model(tmp_path, monkeypatch):
    import pipelines.build as build_module

    def refuse(*args, **kwargs):
        raise AssertionError("the contact model was built")

    monkeypatch.setattr(build_module, "build", refuse)
    monkeypatch.setattr(coupling, "multibody_loading", refuse)
    before = dict(stages.EXECUTIONS)
    scene = tmp_path / "cw.toml"
    text = SCENE.read_text().replace("n_modes = 6", "n_modes = 2").replace("revolutions = 12.0 ", "revolutions = 0.5")
    assert "revolutions = 0.5" in text
    scene.write_text(text)
    assert main(["sweep", str(scene), "--speeds", "700,750", "--out", str(tmp_path / "sweep.h5"), "--workers", "0",
                 "--json"]) == 0
    assert dict(stages.EXECUTIONS) == before


def test_stages_with_unchanged_inputs_are_read_from_the_cache(tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(coupling, "counterweight_loading", lambda params, cw: calls.append(params) or "histories")
    scene = scenes.load(SCENE, COARSE)
    cache = stages.StageCache(tmp_path)
    before = stages.EXECUTIONS["multibody"]
    assert multibody_loading(scene, cache) == "histories"
    assert multibody_loading(scenes.load(SCENE, COARSE), cache) == "histories"
    assert len(calls) == 1 and stages.EXECUTIONS["multibody"] == before + 1
    changed = scenes.load(SCENE, dict(COARSE, **{"mbs.speed_rpm": 700.0}))
    multibody_loading(changed, cache)
    assert len(calls) == 2
    contact_only = scenes.load(SCENE, dict(COARSE, **{"contact.cof_max": 0.6}))
    multibody_loading(contact_only, cache)  # contact settings are not multibody inputs
    assert len(calls) == 2


def test_stage_cache_survives_a_broken_entry(tmp_path):
    cache = stages.StageCache(tmp_path)
    assert cache.get("demo", {"a": 1}, lambda: 41) == 41
    entry = next(tmp_path.glob("demo-*.pkl"))
    entry.write_bytes(b"not a pickle")
    assert cache.get("demo", {"a": 1}, lambda: 42) == 42
    assert cache.get("demo", {"a": np.arange(3)}, lambda: 43) == 43
    assert not list(tmp_path.glob(".*.tmp"))


def test_sweep_margins_are_limit_over_calibrated_amplitude(tmp_path, monkeypatch, capsys):
    """`fretwork sweep --margins`: the wing amplitude at the scene's speed is the stated one
    (calibration), margin = the largest amplitude shown to stick (the bracket's lower end) / amplitude
    at every speed, /margins in the sweep file, the limit's limit.json and limit.png beside its runs."""
    import h5py

    monkeypatch.setattr(limits, "run_amplitude", _fake_run)
    scene = tmp_path / "cw.toml"
    scene.write_text(SCENE.read_text().replace("n_modes = 6", "n_modes = 4").replace("revolutions = 12.0 ",
                                                                                       "revolutions = 1.5"))
    assert "revolutions = 1.5" in scene.read_text()
    out = tmp_path / "sweep.h5"
    assert main(["sweep", str(scene), "--speeds", "700,750", "--margins", "--amplitude", "100:400",
                 "--tolerance", "5", "--out", str(out), "--workers", "0", "--cache", str(tmp_path), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    amplitude = dict(zip(summary["speeds_rpm"], summary["wing_amplitude_um"]))
    assert amplitude[750.0] == pytest.approx(100.0, rel=1e-9)
    assert summary["limit_um"] == pytest.approx(263.7, abs=5.0)
    stuck = summary["bracket_um"][0]  # the largest amplitude shown to stick: what the margins divide
    assert stuck < 263.7 <= summary["limit_um"] and summary["margin_amplitude_um"] == stuck
    for a, m in zip(summary["wing_amplitude_um"], summary["margin"]):
        assert m == pytest.approx(stuck / a, rel=1e-9)
    with h5py.File(out) as results:
        assert results["margins/margin"].attrs["units"] == "1"
        assert np.allclose(results["margins/margin"][()], summary["margin"])
    written = json.loads((tmp_path / "limit_runs" / "limit.json").read_text())
    assert written["bracket_um"] == summary["bracket_um"] and written["margin_amplitude_um"] == stuck
    assert (tmp_path / "limit_runs" / "limit.png").stat().st_size > 0


def test_a_repeated_amplitude_run_is_read_from_the_cache(tmp_path):
    overrides = dict(COARSE, **{"procedure.cof_cycles": 3, "procedure.vibration_run_up": 0,
                                  "procedure.wear_cycles": 0})
    before = stages.EXECUTIONS["contact_run"]
    first = limits.run_amplitude(str(SCENE), overrides, 0.1, str(tmp_path))
    again = limits.run_amplitude(str(SCENE), overrides, 0.1, str(tmp_path))
    assert stages.EXECUTIONS["contact_run"] == before + 1
    assert again == first and first.verdict in ("stick", "damage")
    other = limits.run_amplitude(str(SCENE), overrides, 0.2, str(tmp_path))
    assert stages.EXECUTIONS["contact_run"] == before + 2 and other.amplitude_mm == 0.2


def test_limit_of_an_uncoupled_scene_is_bad_input(capsys):
    assert main(["limit", str(EXAMPLES / "cylinder_on_plane.toml"), "--amplitude", "100:200"]) == 2
    assert "needs a coupled scene" in capsys.readouterr().err


def test_a_model_rebuilt_for_another_amplitude_states_it_in_its_scene(cache):
    """The scene a run records (results.h5's scene_toml) is the one run: a limit search's runs
    stated the scene's own 100 µm whatever amplitude they ran (QA)."""
    from pipelines.coupling import coupled_program

    model = build(scenes.load(SCENE, COARSE), cache=cache)
    rebuilt = coupled_program(model, 0.23875)
    assert rebuilt.scene.data["coupling"]["wing_amplitude"] == 0.23875
    assert 'wing_amplitude = 0.23875' in scenes.resolved_text(rebuilt.scene)
    assert model.scene.data["coupling"]["wing_amplitude"] == 0.1  # the built model is not changed
    assert "wing_amplitude" not in coupled_program(model, None).scene.data["coupling"]  # the multibody one
