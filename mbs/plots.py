"""PNG plots of a run: wing time history, spectrum / order spectrum, Campbell diagram, sweep."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402 (backend must be chosen first)
import numpy as np  # noqa: E402

from mbs.campbell import Campbell  # noqa: E402
from mbs.histories import RunHistories  # noqa: E402
from mbs.spectra import Spectrum  # noqa: E402


def _save(figure, path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path


def plot_time_history(histories: RunHistories, path) -> Path:
    """Wing-tip axial motion of both CWs (micrometres) over shaft revolutions."""
    figure, axes = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
    revolutions = (histories.crank_angle - histories.crank_angle[0]) / (2.0 * np.pi)
    for c, ax in enumerate(axes):
        ax.plot(revolutions, 1e3 * histories.cw_wing_tip_axial[c, :, 0], lw=0.8, label="-x wing tip")
        ax.plot(revolutions, 1e3 * histories.cw_wing_tip_axial[c, :, 1], lw=0.8, label="+x wing tip")
        ax.set_ylabel(f"CW{c + 1} axial tip (um)")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("shaft revolutions")
    return _save(figure, path)


def plot_spectrum(spectrum: Spectrum, path, *, xlabel: str = "frequency (Hz)", title: str = "",
                  x_max: float | None = None) -> Path:
    """Amplitude spectrum (micrometres) on a log scale, up to x_max (default: Nyquist)."""
    figure, ax = plt.subplots(figsize=(8, 4))
    amplitude = np.atleast_2d(np.asarray(spectrum.amplitude).T).T
    shown = spectrum.frequency <= (np.inf if x_max is None else x_max)
    for k in range(amplitude.shape[1]):
        ax.semilogy(spectrum.frequency[shown], 1e3 * amplitude[shown, k] + 1e-12, lw=0.8, label=f"CW{k + 1}")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("amplitude (um)")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return _save(figure, path)


def plot_campbell(campbell: Campbell, path, *, operating_rpm: float | None = None) -> Path:
    """Mode lines (reduced CW black, coupled model grey) and engine-order lines over speed;
    crossings with the coupled-model modes marked red, with the CW modes as open circles."""
    figure, ax = plt.subplots(figsize=(7, 5))
    for mode in range(campbell.frequencies.shape[1]):
        ax.plot(campbell.speeds_rpm, campbell.frequencies[:, mode], "k-", lw=1.2,
                label="reduced CW (interface held)" if mode == 0 else None)
    f_max = 1.15 * campbell.frequencies.max()
    if campbell.system_frequencies is not None:
        system = campbell.system_frequencies
        for mode in range(system.shape[1]):
            ax.plot(campbell.speeds_rpm, system[:, mode], "-", color="0.6", lw=0.8,
                    label="coupled multibody model" if mode == 0 else None)
    for order in campbell.orders:
        ax.plot(campbell.speeds_rpm, order * campbell.speeds_rpm / 60.0, "--", lw=0.7, label=f"order {order:g}")
    for crossing in campbell.crossings:
        ax.plot(crossing["speed_rpm"], crossing["frequency_hz"], "ko", ms=6, mfc="none")
    for crossing in campbell.system_crossings:
        ax.plot(crossing["speed_rpm"], crossing["frequency_hz"], "ro", ms=4)
    if operating_rpm is not None:
        ax.axvline(operating_rpm, color="gray", lw=0.8)
    ax.set_ylim(0.0, f_max)
    ax.set_xlabel("engine speed (rpm)")
    ax.set_ylabel("frequency (Hz)")
    ax.set_title("Campbell diagram (rotating frame)")
    if len(campbell.orders) <= 12:
        ax.legend(fontsize=7, loc="upper left")
    ax.grid(True, alpha=0.3)
    return _save(figure, path)


def plot_sweep(speeds_rpm, wing_amplitude, path, *, crossings_rpm=()) -> Path:
    """Wing torsion amplitude (micrometres) per engine speed, Campbell crossings marked."""
    figure, ax = plt.subplots(figsize=(7, 4))
    amplitude = np.atleast_2d(np.asarray(wing_amplitude).T).T
    for c in range(amplitude.shape[1]):
        ax.plot(speeds_rpm, 1e3 * amplitude[:, c], "o-", ms=3, label=f"CW{c + 1}")
    for speed in crossings_rpm:
        ax.axvline(speed, color="r", lw=0.8, ls=":")
    ax.set_xlabel("engine speed (rpm)")
    ax.set_ylabel("wing torsion amplitude (um)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return _save(figure, path)
