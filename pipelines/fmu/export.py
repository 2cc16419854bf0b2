"""Export load histories as co-simulation FMUs that other simulation tools play back.

The FMU holds a small generic C player (``pipelines/fmu/template``) and the sampled
histories as a binary table in ``resources/histories.bin``; the player interpolates
linearly between samples. One compiled player serves every export, so the FMU grows
only with the data (8 bytes per sample and signal, before zip compression).

Playback parameters of every exported FMU (all ``fixed``: set before initialization):

- ``time_offset`` (s): the output at simulation time t is the history at t - time_offset.
- ``periodic`` (Boolean): repeat the history instead of holding the first/last sample.
- ``period`` (s): repetition period, default the sampled span t_last - t_first. A longer
  period bridges the gap after the last sample linearly back to the first sample.

Units follow the results file (fretwork uses mm, N, MPa, t, s, mJ).
"""

from __future__ import annotations

import argparse
import datetime
import hashlib
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import uuid
import warnings
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import h5py
import numpy as np

from reduction.errors import InputError

TEMPLATE_DIR = Path(__file__).parent / "template"
TABLE_FILE = "histories.bin"
TABLE_MAGIC = b"FRETHIS1"
TOKEN_SIZE = 64

# Value references, mirrored in template/player.h.
VR_TIME = 0
VR_TIME_OFFSET = 1
VR_PERIOD = 2
VR_PERIODIC = 3
VR_FIRST_OUTPUT = 100

PARAMETER_NAMES = ("time", "time_offset", "period", "periodic")

PLAYER_SOURCES = ("player.c",)
PLAYER_HEADERS = ("player.h",)
FMI_SOURCES = {2: ("fmi2_player.c",), 3: ("fmi3_player.c",)}
FMI_HEADERS = {
    2: ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h"),
    3: ("fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h"),
}

# SI base-unit exponents and factor (value_SI = factor * value) of the units fretwork writes,
# so importing tools can convert; other units are declared by name only.
BASE_UNITS = {
    "s": ({"s": 1}, 1.0),
    "m": ({"m": 1}, 1.0),
    "mm": ({"m": 1}, 1e-3),
    "mm/s": ({"m": 1, "s": -1}, 1e-3),
    "mm/s^2": ({"m": 1, "s": -2}, 1e-3),
    "m/s": ({"m": 1, "s": -1}, 1.0),
    "m/s^2": ({"m": 1, "s": -2}, 1.0),
    "rad": ({"rad": 1}, 1.0),
    "rad/s": ({"rad": 1, "s": -1}, 1.0),
    "rad/s^2": ({"rad": 1, "s": -2}, 1.0),
    "N": ({"kg": 1, "m": 1, "s": -2}, 1.0),
    "N*mm": ({"kg": 1, "m": 2, "s": -2}, 1e-3),
    "N.mm": ({"kg": 1, "m": 2, "s": -2}, 1e-3),
    "MPa": ({"kg": 1, "m": -1, "s": -2}, 1e6),
    "t": ({"kg": 1}, 1e3),
    "mJ": ({"kg": 1, "m": 2, "s": -2}, 1e-3),
    "Hz": ({"s": -1}, 1.0),
}

_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
# Characters FMI allows inside a quoted ('...') structured name.
_QUOTED_NAME = re.compile(r"[A-Za-z0-9_!#$%&()*+,\-./:;<=>?@\[\]^{}|~ ]+\Z")


class SourceOnlyFmuWarning(UserWarning):
    """The FMU was exported without a compiled binary (sources only)."""


class FmuBuildError(RuntimeError):
    """The C compiler failed on the player sources: a fretwork or toolchain defect, not bad input."""


@dataclass(frozen=True)
class PlaybackTable:
    """Histories flattened to scalar FMU outputs.

    time: (n,) strictly increasing sample times, s.
    values: (n, m) output values at the samples, in each output's unit.
    names, units, descriptions: (m,) FMI variable name, unit ('' if none) and description.
    """

    time: np.ndarray
    values: np.ndarray
    names: tuple[str, ...]
    units: tuple[str, ...]
    descriptions: tuple[str, ...]


