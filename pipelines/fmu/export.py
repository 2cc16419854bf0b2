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

The FMU file never takes the place of a file fretwork did not write: it must be named ``*.fmu``
(the FMI standard's extension, which importing tools look for, and a name no results file, scene
or other input of fretwork has), may not be the results file it is made from, and replaces an
existing file only if that is an FMU fretwork wrote (:func:`written_by_fretwork`). Its folder is
claimed as every command's output folder is (:func:`pipelines.output.locks.claim`: checked,
created, locked while the FMU is written).

Units follow the results file (fretwork uses mm, N, MPa, t, s, mJ).
"""

from __future__ import annotations

import os
import platform
import shutil
import subprocess
import sys
import tempfile
import uuid
import warnings
import xml.etree.ElementTree as ET
import zipfile
import zlib
from pathlib import Path
from typing import Sequence

from reduction.errors import InputError
from pipelines.fmu.table import (TABLE_FILE, TABLE_MAGIC, instantiation_token, model_identifier, read_playback_table,
                                 results_file, write_table)
from pipelines.fmu.description import (FMI_HEADERS, FMI_SOURCES, GENERATION_TOOL, PLAYER_HEADERS, PLAYER_SOURCES,
                                       build_description_xml, model_description_xml)
from pipelines.output.locks import claim


TEMPLATE_DIR = Path(__file__).parent / "template"
FMU_SUFFIX = ".fmu"
#: what reading a damaged or foreign zip file may raise
_UNREADABLE = (OSError, EOFError, KeyError, ValueError, RuntimeError, NotImplementedError, zipfile.BadZipFile,
               zlib.error, ET.ParseError)


class SourceOnlyFmuWarning(UserWarning):
    """The FMU was exported without a compiled binary (sources only)."""


class FmuBuildError(RuntimeError):
    """The C compiler failed on the player sources: a fretwork or toolchain defect, not bad input."""


def export_fmu(
    results_path: str | os.PathLike,
    output_path: str | os.PathLike,
    signals: Sequence[str] | None = None,
    fmi_version: int = 2,
    *,
    whole: bool = False,
    model_name: str | None = None,
    compiler: str | None = None,
) -> Path:
    """Write a co-simulation FMU that plays back the ``/histories`` of a results file.

    results_path: HDF5 results file with a ``/histories`` group (time in s, signals (n,) or (n, k)),
        or a run's output folder (:func:`pipelines.fmu.table.results_file`).
    output_path: FMU file to write, named ``*.fmu``; parent folders are created. Not the results
        file; an existing file there is replaced only if it is an FMU fretwork wrote. Written
        atomically: on any error no FMU file is left at output_path.
    signals: dataset names under ``/histories`` to export, in this order; None exports all.
        A signal of shape (n, k) becomes k outputs ``<signal>.<component>`` when the dataset has a
        ``components`` attribute, else ``<signal>[1]`` .. ``<signal>[k]``.
    fmi_version: 2 (FMI 2.0, default) or 3 (FMI 3.0).
    whole: of ``fretwork mbs``'s run.h5, play the whole run, start-up transient included; by
        default its steady part (:func:`mbs.histories.steady_part`), where the wing amplitude is
        measured.
    model_name: model name and identifier (binary name); default from the output file name.
    compiler: C compiler command; default $CC, then cc, gcc, clang. If none is found, or this
        platform has no FMI binary folder, the FMU holds sources only and a
        SourceOnlyFmuWarning is issued.

    Raises InputError for bad input (missing file, group or signal; empty, non-finite or
    non-increasing time; NaN or infinite data; an output path that is not an FMU's to take) and
    FmuBuildError if compilation fails. Returns the path of the written FMU.
    """
    if fmi_version not in (2, 3):
        raise InputError(f"FMI version {fmi_version!r} is not supported: choose 2 or 3")
    output_path = Path(output_path)
    if output_path.is_dir():
        raise InputError(f"FMU output path {output_path} is a folder; give a file name such as loads.fmu")
    source = results_file(results_path)
    table = read_playback_table(source, signals, whole=whole)
    identifier = model_identifier(model_name or output_path.stem)
    token = instantiation_token(table)

    # locked while written: no other fretwork command writes there meanwhile; partial=(): the one
    # half-written file, the zip's, is removed by _zip_atomically itself
    with claim(output_path.parent, clear=False, partial=(), option="-o",
               ready=lambda: check_output(output_path, source)), \
            tempfile.TemporaryDirectory(prefix="fretwork-fmu-") as work:
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


def check_output(output_path: Path, source: Path) -> None:
    """InputError unless ``output_path`` may take the FMU of the results file ``source``: a name
    ending in .fmu, not ``source`` itself, and no file there but an FMU fretwork wrote."""
    if output_path.exists() and source.exists() and os.path.samefile(output_path, source):
        raise InputError(f"-o {output_path} is the results file being exported: the FMU needs a file of its own, "
                         f"e.g. -o {source.with_suffix(FMU_SUFFIX)}")
    if output_path.suffix.lower() != FMU_SUFFIX:
        raise InputError(f"-o {output_path}: an FMU's file name ends in {FMU_SUFFIX} (the FMI standard's extension, "
                         f"which importing tools look for); give e.g. -o {output_path.with_suffix(FMU_SUFFIX)}")
    if os.path.lexists(output_path) and not written_by_fretwork(output_path):
        raise InputError(f"-o {output_path} exists and is not an FMU that fretwork wrote: it is left alone; give "
                         "another -o, or move or remove it yourself")


def written_by_fretwork(path: str | os.PathLike) -> bool:
    """Whether ``path`` is an FMU that fretwork wrote: a zip file whose modelDescription.xml names
    fretwork as its generationTool and whose resources hold the player's table (its magic)."""
    try:
        with zipfile.ZipFile(path) as archive:
            tool = ET.fromstring(archive.read("modelDescription.xml")).get("generationTool")
            with archive.open(f"resources/{TABLE_FILE}") as table:
                magic = table.read(len(TABLE_MAGIC))
    except _UNREADABLE:
        return False
    return tool == GENERATION_TOOL and magic == TABLE_MAGIC


def _write_sources(sources_dir: Path, fmi_version: int, identifier: str) -> None:
    sources_dir.mkdir(parents=True)
    for name in PLAYER_SOURCES + PLAYER_HEADERS + FMI_SOURCES[fmi_version] + FMI_HEADERS[fmi_version]:
        shutil.copyfile(TEMPLATE_DIR / name, sources_dir / name)
    if fmi_version == 3:
        (sources_dir / "buildDescription.xml").write_bytes(build_description_xml(identifier))


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
    """Zip into a temporary file beside output_path, then rename: no partial FMU is ever visible.

    The temporary file is opened exclusively under a fresh name rather than by mkstemp, whose
    files are private (0600): renamed, the FMU would keep that mode instead of the one the user's
    umask gives every other output."""
    temporary = output_path.parent / f".{output_path.name}.{uuid.uuid4().hex[:12]}.part"
    stream = open(temporary, "xb")
    try:
        # Level 1: float tables compress little, and higher levels cost seconds on large exports.
        with stream, zipfile.ZipFile(stream, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as archive:
            for path in sorted(fmu_dir.rglob("*")):
                archive.write(path, path.relative_to(fmu_dir).as_posix())
        os.replace(temporary, output_path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise
