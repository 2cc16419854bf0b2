"""A multibody integration that fails inside a coupled run (e.g. a density typed in kg/m³,
which the plausibility check warns of) is said as the simulation stopping, exit 1, not as an
"internal error" (QA)."""

import pipelines.jobs.run as jobs
from pipelines.cli.main import main


def test_a_failed_multibody_run_is_no_internal_error(coarse_cylinder, monkeypatch, capsys, tmp_path):
    from mbs.model import SimulationError

    def run(*args, **kwargs):
        raise SimulationError("exudyn: DYNAMIC SOLVER FAILED")

    monkeypatch.setattr(jobs, "run_scene", run)
    assert main(["run", str(coarse_cylinder), "--out", str(tmp_path / "out"), "--quiet"]) == 1
    error = capsys.readouterr().err
    assert error.startswith("fretwork: error: the multibody run stopped: exudyn: DYNAMIC SOLVER FAILED")
    assert "internal error" not in error
