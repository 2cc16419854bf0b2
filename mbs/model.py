"""Running the exudyn crankshaft-counterweight model: fixed-step simulation and eigen-analyses.

:func:`reduce_bodies` reduces the bodies a model needs (done once, by the caller);
:func:`simulate` builds the model's items (:mod:`mbs.items`) with those bodies and runs it at a
fixed time step into :class:`mbs.histories.RunHistories`; :func:`system_eigenfrequencies`,
:func:`torsion_decay_mode` and :func:`wing_torsion_decay_components` analyse the assembled
model linearised at its initial state. exudyn's own output is captured into the error, not
printed. Units: mm, N, t, s, rad.
"""

from __future__ import annotations

import contextlib
import io
import signal
import threading
import time as wallclock

import exudyn as exu
import numpy as np

from mbs.counterweight import ReducedCounterweight, reduce_counterweight
from mbs.flexible_throw import ReducedThrow, reduce_throw
from mbs.histories import RunHistories, collect_histories
from mbs.parameters import ModelParams
from reduction.errors import InputError
from mbs.items import add_sensors, build_system


class SimulationError(RuntimeError):
    """The time integration of a run failed (Newton did not converge)."""


class _Interrupt:
    """Ctrl-C while exudyn integrates. The interpreter runs the SIGINT handler, which raises
    KeyboardInterrupt, in the next Python code that runs, and during a solve that is one of the
    model's user functions; exudyn does not let it through: it turns it into its own ModelError,
    or takes it for a failed step and retries it with a smaller one (the histories then lose their
    fixed sample rate). So while the solve runs, the handler is wrapped to record the interrupt
    first (:meth:`recorded`); :meth:`pre_step`, exudyn's PreStepUserFunction, stops the solve
    after the step (its False) once one is recorded, and gives the interpreter a place to run the
    handler once a step in a model without loads; :func:`simulate` raises KeyboardInterrupt when
    the solve has returned or failed."""

    def __init__(self) -> None:
        self.requested = False

    def pre_step(self, mbs_, t) -> bool:
        return not self.requested

    @contextlib.contextmanager
    def recorded(self):
        """The SIGINT handler, recording the interrupt before it runs, for the block. Only the
        main thread has handlers; an ignored or default SIGINT raises nothing and stays as it is."""
        previous = signal.getsignal(signal.SIGINT)
        if threading.current_thread() is not threading.main_thread() or not callable(previous):
            yield
            return

        def record(signum, frame):
            self.requested = True
            previous(signum, frame)

        signal.signal(signal.SIGINT, record)
        try:
            yield
        finally:
            # a handler that replaced itself (fretwork's ignores a second Ctrl-C) keeps its choice
            if signal.getsignal(signal.SIGINT) is record:
                signal.signal(signal.SIGINT, previous)


def reduce_bodies(params: ModelParams) -> tuple[ReducedCounterweight, ReducedThrow | None]:
    """The reduction stage before every simulation of ``params``: the CW (Craig-Bampton with
    params.n_modes fixed-interface modes) and, with the "flexible_crankshaft" effect, the throw
    (else None). A run, a sweep and a coupled scene each call it once and pass the bodies on:
    nothing in this module reduces a body by itself."""
    reduced = reduce_counterweight(params.counterweight, params.n_modes)
    return reduced, (reduce_throw(params.throw) if "flexible_crankshaft" in params.effects else None)


def system_eigenfrequencies(params: ModelParams, reduced: ReducedCounterweight,
                            max_frequency: float = 2000.0, *, reduced_throw: ReducedThrow | None = None) -> np.ndarray:
    """Eigenfrequencies (Hz, ascending, up to max_frequency) of the assembled multibody model.

    Undamped, constraints projected out (exudyn ComputeODE2Eigenvalues), linearised at the
    initial state of a run at params.speed_rpm; gyroscopic coupling is not included. These are
    the coupled crank-throw + counterweight modes a run resonates at.
    """
    params.validate()
    system, mbs, _ = build_system(params, reduced, loads=False, reduced_throw=reduced_throw)
    mbs.Assemble()
    frequencies, _ = mbs.ComputeODE2Eigenvalues(convert2Frequencies=True, ignoreAlgebraicEquations=False)
    frequencies = np.sort(np.asarray(frequencies))
    return frequencies[(frequencies > 1e-3) & (frequencies <= max_frequency)]


