"""Body loads from acceleration fields against closed forms, and their condensation."""

import numpy as np
import pytest
import skfem

from reduction.body_loads import centrifugal, gravity, mode_shape_inertia, rigid_body_inertia
from reduction.condensation import condense
from reduction.elasticity import assemble_elastic_body
from reduction.errors import InputError

DENSITY = 7.85e-9  # t/mm^3


@pytest.fixture(scope="module")
def block():
    """Hex block 40 x 20 x 10 mm, mass 8e3 mm^3 * 7.85e-9 t/mm^3."""
    mesh = skfem.MeshHex.init_tensor(np.linspace(0, 40, 9), np.linspace(0, 20, 5), np.linspace(0, 10, 3))
    return assemble_elastic_body(mesh, 210_000.0, 0.3, DENSITY)


def _resultant(body, load):
    return load[body.node_dofs].sum(axis=0)


def test_gravity_resultant_is_the_weight(block):
    load = gravity(block, [0, 0, -9810.0])
    weight = 9810.0 * DENSITY * 8000.0  # N; the zero components are judged against it
    np.testing.assert_allclose(_resultant(block, load), [0, 0, -weight], rtol=1e-12, atol=1e-12 * weight)


def test_centrifugal_resultant_is_m_omega2_r_of_centre_of_mass(block):
    omega = 300.0  # rad/s about the z axis through the origin
    load = centrifugal(block, [0, 0, omega])
    mass = DENSITY * 8000.0
    expected = [mass * omega**2 * 20.0, mass * omega**2 * 10.0, 0.0]
    np.testing.assert_allclose(_resultant(block, load), expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
    # the axis through the centre of mass: no resultant, only self-equilibrated radial loads
    centred = centrifugal(block, [0, 0, omega], axis_point=[20.0, 10.0, 5.0])
    np.testing.assert_allclose(_resultant(block, centred), 0.0, atol=1e-12 * np.abs(centred).sum())


def test_rigid_body_inertia_moment_is_inertia_times_angular_acceleration(block):
    alpha = 1e4  # rad/s^2 about z through the centre of mass
    load = rigid_body_inertia(block, [0, 0, 0], angular_acceleration=[0, 0, alpha], origin=[20, 10, 5])
    r = block.coordinates - [20, 10, 5]
    forces = load[block.node_dofs]
    moment_z = np.sum(r[:, 0] * forces[:, 1] - r[:, 1] * forces[:, 0])
    polar_inertia = DENSITY * 8000.0 * (40.0**2 + 20.0**2) / 12
    assert moment_z == pytest.approx(-polar_inertia * alpha, rel=1e-12)


def test_free_body_with_dalembert_load_is_in_equilibrium(block):
    """A force F at one end accelerates the free block by F/m; F plus the inertia load is
    self-equilibrated, so the condensed problem (ends retained, no clamp) is solvable."""
    x = block.coordinates
    end = np.flatnonzero(np.isclose(x[:, 0], 40))
    start = np.flatnonzero(np.isclose(x[:, 0], 0))
    force = np.zeros(block.n_dofs)
    force[block.node_dofs[end, 0]] = 1000.0 / end.size
    inertia = rigid_body_inertia(block, [1000.0 / (DENSITY * 8000.0), 0, 0])
    retained = np.concatenate([block.node_dofs[end].ravel(), block.node_dofs[start].ravel()])
    condensed = condense(block.stiffness, retained, loads={"force": force, "inertia": inertia})
    total = condensed.loads["force"] + condensed.loads["inertia"]
    # the 1000 N pull and the inertia balance to round-off of the 1000 N they carry
    np.testing.assert_allclose(total.reshape(-1, 3).sum(axis=0), 0.0, atol=1e-10 * 1000.0)


def test_mode_shape_inertia_of_a_rigid_translation_mode_is_the_weight(block):
    translation = np.zeros((block.n_dofs, 1))
    translation[block.node_dofs[:, 1], 0] = 1.0
    loads = mode_shape_inertia(block, translation)
    assert loads.shape == (block.n_dofs, 1)
    mass = DENSITY * 8000.0
    np.testing.assert_allclose(_resultant(block, loads[:, 0]), [0, -mass, 0], rtol=1e-12, atol=1e-12 * mass)


def test_plane_strain_centrifugal_and_errors():
    body = assemble_elastic_body(skfem.MeshQuad.init_tensor(np.linspace(0, 10, 3), np.linspace(0, 10, 3)),
                                 1000.0, 0.3, DENSITY)
    load = centrifugal(body, 100.0, axis_point=[0, 0])
    np.testing.assert_allclose(_resultant(body, load), DENSITY * 100.0 * 100.0**2 * np.array([5.0, 5.0]), rtol=1e-12)
    with pytest.raises(InputError, match="needs 2 components"):
        gravity(body, [0, 0, -9810.0])
    no_mass = assemble_elastic_body(body.mesh, 1000.0, 0.3)
    with pytest.raises(InputError, match="density"):
        gravity(no_mass, [0, -9810.0])
