"""PNG plots of a run: wing time history, spectrum / order spectrum, Campbell diagram, sweep."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402 (backend must be chosen first)
import numpy as np  # noqa: E402

from mbs.campbell import Campbell  # noqa: E402
from mbs.histories import SETTLED_CHANGE, RunHistories, steady_part  # noqa: E402
from mbs.spectra import Spectrum  # noqa: E402


def _save(figure, path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path


def plot_time_history(histories: RunHistories, path) -> Path:
    """Wing-tip axial motion and wing torsion of every CW (µm) over the steady part of the run
    (:func:`mbs.histories.steady_part`, where the wing amplitude is measured), against shaft
    revolutions from the start of the run; the start-up transient before it is left out."""
    n_cw = histories.cw_wing_tip_axial.shape[0]
    steady = steady_part(len(histories.time))
    figure, axes = plt.subplots(n_cw, 1, figsize=(8, 1.2 + 2.2 * n_cw), sharex=True, squeeze=False)
    revolutions = ((histories.crank_angle - histories.crank_angle[0]) / (2.0 * np.pi))[steady]
    amplitudes = histories.wing_amplitude
    for c, ax in enumerate(axes[:, 0]):
        ax.plot(revolutions, 1e3 * histories.cw_wing_tip_axial[c, steady, 0], lw=0.8, label="-x wing tip")
        ax.plot(revolutions, 1e3 * histories.cw_wing_tip_axial[c, steady, 1], lw=0.8, label="+x wing tip")
        ax.plot(revolutions, 1e3 * histories.wing_torsion[c, steady], "k", lw=1.0,
                label=f"wing torsion (u+x - u-x)/2, amplitude {1e3 * amplitudes[c]:.3g} µm")
        ax.set_ylabel(f"CW{c + 1} axial motion (µm)")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=7)
    change = histories.unsettled_change
    steadiness = ("NOT STEADY: too short to check" if change is None else
                  f"amplitude over its first and last engine cycle within {100 * change:.1f} %"
                  if change <= SETTLED_CHANGE else
                  f"NOT STEADY: amplitude over its first and last engine cycle differs by {100 * change:.0f} %")
    axes[0, 0].set_title("wing tips over the second half of the run, where the wing amplitude is measured\n"
                         f"({steadiness})", fontsize=9, color="k" if change is not None and change <= SETTLED_CHANGE
                         else "tab:red")
    axes[-1, 0].set_xlabel("shaft revolutions from the start of the run (rev)")
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
    ax.set_ylabel("amplitude (µm)")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return _save(figure, path)


def _crossing_orders(campbell: Campbell) -> set:
    return {crossing["order"] for crossing in campbell.crossings + campbell.system_crossings}


def plot_campbell(campbell: Campbell, path, *, operating_rpm: float | None = None) -> Path:
    """Mode lines (reduced CW black, coupled model grey) and engine-order lines over speed;
    crossings with the coupled-model modes marked red, with the CW modes as open circles.

    The legend names every line kind: each order that crosses a mode line in its own colour,
    the orders that cross none (a gas-torque series) as one grey entry when there are many."""
    figure, ax = plt.subplots(figsize=(10, 5.5))
    for mode in range(campbell.frequencies.shape[1]):
        ax.plot(campbell.speeds_rpm, campbell.frequencies[:, mode], "k-", lw=1.2,
                label=f"CW modes, interface held ({campbell.frequencies.shape[1]})" if mode == 0 else None)
    f_max = 1.15 * campbell.frequencies.max()
    if campbell.system_frequencies is not None:
        system = campbell.system_frequencies
        found = np.flatnonzero(np.isfinite(system).any(axis=0))  # a mode no speed found is no line
        for mode in found:
            ax.plot(campbell.speeds_rpm, system[:, mode], "-", color="0.6", lw=0.8,
                    label=f"coupled multibody model modes ({found.size})" if mode == found[0] else None)
    crossing = _crossing_orders(campbell)
    quiet = [order for order in campbell.orders if order not in crossing]
    grouped = len(campbell.orders) > 6 and len(quiet) > 1
    colours = iter(plt.rcParams["axes.prop_cycle"].by_key()["color"] * 4)
    for order in campbell.orders:
        line = order * campbell.speeds_rpm / 60.0
        if grouped and order in quiet:
            label = (f"engine orders {min(quiet):g} … {max(quiet):g} ({len(quiet)}, no crossing)"
                     if order == quiet[0] else None)
            ax.plot(campbell.speeds_rpm, line, "--", color="0.45", lw=0.6, label=label)
        else:
            ax.plot(campbell.speeds_rpm, line, "--", color=next(colours), lw=1.0,
                    label=f"engine order {order:g} (f = {order:g} · rpm / 60)")
    if campbell.crossings:
        ax.plot([c["speed_rpm"] for c in campbell.crossings], [c["frequency_hz"] for c in campbell.crossings],
                "ko", ms=7, mfc="none", ls="none", label="order crosses a CW mode")
    if campbell.system_crossings:
        ax.plot([c["speed_rpm"] for c in campbell.system_crossings],
                [c["frequency_hz"] for c in campbell.system_crossings],
                "ro", ms=4, ls="none", label="order crosses a coupled mode (resonance)")
    if operating_rpm is not None:
        ax.axvline(operating_rpm, color="k", lw=0.9, ls=":", label=f"operating speed {operating_rpm:g} rpm")
    ax.set_ylim(0.0, f_max)
    ax.set_xlabel("engine speed (rpm)")
    ax.set_ylabel("frequency (Hz)")
    ax.set_title("Campbell diagram (rotating frame)")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    ax.grid(True, alpha=0.3)
    return _save(figure, path)


def plot_sweep(speeds_rpm, wing_amplitude, path, *, crossings_rpm=()) -> Path:
    """Wing torsion amplitude (micrometres) per engine speed, Campbell crossings marked."""
    figure, ax = plt.subplots(figsize=(7, 4))
    amplitude = np.atleast_2d(np.asarray(wing_amplitude).T).T
    for c in range(amplitude.shape[1]):
        ax.plot(speeds_rpm, 1e3 * amplitude[:, c], "o-", ms=3, label=f"CW{c + 1}")
    for k, speed in enumerate(crossings_rpm):
        ax.axvline(speed, color="r", lw=0.8, ls=":", label="Campbell crossing (resonance)" if k == 0 else None)
    ax.set_xlabel("engine speed (rpm)")
    ax.set_ylabel("wing torsion amplitude (µm)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return _save(figure, path)
