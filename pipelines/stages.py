"""Stage cache: a pipeline stage whose inputs have not changed is read back, not recomputed.

Each stage (``multibody``, ``contact_model``, ``contact_run``, ...) is a pure function of its
inputs. :meth:`StageCache.get` hashes the inputs (JSON-like values and numpy arrays) together
with a fingerprint of fretwork's own source code, so a changed model or a changed fretwork
never reuses a stale result. Values are pickled to ``<directory>/<stage>-<key>.pkl``, written
atomically (temporary file + rename): an interrupted run never leaves a half-written entry.

``EXECUTIONS`` counts the stages actually computed in this process (tests use it to prove that
a command runs only the stages it needs). The directory comes from ``--cache``, else the
environment variable ``FRETWORK_CACHE``, else ``.fretwork-cache`` in the working directory;
``None`` switches caching off. :func:`check_directory` says before any stage runs when the
directory cannot hold the cache (a file, not writable), naming the way out.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import pickle
import tempfile
from collections import Counter
from functools import lru_cache
from pathlib import Path
from typing import Callable, TypeVar

import numpy as np

from reduction.errors import InputError

EXECUTIONS: Counter = Counter()
T = TypeVar("T")
_PACKAGES = ("mbs", "reduction", "contact", "pipelines")


@lru_cache(maxsize=1)
def code_fingerprint() -> str:
    """SHA-256 over the source files of fretwork's packages (contents, not dates)."""
    digest = hashlib.sha256()
    root = Path(__file__).resolve().parent.parent
    for package in _PACKAGES:
        for path in sorted((root / package).rglob("*.py")):
            digest.update(str(path.relative_to(root)).encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()


def _canonical(value):
    if isinstance(value, np.ndarray):
        return {"__array__": hashlib.sha256(np.ascontiguousarray(value).tobytes()).hexdigest(),
                "dtype": str(value.dtype), "shape": list(value.shape)}
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {"__dataclass__": type(value).__name__,
                **{f.name: getattr(value, f.name) for f in dataclasses.fields(value)}}
    if isinstance(value, (set, frozenset)):
        return sorted(value)
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"stage input of type {type(value).__name__} cannot be hashed")


def stage_key(stage: str, inputs) -> str:
    text = json.dumps(inputs, sort_keys=True, default=_canonical)
    return hashlib.sha256(f"{stage}\0{code_fingerprint()}\0{text}".encode()).hexdigest()[:24]


def default_directory() -> Path:
    return Path(os.environ.get("FRETWORK_CACHE", ".fretwork-cache"))


def check_directory(directory: str | Path) -> Path:
    """``directory`` as a folder the stage cache can be kept in (it may not exist yet); an
    InputError naming the stage cache and the way out if not."""
    from pipelines.output.locks import check_folder

    try:
        return check_folder(directory, "the stage cache")
    except InputError as error:
        raise InputError(f"{error}; or keep the cache in another folder with --cache DIR (or FRETWORK_CACHE=DIR), "
                         "or run without it: --no-cache") from None


class StageCache:
    """Pickled stage results keyed by their inputs; ``directory=None`` computes every time."""

    def __init__(self, directory: str | Path | None):
        self.directory = None if directory is None else Path(directory)

    def get(self, stage: str, inputs, compute: Callable[[], T]) -> T:
        """The stage's value for ``inputs``: read back if cached, else computed and stored."""
        if self.directory is None:
            EXECUTIONS[stage] += 1
            return compute()
        path = self.directory / f"{stage}-{stage_key(stage, inputs)}.pkl"
        if path.is_file():
            try:
                with path.open("rb") as stream:
                    return pickle.load(stream)
            except (OSError, pickle.UnpicklingError, EOFError, AttributeError, ImportError):
                pass  # unreadable entry (e.g. from an older fretwork): compute it again
        value = compute()
        EXECUTIONS[stage] += 1
        self.directory.mkdir(parents=True, exist_ok=True)
        handle, temporary = tempfile.mkstemp(dir=self.directory, prefix=f".{stage}-", suffix=".tmp")
        try:
            with os.fdopen(handle, "wb") as stream:
                pickle.dump(value, stream, protocol=pickle.HIGHEST_PROTOCOL)
            os.replace(temporary, path)
        except BaseException:
            Path(temporary).unlink(missing_ok=True)
            raise
        return value
