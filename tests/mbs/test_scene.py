"""Scene [mbs] table: sub-tables map onto the dataclasses; a pressure curve becomes the order table."""

import numpy as np
import pytest

from mbs.scene import load_model_params
from reduction.errors import InputError


def test_scene_tables_set_the_model(tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text('[mbs]\nspeed_rpm = 700\neffects = ["gear_mesh"]\n'
                     '[mbs.counterweight]\nwidth = 650\n[mbs.excitation]\ngear_teeth = 60\n')
    params = load_model_params(scene)
    assert params.speed_rpm == 700 and params.effects == frozenset({"gear_mesh"})
    assert params.counterweight.width == 650 and params.excitation.gear_teeth == 60


def test_pressure_curve_file_replaces_the_order_table(tmp_path):
    angles = np.linspace(0.0, 719.0, 720)
    pressure = 0.2 + 18.0 * np.exp(-0.5 * ((angles - 370.0) / 25.0) ** 2)
    np.savetxt(tmp_path / "pressure.csv", np.column_stack([angles, pressure]), delimiter=",",
               header="crank angle deg, pressure MPa")
    scene = tmp_path / "scene.toml"
    scene.write_text('[mbs.gas_pressure]\nfile = "pressure.csv"\nbore = 320\nconrod_length = 800\nmax_order = 6\n')
    excitation = load_model_params(scene).excitation
    assert excitation.gas_orders == pytest.approx(np.arange(1, 13) / 2.0)
    assert max(excitation.gas_torque_amplitudes) > 1e6  # N mm: kN m class for a 320 mm bore


def test_missing_pressure_keys_are_named(tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text('[mbs.gas_pressure]\nfile = "pressure.csv"\n')
    with pytest.raises(InputError, match=r"missing key\(s\) \['bore', 'conrod_length'\]"):
        load_model_params(scene)


def test_a_scene_without_an_mbs_table_is_refused_not_run_with_defaults(tmp_path, capsys):
    from pipelines.cli.main import main

    scene = tmp_path / "contact_only.toml"
    scene.write_text('[scene]\nname = "contact only"\n')
    with pytest.raises(InputError, match=r"has no \[mbs\] table"):
        load_model_params(scene)
    assert main(["mbs", str(scene), "--out", str(tmp_path / "out")]) == 2
    assert "no [mbs] table" in capsys.readouterr().err and not (tmp_path / "out").exists()


def test_every_tables_unknown_keys_are_named_at_once_with_the_key_meant(tmp_path):
    """A misspelt key in [mbs] and another in [mbs.solver]: both in one message (only the first
    was named; QA, 2026-11-28)."""
    from mbs.scene import load_model_params

    path = tmp_path / "typos.toml"
    path.write_text("[mbs]\nspeed_rmp = 700\nn_modes = 2\n[mbs.solver]\ntimestep = 1e-4\n")
    with pytest.raises(InputError) as refused:
        load_model_params(path)
    message = str(refused.value)
    assert "unknown key(s) ['speed_rmp'] ('speed_rmp': did you mean 'speed_rpm'?)" in message
    assert "[mbs.solver]: unknown key(s) ['timestep'] ('timestep': did you mean 'time_step'?)" in message


@pytest.mark.parametrize("value", ["0", "-2", "2.5"])
def test_a_mode_count_that_is_not_a_positive_whole_number_is_refused_by_its_key(tmp_path, value):
    """It was refused only once the Craig-Bampton reduction ran, without the key (QA, 2026-11-28)."""
    from mbs.scene import load_model_params

    path = tmp_path / "modes.toml"
    path.write_text(f"[mbs]\nn_modes = {value}\n")
    with pytest.raises(InputError, match=rf"\[mbs\] n_modes = {value}: must be a whole number"):
        load_model_params(path)
