"""Fretting damage indicators (contact.damage): the surface strain of an exactly linear
displacement field, the surface stress against 3D Hooke's law, FDP and FFDP by hand."""

import numpy as np

from contact.damage import (
    fretting_damage,
    slip_direction,
    surface_strain,
    tangential_stress,
)
from contact.interface import tangent_frame

YOUNG, POISSON = 210e3, 0.3


def _tilted_surface():
    """A 4 × 3 grid of a plane through the origin with normal n, as quads and as triangles."""
    normal = np.array([1.0, 2.0, 2.0]) / 3.0
    t1, t2 = tangent_frame(normal[None])[0]
    s, r = np.meshgrid(np.linspace(0.0, 3.0, 4), np.linspace(0.0, 2.0, 3), indexing="ij")
    # a distorted grid: the quads are not parallelograms
    s, r = s + 0.2 * np.sin(r * 1.3), r + 0.15 * np.cos(s)
    points = s.ravel()[:, None] * t1 + r.ravel()[:, None] * t2
    ids = np.arange(12).reshape(4, 3)
    quads = np.array([[ids[i, j], ids[i + 1, j], ids[i + 1, j + 1], ids[i, j + 1]]
                      for i in range(3) for j in range(2)])
    triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    return points, quads, triangles, normal


def test_linear_field_gives_the_projected_strain_exactly():
    points, quads, triangles, normal = _tilted_surface()
    gradient = np.random.default_rng(3).normal(size=(3, 3)) * 1e-3  # u = A·x + rigid translation
    displacement = points @ gradient.T + np.array([0.1, -0.2, 0.05])
    projector = np.eye(3) - np.outer(normal, normal)
    expected = projector @ (0.5 * (gradient + gradient.T)) @ projector
    for facets in (quads, triangles):
        strain = surface_strain(points, facets, displacement)
        assert np.allclose(strain, expected, rtol=0, atol=1e-12)


def test_rigid_rotation_has_no_strain_to_first_order():
    points, quads, _, _ = _tilted_surface()
    omega = 1e-6 * np.array([[0.0, -3.0, 1.0], [3.0, 0.0, -2.0], [-1.0, 2.0, 0.0]])
    strain = surface_strain(points, quads, points @ omega.T)
    assert np.abs(strain).max() < 1e-18


def test_surface_stress_is_hookes_law_with_the_normal_stress_given():
    """3D: pick ε in the surface plane and σ_nn = −p, solve Hooke for ε_nn, compare σ_dd."""
    rng = np.random.default_rng(5)
    normal = np.array([0.0, 0.6, 0.8])
    t1, t2 = tangent_frame(normal[None])[0]
    e11, e22, e12 = 1e-3 * rng.normal(size=3)
    strain = (e11 * np.outer(t1, t1) + e22 * np.outer(t2, t2) + e12 * (np.outer(t1, t2) + np.outer(t2, t1)))
    pressure = 150.0
    lam = YOUNG * POISSON / ((1 + POISSON) * (1 - 2 * POISSON))
    mu = YOUNG / (2 * (1 + POISSON))
    e33 = (-pressure - lam * (e11 + e22)) / (lam + 2 * mu)  # σ_nn = −p fixes the normal strain
    full = strain + e33 * np.outer(normal, normal)
    stress = lam * np.trace(full) * np.eye(3) + 2 * mu * full
    assert np.isclose(normal @ stress @ normal, -pressure)
    angle = 0.7
    d = np.cos(angle) * t1 + np.sin(angle) * t2
    got = tangential_stress(strain[None], d[None], np.array([pressure]), YOUNG, POISSON)
    assert np.isclose(got[0], d @ stress @ d, rtol=1e-12, atol=1e-9)


def test_plane_strain_surface_stress():
    """2D: ε_zz = 0 out of plane, σ_yy = −p at the surface y = 0, ε_xx given."""
    exx, pressure = 2e-3, 300.0
    lam = YOUNG * POISSON / ((1 + POISSON) * (1 - 2 * POISSON))
    mu = YOUNG / (2 * (1 + POISSON))
    eyy = (-pressure - lam * exx) / (lam + 2 * mu)
    sxx = lam * (exx + eyy) + 2 * mu * exx
    strain = np.array([[[exx, 0.0], [0.0, 0.0]]])
    got = tangential_stress(strain, np.array([[-1.0, 0.0]]), np.array([pressure]), YOUNG, POISSON)
    assert np.isclose(got[0], sxx, rtol=1e-12)


def test_fdp_and_ffdp_by_hand():
    tau = np.array([100.0, 200.0, 50.0])
    slip_range = np.array([0.02, 0.0, 0.1])
    sigma = np.array([300.0, 400.0, -200.0])  # the last compressive: no crack opening
    fdp, ffdp = fretting_damage(tau, slip_range, sigma)
    assert np.allclose(fdp, [1.0, 0.0, 2.5])
    assert np.allclose(ffdp, [300.0, 0.0, 0.0])


def test_slip_direction_in_global_axes():
    normal = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
    tangents = tangent_frame(normal)
    shear = np.array([[3.0, 4.0], [0.0, 0.0]])
    d = slip_direction(shear, tangents)
    assert np.allclose(d[0], (3 * tangents[0, 0] + 4 * tangents[0, 1]) / 5)
    assert np.allclose(d[1], tangents[1, 0])  # no shear: the first tangent
