"""The sampled histories of a results file and the binary table the FMU's C player reads.

Signals come from the ``/histories`` group (one output per component, named and united after
the results file) of either results file that holds one: ``fretwork mbs``'s ``run.h5`` (every
CW over the whole run) or a coupled ``fretwork run``'s ``results.h5`` (the CW that loads the
contact, over the steady part of the multibody run; :mod:`pipelines.output.results`). A run's
output folder stands for its results file (:func:`results_file`). Both play the steady part of
the multibody run, where the wing amplitude is measured (:func:`mbs.histories.steady_part`): of
an mbs run.h5 its second half unless the whole run is asked for, so that the FMU, looped or
not, does not play the start-up ring-down (at 750 rpm a wing torsion 100 times its settled
swing). A coupled run's histories are played as its load cycle used them, scaled to its stated
wing amplitude (:mod:`pipelines.fmu.scaling`). Files of another kind (a sweep, an
interface-histories file) are refused, naming what they are and which command reads them. The
table (``resources/histories.bin``) is laid out as in template/player.c. Units follow the
results file (fretwork uses mm, N, MPa, t, s, mJ).
"""

from __future__ import annotations

import hashlib
import os
import re
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import h5py
import numpy as np

from mbs import histories_file
from mbs.histories import steady_part
from mbs.results import SWEEP_FORMAT, checked_histories
from pipelines.fmu.scaling import LoadScaling, load_scaling
from reduction.errors import InputError


#: Names of the time and the playback parameters, which no output may take.
PARAMETER_NAMES = ("time", "time_offset", "period", "periodic")
TABLE_FILE = "histories.bin"
TABLE_MAGIC = b"FRETHIS1"
TOKEN_SIZE = 64
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
# Characters FMI allows inside a quoted ('...') structured name.
_QUOTED_NAME = re.compile(r"[A-Za-z0-9_!#$%&()*+,\-./:;<=>?@\[\]^{}|~ ]+\Z")
#: fretwork files that hold no histories to play, by their format tag: what they are, what reads them
OTHER_KINDS = {
    SWEEP_FORMAT: "a speed sweep of `fretwork sweep` (wing amplitudes and the Campbell diagram per engine "
                      "speed), which `fretwork report` reads from its folder",
    histories_file.FORMAT: "an interface-histories file (docs/histories_format.md), which a coupled scene reads "
                           "through its [coupling] histories key",
}
#: the results file of a run's output folder, and the command whose folder holds it
FOLDER_RESULTS = (("results.h5", "a coupled `fretwork run`"), ("run.h5", "`fretwork mbs`"))


@dataclass(frozen=True)
class PlaybackTable:
    """Histories flattened to scalar FMU outputs.

    time: (n,) strictly increasing sample times, s.
    values: (n, m) output values at the samples, in each output's unit.
    names, units, descriptions: (m,) FMI variable name, unit ('' if none) and description.
    scaling: how a coupled run scaled the histories (values are scaled), None if played as stored.
    multibody_part: of ``fretwork mbs``'s run.h5, "steady" (its steady part, :func:`steady_part`)
    or "whole"; None for other files, played as stored (a coupled run stores its steady part).
    """

    time: np.ndarray
    values: np.ndarray
    names: tuple[str, ...]
    units: tuple[str, ...]
    descriptions: tuple[str, ...]
    scaling: LoadScaling | None = None
    multibody_part: str | None = None


def results_file(path: str | os.PathLike) -> Path:
    """The results file ``path`` names: the file itself, or of a run's output folder its results
    file (:data:`FOLDER_RESULTS`: a coupled run's results.h5, ``fretwork mbs``'s run.h5)."""
    path = Path(path)
    if not path.is_dir():
        if not path.is_file():
            raise InputError(f"results file {path} does not exist")
        return path
    found = [path / name for name, _ in FOLDER_RESULTS if (path / name).is_file()]
    if len(found) > 1:
        held = " and ".join(f"{name} ({command})" for name, command in FOLDER_RESULTS)
        raise InputError(f"folder {path} holds both {held}: give the file to export")
    if not found:
        raise InputError(f"folder {path} holds no results file: give a results file, or the output folder of "
                         + " or of ".join(f"{command} (its {name})" for name, command in FOLDER_RESULTS))
    return found[0]


