"""One complete multibody run: simulate, analyse (spectra, order spectrum, Campbell), write HDF5
and PNG plots. The pipeline and the CLI call this; it returns data and paths, it prints nothing."""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from mbs.campbell import Campbell, campbell_diagram
from mbs.counterweight import ReducedCounterweight
from mbs.excitation import excitation_orders
from mbs.histories import RunHistories, steady_part
from mbs.model import reduce_bodies, simulate, system_eigenfrequencies
from mbs.parameters import ModelParams
from mbs.plots import plot_campbell, plot_spectrum, plot_time_history
from mbs.results import write_run
from mbs.spectra import Spectrum, amplitude_spectrum, order_spectrum
from mbs.sweep import N_SYSTEM_MODES


@dataclass(frozen=True)
class RunOutputs:
    """Histories and analyses of one run; results_file (HDF5) and plots (name -> PNG path)."""

    histories: RunHistories
    reduced: ReducedCounterweight
    spectra: dict[str, Spectrum]
    campbell: Campbell
    results_file: Path
    plots: dict[str, Path]


def run_model(params: ModelParams, out_dir, *, bodies: tuple | None = None, campbell_speeds_rpm=None,
              scene: str | None = None, stated_wing_amplitude_mm: float | None = None,
              counterweight: int = 1) -> RunOutputs:
    """Simulate params, analyse the steady second half of the run and write run.h5 + PNGs to out_dir.

    bodies: (reduced CW, reduced throw or None) from :func:`mbs.model.reduce_bodies`; reduced here if None.

    scene: its name, for the time-history plot's title. stated_wing_amplitude_mm: the wing
    amplitude a coupled scene states for its CW ``counterweight`` (1 = first), the run being at the
    scene's speed; the time-history plot then names the calibrated amplitudes beside the raw ones
    (:func:`calibration`).

    campbell_speeds_rpm: speeds of the Campbell diagram (default 0.1 to 1.3 x engine speed); the
    diagram carries the reduced-CW modes and the coupled-model modes (one eigen-analysis per speed).
    Spectra: wing torsion of both CWs (frequency axis, Hz) and its order spectrum over the last
    whole revolutions of the second half.
    """
    out_dir = Path(out_dir)
    reduced, reduced_throw = bodies if bodies is not None else reduce_bodies(params)
    histories = simulate(params, reduced=reduced, reduced_throw=reduced_throw)
    steady = steady_part(len(histories.time))
    torsion = histories.wing_torsion[:, steady].T
    spectra = {"wing_torsion": amplitude_spectrum(histories.time[steady], torsion)}
    revolution = 2.0 * np.pi / params.shaft_speed
    steady_duration = histories.time[-1] - histories.time[steady][0] + params.solver.time_step
    if steady_duration >= revolution * (1.0 - 1e-9):
        spectra["wing_torsion_orders"] = order_spectrum(histories.time[steady], torsion, params.shaft_speed)
    speeds = campbell_speeds_rpm if campbell_speeds_rpm is not None else np.linspace(0.1, 1.3, 14) * params.speed_rpm
    orders = excitation_orders(params.excitation, params.effects)
    system = [system_eigenfrequencies(replace(params, speed_rpm=float(s)), reduced, max_frequency=np.inf,
                                      reduced_throw=reduced_throw)[:N_SYSTEM_MODES]
              for s in speeds]
    # as the sweep holds them: one column per mode, NaN at a speed where the solve found fewer
    system_frequencies = np.full((len(system), max(len(f) for f in system)), np.nan)
    for row, frequencies in zip(system_frequencies, system):
        row[:len(frequencies)] = frequencies
    campbell = campbell_diagram(reduced, speeds, orders, system_frequencies=system_frequencies)
    shaft_hz = params.speed_rpm / 60.0
    f_max = 1.25 * max(reduced.eigenfrequencies.max(), (orders.max() if orders.size else 0.0) * shaft_hz)
    factor = calibration(histories, stated_wing_amplitude_mm, counterweight)
    named = f"{scene}: " if scene else ""
    plots = {
        "time_history": plot_time_history(histories, out_dir / "wing_time_history.png", scene=scene,
                                          calibration=factor),
        "spectrum": plot_spectrum(spectra["wing_torsion"], out_dir / "wing_spectrum.png",
                                  title=f"{named}wing torsion spectrum at {params.speed_rpm:g} rpm", x_max=f_max,
                                  calibration=factor),
        "campbell": plot_campbell(campbell, out_dir / "campbell.png", operating_rpm=params.speed_rpm),
    }
    if "wing_torsion_orders" in spectra:
        plots["order_spectrum"] = plot_spectrum(spectra["wing_torsion_orders"], out_dir / "wing_order_spectrum.png",
                                                xlabel="engine order (cycles per revolution)",
                                                title=f"{named}wing torsion order spectrum at {params.speed_rpm:g} rpm",
                                                x_max=f_max / shaft_hz, calibration=factor)
    # last: a run interrupted before its end leaves no results file (plots without one are not a result)
    results_file = write_run(out_dir / "run.h5", params, reduced, histories, spectra, campbell)
    return RunOutputs(histories=histories, reduced=reduced, spectra=spectra, campbell=campbell,
                      results_file=results_file, plots=plots)


def calibration(histories: RunHistories, stated_wing_amplitude_mm: float | None,
                counterweight: int = 1) -> float | None:
    """The factor a coupled scene multiplies this run's amplitudes by: its stated wing amplitude
    (mm) over this run's wing amplitude of its CW ``counterweight`` (1 = first); None when it
    states none, or the run has no such CW or no wing vibration to scale."""
    if stated_wing_amplitude_mm is None or not 1 <= counterweight <= len(histories.wing_amplitude):
        return None
    raw = float(histories.wing_amplitude[counterweight - 1])
    return stated_wing_amplitude_mm / raw if raw > 0 else None
