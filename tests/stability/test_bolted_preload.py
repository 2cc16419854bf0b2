"""Hard case: a bolted joint whose outward body load is ramped in with the bolt pretension.

The user-style joint (examples/user_joint: Abaqus tetrahedra, mortar pairing, two 400 kN
bolts; its shipped C3D10 meshes, and the C3D4 meshes it shipped before 2026-11-28 on which this
hard case was found, kept in tests/stability/meshes/user_joint_c3d4) with the counterweight's centrifugal load, or a gravity pulling it off the web, ramped
in with the pretension. The counterweight is held by the bolts and the contact alone, and its
flat face starts just touching the web: the body load bends it away from the joint, so in the
first Newton iteration the whole interface is open but for one point. The contact-search step
must then hold the body on enough points (one point lets it turn: a singular step of 10⁸ mm,
which used to end the preload as "no static solution exists").

Closed form: at the end of the preload each bolt carries its pretension F (it is locked at that
length, so it still does), and the counterweight's force balance along the bolt axis e (head
to nut) gives the contact's normal resultant

    N = Σ F + R·e,        R = ρ·∫ a dV  (the body load's resultant, from the mesh).

Units: mm, N, t, s.
"""

from pathlib import Path

import meshio
import numpy as np
import pytest

from contact.law import Status
from contact.procedure import Observer, run
from contact.solver import ContactSolver, ConvergenceError, Effects
from pipelines import scene as scenes
from pipelines.build import build

#: the joint's meshes: the shipped quadratic tetrahedra and the linear ones of the hard case
JOINTS = {"c3d10": Path(__file__).resolve().parents[2] / "examples" / "user_joint",
          "c3d4": Path(__file__).resolve().parent / "meshes" / "user_joint_c3d4"}
DENSITY = 7.85e-9
PRETENSION = 400000.0
AXIS = np.array([0.0, -1.0, 0.0])  # head to nut: the counterweight is pulled towards -y
SPIN = {"kind": "centrifugal", "angular_velocity": [0.0, 0.0, 78.539816339744831],  # 750 rpm
        "axis_point": [0.0, -230.0, 0.0]}
OUTWARD_GRAVITY = {"kind": "gravity", "acceleration": [0.0, 5.0e5, 0.0]}

SCENE = """
[scene]
name = "bolted_preload"
dimension = 3
effects = ["bolts"]

[materials.steel]
youngs_modulus = 210000.0
poisson_ratio = 0.3
density = {DENSITY}

[bodies.counterweight]
material = "steel"
mesh = {{ file = "{joint}/cw.inp" }}
reference_points.head_1 = {{ nodes = {{ set = "HEAD_1" }}, position = [60.0, 160.0, 0.0], rotations = true }}
reference_points.head_2 = {{ nodes = {{ set = "HEAD_2" }}, position = [-60.0, 160.0, 0.0], rotations = true }}

[bodies.web]
material = "steel"
mesh = {{ file = "{joint}/web.inp" }}
fixed = {{ nodes = {{ set = "BASE" }}, components = ["ux", "uy", "uz"] }}
reference_points.thread_1 = {{ nodes = {{ set = "THREAD_1" }}, position = [60.0, -35.0, 0.0], rotations = true }}
reference_points.thread_2 = {{ nodes = {{ set = "THREAD_2" }}, position = [-60.0, -35.0, 0.0], rotations = true }}

[bolts.screw_1]
head = "counterweight.head_1"
nut = "web.thread_1"
axis = [0.0, -1.0, 0.0]
stiffness = 8.0e5
pretension = {PRETENSION}

[bolts.screw_2]
head = "counterweight.head_2"
nut = "web.thread_2"
axis = [0.0, -1.0, 0.0]
stiffness = 8.0e5
pretension = {PRETENSION}

[contact]
slave = {{ body = "counterweight", set = "CONTACT" }}
master = {{ body = "web", set = "CONTACT" }}
normal_stiffness = 1.0e6
critical_slip = 1.0e-3
cof_initial = 0.2
cof_max = 0.5

[procedure]
preload_increments = 4
increments_per_cycle = 2
cof_cycles = 1
"""