def export_fmu(
    results_path: str | os.PathLike,
    output_path: str | os.PathLike,
    signals: Sequence[str] | None = None,
    fmi_version: int = 2,
    *,
    model_name: str | None = None,
    compiler: str | None = None,
) -> Path:
    """Write a co-simulation FMU that plays back the ``/histories`` of a results file.

    results_path: HDF5 results file with a ``/histories`` group (time in s, signals (n,) or (n, k)).
    output_path: FMU file to write; parent folders are created. Written atomically: on any error
        no FMU file is left at output_path.
    signals: dataset names under ``/histories`` to export, in this order; None exports all.
        A signal of shape (n, k) becomes k outputs ``<signal>.<component>`` when the dataset has a
        ``components`` attribute, else ``<signal>[1]`` .. ``<signal>[k]``.
    fmi_version: 2 (FMI 2.0, default) or 3 (FMI 3.0).
    model_name: model name and identifier (binary name); default from the output file name.
    compiler: C compiler command; default $CC, then cc, gcc, clang. If none is found, or this
        platform has no FMI binary folder, the FMU holds sources only and a
        SourceOnlyFmuWarning is issued.

    Raises InputError for bad input (missing file, group or signal; empty, non-finite or
    non-increasing time; NaN or infinite data) and FmuBuildError if compilation fails.
    Returns the path of the written FMU.
    """
    if fmi_version not in (2, 3):
        raise InputError(f"FMI version {fmi_version!r} is not supported: choose 2 or 3")
    output_path = Path(output_path)
    if output_path.is_dir():
        raise InputError(f"FMU output path {output_path} is a folder; give a file name such as loads.fmu")
    table = read_playback_table(results_path, signals)
    identifier = model_identifier(model_name or output_path.stem)
    token = instantiation_token(table)

    output_path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="fretwork-fmu-") as work:
        fmu_dir = Path(work) / "fmu"
        _write_sources(fmu_dir / "sources", fmi_version, identifier)
        (fmu_dir / "resources").mkdir()
        write_table(fmu_dir / "resources" / TABLE_FILE, table, token)
        (fmu_dir / "modelDescription.xml").write_bytes(
            model_description_xml(table, fmi_version, identifier, token)
        )
        _add_binary(fmu_dir, fmi_version, identifier, compiler)
        _zip_atomically(fmu_dir, output_path)
    return output_path


def read_playback_table(results_path: str | os.PathLike, signals: Sequence[str] | None = None) -> PlaybackTable:
    """Read and check the ``/histories`` group; flatten (n, k) signals to k scalar outputs."""
    results_path = Path(results_path)
    if not results_path.is_file():
        raise InputError(f"results file {results_path} does not exist")
    try:
        results = h5py.File(results_path, "r")
    except OSError as error:
        raise InputError(f"results file {results_path} is not a readable HDF5 file ({error})") from None
    with results:
        if "histories" not in results or not isinstance(results["histories"], h5py.Group):
            raise InputError(
                f"results file {results_path} has no /histories group: write the load histories first"
            )
        histories = results["histories"]
        time = _read_time(histories, results_path)
        available = [name for name, item in histories.items() if name != "time" and isinstance(item, h5py.Dataset)]
        selected = _select_signals(signals, available, results_path)
        columns, names, units, descriptions = [], [], [], []
        for signal in selected:
            data = _read_signal(histories[signal], signal, time)
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
    )


def _read_time(histories: h5py.Group, results_path: Path) -> np.ndarray:
    if "time" not in histories or not isinstance(histories["time"], h5py.Dataset):
        raise InputError(f"results file {results_path}: /histories/time is missing")
    dataset = histories["time"]
    if dataset.ndim != 1 or not np.issubdtype(dataset.dtype, np.number):
        raise InputError(f"/histories/time must be a 1-D numeric vector, got shape {dataset.shape} of {dataset.dtype}")
    units = _text_attribute(dataset, "units")
    if units not in ("", "s"):
        raise InputError(f"/histories/time is in {units!r}; the FMU plays histories in seconds (units='s')")
    time = np.asarray(dataset[()], dtype=np.float64)
    if time.size == 0:
        raise InputError(f"results file {results_path}: /histories/time is empty, there is nothing to play back")
    if time.size < 2:
        raise InputError("/histories/time has a single sample; linear playback needs at least two")
    if not np.all(np.isfinite(time)):
        first = int(np.flatnonzero(~np.isfinite(time))[0])
        raise InputError(f"/histories/time has a non-finite value ({time[first]}) at sample {first}")
    steps = np.diff(time)
    if np.any(steps <= 0.0):
        k = int(np.flatnonzero(steps <= 0.0)[0])
        raise InputError(
            f"/histories/time must increase strictly, but sample {k + 1} ({time[k + 1]!r} s) "
            f"does not come after sample {k} ({time[k]!r} s)"
        )
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


