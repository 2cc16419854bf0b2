"""The constant-COF comparison's probes: at least one, of the scene's dimension, on the contact
surface; each read at its nearest contact point, which the records name with its distance."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pipelines.cli.main import main
from pipelines.studies import constant_cof
from reduction.errors import InputError

SCENE = Path(__file__).parent / "scenes" / "bolted_blocks.toml"  # 3D, cof_evolution, 20 x 20 mm contact


def _refuse(*args, **kwargs):
    raise AssertionError("the study went on to build or run a model")


def test_no_probe_is_refused_before_any_model_is_built(monkeypatch, capsys):
    monkeypatch.setattr(constant_cof, "build", _refuse)
    assert main(["study", "constant-cof", str(SCENE)]) == 2
    assert "at least one probe point (--probe x,y[,z] in mm)" in capsys.readouterr().err
    with pytest.raises(InputError, match="at least one probe"):
        constant_cof.constant_cof_comparison(SCENE, {})


def test_a_probe_of_the_wrong_dimension_is_refused_before_any_model_is_built(monkeypatch, capsys):
    monkeypatch.setattr(constant_cof, "build", _refuse)
    assert main(["study", "constant-cof", str(SCENE), "--probe", "1,2,0", "--probe", "0,0"]) == 2
    error = capsys.readouterr().err
    assert "probe P2 (0,0) has 2 coordinates, the scene is 3D: give x,y,z in mm" in error and "P1" not in error


def test_a_probe_far_from_the_contact_surface_is_refused_naming_the_nearest_point():
    grid = np.array([[x, y] for x in range(5) for y in range(5)], dtype=float)  # 1 mm apart
    with pytest.raises(InputError) as refused:
        constant_cof.probe_points({"P1": (5000.0, 0.0), "P2": (1.2, 1.1), "P3": (6.1, 2.0)}, grid)
    message = str(refused.value)
    assert "probe P1 (5000,0) is 4996 mm from the nearest contact point (4,0)" in message
    assert "probe P3 (6.1,2) is 2.1 mm from the nearest contact point (4,2), farther than 2 times the " \
           "contact points' spacing there (2 mm)" in message
    assert "P2" not in message
    inside, edge = constant_cof.probe_points({"P2": (1.2, 1.1), "P4": (5.5, 2.0)}, grid)
    assert inside.position_mm == (1.0, 1.0) and inside.distance_mm == pytest.approx(np.hypot(0.2, 0.1))
    assert edge.position_mm == (4.0, 2.0) and edge.distance_mm == pytest.approx(1.5)  # just off the edge: read there


def test_a_far_probe_is_refused_before_either_run(monkeypatch, capsys):
    monkeypatch.setattr(constant_cof, "_last_cycle_max_shear", _refuse)
    assert main(["study", "constant-cof", str(SCENE), "--probe", "5000,0,0"]) == 2
    assert "probe P1 (5000,0,0) is 4990 mm from the nearest contact point (10,0,0)" in capsys.readouterr().err


def test_records_give_the_probe_the_point_used_and_their_distance():
    records = constant_cof.constant_cof_comparison(SCENE, {"P1": (-4.0, 1.0, 0.0)})
    assert [r["model"] for r in records] == ["variable COF", "constant COF 0.6"]
    for record in records:
        assert record["probe_mm"] == [-4.0, 1.0, 0.0]
        used = np.array(record["position_mm"])
        assert record["distance_mm"] == pytest.approx(np.linalg.norm(used - [-4.0, 1.0, 0.0]))
        assert record["distance_mm"] < 20.0 / 6  # within an element of the upper block's contact face
        assert record["max_shear_MPa"] > 0.0
