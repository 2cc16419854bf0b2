"""A scene driven by an interface-histories file is judged at the file's one speed: the commands
that would run its [mbs] model instead (mbs, sweep, sweep --margins) refuse it before any run,
rather than judge an unexcited model (the QA's margins of 1,700-2,300, "safe", where the joint
driven by its own multibody model is unsafe)."""

from pathlib import Path

import pytest

from pipelines.cli.main import main

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.mark.parametrize("command", [["mbs"], ["sweep", "--speeds", "700:800:100"],
                                     ["sweep", "--speeds", "700:800:100", "--margins"]])
def test_a_histories_scene_is_refused_by_the_multibody_commands(tmp_path, capsys, command):
    scene = tmp_path / "from_file.toml"
    scene.write_text(f'[scene]\nbase = "{EXAMPLES / "user_joint.toml"}"\nname = "from_file"\n'
                     'effects = ["bolts", "cof_evolution", "wear", "centrifugal", "flexible_counterweight"]\n\n'
                     '[coupling]\nhistories = "cw1.h5"\n')
    out = tmp_path / "out"
    assert main([command[0], str(scene), *command[1:], "--out", str(out), "--workers", "0"]
                if command[0] == "sweep" else [command[0], str(scene), "--out", str(out)]) == 2
    error = capsys.readouterr().err
    assert "interface-histories file 'cw1.h5'" in error and "recorded at one speed" in error
    assert not out.exists()  # refused before any output