def _read_signal(dataset: h5py.Dataset, signal: str, time: np.ndarray) -> np.ndarray:
    if signal in PARAMETER_NAMES:
        raise InputError(f"signal name {signal!r} is reserved for an FMU playback variable; rename the dataset")
    if dataset.ndim not in (1, 2) or dataset.shape[0] != time.size:
        raise InputError(
            f"signal {signal!r} has shape {dataset.shape}; expected ({time.size},) or ({time.size}, k) "
            f"to match /histories/time"
        )
    if not (np.issubdtype(dataset.dtype, np.integer) or np.issubdtype(dataset.dtype, np.floating)):
        raise InputError(f"signal {signal!r} holds {dataset.dtype} data; only real numbers can be played back")
    data = np.asarray(dataset[()], dtype=np.float64).reshape(time.size, -1)
    if data.shape[1] == 0:
        raise InputError(f"signal {signal!r} has no components")
    bad = ~np.isfinite(data)
    if bad.any():
        sample, component = np.argwhere(bad)[0]
        where = f"sample {sample} (t = {time[sample]!r} s)"
        if dataset.ndim == 2:
            where += f", component {component}"
        raise InputError(f"signal {signal!r} has a NaN or infinite value at {where}")
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


def model_description_xml(table: PlaybackTable, fmi_version: int, identifier: str, token: str) -> bytes:
    """modelDescription.xml of the player FMU for FMI 2.0 or 3.0."""
    fmi3 = fmi_version == 3
    span = float(table.time[-1] - table.time[0])
    root = ET.Element(
        "fmiModelDescription",
        {
            "fmiVersion": "3.0" if fmi3 else "2.0",
            "modelName": identifier,
            ("instantiationToken" if fmi3 else "guid"): token,
            "description": f"Playback of {len(table.names)} load history outputs sampled at {table.time.size} times",
            "generationTool": "fretwork",
            "generationDateAndTime": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
            "variableNamingConvention": "structured",
        },
    )
    if not fmi3:
        root.set("numberOfEventIndicators", "0")
    cosim = ET.SubElement(
        root,
        "CoSimulation",
        {
            "modelIdentifier": identifier,
            "canHandleVariableCommunicationStepSize": "true",
            "canGetAndSetFMUState" if fmi3 else "canGetAndSetFMUstate": "false",
            "canSerializeFMUState" if fmi3 else "canSerializeFMUstate": "false",
        },
    )
    if not fmi3:
        files = ET.SubElement(cosim, "SourceFiles")
        for name in PLAYER_SOURCES + FMI_SOURCES[2]:
            ET.SubElement(files, "File", {"name": name})

    units = sorted({unit for unit in table.units if unit} | {"s"})
    unit_definitions = ET.SubElement(root, "UnitDefinitions")
    for unit in units:
        unit_element = ET.SubElement(unit_definitions, "Unit", {"name": unit})
        if unit in BASE_UNITS:
            exponents, factor = BASE_UNITS[unit]
            attributes = {key: str(value) for key, value in exponents.items()}
            if factor != 1.0:
                attributes["factor"] = repr(factor)
            ET.SubElement(unit_element, "BaseUnit", attributes)

    log_categories = ET.SubElement(root, "LogCategories")
    ET.SubElement(log_categories, "Category", {"name": "logStatusError", "description": "Errors of the player"})

    ET.SubElement(
        root,
        "DefaultExperiment",
        {
            "startTime": repr(float(table.time[0])),
            "stopTime": repr(float(table.time[-1])),
            "stepSize": f"{np.median(np.diff(table.time)):.12g}",
        },
    )

    variables = ET.SubElement(root, "ModelVariables")
    parameters = [
        (VR_TIME_OFFSET, "time_offset", "Real", "s", "0.0",
         "Shift of the history in time: the output at time t is the history at t - time_offset"),
        (VR_PERIOD, "period", "Real", "s", repr(span),
         "Repetition period when periodic; at least the sampled span t_last - t_first"),
        (VR_PERIODIC, "periodic", "Boolean", "", "false",
         "Repeat the history with the given period instead of holding the first/last sample"),
    ]
    if fmi3:
        ET.SubElement(variables, "Float64", {
            "name": "time", "valueReference": str(VR_TIME), "causality": "independent",
            "variability": "continuous", "unit": "s", "description": "Simulation time",
        })
        for vr, name, kind, unit, start, description in parameters:
            attributes = {"name": name, "valueReference": str(vr), "causality": "parameter",
                          "variability": "fixed", "description": description, "start": start}
            if unit:
                attributes["unit"] = unit
            ET.SubElement(variables, "Float64" if kind == "Real" else "Boolean", attributes)
        for j, (name, unit, description) in enumerate(zip(table.names, table.units, table.descriptions)):
            attributes = {"name": name, "valueReference": str(VR_FIRST_OUTPUT + j), "causality": "output",
                          "variability": "continuous"}
            if description:
                attributes["description"] = description
            if unit:
                attributes["unit"] = unit
            ET.SubElement(variables, "Float64", attributes)
        structure = ET.SubElement(root, "ModelStructure")
        for j in range(len(table.names)):
            ET.SubElement(structure, "Output", {"valueReference": str(VR_FIRST_OUTPUT + j)})
        for j in range(len(table.names)):
            ET.SubElement(structure, "InitialUnknown", {"valueReference": str(VR_FIRST_OUTPUT + j)})
    else:
        for vr, name, kind, unit, start, description in parameters:
            variable = ET.SubElement(variables, "ScalarVariable", {
                "name": name, "valueReference": str(vr), "causality": "parameter",
                "variability": "fixed", "description": description,
            })
            attributes = {"start": start}
            if unit:
                attributes["unit"] = unit
            ET.SubElement(variable, kind, attributes)
        for j, (name, unit, description) in enumerate(zip(table.names, table.units, table.descriptions)):
            attributes = {"name": name, "valueReference": str(VR_FIRST_OUTPUT + j), "causality": "output",
                          "variability": "continuous"}
            if description:
                attributes["description"] = description
            variable = ET.SubElement(variables, "ScalarVariable", attributes)
            ET.SubElement(variable, "Real", {"unit": unit} if unit else {})
        structure = ET.SubElement(root, "ModelStructure")
        # FMI 2.0 ModelStructure refers to variables by 1-based position in ModelVariables.
        first_output_index = len(parameters) + 1
        outputs = ET.SubElement(structure, "Outputs")
        initial = ET.SubElement(structure, "InitialUnknowns")
        for j in range(len(table.names)):
            ET.SubElement(outputs, "Unknown", {"index": str(first_output_index + j)})
            ET.SubElement(initial, "Unknown", {"index": str(first_output_index + j)})
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def _build_description_xml(identifier: str) -> bytes:
    """FMI 3.0 sources/buildDescription.xml listing the player sources."""
    root = ET.Element("fmiBuildDescription", {"fmiVersion": "3.0"})
    configuration = ET.SubElement(root, "BuildConfiguration", {"modelIdentifier": identifier})
    file_set = ET.SubElement(configuration, "SourceFileSet", {"language": "C99"})
    for name in PLAYER_SOURCES + FMI_SOURCES[3]:
        ET.SubElement(file_set, "SourceFile", {"name": name})
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def _write_sources(sources_dir: Path, fmi_version: int, identifier: str) -> None:
    sources_dir.mkdir(parents=True)
    for name in PLAYER_SOURCES + PLAYER_HEADERS + FMI_SOURCES[fmi_version] + FMI_HEADERS[fmi_version]:
        shutil.copyfile(TEMPLATE_DIR / name, sources_dir / name)
    if fmi_version == 3:
        (sources_dir / "buildDescription.xml").write_bytes(_build_description_xml(identifier))


