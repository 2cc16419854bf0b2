"""Reduced bodies handed to exudyn (ObjectFFRFreducedOrder) against the full sparse model."""

import numpy as np
import pytest
import scipy.sparse.linalg as spla
import skfem

exu = pytest.importorskip("exudyn")
from exudyn.itemInterface import (  # noqa: E402
    GenericJoint, LoadForceVector, MarkerBodyRigid, MarkerNodeRigid, MarkerSuperElementPosition,
    MarkerSuperElementRigid, ObjectGround, SensorSuperElement,
)

from reduction.coupling import rigid_couplings  # noqa: E402
from reduction.elasticity import assemble_elastic_body  # noqa: E402
from reduction.errors import InputError  # noqa: E402
from reduction.exudyn_bridge import add_floating_body, floating_frame_modes, surface_triangles  # noqa: E402

FORCE = np.array([0.0, 0.0, -100.0])  # N, step load on the tip face
STEP = 2e-5  # s
END_TIME = 0.01  # s, two periods of the first bending mode (224 Hz)


@pytest.fixture(scope="module")
def beam():
    """Steel bar 200 x 20 x 10 mm (1845 DOFs); root face x = 0, tip face x = 200."""
    mesh = skfem.MeshHex.init_tensor(np.linspace(0, 200, 41), np.linspace(0, 20, 5), np.linspace(0, 10, 3))
    body = assemble_elastic_body(mesh, 210_000.0, 0.3, 7.85e-9)
    x = body.coordinates
    root = np.flatnonzero(np.isclose(x[:, 0], 0))
    tip = np.flatnonzero(np.isclose(x[:, 0], 200))
    return body, root, tip


def _newmark_full_model(stiffness, mass, load, steps, observe):
    """Average-acceleration Newmark (trapezoidal) on the full sparse model, starting at rest."""
    effective = spla.splu((stiffness + 4 / STEP**2 * mass).tocsc())
    u = np.zeros(stiffness.shape[0])
    v = np.zeros_like(u)
    a = spla.spsolve(mass.tocsc(), load)
    history = [observe @ u]
    for _ in range(steps):
        u_new = effective.solve(load + mass @ (4 / STEP**2 * u + 4 / STEP * v + a))
        a_new = 4 / STEP**2 * (u_new - u) - 4 / STEP * v - a
        v = v + STEP / 2 * (a + a_new)
        u, a = u_new, a_new
        history.append(observe @ u)
    return np.array(history)


def _reduced_tip_history(body, modes, tip, force, clamp_frame: bool, end_time: float) -> tuple[np.ndarray, int]:
    """exudyn run: step force (N) on the tip face (equal weights), Newmark; z displacement of the tip centre."""
    system = exu.SystemContainer()
    mbs = system.AddSystem()
    items = add_floating_body(mbs, body, modes)
    if clamp_frame:
        ground = mbs.AddObject(ObjectGround())
        mbs.AddObject(GenericJoint(markerNumbers=[
            mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0])),
            mbs.AddMarker(MarkerNodeRigid(nodeNumber=items.rigid_body_node)),
        ], constrainedAxes=[1] * 6))
    tip_marker = mbs.AddMarker(MarkerSuperElementPosition(
        bodyNumber=items.object, meshNodeNumbers=modes.interface_nodes[1], weightingFactors=modes.interface_weights[1]))
    mbs.AddLoad(LoadForceVector(markerNumber=tip_marker, loadVector=list(force)))
    x = body.coordinates
    tip_centre = int(tip[np.argmin(np.linalg.norm(x[tip] - [200.0, 10.0, 5.0], axis=1))])
    sensor = mbs.AddSensor(SensorSuperElement(bodyNumber=items.object, meshNodeNumber=tip_centre, storeInternal=True,
                                              outputVariableType=exu.OutputVariableType.Displacement))
    mbs.Assemble()
    settings = exu.SimulationSettings()
    settings.timeIntegration.numberOfSteps = int(round(end_time / STEP))
    settings.timeIntegration.endTime = end_time
    settings.timeIntegration.generalizedAlpha.useNewmark = True
    settings.timeIntegration.generalizedAlpha.spectralRadius = 1.0
    settings.timeIntegration.verboseMode = 0
    settings.solution.file.write = False
    settings.solution.sensors.writePeriod = STEP
    exu.SolveDynamic(mbs, settings)
    return mbs.GetSensorStoredData(sensor)[:, 3], tip_centre


