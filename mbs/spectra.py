"""Spectra of uniformly sampled histories: amplitude spectrum, order spectrum, peak frequency.

Amplitude scaling: a sinusoid A sin(2 pi f t) sampled over a whole number of periods shows a
peak of height A (single-sided spectrum, DC not doubled). With a Hann window the spectrum is
divided by the window's coherent gain (mean of the window), so a bin-centred sinusoid still
reads A. Units follow the signal (mm in, mm out); frequencies in Hz, orders in multiples of
shaft speed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from reduction.errors import InputError


@dataclass(frozen=True)
class Spectrum:
    """Single-sided amplitude spectrum. frequency (n_f,) Hz; amplitude (n_f,) or (n_f, k)."""

    frequency: np.ndarray
    amplitude: np.ndarray

    def orders(self, shaft_frequency: float) -> np.ndarray:
        """Frequency axis in engine orders (multiples of the shaft frequency in Hz)."""
        return self.frequency / shaft_frequency


def _sample_period(time: np.ndarray) -> float:
    steps = np.diff(np.asarray(time, dtype=float))
    if steps.size == 0 or np.any(steps <= 0):
        raise InputError("signal time must be strictly increasing with at least two samples")
    step = float(np.mean(steps))
    if np.max(np.abs(steps - step)) > 1e-6 * step:
        raise InputError("signal time step is not uniform; spectra need a fixed sample rate")
    return step


def amplitude_spectrum(time, signal, *, window: str = "hann", detrend: bool = True) -> Spectrum:
    """Single-sided amplitude spectrum of signal (n,) or (n, k) sampled at time (n,), s.

    window: "hann" (leakage control, amplitude corrected by coherent gain) or "rectangular"
    (exact for signals periodic in the record). detrend removes the mean before windowing.
    """
    values = np.asarray(signal, dtype=float)
    if values.shape[0] != len(time):
        raise InputError(f"signal has {values.shape[0]} samples but time has {len(time)}")
    step = _sample_period(np.asarray(time))
    n = values.shape[0]
    if detrend:
        values = values - values.mean(axis=0)
    if window == "hann":
        weights = np.hanning(n)
    elif window == "rectangular":
        weights = np.ones(n)
    else:
        raise InputError(f"unknown spectrum window {window!r}; use 'hann' or 'rectangular'")
    shape = (n,) + (1,) * (values.ndim - 1)
    transform = np.fft.rfft(values * weights.reshape(shape), axis=0)
    amplitude = np.abs(transform) / weights.sum()
    amplitude[1:] *= 2.0
    if n % 2 == 0:
        amplitude[-1] /= 2.0  # the Nyquist bin has no mirror image
    return Spectrum(frequency=np.fft.rfftfreq(n, step), amplitude=amplitude)


def peak_frequency(time, signal, *, band: tuple[float, float] | None = None) -> float:
    """Frequency (Hz) of the largest spectral peak of a 1-D signal, refined between bins.

    Hann window, then a parabola through the log-amplitudes of the peak bin and its neighbours
    (accurate to a small fraction of a bin for a single dominant sinusoid). band: (f_min, f_max)
    in Hz restricts the search.
    """
    spectrum = amplitude_spectrum(time, signal)
    amplitude = spectrum.amplitude
    mask = np.ones_like(amplitude, dtype=bool)
    mask[0] = False
    if band is not None:
        mask &= (spectrum.frequency >= band[0]) & (spectrum.frequency <= band[1])
    if not mask[1:-1].any():
        raise InputError(f"no spectral line inside band {band} Hz")
    candidates = np.nonzero(mask[1:-1])[0] + 1
    peak = candidates[np.argmax(amplitude[candidates])]
    left, centre, right = np.log(amplitude[peak - 1: peak + 2] + 1e-300)
    curvature = left - 2.0 * centre + right
    shift = 0.5 * (left - right) / curvature if curvature < 0 else 0.0
    bin_width = spectrum.frequency[1] - spectrum.frequency[0]
    return float(spectrum.frequency[peak] + shift * bin_width)


def dominant_frequencies(spectrum: Spectrum, count: int = 3, min_separation: float = 0.0) -> np.ndarray:
    """Frequencies (Hz) of the `count` largest local maxima of a 1-D amplitude spectrum,
    strongest first, at least min_separation Hz apart."""
    amplitude = np.asarray(spectrum.amplitude)
    if amplitude.ndim != 1:
        raise InputError("dominant_frequencies needs a spectrum of one signal")
    inner = np.nonzero((amplitude[1:-1] >= amplitude[:-2]) & (amplitude[1:-1] > amplitude[2:]))[0] + 1
    chosen: list[float] = []
    for index in inner[np.argsort(amplitude[inner])[::-1]]:
        frequency = float(spectrum.frequency[index])
        if all(abs(frequency - other) >= min_separation for other in chosen):
            chosen.append(frequency)
        if len(chosen) == count:
            break
    return np.asarray(chosen)


def order_spectrum(time, signal, shaft_speed: float, *, window: str = "hann") -> Spectrum:
    """Amplitude spectrum over a whole number of shaft revolutions, axis in engine orders.

    shaft_speed: rad/s (constant). The record is cut to the last whole number of revolutions so
    that integer and half orders fall on bins when the record holds an even number of them.
    Returns a Spectrum whose `frequency` field holds orders.
    """
    time = np.asarray(time, dtype=float)
    step = _sample_period(time)
    revolution = 2.0 * np.pi / shaft_speed
    n_revolutions = int(np.floor((time[-1] - time[0] + step) / revolution + 1e-9))
    if n_revolutions < 1:
        raise InputError("order analysis needs at least one full shaft revolution of signal")
    n = int(round(n_revolutions * revolution / step))
    spectrum = amplitude_spectrum(time[-n:], np.asarray(signal)[-n:], window=window)
    return Spectrum(frequency=spectrum.frequency * revolution, amplitude=spectrum.amplitude)