def simulate(params: ModelParams, *, reduced: ReducedCounterweight,
             initial_modal_coordinates: np.ndarray | None = None, energy: bool = False,
             reduced_throw: ReducedThrow | None = None) -> RunHistories:
    """Run the model at params.speed_rpm for params.solver.revolutions, fixed time step.

    reduced: the reduced CW (:func:`reduce_bodies`; reuse it across a sweep).
    initial_modal_coordinates: (n_modes,) initial CW modal coordinates (both CWs), e.g. to
    release the torsion mode for a free-decay frequency check. energy: also record the total
    mechanical energy (meaningful with drive="free", damping off and no excitation; rigid throws).
    reduced_throw: the Craig-Bampton throw, required by the "flexible_crankshaft" effect
    (:func:`reduce_bodies`).
    """
    params.validate()
    if energy and "flexible_crankshaft" in params.effects:
        raise InputError("energy bookkeeping covers rigid throws only; switch the flexible_crankshaft effect off")
    system, mbs, items = build_system(params, reduced, loads=True, initial_modal_coordinates=initial_modal_coordinates,
                                reduced_throw=reduced_throw)
    sensors = add_sensors(mbs, items, energy)
    interrupt = _Interrupt()
    mbs.SetPreStepUserFunction(interrupt.pre_step)
    mbs.Assemble()

    solver = params.solver
    end_time = solver.revolutions * 2.0 * np.pi / params.shaft_speed
    n_steps = int(round(end_time / solver.time_step))
    settings = exu.SimulationSettings()
    settings.timeIntegration.numberOfSteps = n_steps
    settings.timeIntegration.endTime = n_steps * solver.time_step
    settings.timeIntegration.verboseMode = 0
    settings.timeIntegration.generalizedAlpha.spectralRadius = solver.spectral_radius
    settings.timeIntegration.newton.useModifiedNewton = True
    settings.timeIntegration.newton.relativeTolerance = solver.newton_tolerance
    settings.solution.file.write = False
    settings.solution.sensors.writePeriod = solver.time_step
    settings.show.statistics = False
    # exudyn prints its solver diagnostics; keep them out of stdout and in the error instead.
    solver_log = io.StringIO()
    started = wallclock.perf_counter()
    try:
        with contextlib.redirect_stdout(solver_log), interrupt.recorded():
            converged = mbs.SolveDynamic(settings)
    except exu.SolverError:
        converged = False
    except Exception:
        if interrupt.requested:  # exudyn's error around the KeyboardInterrupt of a user function
            raise KeyboardInterrupt from None
        raise
    if interrupt.requested:  # the solve stopped early, or ran on with the interrupt swallowed
        raise KeyboardInterrupt
    wall_time = wallclock.perf_counter() - started
    if not converged:
        raise SimulationError(f"time integration did not converge at {params.speed_rpm} rpm (time step "
                              f"{solver.time_step} s); exudyn: {' '.join(solver_log.getvalue().split())[:400]}")
    return collect_histories(mbs, sensors, reduced, energy, wall_time)


