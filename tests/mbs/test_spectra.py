"""Spectra: amplitude scaling against known sinusoids, peak refinement, order axis."""

import numpy as np
import pytest

from mbs.spectra import amplitude_spectrum, dominant_frequencies, order_spectrum, peak_frequency
from reduction.errors import InputError

RATE = 2000.0


def _time(duration):
    return np.arange(int(round(duration * RATE))) / RATE


def test_rectangular_window_reads_the_amplitude_of_a_periodic_sinusoid():
    time = _time(1.0)
    signal = 0.3 + 2.5 * np.sin(2 * np.pi * 50.0 * time) + 0.7 * np.cos(2 * np.pi * 120.0 * time)
    spectrum = amplitude_spectrum(time, signal, window="rectangular", detrend=False)
    assert spectrum.amplitude[0] == pytest.approx(0.3, rel=1e-9)
    assert spectrum.amplitude[spectrum.frequency == 50.0][0] == pytest.approx(2.5, rel=1e-9)
    assert spectrum.amplitude[spectrum.frequency == 120.0][0] == pytest.approx(0.7, rel=1e-9)


def test_hann_window_is_corrected_by_its_coherent_gain():
    time = _time(1.0)
    spectrum = amplitude_spectrum(time, 1.8 * np.sin(2 * np.pi * 40.0 * time))
    assert spectrum.amplitude.max() == pytest.approx(1.8, rel=1e-3)
    assert spectrum.frequency[np.argmax(spectrum.amplitude)] == 40.0


def test_peak_frequency_resolves_far_below_the_bin_width():
    time = _time(0.5)  # bin width 2 Hz
    true = 123.37
    estimate = peak_frequency(time, np.sin(2 * np.pi * true * time + 0.4), band=(50, 500))
    assert abs(estimate - true) < 0.05 * 2.0


def test_order_spectrum_puts_half_orders_on_their_lines():
    speed = 2 * np.pi * 12.5  # 750 rpm
    time = _time(8 * 2 * np.pi / speed)
    signal = 0.9 * np.cos(1.5 * speed * time) + 0.2 * np.cos(4.0 * speed * time)
    spectrum = order_spectrum(time, signal, speed, window="rectangular")
    assert spectrum.frequency[np.argmax(spectrum.amplitude)] == pytest.approx(1.5)
    assert spectrum.amplitude.max() == pytest.approx(0.9, rel=1e-2)
    strongest = dominant_frequencies(spectrum, count=2)
    assert strongest == pytest.approx([1.5, 4.0])


def test_nonuniform_sampling_is_rejected_with_a_clear_message():
    with pytest.raises(InputError, match="not uniform"):
        amplitude_spectrum([0.0, 0.1, 0.3], [1.0, 2.0, 3.0])
