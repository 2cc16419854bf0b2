"""The surface tangential stress behind FFDP, recovered from the condensed surface
displacements, against the closed form of a sliding Hertz line contact; FDP and FFDP in a
run's --json and results file.

Johnson, Contact Mechanics §7.2 (eq. 7.41 with q = μp): a half-plane whose surface carries
the Hertz pressure p = p₀√(1 − x²/a²) and the traction q = μ_s·p along +x (μ_s signed) has at
its surface σ_x = −p₀[√(1 − ξ²) + 2μ_s·ξ] for |ξ| = |x/a| ≤ 1 and σ_x = −2μ_s·p₀[ξ − sgn ξ·√(ξ² − 1)]
outside: the pressure's σ_x = −p inside, and the Hilbert transform of q, σ_x = −(2/π)∫q(s)/(x − s)ds.
The trailing edge (the side the traction points away from) is in tension, 2|μ|p₀ at its peak.
"""

import json

import h5py
import numpy as np
import pytest

from contact.law import Status
from contact.procedure import IncrementRecord, Observer
from contact.solver import ContactSolver, Effects
from contact.structure import ContactSpace
from pipelines import scene as scenes
from pipelines.build import build
from pipelines.output.damage import DamageObserver

LINE_LOAD, RADIUS, YOUNG, POISSON, COF = 1066.0, 80.0, 120e3, 0.3, 0.56
SIZE = 60.0  # mm: bodies 30 half-widths a across, so that the finite-body stress (~P/SIZE) is small
ELEMENT = 0.05  # mm at the contact


def johnson_surface_stress(x, a, p0, signed_cof):
    xi = x / a
    inside = -p0 * (np.sqrt(np.clip(1 - xi ** 2, 0, None)) + 2 * signed_cof * xi)
    outside = -2 * signed_cof * p0 * (xi - np.sign(xi) * np.sqrt(np.clip(xi ** 2 - 1, 0, None)))
    return np.where(np.abs(xi) <= 1, inside, outside)


@pytest.fixture(scope="module")
def sliding_cylinder(tmp_path_factory):
    """The cylinder scene, bodies SIZE mm deep and wide, pressed and then slid (every point at μ)."""
    from pipelines import examples

    text = examples.scene_path("cylinder_on_plane").read_text()
    text = (text.replace("half_width = 20.0, height = 20.0", f"half_width = {SIZE}, height = {SIZE}")
            .replace("half_width = 20.0, depth = 20.0", f"half_width = {SIZE}, depth = {SIZE}")
            .replace("value = 20.0 }, position = [0.0, 20.0]", f"value = {SIZE} }}, position = [0.0, {SIZE}]")
            .replace("value = -20.0 }", f"value = -{SIZE} }}"))
    path = tmp_path_factory.mktemp("hertz") / "big.toml"
    path.write_text(text)
    model = build(scenes.load(path, {}))
    space = ContactSpace(model.assembly.structure)
    solver = ContactSolver(space, model.law, model.settings)
    state, equilibrium = model.initial_state(), solver.initial_equilibrium()
    for k in range(1, 11):
        equilibrium, state, status, _ = solver.increment(equilibrium, state, model.program.preload(k / 10), Effects())
    for k in range(1, 11):  # the quarter cycle to the peak of the tangential motion
        equilibrium, state, status, _ = solver.increment(equilibrium, state, model.program.cycle(0.025 * k),
                                                         Effects())
    observer = DamageObserver(Observer(), model, space)
    observer.increment(IncrementRecord("cof", 1, 0.25, equilibrium, state, status, 0, 0, 0, 0))
    return model, equilibrium, status, observer.tracker.largest


def test_surface_stress_of_sliding_hertz_contact(sliding_cylinder):
    model, equilibrium, status, sigma = sliding_cylinder
    closed = status != Status.OPEN
    assert np.all(status[closed] == Status.SLIP_AT_MAX), "the contact must slide everywhere"
    area = model.assembly.structure.area
    per_point = equilibrium.forces.reshape(-1, 2) / area[:, None]
    x = model.assembly.pairing.slave.coordinates[:, 0]
    # The traction on the slave (the cylinder) is −τ; its x component over p is μ_s.
    tangent_x = model.assembly.pairing.tangents[:, 0, 0]
    signed_cof = -np.sum(per_point[:, 1] * tangent_x * area) / np.sum(per_point[:, 0] * area)
    assert abs(abs(signed_cof) - COF) < 1e-9
    effective = YOUNG / (2 * (1 - POISSON ** 2))
    a = np.sqrt(4 * LINE_LOAD * RADIUS / (np.pi * effective))
    p0 = 2 * LINE_LOAD / (np.pi * a)
    reference = johnson_surface_stress(x, a, p0, signed_cof)
    error = np.abs(sigma - reference)
    near_edge = np.abs(np.abs(x) - a) < 2 * ELEMENT
    # Away from the contact edges: the finite bodies' own stress, of order P/SIZE, and the
    # strain recovery's O(h/a). At the edges the closed form has a square-root kink that a
    # facet of size h smears by O(√(h/a))·p₀.
    assert error[~near_edge].max() <= LINE_LOAD / SIZE + p0 * ELEMENT / a
    assert error[near_edge].max() <= p0 * np.sqrt(ELEMENT / a)
    # the tensile peak (2|μ|p₀ at x = ±a, sampled at the nodes) at the trailing edge
    trailing = np.sign(-signed_cof) * a
    assert abs(x[np.argmax(sigma)] - trailing) <= 2 * ELEMENT
    assert abs(sigma.max() - reference.max()) <= p0 * np.sqrt(ELEMENT / a)
    assert reference.max() > 0.8 * 2 * COF * p0


def test_fdp_and_ffdp_in_json_and_results(coarse_cylinder, tmp_path):
    from pipelines.jobs.run import run_scene

    outcome = run_scene(scenes.load(coarse_cylinder), tmp_path / "out", progress=False, plots=False)
    summary = json.loads(json.dumps(outcome.summary))
    for key in ("fdp_max_MPa_mm", "ffdp_max_MPa2_mm", "surface_tangential_stress_max_MPa"):
        assert np.isfinite(summary[key]) and summary[key] > 0.0
    with h5py.File(outcome.results_path) as file:
        final = file["final"]
        fdp, ffdp, sigma = final["fdp"][()], final["ffdp"][()], final["surface_tangential_stress"][()]
        expected = final["max_shear"][()] * 0.5 * final["slip_range"][()]
        coordinates = file["points/coordinates"][()]
        pressure = final["pressure"][()]
        assert final["fdp"].attrs["units"] == "MPa*mm"
    assert np.allclose(fdp, expected)
    assert np.allclose(ffdp, np.maximum(sigma, 0.0) * fdp)
    assert summary["fdp_max_MPa_mm"] == pytest.approx(fdp.max())
    assert summary["fdp_max_location_mm"] == pytest.approx(coordinates[np.argmax(fdp)].tolist())
    # gross slip: τ = μp, and δ the 75 µm slip amplitude less the 1 µm elastic slip
    assert summary["fdp_max_MPa_mm"] == pytest.approx(COF * pressure.max() * 0.074, rel=0.1)
