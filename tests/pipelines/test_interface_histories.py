"""Interface-histories files: our multibody run exported by `fretwork mbs`, read back as a scene's
'coupling.histories', gives the in-process result bit for bit; bad files are one clear error."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mbs.histories_file import InterfaceHistories, write_interface_histories
from pipelines import scene as scenes
from pipelines.cli.main import main
from pipelines.jobs.run import run_scene

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
COARSE = """
[bodies.counterweight.mesh]
contact_size = 20.0
[bodies.web.mesh]
contact_size = 20.0
[mbs]
n_modes = 4
[mbs.solver]
revolutions = 2.0
[procedure]
increments_per_cycle = 8
cof_cycles = 6
vibration_run_up = 0
wear_cycles = 2
cycle_jump = 20.0
stationary_window = 3
loosening_window = 3
checkpoint_every = 0
"""
#: summary entries that time the run or describe where it came from, not what it found (a
#: multibody run's steadiness: histories read from a file are the file author's to judge)
NOT_FIGURES = {"wall_time_s", "linear_solver", "multibody_unsettled_change", "multibody_warning"}


def _scene(folder: Path, name: str, extra: str) -> Path:
    path = folder / name
    path.write_text(f'[scene]\nbase = "{EXAMPLES / "counterweight.toml"}"\n{extra}\n{COARSE}')
    return path


@pytest.mark.parametrize("fields", ["all", pytest.param("wing_mode", marks=pytest.mark.slow)])
def test_histories_exported_by_fretwork_mbs_reproduce_the_in_process_coupling(tmp_path, capsys, fields):
    in_process = _scene(tmp_path, "in_process.toml", f'[coupling]\nfields = "{fields}"\nwing_amplitude = 0.2')
    assert main(["mbs", str(in_process), "--out", str(tmp_path / "mbs"), "--interface-histories",
                 str(tmp_path / "cw1.h5"), "--json"]) == 0
    written = json.loads(capsys.readouterr().out)
    assert written["interface_histories"] == str(tmp_path / "cw1.h5") and written["counterweight"] == 1
    from_file = _scene(tmp_path, "from_file.toml",
                       'effects = ["bolts", "cof_evolution", "wear", "centrifugal", "flexible_counterweight"]\n'
                       f'[coupling]\nfields = "{fields}"\nwing_amplitude = 0.2\nhistories = "cw1.h5"')
    direct = run_scene(scenes.load(in_process), tmp_path / "direct", progress=False, plots=False).summary
    read = run_scene(scenes.load(from_file), tmp_path / "read", progress=False, plots=False).summary
    assert direct["verdict"] == read["verdict"]
    assert {k: v for k, v in direct.items() if k not in NOT_FIGURES} == \
        {k: v for k, v in read.items() if k not in NOT_FIGURES}


def _constant_histories(folder: Path, name: str, wing_torsion_mm: float) -> str:
    """A static check's file for the user joint (examples/user_joint.toml): the centrifugal frame
    acceleration of 230 mm at 750 rpm, constant, and a wing torsion of that amplitude at 375 Hz."""
    n = 400
    time = 0.48 + 5e-5 * np.arange(n)
    spin = 750.0 * np.pi / 30.0
    frame = np.tile([0.0, -230.0 * spin ** 2, 0.0], (n, 1))
    histories = InterfaceHistories(750.0, time, frame, np.tile([0.0, 0.0, spin], (n, 1)), np.zeros((n, 3)),
                                   wing_torsion_mm * np.sin(2 * np.pi * 375.0 * time), np.zeros((n, 0)),
                                   np.zeros((n, 0)), np.zeros((n, 0)), None)
    write_interface_histories(folder / name, histories)
    return name


def test_a_static_check_from_a_file_is_the_constant_load_run(tmp_path):
    """Zero wing torsion and no stated amplitude: the load cycle is the histories' means. Its clamp
    force is that of the same loads with a 1e-6 mm wing vibration (stick, 806,222.6 N on the
    shipped C3D10 meshes; QA found 803,385.5 N on the C3D4 meshes shipped before), to what 1e-6 mm
    of a bolt's stretch carries (8e5 N/mm: 0.8 N)."""
    joint = (EXAMPLES / "user_joint.toml").read_text().replace('"user_joint/', f'"{EXAMPLES / "user_joint"}/')
    joint = "\n".join(line for line in joint.splitlines() if not line.startswith("wing_amplitude"))
    joint = joint.replace(', "flexible_counterweight", "gas_torque", "gear_mesh"]', "]")
    summaries = {}
    for name, torsion in (("static", 0.0), ("tiny", 1e-6)):
        histories = _constant_histories(tmp_path, f"{name}.csv", torsion)
        scene = tmp_path / f"{name}.toml"
        scene.write_text(joint.replace('\nfields = "wing_mode"', f'\nfields = "all"\nhistories = "{histories}"'))
        summaries[name] = run_scene(scenes.load(scene), tmp_path / name, progress=False, plots=False).summary
    static, tiny = summaries["static"], summaries["tiny"]
    assert static["vibration_scale"] == 0.0 and static["wing_amplitude_mm"] == 0.0
    assert tiny["wing_amplitude_mm"] == pytest.approx(1e-6, rel=1e-3)
    assert static["verdict"] == tiny["verdict"] == "stick"
    assert static["clamp_force_N"] == pytest.approx(tiny["clamp_force_N"], abs=8e5 * 1e-6)
    assert static["clamp_force_N"] == pytest.approx(806222.6, abs=8e5 * 1e-6)
