"""A scene warning raised while the model is built (a tilted bolt, a reference point off its
ring) reaches the user at once as one `fretwork: warning:` line, not as Python's two-line
warning with a source location."""

import warnings

from pipelines.cli.main import _scene_warnings_said
from pipelines.scene.checks import SceneWarning


def test_a_scene_warning_is_said_as_fretwork_says_warnings(capsys):
    with _scene_warnings_said():
        warnings.warn("'bolts.m12.axis' is 5° off the joint's normal", SceneWarning)
        said_at_once = capsys.readouterr().err
        warnings.warn("something else", DeprecationWarning)
    assert said_at_once == "fretwork: warning: 'bolts.m12.axis' is 5° off the joint's normal\n"
    assert "fretwork: warning" not in capsys.readouterr().err
