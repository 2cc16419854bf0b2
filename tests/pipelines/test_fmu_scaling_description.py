"""The description of a coupled run's FMU states its scaling so that the numbers add up: the scale
times the multibody amplitude it applies to (the wing torsion's harmonic at the wing frequency in
a wing_period cycle, half its peak-to-peak in a revolution cycle) is the stated wing amplitude."""

import re

import h5py
import numpy as np
import pytest

from pipelines.fmu.table import read_playback_table

SCALE = 50.0


def scaled_run(path, cycle):
    """A coupled run's results: a 400 Hz and a 1200 Hz part in the wing torsion, so that its
    400 Hz harmonic (2 µm) differs from its half peak-to-peak."""
    time = np.arange(2000) * 5e-5
    torsion = 0.01 + 0.002 * np.sin(2 * np.pi * 400 * time) + 0.001 * np.sin(2 * np.pi * 1200 * time)
    with h5py.File(path, "w") as results:
        results.attrs["fretwork_format"] = "fretwork-results"
        group = results.create_group("histories")
        group.create_dataset("time", data=time).attrs["units"] = "s"
        group.create_dataset("cw1_wing_torsion", data=torsion).attrs["units"] = "mm"
        group.attrs.update(vibration_scale=SCALE, load_cycle=cycle, counterweight=1, speed_rpm=750.0)
    return path, 0.5 * np.ptp(torsion)


def numbers(text):
    return [float(value) for value in re.findall(r"(?<![\w.])\d[\d.e+-]*(?= mm)", text)]


@pytest.mark.parametrize("cycle", ["wing_period", "revolution"])
def test_scale_times_the_scaled_amplitude_is_the_stated_amplitude(cycle, tmp_path):
    path, half_peak_to_peak = scaled_run(tmp_path / "results.h5", cycle)
    scaling = read_playback_table(path).scaling
    text = scaling.describe()
    scaled = 0.002 if cycle == "wing_period" else half_peak_to_peak
    assert scaling.scaled_amplitude == pytest.approx(scaled, rel=1e-6)
    assert scaling.wing_amplitude == pytest.approx(SCALE * scaled, rel=1e-6)
    assert f"scaled by {SCALE:.6g}" in text and f"stated wing amplitude {SCALE * scaled:.6g} mm" in text
    assert f"{scaled:.6g} mm" in text and f"{half_peak_to_peak:.6g} mm" in text
    # every amplitude the sentence names: the scaled one times the scale is the stated one
    stated = SCALE * scaled
    assert any(abs(SCALE * value - stated) <= 1e-5 * stated for value in numbers(text) if value != stated)
    if cycle == "wing_period":
        assert "harmonic at 400 Hz" in text and "half the peak-to-peak" in text
        # the multibody wing amplitude is named as such, apart from the harmonic the scale applies to
        assert re.search(r"multibody wing amplitude \(half the peak-to-peak[^)]*\) is "
                         + re.escape(f"{half_peak_to_peak:.6g} mm"), text)
    else:
        assert "half the peak-to-peak" in text
