"""`fretwork mbs` hands the scene's name and stated wing amplitude to the run, which draws
wing_time_history.png once, calibrated (it was drawn a second time by the command, 3de3c62)."""

from pathlib import Path
from types import SimpleNamespace

import numpy as np

from pipelines.cli.main import main

COUNTERWEIGHT = Path(__file__).resolve().parents[2] / "examples" / "counterweight.toml"


def test_fretwork_mbs_passes_the_scenes_name_and_stated_amplitude_to_the_run(tmp_path, monkeypatch):
    import pipelines.cli.mbs as cli

    given = {}

    def run(params, folder, **kwargs):
        given.update(kwargs)
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "run.h5").write_bytes(b"run")
        histories = SimpleNamespace(wing_amplitude=np.array([1e-4, 2e-4]), unsettled_change=0.001,
                                    real_time_factor=0.5)
        return SimpleNamespace(histories=histories, reduced=SimpleNamespace(torsion_frequency=80.0),
                               results_file=folder / "run.h5", plots={"time_history": folder / "t.png"})

    monkeypatch.setattr(cli, "run_model", run)
    assert not hasattr(cli, "plot_time_history")  # the command does not draw it again
    assert main(["mbs", str(COUNTERWEIGHT), "--out", str(tmp_path / "out"), "--json"]) == 0
    # counterweight.toml: [scene] name "counterweight", [coupling] wing_amplitude 0.100 mm of CW1
    assert given == {"scene": "counterweight", "stated_wing_amplitude_mm": 0.1, "counterweight": 1}