def test_clamped_reduced_beam_step_load_matches_full_transient(beam):
    body, root, tip = beam
    modes = floating_frame_modes(body, [root, tip], n_modes=10)
    reduced, tip_centre = _reduced_tip_history(body, modes, tip, FORCE, clamp_frame=True, end_time=END_TIME)

    # full model: same clamp, same rigid tip face (RBE2 at the face centroid), same load and step
    x = body.coordinates
    coupling = rigid_couplings(body.n_dofs, body.node_dofs, x, [(tip, x[tip].mean(axis=0))], rotations=True)
    k = coupling.reduce_matrix(body.stiffness)
    m = coupling.reduce_matrix(body.mass)
    free = np.setdiff1d(np.arange(k.shape[0]), coupling.kept[body.node_dofs[root].ravel()])
    load = np.zeros(k.shape[0])
    load[coupling.reference_dofs[0, :3]] = FORCE
    observe = coupling.transformation[body.node_dofs[tip_centre, 2]][:, free].toarray().ravel()
    full = _newmark_full_model(k[free][:, free], m[free][:, free], load[free], reduced.size - 1, observe)

    assert reduced.shape == full.shape
    assert np.abs(full).max() > 1.0  # mm: a real dynamic response (overshoot of the 0.66 mm static sag)
    assert np.abs(reduced - full).max() < 0.01 * np.abs(full).max()