def binary_platform(fmi_version: int) -> tuple[str, str] | None:
    """(binaries folder, shared library suffix) of this platform, None where the player is not built."""
    machine = platform.machine().lower()
    if sys.platform.startswith("linux") and machine in ("x86_64", "amd64"):
        return ("linux64" if fmi_version == 2 else "x86_64-linux"), ".so"
    if sys.platform.startswith("linux") and machine in ("aarch64", "arm64") and fmi_version == 3:
        return "aarch64-linux", ".so"
    if sys.platform == "darwin":
        if fmi_version == 2:
            return "darwin64", ".dylib"
        return ("aarch64-darwin" if machine == "arm64" else "x86_64-darwin"), ".dylib"
    return None


def find_compiler(compiler: str | None = None) -> str | None:
    """Path of the C compiler to use: `compiler`, else $CC, cc, gcc, clang; None if none is found."""
    candidates = [compiler] if compiler else [os.environ.get("CC"), "cc", "gcc", "clang"]
    for candidate in candidates:
        if candidate and shutil.which(candidate):
            return shutil.which(candidate)
    return None


def _add_binary(fmu_dir: Path, fmi_version: int, identifier: str, compiler: str | None) -> None:
    target = binary_platform(fmi_version)
    compiler_path = find_compiler(compiler)
    if target is None or compiler_path is None:
        reason = (
            f"no FMI binary folder is known for {sys.platform}/{platform.machine()}"
            if target is None
            else f"no C compiler found (tried {compiler or '$CC, cc, gcc, clang'})"
        )
        warnings.warn(
            SourceOnlyFmuWarning(
                f"{reason}: the FMU holds C sources only; importing tools must compile it "
                f"(e.g. FMPy: fmpy.build.build_platform_binary)"
            ),
            stacklevel=3,
        )
        return
    folder, suffix = target
    binary_dir = fmu_dir / "binaries" / folder
    binary_dir.mkdir(parents=True)
    sources_dir = fmu_dir / "sources"
    command = [
        compiler_path, "-std=c99", "-O2", "-shared", "-fPIC", "-fvisibility=hidden",
        "-I", str(sources_dir),
        *(str(sources_dir / name) for name in PLAYER_SOURCES + FMI_SOURCES[fmi_version]),
        "-o", str(binary_dir / (identifier + suffix)), "-lm",
    ]
    completed = subprocess.run(command, capture_output=True, text=True)
    if completed.returncode != 0:
        raise FmuBuildError(
            f"compiling the FMU player failed ({' '.join(command)}):\n{completed.stderr.strip()}"
        )