def read_playback_table(results_path: str | os.PathLike, signals: Sequence[str] | None = None, *,
                        whole: bool = False) -> PlaybackTable:
    """Read and check the ``/histories`` group; flatten (n, k) signals to k scalar outputs, scaled
    as a coupled run's load cycle used them (:mod:`pipelines.fmu.scaling`).
    ``results_path``: a results file, or a run's output folder (:func:`results_file`).
    whole: of ``fretwork mbs``'s run.h5, every sample, the start-up transient included; by default
    its steady part (:func:`mbs.histories.steady_part`). A coupled run's file holds only the steady
    part: refused there."""
    results_path = results_file(results_path)
    try:
        results = h5py.File(results_path, "r")
    except OSError as error:
        raise InputError(f"results file {results_path} is not a readable HDF5 file ({error})") from None
    with results:
        _refuse_other_kinds(results, results_path)
        if "histories" not in results or not isinstance(results["histories"], h5py.Group):
            raise InputError(
                f"results file {results_path} has no /histories group: the multibody histories are in the "
                "run.h5 of `fretwork mbs` and in the results.h5 of a coupled `fretwork run` (a scene with "
                "[coupling]); this run has none"
            )
        histories = results["histories"]
        stored = checked_histories(histories, results_path)
        stored_time = _played_time(histories["time"], stored["time"], results_path)
        part = _multibody_part(results, whole, results_path)
        played = steady_part(stored_time.size) if part == "steady" else slice(None)
        time = stored_time[played]
        if time.size < 2:
            raise InputError(f"results file {results_path}: the steady part of the run has a single sample; "
                             "linear playback needs at least two (export the whole run)")
        available = [name for name in stored if name != "time"]
        selected = _select_signals(signals, available, results_path)
        scaling = load_scaling(results, time, results_path)
        columns, names, units, descriptions = [], [], [], []
        for signal in selected:
            data = _played_signal(stored[signal], signal, played)
            if scaling is not None:
                data = scaling.apply(time, data)
            unit = _text_attribute(histories[signal], "units")
            description = _text_attribute(histories[signal], "description")
            outputs = _outputs_of(histories[signal], signal, data.shape[1])
            columns.append(data)
            names.extend(name for name, _ in outputs)
            units.extend([unit] * len(outputs))
            descriptions.extend(
                f"{description} ({label})" if label and description else description or label
                for _, label in outputs
            )
    return PlaybackTable(
        time=time,
        values=np.ascontiguousarray(np.hstack(columns)),
        names=tuple(names),
        units=tuple(units),
        descriptions=tuple(descriptions),
        scaling=scaling,
        multibody_part=part,
    )


def _multibody_part(results: h5py.File, whole: bool, results_path: Path) -> str | None:
    """The part of the multibody run to play: "steady" or "whole" for ``fretwork mbs``'s run.h5
    (the file with /model, which :func:`mbs.results.write_run` alone writes), None for a file
    played as stored; InputError for ``whole`` of a coupled run, which stores the steady part only."""
    if isinstance(results.get("model"), h5py.Group):
        return "whole" if whole else "steady"
    if whole and "counterweight" in results["histories"].attrs:
        raise InputError(f"{results_path} holds only the steady part of its multibody run (what drove the coupled "
                         "run's loads), not the whole run: the whole run, start-up included, is in the run.h5 of "
                         "`fretwork mbs`")
    return None


def _refuse_other_kinds(results: h5py.File, results_path: Path) -> None:
    """InputError for a fretwork file of a kind that holds no histories to play back."""
    tag = results.attrs.get("fretwork_format", results.attrs.get("format"))
    tag = tag.decode() if isinstance(tag, bytes) else tag
    # sweeps written before they had their own tag carry the results tag
    if tag == "fretwork-results" and "sweep" in results and "histories" not in results:
        tag = SWEEP_FORMAT
    if tag in OTHER_KINDS:
        raise InputError(f"{results_path} is {OTHER_KINDS[tag]}, not a run's results: `fretwork export-fmu` plays "
                         "the /histories of the run.h5 of `fretwork mbs` or of the results.h5 of a coupled "
                         "`fretwork run`")


def _played_time(dataset: h5py.Dataset, time: np.ndarray, results_path: Path) -> np.ndarray:
    """The stored sample times (s, checked by :func:`mbs.results.checked_histories`), if the FMU can play them."""
    units = _text_attribute(dataset, "units")
    if units not in ("", "s"):
        raise InputError(f"results file {results_path}: /histories/time is in {units!r}; the FMU plays histories "
                         "in seconds (units='s')")
    if time.size < 2:
        raise InputError(f"results file {results_path}: /histories/time has a single sample; linear playback needs "
                         "at least two")
    return time


