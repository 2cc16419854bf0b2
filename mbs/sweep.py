"""Engine-speed sweep: wing amplitude and dominant frequencies per speed, order/mode crossings.

Each speed is one case (:func:`run_speed`): a fixed-step run of the model plus the coupled
eigenfrequencies at that speed. :func:`collect_sweep` gathers the cases into a
:class:`SweepResult` and :func:`write_sweep` stores it; running the cases (in parallel, on a
cluster) is the pipeline's job (``pipelines.jobs.sweep``). Amplitudes and spectra use the
steady state of every run (:mod:`mbs.histories`). A speed whose time integration fails is
recorded in ``failures`` and the sweep goes on; a speed whose response is not steady in the
measuring window (:func:`mbs.histories.unsettled_change`) is recorded in ``unsettled``, its
amplitude kept but not to be trusted. Units: rpm, Hz, mm.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

from mbs.campbell import Campbell, campbell_diagram
from mbs.excitation import excitation_orders
from mbs.histories import steady_part, unsettled_message
from mbs.model import SimulationError, simulate, system_eigenfrequencies
from mbs.parameters import ModelParams
from mbs.results import FORMAT_VERSION, SWEEP_FORMAT, write_campbell
from mbs.spectra import amplitude_spectrum, dominant_frequencies

#: Number of dominant frequencies recorded per speed and number of system modes kept.
N_DOMINANT = 3
N_SYSTEM_MODES = 24


@dataclass(frozen=True)
class SweepResult:
    """speeds_rpm (n,); wing_amplitude (n, number of CWs) mm: half peak-to-peak of the wing torsion of CW1,
    CW2 in the evaluation window (NaN where the run failed); dominant_frequencies (n, 3) Hz of the
    CW1 wing torsion, strongest first; dominant_orders (n, 3) the same in engine orders;
    real_time_factor (n,); system_frequencies (n, N_SYSTEM_MODES) Hz: coupled model eigenfrequencies;
    crossings: engine-order lines meeting system modes (dicts: order, mode, speed_rpm,
    frequency_hz); resonance: (n,) True where a crossing lies within half a sweep step (a crossing:
    a resonance only where the amplitude peaks there; the name kept for compatibility);
    failures: {speed_rpm: message}; campbell: the Campbell diagram (reduced CW and system).
    unsettled_change (n,): how far each run was from steady (:func:`mbs.histories.unsettled_change`;
    NaN where the run was too short to tell or failed); unsettled: {speed_rpm: message} for the
    speeds whose amplitude is not to be trusted (not steady, or too short to tell).
    """

    speeds_rpm: np.ndarray
    wing_amplitude: np.ndarray
    dominant_frequencies: np.ndarray
    dominant_orders: np.ndarray
    real_time_factor: np.ndarray
    system_frequencies: np.ndarray
    crossings: list
    resonance: np.ndarray
    failures: dict
    campbell: Campbell
    unsettled_change: np.ndarray | None = None
    unsettled: dict | None = None

    def peak_speed(self, counterweight: int = 0) -> float:
        """Speed (rpm) of the largest wing amplitude among the converged runs."""
        return float(self.speeds_rpm[np.nanargmax(self.wing_amplitude[:, counterweight])])

    def to_json(self) -> dict:
        """Plain summary for --json output."""
        return {
            "speeds_rpm": self.speeds_rpm.tolist(),
            "wing_amplitude_mm": [[None if np.isnan(v) else float(v) for v in row] for row in self.wing_amplitude],
            "dominant_frequencies_hz": [[None if np.isnan(v) else float(v) for v in row] for row in self.dominant_frequencies],
            "resonance": self.resonance.tolist(),
            "crossings": self.crossings,
            "failures": {str(k): v for k, v in self.failures.items()},
            "unsettled": {str(k): v for k, v in (self.unsettled or {}).items()},
            "peak_speed_rpm": self.peak_speed() if np.isfinite(self.wing_amplitude).any() else None,
        }


def _evaluate(run, shaft_speed: float):
    steady = steady_part(len(run.time))
    spectrum = amplitude_spectrum(run.time[steady], run.wing_torsion[0, steady])
    resolution = spectrum.frequency[1]
    frequencies = np.full(N_DOMINANT, np.nan)
    found = dominant_frequencies(spectrum, N_DOMINANT, min_separation=3.0 * resolution)
    frequencies[: len(found)] = found
    return run.wing_amplitude, frequencies, frequencies / (shaft_speed / (2.0 * np.pi))


@dataclass(frozen=True)
class SpeedCase:
    """What one speed gave: wing amplitude (number of CWs,) mm, dominant frequencies and orders
    (N_DOMINANT,) Hz and orders, real-time factor, system eigenfrequencies (<= N_SYSTEM_MODES,) Hz;
    failure: the integration's message when it failed (then only the eigenfrequencies are set);
    unsettled_change: how far the run was from steady (:func:`mbs.histories.unsettled_change`)."""

    system_frequencies: np.ndarray
    wing_amplitude: np.ndarray | None = None
    dominant_frequencies: np.ndarray | None = None
    dominant_orders: np.ndarray | None = None
    real_time_factor: float = np.nan
    failure: str | None = None
    unsettled_change: float | None = None


def run_speed(params: ModelParams, reduced, reduced_throw) -> SpeedCase:
    """One sweep case: the coupled eigenfrequencies and the run at params.speed_rpm (a dask task)."""
    eigen = system_eigenfrequencies(params, reduced, max_frequency=np.inf,
                                    reduced_throw=reduced_throw)[:N_SYSTEM_MODES]
    try:
        run = simulate(params, reduced=reduced, reduced_throw=reduced_throw)
    except SimulationError as error:
        return SpeedCase(eigen, failure=str(error))
    amplitude, frequencies, orders = _evaluate(run, params.shaft_speed)
    return SpeedCase(eigen, amplitude, frequencies, orders, run.real_time_factor,
                     unsettled_change=run.unsettled_change)


def collect_sweep(model_params: ModelParams, speeds: np.ndarray, cases: list, reduced) -> SweepResult:
    """The sweep from its cases: ``cases`` holds per speed a :class:`SpeedCase`, or the message of
    a case that failed outright (str); the Campbell diagram uses the reduced CW ``reduced``."""
    n = speeds.size
    amplitude = np.full((n, model_params.n_counterweights), np.nan)
    frequencies = np.full((n, N_DOMINANT), np.nan)
    orders = np.full((n, N_DOMINANT), np.nan)
    real_time = np.full(n, np.nan)
    system = np.full((n, N_SYSTEM_MODES), np.nan)
    change = np.full(n, np.nan)
    failures, unsettled = {}, {}
    for i, (speed, case) in enumerate(zip(speeds, cases)):
        if isinstance(case, str):
            failures[float(speed)] = case
            continue
        system[i, : case.system_frequencies.size] = case.system_frequencies
        if case.failure is not None:
            failures[float(speed)] = case.failure
            continue
        amplitude[i], frequencies[i], orders[i] = case.wing_amplitude, case.dominant_frequencies, case.dominant_orders
        real_time[i] = case.real_time_factor
        if case.unsettled_change is not None:
            change[i] = case.unsettled_change
        message = unsettled_message(case.unsettled_change, model_params.solver.revolutions, float(speed))
        if message is not None:
            unsettled[float(speed)] = message
    active_orders = excitation_orders(model_params.excitation, model_params.effects)
    campbell = campbell_diagram(reduced, speeds, active_orders, system_frequencies=system)
    crossings = campbell.system_crossings if n > 1 else []
    half_step = 0.5 * np.min(np.diff(speeds)) if n > 1 else 0.0
    resonance = np.array([any(abs(c["speed_rpm"] - s) <= half_step for c in crossings) for s in speeds])
    return SweepResult(
        speeds_rpm=speeds, wing_amplitude=amplitude, dominant_frequencies=frequencies, dominant_orders=orders,
        real_time_factor=real_time, system_frequencies=system, crossings=crossings, resonance=resonance,
        failures=failures, campbell=campbell, unsettled_change=change, unsettled=unsettled,
    )


def write_sweep(path, result: SweepResult) -> Path:
    """One HDF5 file for the whole sweep: /sweep datasets and the /campbell diagram."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with h5py.File(path, "w") as root:
        root.attrs["fretwork_format"] = SWEEP_FORMAT
        root.attrs["format_version"] = FORMAT_VERSION
        group = root.create_group("sweep")
        fields = [
            ("speed", result.speeds_rpm, "rpm", "Engine speeds of the sweep."),
            ("wing_amplitude", result.wing_amplitude, "mm",
             "Wing torsion amplitude (half peak-to-peak over the steady second half) of CW1, CW2, ... "
             "as the multibody model computes it: raw, uncalibrated (a coupled scene scales it to its "
             "stated wing amplitude) (NaN: failed)."),
            ("dominant_frequencies", result.dominant_frequencies, "Hz", "Strongest CW1 wing-torsion frequencies."),
            ("dominant_orders", result.dominant_orders, "order", "The same frequencies in engine orders."),
            ("real_time_factor", result.real_time_factor, "1", "Simulated seconds per wall-clock second."),
            ("system_frequencies", result.system_frequencies, "Hz", "Coupled model eigenfrequencies per speed."),
            ("resonance", result.resonance.astype(np.int8), "1",
             "1 at a speed within half a sweep step of an order/mode crossing (crossings_json): a "
             "crossing, not a shown resonance, which is only where wing_amplitude peaks at the "
             "crossing; the dataset keeps the name 'resonance' for compatibility."),
        ]
        if result.unsettled_change is not None:
            fields.append(("unsettled_change", result.unsettled_change, "1",
                           "Relative change of the wing amplitude between the first and the last engine "
                           "cycle of the steady half (NaN: too short to tell); above 0.05 the run had not settled."))
        for name, data, units, description in fields:
            dataset = group.create_dataset(name, data=data)
            dataset.attrs["units"] = units
            dataset.attrs["description"] = description
        group.attrs["crossings_json"] = json.dumps(result.crossings)
        group.attrs["failures_json"] = json.dumps({str(k): v for k, v in result.failures.items()})
        group.attrs["unsettled_json"] = json.dumps({str(k): v for k, v in (result.unsettled or {}).items()})
        write_campbell(root.create_group("campbell"), result.campbell)
    return path