def _zip_atomically(fmu_dir: Path, output_path: Path) -> None:
    """Zip into a temporary file beside output_path, then rename: no partial FMU is ever visible."""
    handle, temporary = tempfile.mkstemp(prefix=f".{output_path.name}.", suffix=".part", dir=output_path.parent)
    os.close(handle)
    try:
        # Level 1: float tables compress little, and higher levels cost seconds on large exports.
        with zipfile.ZipFile(temporary, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as archive:
            for path in sorted(fmu_dir.rglob("*")):
                archive.write(path, path.relative_to(fmu_dir).as_posix())
        os.replace(temporary, output_path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def add_export_fmu_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``export-fmu`` on a subparsers object; the handler is set as ``func``."""
    parser = subparsers.add_parser(
        "export-fmu",
        help="export load histories as a co-simulation FMU",
        description="Export the /histories of a results file as a co-simulation FMU whose outputs play "
        "the histories back (linear interpolation, parameters time_offset, periodic, period).",
    )
    _configure_parser(parser)
    return parser


def _configure_parser(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("results", type=Path, help="results file (HDF5) with a /histories group")
    parser.add_argument(
        "--signals", nargs="+", metavar="NAME",
        help="signals to export (names under /histories, space or comma separated); default: all",
    )
    parser.add_argument("--fmi", type=int, choices=(2, 3), default=2, help="FMI version (default 2)")
    parser.add_argument("-o", "--output", type=Path, required=True, help="FMU file to write, e.g. loads.fmu")
    parser.add_argument("--model-name", help="model name (default: output file name)")
    parser.set_defaults(func=run_export_fmu)


def run_export_fmu(args: argparse.Namespace) -> int:
    """Run ``export-fmu`` from parsed arguments; prints the result. Returns the exit code (2: bad input)."""
    signals = None
    if args.signals:
        signals = [name for item in args.signals for name in item.split(",") if name]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", SourceOnlyFmuWarning)
        try:
            path = export_fmu(args.results, args.output, signals, args.fmi, model_name=args.model_name)
        except InputError as error:
            print(f"error: {error}", file=sys.stderr)
            return 2
    for warning in caught:
        print(f"warning: {warning.message}", file=sys.stderr)
    content = "sources only, no binary" if caught else "binary and sources"
    print(f"wrote {path} (FMI {args.fmi}.0 co-simulation, {content}, {path.stat().st_size / 1e6:.2f} MB)")
    return 0


def main_export(argv: Sequence[str] | None = None) -> int:
    """Stand-alone entry: ``python -m pipelines.fmu.export RESULTS.h5 [--signals ...] [--fmi 2|3] -o loads.fmu``."""
    parser = argparse.ArgumentParser(prog="fretwork export-fmu", description="Export load histories as an FMU.")
    _configure_parser(parser)
    return run_export_fmu(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main_export())