def test_free_reduced_beam_step_load_matches_full_transient(beam):
    """Unsupported beam pushed at its tip: rigid acceleration, rotation and vibration together.
    10 N for 5 ms turns it by 0.012 rad (torque 1e3 N mm, inertia 1.05 t mm^2), small enough for
    the linear full model to be the reference."""
    body, root, tip = beam
    modes = floating_frame_modes(body, [root, tip], n_modes=10)
    force = 0.1 * FORCE
    reduced, tip_centre = _reduced_tip_history(body, modes, tip, force, clamp_frame=False, end_time=END_TIME / 2)

    x = body.coordinates
    coupling = rigid_couplings(body.n_dofs, body.node_dofs, x,
                               [(root, modes.reference_points[0]), (tip, modes.reference_points[1])], rotations=True)
    load = np.zeros(coupling.n_reduced)
    load[coupling.reference_dofs[1, :3]] = force
    observe = coupling.transformation[body.node_dofs[tip_centre, 2]].toarray().ravel()
    full = _newmark_full_model(coupling.reduce_matrix(body.stiffness), coupling.reduce_matrix(body.mass), load,
                               reduced.size - 1, observe)

    assert abs(full[-1]) > 10 * abs(full[reduced.size // 10])  # mostly rigid-body acceleration
    assert np.abs(reduced - full).max() < 0.01 * np.abs(full).max()


@pytest.fixture(scope="module")
def quadratic_beam():
    """The same bar in quadratic tetrahedra (Tet10), 20 x 2 x 1 cells: mid-edge nodes in the mode basis."""
    mesh = skfem.MeshTet.init_tensor(np.linspace(0, 200, 21), np.linspace(0, 20, 3), np.linspace(0, 10, 2))
    body = assemble_elastic_body(mesh, 210_000.0, 0.3, 7.85e-9, quadratic=True)
    x = body.coordinates
    return body, np.flatnonzero(np.isclose(x[:, 0], 0)), np.flatnonzero(np.isclose(x[:, 0], 200))


@pytest.mark.parametrize("which", ["beam", "quadratic_beam"])
def test_free_reduced_body_eigenfrequencies_match_full_model(which, request):
    body, root, tip = request.getfixturevalue(which)
    modes = floating_frame_modes(body, [root, tip], n_modes=20)
    system = exu.SystemContainer()
    mbs = system.AddSystem()
    add_floating_body(mbs, body, modes)
    mbs.Assemble()
    eigenvalues, _ = mbs.ComputeODE2Eigenvalues()
    reduced_hz = np.sqrt(np.sort(np.abs(eigenvalues))[6:12]) / (2 * np.pi)

    # full free-free model with the same rigid root and tip faces
    x = body.coordinates
    coupling = rigid_couplings(body.n_dofs, body.node_dofs, x,
                               [(root, modes.reference_points[0]), (tip, modes.reference_points[1])], rotations=True)
    values = spla.eigsh(coupling.reduce_matrix(body.stiffness).tocsc(), k=12,
                        M=coupling.reduce_matrix(body.mass).tocsc(), sigma=-1e3, return_eigenvectors=False)
    full_hz = np.sqrt(np.sort(values)[6:]) / (2 * np.pi)
    assert full_hz[0] > 1000.0  # free-free bending, far above the 224 Hz of the clamped beam
    np.testing.assert_allclose(reduced_hz, full_hz, rtol=0.005)


def test_surface_triangles_point_outwards(beam):
    body = beam[0]
    triangles = surface_triangles(body)
    p = body.mesh.p.T
    normals = np.cross(p[triangles[:, 1]] - p[triangles[:, 0]], p[triangles[:, 2]] - p[triangles[:, 0]])
    # divergence theorem: the enclosed volume from outward normals is the bar's volume
    volume = np.einsum("ij,ij->", normals, p[triangles].mean(axis=1)) / 6.0
    assert volume == pytest.approx(200 * 20 * 10, rel=1e-12)


def test_two_dimensional_body_is_refused(beam):
    flat = assemble_elastic_body(skfem.MeshTri().refined(1), 1000.0, 0.3, 1e-9)
    with pytest.raises(InputError, match="3D"):
        floating_frame_modes(flat, [np.array([0, 1])], n_modes=1)


def test_body_clamped_through_a_rigid_marker_on_its_second_interface(beam):
    """Joint on interface 1 (MarkerSuperElementRigid, the marker the multibody model uses), frame
    free: the linearised frequencies equal the full model clamped rigidly at that face."""
    body, root, tip = beam
    modes = floating_frame_modes(body, [root, tip], n_modes=20)
    system = exu.SystemContainer()
    mbs = system.AddSystem()
    items = add_floating_body(mbs, body, modes)
    ground = mbs.AddObject(ObjectGround())
    mbs.AddObject(GenericJoint(markerNumbers=[
        mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=list(modes.reference_points[1]))),
        mbs.AddMarker(MarkerSuperElementRigid(bodyNumber=items.object, meshNodeNumbers=modes.interface_nodes[1],
                                              weightingFactors=modes.interface_weights[1])),
    ], constrainedAxes=[1] * 6))
    mbs.Assemble()
    eigenvalues, _ = mbs.ComputeODE2Eigenvalues()
    reduced_hz = np.sqrt(np.sort(np.abs(eigenvalues))[:6]) / (2 * np.pi)

    coupling = rigid_couplings(body.n_dofs, body.node_dofs, body.coordinates,
                               [(root, modes.reference_points[0]), (tip, modes.reference_points[1])], rotations=True)
    k = coupling.reduce_matrix(body.stiffness)
    m = coupling.reduce_matrix(body.mass)
    free = np.setdiff1d(np.arange(k.shape[0]), coupling.reference_dofs[1])
    values = spla.eigsh(k[free][:, free].tocsc(), k=6, M=m[free][:, free].tocsc(), sigma=0, return_eigenvectors=False)
    full_hz = np.sqrt(np.sort(values)) / (2 * np.pi)
    assert full_hz[0] == pytest.approx(223.5, rel=1e-3)  # the cantilever again, clamped at the other end
    np.testing.assert_allclose(reduced_hz, full_hz, rtol=0.005)
