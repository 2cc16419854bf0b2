"""PNG plots of a run: wing time history, spectrum / order spectrum, Campbell diagram, sweep."""

from __future__ import annotations

import textwrap
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


def plot_time_history(histories: RunHistories, path, *, scene: str | None = None,
                      calibration: float | None = None) -> Path:
    """Wing-tip axial motion and wing torsion of every CW (µm) over the steady part of the run
    (:func:`mbs.histories.steady_part`, where the wing amplitude is measured), against shaft
    revolutions from the start of the run; the start-up transient before it is left out.

    The values are the multibody model's own, uncalibrated, and said to be. scene: its name, for
    the title. calibration: the factor a coupled scene multiplies this run's amplitudes by (its
    stated wing amplitude / this run's wing amplitude of its CW, the run being at its speed); the
    calibrated amplitudes are then named beside the raw ones."""
    n_cw = histories.cw_wing_tip_axial.shape[0]
    steady = steady_part(len(histories.time))
    figure, axes = plt.subplots(n_cw, 1, figsize=(10.5, 1.6 + 2.2 * n_cw), sharex=True, squeeze=False)
    revolutions = ((histories.crank_angle - histories.crank_angle[0]) / (2.0 * np.pi))[steady]
    amplitudes = histories.wing_amplitude
    for c, ax in enumerate(axes[:, 0]):
        ax.plot(revolutions, 1e3 * histories.cw_wing_tip_axial[c, steady, 0], lw=0.8, label="-x wing tip")
        ax.plot(revolutions, 1e3 * histories.cw_wing_tip_axial[c, steady, 1], lw=0.8, label="+x wing tip")
        label = f"wing torsion (u+x - u-x)/2,\nraw amplitude {1e3 * amplitudes[c]:.3g} µm"
        if calibration is not None:
            label += f"\n× calibration {calibration:.4g} → {1e3 * calibration * amplitudes[c]:.3g} µm"
        ax.plot(revolutions, 1e3 * histories.wing_torsion[c, steady], "k", lw=1.0, label=label)
        ax.set_ylabel(f"CW{c + 1} axial motion,\nraw (µm)")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, fontsize=7)
    change = histories.unsettled_change
    steadiness = ("NOT STEADY: too short to check" if change is None else
                  f"amplitude over its first and last engine cycle within {100 * change:.1f} %"
                  if change <= SETTLED_CHANGE else
                  f"NOT STEADY: amplitude over its first and last engine cycle differs by {100 * change:.0f} %")
    speed_rpm = 60.0 * float(np.mean(histories.crank_speed)) / (2.0 * np.pi)
    raw = ("multibody model's raw wing motion, uncalibrated" if calibration is None else
           "multibody model's raw wing motion; × calibration → the scene's wing amplitude")
    axes[0, 0].set_title(f"{scene + ': ' if scene else ''}wing tips at {speed_rpm:.0f} rpm ({raw})\n"
                         "second half of the run, where the wing amplitude is measured "
                         f"({steadiness})", fontsize=9, color="k" if change is not None and change <= SETTLED_CHANGE
                         else "tab:red")
    axes[-1, 0].set_xlabel("shaft revolutions from the start of the run (rev)")
    return _save(figure, path)


