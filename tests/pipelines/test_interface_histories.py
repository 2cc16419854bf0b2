"""Interface-histories files: our multibody run exported by `fretwork mbs`, read back as a scene's
'coupling.histories', gives the in-process result bit for bit; bad files are one clear error."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

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
