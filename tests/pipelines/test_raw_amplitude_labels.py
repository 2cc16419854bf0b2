"""The multibody model's wing amplitudes are raw, and said to be (QA: `fretwork sweep` printed
"CW1 wing µm" 0.557 at 750 rpm while the scene says 100 µm; the spectra's axes read "amplitude
(µm)" with raw values; sweep.h5 called a crossing a resonance)."""

from __future__ import annotations

import h5py
import numpy as np

from mbs.campbell import Campbell
from mbs.sweep import SweepResult, write_sweep
from pipelines.cli.mbs import _table


def _result() -> SweepResult:
    speeds = np.array([700.0, 750.0, 800.0])
    crossing = {"order": 30.0, "mode": 5, "speed_rpm": 749.4, "frequency_hz": 374.7}
    campbell = Campbell(speeds, np.array([[70.0, 140.0]] * 3), np.array([3.0, 6.0]), [crossing])
    amplitude = np.array([[4.34e-4, 3.21e-4], [5.57e-4, 2.56e-4], [3.73e-4, 0.78e-4]])
    return SweepResult(speeds, amplitude, np.full((3, 3), 375.0), np.full((3, 3), 30.0), np.ones(3),
                       np.full((3, 4), 370.0), [crossing], np.array([False, True, False]), {}, campbell,
                       np.zeros(3), {})


def test_the_sweep_table_says_raw_and_adds_the_scenes_calibrated_column():
    result = _result()
    factor = 0.1 / 5.57e-4  # the scene's 100 µm over CW1's raw amplitude at its speed
    text = _table(result, (factor, "calibration = the scene's stated 100 µm / CW1's 0.557 µm at 750 rpm"), 1)
    header, *rows = text.splitlines()
    assert "CW1 raw µm" in header and "CW2 raw µm" in header and "CW1 scene µm" in header
    assert "wing µm" not in header
    at_750 = rows[1].split()
    assert float(at_750[1]) == 0.557 and float(at_750[3]) == 100.0  # raw, and raw × calibration
    assert float(rows[0].split()[3]) == round(factor * 0.434, 1)
    assert any(line.startswith("raw: the multibody model's own") for line in rows)
    # the second CW's calibration scales CW2's column
    second = _table(result, (2.0, "calibration = … CW2's …"), 2).splitlines()
    assert "CW2 scene µm" in second[0] and float(second[1].split()[3]) == round(2.0 * 0.321, 1)


def test_without_a_calibration_the_table_has_only_raw_columns_and_says_why():
    text = _table(_result(), (None, "a scene that states no wing amplitude uses these amplitudes as they are"))
    header = text.splitlines()[0]
    assert "raw" in header and "scene µm" not in header
    assert "calibration: a scene that states no wing amplitude" in text


def test_sweep_h5_describes_its_crossing_flag_as_a_crossing_and_its_amplitude_as_raw(tmp_path):
    path = write_sweep(tmp_path / "sweep.h5", _result())
    with h5py.File(path) as file:
        flag = file["sweep/resonance"].attrs["description"]
        amplitude = file["sweep/wing_amplitude"].attrs["description"]
    assert "crossing" in flag and "not a shown resonance" in flag and "compatibility" in flag
    assert "raw, uncalibrated" in amplitude


def test_a_spectrum_says_its_amplitudes_are_raw_and_names_the_calibration(tmp_path, monkeypatch):
    import mbs.plots as mbs_plots
    from mbs.spectra import Spectrum

    kept = []
    monkeypatch.setattr(mbs_plots, "_save", lambda fig, path: kept.append(fig) or path)
    spectrum = Spectrum(np.linspace(0.0, 500.0, 11), np.full((11, 2), 1e-4))
    mbs_plots.plot_spectrum(spectrum, tmp_path / "s.png", title="counterweight: wing torsion spectrum at 750 rpm",
                            calibration=179.6)
    mbs_plots.plot_spectrum(spectrum, tmp_path / "s.png")
    calibrated, plain = (fig.axes[0] for fig in kept)
    assert "raw" in calibrated.get_ylabel() and "µm" in calibrated.get_ylabel()
    assert calibrated.get_title().startswith("counterweight: wing torsion spectrum at 750 rpm\n")
    assert "raw amplitudes" in calibrated.get_title() and "179.6" in calibrated.get_title()
    assert "uncalibrated" in plain.get_title()
    assert np.allclose(calibrated.lines[0].get_ydata(), 0.1, rtol=1e-6)  # drawn raw, in µm