def plot_spectrum(spectrum: Spectrum, path, *, xlabel: str = "frequency (Hz)", title: str = "",
                  x_max: float | None = None, calibration: float | None = None) -> Path:
    """Amplitude spectrum (micrometres) on a log scale, up to x_max (default: Nyquist): the
    multibody model's raw amplitudes, and said to be on the axis and under the title.
    calibration: the factor a coupled scene multiplies them by (:func:`mbs.run.calibration`), named
    under the title."""
    figure, ax = plt.subplots(figsize=(8, 4.3))
    amplitude = np.atleast_2d(np.asarray(spectrum.amplitude).T).T
    shown = spectrum.frequency <= (np.inf if x_max is None else x_max)
    for k in range(amplitude.shape[1]):
        ax.semilogy(spectrum.frequency[shown], 1e3 * amplitude[shown, k] + 1e-12, lw=0.8, label=f"CW{k + 1}")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("multibody amplitude,\nraw (µm)")
    raw = ("the multibody model's raw amplitudes, uncalibrated" if calibration is None else
           f"the multibody model's raw amplitudes; the scene's coupling multiplies them by {calibration:.4g}")
    ax.set_title(f"{title}\n{raw}" if title else raw, fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return _save(figure, path)


def _crossing_orders(campbell: Campbell) -> set:
    return {crossing["order"] for crossing in campbell.crossings + campbell.system_crossings}


def plot_campbell(campbell: Campbell, path, *, operating_rpm: float | None = None) -> Path:
    """Mode lines (reduced CW black, coupled model grey) and engine-order lines over speed;
    crossings with the coupled-model modes marked red, with the CW modes as open circles. A
    crossing is where an order's frequency meets a mode's; whether the response is amplified
    there is for a sweep's amplitudes to show, so it is not called a resonance here.

    The legend names every line kind: each order that crosses a mode line in its own colour,
    the orders that cross none (a gas-torque series) as one grey entry when there are many; those
    are drawn again in a zoomed panel below, each named by its order."""
    crossing = _crossing_orders(campbell)
    quiet = [order for order in campbell.orders if order not in crossing]
    grouped = len(campbell.orders) > 6 and len(quiet) > 1
    if grouped:
        figure, (ax, zoom) = plt.subplots(2, 1, figsize=(12, 7.5), sharex=True, height_ratios=(3, 1.4))
    else:
        figure, ax = plt.subplots(figsize=(12, 5.5))
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
    colours = iter(plt.rcParams["axes.prop_cycle"].by_key()["color"] * 4)
    for order in campbell.orders:
        line = order * campbell.speeds_rpm / 60.0
        if grouped and order in quiet:
            label = (f"engine orders {min(quiet):g} … {max(quiet):g} ({len(quiet)}, no crossing; zoomed below)"
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
                "ro", ms=4, ls="none", label="order crosses a coupled mode (a crossing, not a shown resonance)")
    if operating_rpm is not None:
        ax.axvline(operating_rpm, color="k", lw=0.9, ls=":", label=f"operating speed {operating_rpm:g} rpm")
    ax.set_ylim(0.0, f_max)
    ax.set_ylabel("frequency (Hz)")
    ax.set_title("Campbell diagram (rotating frame)")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    ax.grid(True, alpha=0.3)
    if grouped:
        _zoomed_orders(zoom, campbell, quiet, operating_rpm)
    (zoom if grouped else ax).set_xlabel("engine speed (rpm)")
    return _save(figure, path)


def _zoomed_orders(ax, campbell: Campbell, orders: list, operating_rpm: float | None) -> None:
    """The engine orders that cross no mode, on their own frequency scale, each named at its
    right end (every k-th when they lie closer than a label's height)."""
    speeds = campbell.speeds_rpm
    top = 1.1 * max(orders) * speeds.max() / 60.0
    for order in orders:
        ax.plot(speeds, order * speeds / 60.0, "--", color="0.45", lw=0.7)
    modes = [campbell.frequencies] + ([campbell.system_frequencies] if campbell.system_frequencies is not None else [])
    for frequencies in modes:  # a mode low enough to meet them would show here
        for mode in frequencies.T:
            if np.any(mode <= top):  # NaN where a speed's solve did not find the mode
                ax.plot(speeds, mode, "-", color="0.6", lw=0.8)
    spacing_hz = min(np.diff(sorted(orders))) * speeds.max() / 60.0
    height_pt = ax.get_position().height * ax.figure.get_figheight() * 72.0
    every = max(1, int(np.ceil(8.0 / (spacing_hz * height_pt / top))))  # 8 pt: a 7 pt label's height
    for order in sorted(orders)[every - 1::every]:
        ax.annotate(f"{order:g}", (speeds.max(), order * speeds.max() / 60.0), xytext=(3, 0),
                    textcoords="offset points", va="center", fontsize=7, annotation_clip=False)
    if operating_rpm is not None:
        ax.axvline(operating_rpm, color="k", lw=0.9, ls=":")
    ax.set_ylim(0.0, top)
    ax.set_ylabel("frequency (Hz)")
    ax.set_title(f"engine orders {min(orders):g} … {max(orders):g} that cross no mode, zoomed "
                 f"(each named by its order{'' if every == 1 else f', every {every}th'})", fontsize=9)
    ax.grid(True, alpha=0.3)


def _peak_speeds(speeds_rpm: np.ndarray, amplitude: np.ndarray) -> np.ndarray:
    """Speeds (rpm) where some CW's wing amplitude is higher than at both neighbouring speeds."""
    higher = (amplitude[1:-1] > amplitude[:-2]) & (amplitude[1:-1] > amplitude[2:])
    return speeds_rpm[1:-1][higher.any(axis=1)]


def plot_sweep(speeds_rpm, wing_amplitude, path, *, crossings_rpm=(), calibration: float | None = None,
               calibration_note: str = "") -> Path:
    """The multibody model's raw wing torsion amplitude (micrometres) per engine speed, order/mode
    crossings marked: a resonance where the amplitude peaks within half a sweep step of the
    crossing, else a crossing only.

    calibration: the factor a coupled scene multiplies these amplitudes by (its stated wing
    amplitude / the multibody amplitude at its speed), drawn as a right-hand axis of the scene's
    wing amplitude; calibration_note: where it comes from, or, without a factor, how the scene
    would calibrate."""
    figure, ax = plt.subplots(figsize=(8, 4.6))
    speeds = np.asarray(speeds_rpm, dtype=float)
    amplitude = np.atleast_2d(np.asarray(wing_amplitude).T).T
    for c in range(amplitude.shape[1]):
        ax.plot(speeds, 1e3 * amplitude[:, c], "o-", ms=3, label=f"CW{c + 1}")
    peaks = _peak_speeds(speeds, amplitude)
    half_step = 0.5 * float(np.min(np.diff(np.sort(speeds)))) if len(speeds) > 1 else 0.0
    labelled = set()
    for speed in crossings_rpm:
        resonant = bool(np.any(np.abs(peaks - speed) <= half_step))
        label = ("order/mode crossing at an amplitude peak (resonance)" if resonant else
                 "order/mode crossing (no amplitude peak in the sweep)")
        ax.axvline(speed, color="r" if resonant else "0.4", lw=0.8, ls="-" if resonant else ":",
                   label=None if label in labelled else label)
        labelled.add(label)
    ax.set_xlabel("engine speed (rpm)")
    ax.set_ylabel("multibody wing torsion amplitude,\nraw (µm)")
    if calibration is not None:
        scene_axis = ax.secondary_yaxis("right", functions=(lambda a: a * calibration, lambda a: a / calibration))
        scene_axis.set_ylabel(f"the scene's wing amplitude,\nraw × calibration {calibration:.4g} (µm)")
    ax.set_title("wing torsion amplitude of the multibody model: raw, uncalibrated"
                 + (f"\n{textwrap.fill(calibration_note, 100)}" if calibration_note else ""), fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return _save(figure, path)