def _scene(load: dict, history: str, joint: Path):
    """The joint of the meshes in ``joint`` with ``load`` on the counterweight, its history ``history``."""
    entries = "".join(f"{key} = {value!r}\n".replace("'", '"') for key, value in load.items())
    table = f'[[body_loads]]\nname = "outward"\nbody = "counterweight"\nhistory = "{history}"\n{entries}'
    scene = SCENE.format(joint=joint, DENSITY=DENSITY, PRETENSION=PRETENSION)
    return build(scenes.parse(scene + table, "bolted_preload"))


def _resultant(load: dict, joint: Path) -> np.ndarray:
    """ρ·∫ a dV over the counterweight's tetrahedra (a linear in x: exact at the centroids; a
    straight-edged C3D10's volume and centroid are its corners'), N."""
    mesh = meshio.read(joint / "cw.inp")
    cells = mesh.cells_dict.get("tetra10", mesh.cells_dict.get("tetra"))
    tets = mesh.points[cells[:, :4]]
    volume = np.abs(np.linalg.det(tets[:, 1:] - tets[:, :1])) / 6.0
    centroid = tets.mean(axis=1)
    if load["kind"] == "gravity":
        return DENSITY * volume.sum() * np.asarray(load["acceleration"])
    omega = np.asarray(load["angular_velocity"])
    radius = centroid - np.asarray(load["axis_point"])
    radius -= np.outer(radius @ omega, omega) / (omega @ omega)
    return DENSITY * (omega @ omega) * (volume @ radius)


class _LastPreload(Observer):
    def __init__(self):
        self.record = None

    def increment(self, record):
        if record.phase == "preload":
            self.record = record


@pytest.mark.parametrize("elements", list(JOINTS))
@pytest.mark.parametrize("load, history", [(SPIN, "ramp"), (OUTWARD_GRAVITY, "ramp"), (SPIN, "constant")],
                         ids=["spin-ramped", "gravity-off-the-web-ramped", "spin-constant"])
def test_outward_body_load_with_the_pretension_converges_to_the_force_balance(load, history, elements,
                                                                               record_property):
    model = _scene(load, history, JOINTS[elements])
    solver = ContactSolver(model.contact_space(), model.law, model.settings)
    observer = _LastPreload()
    result = run(solver, model.initial_state(), model.program, model.procedure, cof_evolution=False,
                 wear=False, observer=observer)
    record = observer.record
    outward = float(_resultant(load, JOINTS[elements]) @ AXIS)
    assert outward < -1.0e4  # pulls the counterweight off the web: 18 kN (gravity) to 73 kN (spin)
    normal = float(record.equilibrium.forces.reshape(solver.n_points, 3)[:, 0].sum())
    record_property("outcome", {"normal_N": normal, "outward_N": outward, "cutbacks": record.cutbacks})
    np.testing.assert_allclose(record.bolt_forces, PRETENSION, rtol=1e-12)
    # to the solver's force tolerance (a fraction 1e-9 of the force scale, the bolt load)
    assert normal == pytest.approx(2 * PRETENSION + outward, abs=model.settings.force_tolerance * 2 * PRETENSION)
    # locked at the end of the preload, the bolts keep their force while nothing else changes
    assert result.cycles[-1].clamp_force == pytest.approx(2 * PRETENSION, rel=1e-9)


def test_a_failed_newton_iteration_that_slides_everywhere_is_not_called_a_slide_off(monkeypatch):
    """With the search step held on the nearest point alone (the old behaviour), the first
    increment fails: its iterate slides everywhere, but friction at its pressures could carry
    the load, so the failure is Newton's and not a lost tangential equilibrium. On the C3D4
    meshes the case was found on (on the C3D10 ones that iterate's pressures cannot carry it)."""
    monkeypatch.setattr(ContactSolver, "_search_points", lambda self, penetration:
                        penetration >= penetration.max() - 1e-9)
    model = _scene(SPIN, "ramp", JOINTS["c3d4"])
    solver = ContactSolver(model.contact_space(), model.law, model.settings)
    with pytest.raises(ConvergenceError) as failure:
        solver.increment(solver.initial_equilibrium(), model.initial_state(), model.program.preload(0.25),
                         Effects())
    assert failure.value.cause == "diverged"
    assert "no static solution" not in str(failure.value)
    response = solver._last_failure[0]
    assert np.all(response.status[response.status != Status.OPEN] >= Status.SLIP)