def _select_signals(signals: Sequence[str] | None, available: list[str], results_path: Path) -> list[str]:
    if isinstance(signals, str):
        signals = [signals]
    if signals is None:
        if not available:
            raise InputError(f"results file {results_path}: /histories holds no signal besides time")
        return available
    if len(signals) == 0:
        raise InputError("no signals selected for the FMU: name at least one, or pass None for all")
    unknown = [name for name in signals if name not in available]
    if unknown:
        raise InputError(
            f"unknown signal(s) {', '.join(map(repr, unknown))} in /histories of {results_path}; "
            f"available: {', '.join(available) or 'none'}"
        )
    duplicates = sorted({name for name in signals if list(signals).count(name) > 1})
    if duplicates:
        raise InputError(f"signal(s) {', '.join(map(repr, duplicates))} selected more than once")
    return list(signals)


def _played_signal(data: np.ndarray, signal: str, played: slice) -> np.ndarray:
    """The samples ``played`` of a stored signal (checked by :func:`mbs.results.checked_histories`)
    as (n_played, k) floats."""
    if signal in PARAMETER_NAMES:
        raise InputError(f"signal name {signal!r} is reserved for an FMU playback variable; rename the dataset")
    data = data.reshape(data.shape[0], -1)[played]
    if data.shape[1] == 0:
        raise InputError(f"signal {signal!r} has no components")
    return data


def _outputs_of(dataset: h5py.Dataset, signal: str, n_components: int) -> list[tuple[str, str]]:
    """(FMI name, component label for the description) of each output a signal becomes."""
    base = _fmi_name(signal)
    if dataset.ndim == 1:
        return [(base, "")]
    components = dataset.attrs.get("components")
    if components is None:
        return [(f"{base}[{j + 1}]", f"component {j + 1} of {n_components}") for j in range(n_components)]
    components = [c.decode() if isinstance(c, bytes) else str(c) for c in np.atleast_1d(components)]
    if len(components) != n_components:
        raise InputError(
            f"signal {signal!r} lists {len(components)} component names for {n_components} columns"
        )
    if len(set(components)) != len(components):
        raise InputError(f"signal {signal!r} repeats a component name: {components}")
    return [(f"{base}.{_fmi_name(component)}", f"component {component}") for component in components]


def _fmi_name(name: str) -> str:
    """Structured FMI name part: identifiers as they are, other names quoted."""
    if _IDENTIFIER.match(name):
        return name
    if _QUOTED_NAME.match(name):
        return f"'{name}'"
    raise InputError(
        f"name {name!r} cannot become an FMI variable name: use letters, digits, spaces and ASCII punctuation "
        f"other than quotes and backslashes"
    )


def _text_attribute(dataset: h5py.Dataset, key: str) -> str:
    value = dataset.attrs.get(key, "")
    if isinstance(value, bytes):
        value = value.decode()
    return str(value)


def model_identifier(name: str) -> str:
    """C identifier made from a model name (it names the shared library and the model)."""
    identifier = re.sub(r"[^A-Za-z0-9_]", "_", name)
    if not identifier or identifier[0].isdigit():
        identifier = "fmu_" + identifier
    return identifier


def instantiation_token(table: PlaybackTable) -> str:
    """GUID derived from the data, so a modelDescription and its table file are matched."""
    digest = hashlib.sha256()
    digest.update(table.time.tobytes())
    digest.update(table.values.tobytes())
    digest.update("\0".join(table.names + table.units).encode())
    return "{" + str(uuid.UUID(bytes=digest.digest()[:16])) + "}"


def write_table(path: Path, table: PlaybackTable, token: str) -> None:
    """Write the binary table the C player reads (layout in template/player.c)."""
    token_bytes = token.encode("ascii")
    if len(token_bytes) >= TOKEN_SIZE:
        raise ValueError(f"instantiation token longer than {TOKEN_SIZE - 1} bytes")
    n_samples, n_signals = table.values.shape
    header = (
        TABLE_MAGIC
        + np.array([0x01020304, 0], dtype="<u4").tobytes()
        + np.array([n_samples, n_signals], dtype="<u8").tobytes()
        + token_bytes.ljust(TOKEN_SIZE, b"\0")
    )
    with open(path, "wb") as file:
        file.write(header)
        file.write(np.ascontiguousarray(table.time, dtype="<f8").tobytes())
        file.write(np.ascontiguousarray(table.values, dtype="<f8").tobytes())
