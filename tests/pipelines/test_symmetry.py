"""Symmetry planes through the contact surface: several supports per body, a half model that
reproduces the full model."""

from __future__ import annotations

import meshio
import numpy as np
import pytest
import skfem

from pipelines import scene as scenes
from pipelines.jobs.run import run_scene

SCENE = """
[scene]
name = "{name}"
dimension = 3
effects = ["cof_evolution"]

[materials.steel]
youngs_modulus = 210000.0
poisson_ratio = 0.3

[bodies.pad]
material = "steel"
mesh = {{ file = "{name}_pad.inp" }}
reference_points.rp = {{ nodes = {{ axis = "z", value = 4.0 }}, position = [0.0, 0.0, 4.0] }}
{pad_symmetry}

[bodies.base]
material = "steel"
mesh = {{ file = "{name}_base.inp" }}
{base_supports}

[contact]
slave = {{ body = "pad", axis = "z", value = 0.0 }}
master = {{ body = "base", box = [[{x0}, -4.0, -0.01], [6.0, 4.0, 0.01]] }}
normal_stiffness = 1.0e6
critical_slip = 1.0e-4
cof_initial = 0.3
cof_max = 0.6
cof_rate = 0.5

[[loads]]
name = "press"
dof = "pad.rp.uz"
value = {press}
history = "ramp"

[[motions]]
name = "hold_x"
dof = "pad.rp.ux"
value = 0.0
history = "constant"

[[motions]]
name = "shift"
dof = "pad.rp.uy"
value = 6.0e-4
history = "cyclic"

[procedure]
preload_increments = 4
increments_per_cycle = 12
cof_cycles = 3
wear_cycles = 0
"""
BASE = '[[bodies.base.fixed]]\nnodes = { axis = "z", value = -4.0 }\ncomponents = ["ux", "uy", "uz"]\n'
SYMMETRY = '[[bodies.{body}.fixed]]\nnodes = {{ box = [[0.0, -8.0, -4.0], [0.0, 8.0, {top}]] }}\ncomponents = ["ux"]\n'


def _block(path, x0, x1, y, z0, z1, size=2.0):
    """A hexahedral block (Abaqus C3D8) of cubes of ``size`` mm."""
    count = lambda a, b: round((b - a) / size) + 1
    mesh = skfem.MeshHex.init_tensor(np.linspace(x0, x1, count(x0, x1)), np.linspace(-y, y, count(-y, y)),
                                     np.linspace(z0, z1, count(z0, z1)))
    meshio.write(path, meshio.Mesh(mesh.p.T, [("hexahedron", mesh.t.T[:, [0, 2, 4, 1, 3, 6, 7, 5]])]))


def _run(folder, name, half):
    x0 = 0.0 if half else -6.0
    _block(folder / f"{name}_pad.inp", x0, 6.0, 4.0, 0.0, 4.0)
    _block(folder / f"{name}_base.inp", 0.0 if half else -10.0, 10.0, 8.0, -4.0, 0.0)
    text = SCENE.format(name=name, x0=x0, press=-1000.0 if half else -2000.0,
                        pad_symmetry=SYMMETRY.format(body="pad", top=3.99) if half else "",
                        base_supports=BASE + (SYMMETRY.format(body="base", top=0.0) if half else ""))
    path = folder / f"{name}.toml"
    path.write_text(text)
    return run_scene(scenes.load(path), folder / name, progress=False, plots=False).summary


def test_a_half_model_with_a_symmetry_plane_through_the_contact_reproduces_the_full_model(tmp_path):
    full = _run(tmp_path, "full", half=False)
    half = _run(tmp_path, "half", half=True)
    assert 0.05 < full["slip_area_fraction"] < 0.95  # partial slip: the comparison means something
    for key in ("stick_area_fraction", "slip_area_fraction", "min_stick_margin"):
        assert half[key] == pytest.approx(full[key], rel=5e-3), key
    for key in ("nominal_contact_area", "dissipated_energy_mJ"):  # extensive: the half model has half
        assert 2.0 * half[key] == pytest.approx(full[key], rel=5e-3), key
    assert half["verdict"] == full["verdict"]
