"""Write multibody results to the shared HDF5 layout (``/histories``) and read them back.

Layout (see the team contract): root attrs fretwork_format="fretwork-results", format_version=1;
``/histories/time`` and one dataset per signal with attrs units, description and, for (n, k)
signals, components. Counterweights are cw1 (journal-1 side) and cw2 (journal-2 side) of throw 1, cw3 and cw4 of
throw 2, and so on; vectors
are in the CW frame (x tangential, y radial outward, z along the crank axis).
``/model`` holds what is needed to rebuild acceleration fields on the CW mesh (node coordinates,
mode shapes, interface and wing-tip nodes); ``/spectra`` and ``/campbell`` hold the analyses.
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING

import h5py
import numpy as np

from mbs.campbell import Campbell
from mbs.counterweight import ReducedCounterweight
from mbs.histories import RunHistories
from mbs.parameters import ModelParams
from mbs.spectra import Spectrum
from reduction.errors import InputError

if TYPE_CHECKING:  # mbs.loading runs the model (exudyn): not imported to write files
    from mbs.loading import MultibodyLoading

FORMAT = "fretwork-results"
FORMAT_VERSION = 1
#: the root attribute ``fretwork_format`` of a sweep file (:func:`mbs.sweep.write_sweep`)
SWEEP_FORMAT = "fretwork-sweep"
_XYZ = ["x (tangential)", "y (radial)", "z (crank axis)"]
MODAL_UNITS = "mm*sqrt(t)"  # mode shapes are mass-normalised (1/sqrt(t)), u = Psi q in mm


def acceleration_field(histories: RunHistories, reduced: ReducedCounterweight, counterweight: int,
                       sample: int) -> np.ndarray:
    """(n_nodes, 3) absolute acceleration (mm/s^2, CW frame) of every CW mesh node at one sample.

    a = a_frame + alpha x r + omega x (omega x r) + 2 omega x (Psi q') + Psi q'', r = x + Psi q:
    rigid-body, centrifugal, Coriolis and modal parts, the loads that drive the contact model.
    """
    c, s = counterweight, sample
    psi = reduced.mode_shapes
    deformation = (psi @ histories.cw_modal_coordinates[c, s]).reshape(-1, 3)
    velocity = (psi @ histories.cw_modal_velocities[c, s]).reshape(-1, 3)
    modal = (psi @ histories.cw_modal_accelerations[c, s]).reshape(-1, 3)
    position = reduced.node_coordinates + deformation
    omega = histories.cw_angular_velocity[c, s]
    alpha = histories.cw_angular_acceleration[c, s]
    centrifugal = np.cross(omega, np.cross(omega, position))
    return (histories.cw_frame_acceleration[c, s] + np.cross(alpha, position) + centrifugal
            + 2.0 * np.cross(omega, velocity) + modal)


def _signal(group, name, data, units, description, components=None):
    dataset = group.create_dataset(name, data=np.asarray(data, dtype=np.float64))
    dataset.attrs["units"] = units
    dataset.attrs["description"] = description
    if components is not None:
        dataset.attrs["components"] = list(components)


def _driving_signals(tag, frame_acceleration, angular_velocity, angular_acceleration, modal_coordinates,
                     modal_accelerations, modes):
    """The signals of one CW that drive a coupled contact model (its inertia fields); the modal
    ones only when it has ``modes`` (component names)."""
    if modes:
        yield from _modal_signals(tag, modal_coordinates, modal_accelerations, modes)
    yield (f"{tag}_frame_acceleration", frame_acceleration, "mm/s^2",
           f"Absolute acceleration of the {tag} interface origin (rigid-body part of the field).", _XYZ)
    yield (f"{tag}_angular_velocity", angular_velocity, "rad/s",
           f"Angular velocity of the {tag} frame (gives the centrifugal field omega x (omega x r)).", _XYZ)
    yield (f"{tag}_angular_acceleration", angular_acceleration, "rad/s^2",
           f"Angular acceleration of the {tag} frame (rigid-body field alpha x r).", _XYZ)


def _modal_signals(tag, modal_coordinates, modal_accelerations, modes):
    yield (f"{tag}_modal_coordinates", modal_coordinates, MODAL_UNITS,
           f"Craig-Bampton modal coordinates of {tag} (mass-normalised fixed-interface modes).", modes)
    yield (f"{tag}_modal_acceleration", modal_accelerations, MODAL_UNITS + "/s^2",
           f"Second time derivative of the {tag} modal coordinates (modal acceleration field = Psi q'').", modes)


def _wing_torsion_signal(tag, wing_torsion):
    return (f"{tag}_wing_torsion", wing_torsion, "mm",
            f"Opposite-phase ('torsion') part of the {tag} wing-tip axial motion, (u(+x) - u(-x))/2.", None)


def _history_signals(histories: RunHistories, reduced: ReducedCounterweight):
    modes = _mode_names(reduced.eigenfrequencies)
    for c in range(histories.cw_modal_coordinates.shape[0]):
        tag = f"cw{c + 1}"
        com = reduced.center_of_mass
        omega = histories.cw_angular_velocity[c]
        yield (f"{tag}_interface_displacement", histories.cw_interface_displacement[c], "mm",
               f"Translation of the {tag} interface relative to its web (rigid joint: constraint residual).", _XYZ)
        yield (f"{tag}_interface_rotation", histories.cw_interface_rotation[c], "rad",
               f"Rotation of the {tag} interface relative to its web (rigid joint: constraint residual).", _XYZ)
        yield (f"{tag}_interface_force", histories.cw_interface_force[c], "N",
               f"Force the web applies to {tag} at the interface (joint reaction).", _XYZ)
        yield (f"{tag}_interface_moment", histories.cw_interface_moment[c], "N*mm",
               f"Moment the web applies to {tag} about the interface centre (joint reaction).", _XYZ)
        yield from _driving_signals(tag, histories.cw_frame_acceleration[c], omega, histories.cw_angular_acceleration[c],
                                    histories.cw_modal_coordinates[c], histories.cw_modal_accelerations[c], modes)
        yield (f"{tag}_centrifugal_acceleration_com", np.cross(omega, np.cross(omega, com)), "mm/s^2",
               f"Centrifugal acceleration at the {tag} centre of mass relative to the interface origin.", _XYZ)
        yield (f"{tag}_wing_tip_displacement", histories.cw_wing_tip_axial[c], "mm",
               f"Axial (crank-axis) deformation of the two {tag} wing tips relative to the interface.",
               ["-x wing tip", "+x wing tip"])
        yield _wing_torsion_signal(tag, histories.wing_torsion[c])


def _mode_names(frequencies) -> list[str]:
    return [f"mode {k + 1} ({f:.1f} Hz)" for k, f in enumerate(frequencies)]


def write_loading_histories(group, loading: MultibodyLoading, counterweight: int) -> None:
    """Write into ``group`` (a results file's ``/histories``) the histories a coupled contact run
    is driven by: CW ``counterweight`` (1 = first) over the steady part of the multibody run (or
    as its interface-histories file gives them), named, united and described as :func:`write_run`
    writes them, plus its modal velocities; no modal signals when the histories have no modes."""
    tag = f"cw{counterweight}"
    modes = _mode_names(loading.mode_frequencies_hz)
    _signal(group, "time", loading.time, "s", "Sample times (fixed step).")
    for name, data, units, description, components in _driving_signals(
            tag, loading.frame_acceleration, loading.angular_velocity, loading.angular_acceleration,
            loading.modal_coordinates, loading.modal_accelerations, modes):
        _signal(group, name, data, units, description, components)
    if modes:
        _signal(group, f"{tag}_modal_velocity", loading.modal_velocities, MODAL_UNITS + "/s",
                f"Time derivative of the {tag} modal coordinates (Coriolis field 2 omega x (Psi q')).", modes)
    _signal(group, *_wing_torsion_signal(tag, loading.wing_torsion))
    group.attrs["counterweight"] = counterweight
    group.attrs["speed_rpm"] = loading.speed_rpm
    group.attrs["description"] = (f"Histories of {tag} at {loading.speed_rpm:g} rpm that drive the coupled contact "
                                  "run's inertia loads: the steady part of the multibody run, or the scene's "
                                  "interface-histories file.")


def write_run(path, params: ModelParams, reduced: ReducedCounterweight, histories: RunHistories,
              spectra: dict[str, Spectrum] | None = None, campbell: Campbell | None = None) -> Path:
    """Write one run (histories, model data, optional spectra and Campbell diagram) to path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with h5py.File(path, "w") as root:
        root.attrs["fretwork_format"] = FORMAT
        root.attrs["format_version"] = FORMAT_VERSION
        group = root.create_group("histories")
        _signal(group, "time", histories.time, "s", "Sample times (fixed step).")
        _signal(group, "crank_angle", histories.crank_angle, "rad", "Spin angle of journal 1.")
        _signal(group, "crank_speed", histories.crank_speed, "rad/s", "Spin speed of journal 1.")
        for name, data, units, description, components in _history_signals(histories, reduced):
            _signal(group, name, data, units, description, components)
        _write_model(root.create_group("model"), params, reduced, histories)
        if spectra:
            spectra_group = root.create_group("spectra")
            for name, spectrum in spectra.items():
                sub = spectra_group.create_group(name)
                _signal(sub, "frequency", spectrum.frequency, "Hz" if not name.endswith("orders") else "order",
                        "Frequency axis (or engine orders for order spectra).")
                _signal(sub, "amplitude", spectrum.amplitude, "mm", "Single-sided amplitude (peak) spectrum.")
        if campbell is not None:
            write_campbell(root.create_group("campbell"), campbell)
    return path


def _write_model(group, params: ModelParams, reduced: ReducedCounterweight, histories: RunHistories) -> None:
    group.attrs["parameters_json"] = json.dumps(asdict(params), default=sorted)
    group.attrs["real_time_factor"] = histories.real_time_factor
    group.attrs["acceleration_field"] = ("a = a_frame + alpha x r + omega x (omega x r) + 2 omega x (Psi q') "
                                         "+ Psi q'', r = node_coordinates + Psi q (CW frame)")
    _signal(group, "node_coordinates", reduced.node_coordinates, "mm", "CW mesh nodes in the CW frame.", _XYZ)
    _signal(group, "mode_shapes", reduced.mode_shapes, "1/sqrt(t)",
            "Mass-normalised fixed-interface modes, node-interleaved rows (3 per node).")
    _signal(group, "eigenfrequencies", reduced.eigenfrequencies, "Hz", "Fixed-interface eigenfrequencies.")
    group.create_dataset("interface_nodes", data=reduced.interface_nodes)
    group.create_dataset("wing_tip_nodes", data=reduced.wing_tip_nodes)
    group.attrs["torsion_mode"] = reduced.torsion_mode


def write_campbell(group, campbell: Campbell) -> None:
    _signal(group, "speed", campbell.speeds_rpm, "rpm", "Engine speeds of the diagram.")
    _signal(group, "frequency", campbell.frequencies, "Hz", "Reduced-CW eigenfrequencies per speed (rotating frame).")
    _signal(group, "orders", campbell.orders, "order", "Engine orders drawn as lines f = order * rpm / 60.")
    group.attrs["crossings_json"] = json.dumps(campbell.crossings)
    if campbell.system_frequencies is not None:
        _signal(group, "system_frequency", campbell.system_frequencies, "Hz",
                "Coupled multibody model eigenfrequencies per speed (undamped, no gyroscopic terms).")
        group.attrs["system_crossings_json"] = json.dumps(campbell.system_crossings)


def read_histories(path, required: tuple[str, ...] = ()) -> dict[str, np.ndarray]:
    """All ``/histories`` datasets of a results file as arrays, keyed by signal name, checked by
    :func:`checked_histories`; InputError naming the file when it cannot be read, has none, or
    lacks a ``required`` signal."""
    try:
        root = h5py.File(path, "r")
    except OSError as error:
        raise InputError(f"results file {path} is not a readable HDF5 file ({error})") from None
    with root:
        if not isinstance(root.get("histories"), h5py.Group):
            raise InputError(f"results file {path} has no /histories group")
        signals = checked_histories(root["histories"], path)
    missing = [name for name in required if name not in signals]
    if missing:
        raise InputError(f"results file {path}: /histories/{missing[0]} is missing")
    return signals


def checked_histories(group: h5py.Group, path) -> dict[str, np.ndarray]:
    """The datasets of a results file's ``/histories`` ``group`` as float arrays keyed by name,
    the one check every reader of them makes: a time (s) that is a finite, strictly increasing
    vector, and every signal one finite row per sample. A file that breaks it (written over, cut
    short, never written by fretwork) is an InputError naming the file ``path`` and the dataset."""
    where = f"results file {path}"
    if not isinstance(group.get("time"), h5py.Dataset):
        raise InputError(f"{where}: /histories/time is missing")
    time = _checked_time(group["time"], where)
    signals = {"time": time}
    for name, dataset in group.items():
        if name != "time" and isinstance(dataset, h5py.Dataset):
            signals[name] = _checked_signal(dataset, name, time, where)
    return signals


def _checked_time(dataset: h5py.Dataset, where: str) -> np.ndarray:
    if dataset.ndim != 1 or not _real(dataset):
        raise InputError(f"{where}: /histories/time must be a 1-D numeric vector, got shape {dataset.shape} "
                         f"of {dataset.dtype}")
    time = np.asarray(dataset[()], dtype=np.float64)
    if time.size == 0:
        raise InputError(f"{where}: /histories/time is empty, there is nothing to read")
    if not np.all(np.isfinite(time)):
        first = int(np.flatnonzero(~np.isfinite(time))[0])
        raise InputError(f"{where}: /histories/time has a non-finite value ({time[first]}) at sample {first}")
    steps = np.diff(time)
    if np.any(steps <= 0.0):
        k = int(np.flatnonzero(steps <= 0.0)[0])
        raise InputError(f"{where}: /histories/time must increase strictly, but sample {k + 1} "
                         f"({float(time[k + 1])!r} s) does not come after sample {k} ({float(time[k])!r} s)")
    return time


def _checked_signal(dataset: h5py.Dataset, name: str, time: np.ndarray, where: str) -> np.ndarray:
    if dataset.ndim not in (1, 2) or dataset.shape[0] != time.size:
        raise InputError(f"{where}: signal {name!r} has shape {dataset.shape}; expected "
                         f"({time.size},) or ({time.size}, k) to match /histories/time")
    if not _real(dataset):
        raise InputError(f"{where}: signal {name!r} holds {dataset.dtype} data, not real numbers")
    data = np.asarray(dataset[()], dtype=np.float64)
    bad = ~np.isfinite(data)
    if bad.any():
        sample, *component = np.argwhere(bad)[0]
        at = f"sample {sample} (t = {float(time[sample]):.6g} s)"
        at += f", component {component[0]}" if component else ""
        raise InputError(f"{where}: signal {name!r} has a NaN or infinite value at {at}")
    return data


def _real(dataset: h5py.Dataset) -> bool:
    return np.issubdtype(dataset.dtype, np.integer) or np.issubdtype(dataset.dtype, np.floating)