def _released_torsion_expansion(params: ModelParams, reduced: ReducedCounterweight,
                                reduced_throw: ReducedThrow | None):
    """Undamped eigen-analysis of the assembled model and the expansion x0 = V c of the state in
    which every CW's torsion mode is released by 0.1: (frequencies Hz, V, c, ODE2 index of each
    CW's first modal coordinate, reduced CW)."""
    params.validate()
    _system, mbs, items = build_system(params, reduced, loads=False, reduced_throw=reduced_throw)  # _system owns mbs
    mbs.Assemble()
    frequencies, vectors = mbs.ComputeODE2Eigenvalues(convert2Frequencies=True, ignoreAlgebraicEquations=False)
    frequencies, vectors = np.asarray(frequencies), np.asarray(vectors)
    first_modal = [mbs.GetNodeODE2Index(node) for node in items.cw_modal_nodes]
    released = np.zeros(vectors.shape[0])
    released[[index + reduced.torsion_mode for index in first_modal]] = 0.1
    participation = np.linalg.lstsq(vectors, released, rcond=None)[0]
    return frequencies, vectors, participation, first_modal, reduced


def torsion_decay_mode(params: ModelParams, reduced: ReducedCounterweight, *,
                       reduced_throw: ReducedThrow | None = None) -> tuple[float, float]:
    """Frequency (Hz) and amplitude of the coupled mode that dominates CW 1's torsion coordinate
    when the torsion mode of every CW is released by 0.1 (the free-decay test), from the
    eigen-analysis of the assembled model.

    The released state x0 is expanded in the undamped eigenvectors (x0 = V c, least squares,
    exact: x0 touches only unconstrained CW modal coordinates); the mode with the largest
    |c_i V[torsion of CW 1, i]| is the one a free-decay run rings at. Linearised at the initial
    state, no gyroscopic terms (as system_eigenfrequencies). The decay run of a flexible throw
    costs about 7 ms per step, this analysis about a second. Measured against decay runs: flexible
    throw 394.3 Hz (decay 393.8), two rigid throws 493.9 Hz (decay 492.9). Where two modes share
    the torsion almost equally the answer is ambiguous: the single rigid throw rings at 399.9 and
    692.9 Hz with shares 0.036 / 0.038 (this returns 692.9 Hz, a decay run's peak is 399.7 Hz);
    wing_torsion_decay_components lists every mode's share of the measured signal instead.
    """
    frequencies, vectors, participation, first_modal, reduced = _released_torsion_expansion(
        params, reduced, reduced_throw)
    amplitude = np.abs(participation * vectors[first_modal[0] + reduced.torsion_mode, :]) * (frequencies > 1.0)
    dominant = int(np.argmax(amplitude))
    return float(frequencies[dominant]), float(amplitude[dominant])


def wing_torsion_decay_components(params: ModelParams, reduced: ReducedCounterweight, *,
                                  count: int = 4, reduced_throw: ReducedThrow | None = None) -> list[tuple[float, float]]:
    """The ``count`` largest sinusoids of CW 1's wing torsion (u(+x) - u(-x))/2 in the free-decay
    test (every CW's torsion mode released by 0.1, damping and excitation off), as
    (frequency Hz, amplitude mm), largest first, from the eigen-analysis of the assembled model.

    Component i of the signal is c_i T V_i: the released state's expansion coefficient times the
    wing-torsion shape T applied to CW 1's modal coordinates of eigenvector i. This is what a
    decay run's spectrum shows; in the single rigid throw two coupled modes carry almost equal
    shares (750 rpm: 399.9 and 692.9 Hz), so "the" torsion frequency is the lower one by the
    paper's naming, and a spectrum's highest peak may be either. Undamped, linearised at the
    initial state, no gyroscopic terms (as system_eigenfrequencies).
    """
    frequencies, vectors, participation, first_modal, reduced = _released_torsion_expansion(
        params, reduced, reduced_throw)
    tips = reduced.wing_tip_axial_shapes()
    torsion_shape = 0.5 * (tips[1] - tips[0])
    cw1 = vectors[first_modal[0]:first_modal[0] + reduced.n_modes, :]
    amplitude = np.abs(participation * (torsion_shape @ cw1)) * (frequencies > 1.0)
    largest = np.argsort(amplitude)[::-1][:count]
    return [(float(frequencies[i]), float(amplitude[i])) for i in largest]
