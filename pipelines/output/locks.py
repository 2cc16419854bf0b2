"""The output folder of a command: checked before any work, held with a lock, cleared of old outputs.

:func:`claim` is what every command does with its ``--out`` folder before it computes anything:

- the folder must be a place for results: not a file, not below a file, not in a system folder
  (/proc, /sys, /dev), writable; anything else is an :class:`InputError` naming the option;
- a lock file (``.fretwork.lock``, holding the process id) marks the folder in use: a second
  command into the same folder is refused while the first runs; the lock of a process that no
  longer exists (killed, machine restarted) is stale and taken over;
- the outputs an earlier run of the command left there (its ``outputs``: names or glob
  patterns) are removed, said in one note line, so that old plots never stand beside new ones;
  only once the command's input has been checked (``ready``): a refused input loses nothing;
- when the command is interrupted (Ctrl-C), its half-written files (``*.part``, ``*.tmp``) go;
- when the command fails, the folders the claim created are removed again if they are empty:
  a refused input leaves nothing behind.
"""

from __future__ import annotations

import os
import shutil
import sys
import time
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

from reduction.errors import InputError

LOCK_NAME = ".fretwork.lock"
#: Kernel and device folders: never a place for results.
SYSTEM_FOLDERS = (Path("/proc"), Path("/sys"), Path("/dev"))
#: Half-written files, removed when a command is interrupted: a results file being written
#: (results.h5.part: the run's whole files are its results.h5 and checkpoint.h5) and the
#: temporary files of atomic writes.
PARTIAL = ("**/*.part", "**/*.tmp")
#: A lock file younger than this without a process id is being written by its owner.
_FRESH_LOCK_S = 10.0


def _note(text: str) -> None:
    print(f"fretwork: note: {text}", file=sys.stderr)


def check_folder(path, option: str = "--out") -> Path:
    """``path`` as a folder results can be written to (it may not exist yet); InputError if not."""
    path = Path(path)
    resolved = path.expanduser().resolve()
    for system in SYSTEM_FOLDERS:
        if resolved == system or system in resolved.parents:
            raise InputError(f"{option} {path}: {system} is a system folder, not a place for results; "
                             "give a folder of your own")
    existing = resolved
    while not existing.exists():
        existing = existing.parent
    if not existing.is_dir():
        what = "is a file" if existing == resolved else f"lies below the file {existing}"
        raise InputError(f"{option} {path} {what}: give a folder (it is created if missing)")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise InputError(f"{option} {path}: {existing} is not writable (permission denied)")
    return path


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # a process of another user
        return True
    return True


def _owner(lock: Path) -> int | None:
    try:
        return int(lock.read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return None


def _in_use(lock: Path) -> str | None:
    """Who holds ``lock`` ("pid N"), or None when the lock is stale."""
    pid = _owner(lock)
    if pid is not None:
        return f"pid {pid}" if _alive(pid) else None
    try:
        fresh = time.time() - lock.stat().st_mtime < _FRESH_LOCK_S
    except FileNotFoundError:
        return None
    return "a process that is starting" if fresh else None


def _acquire(lock: Path, option: str) -> None:
    for _ in range(3):
        try:
            descriptor = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            holder = _in_use(lock)
            if holder is not None:
                raise InputError(f"{option} {lock.parent} is in use by another fretwork command ({holder}); "
                                 "wait for it to end or give another folder") from None
            lock.unlink(missing_ok=True)  # stale: the process that held it is gone
            continue
        except OSError as error:
            raise InputError(f"{option} {lock.parent}: cannot write there ({error.strerror})") from None
        with os.fdopen(descriptor, "w") as stream:
            stream.write(f"{os.getpid()}\n")
        return
    raise InputError(f"{option} {lock.parent} is in use by another fretwork command; give another folder")


def _make(folder: Path, option: str) -> list[Path]:
    """Create ``folder`` and its missing parents; the ones created, outermost first."""
    missing = [p for p in (folder, *folder.parents) if not p.exists()][::-1]
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise InputError(f"{option} {folder}: cannot create the folder ({error.strerror})") from None
    return missing


def _clear(folder: Path, outputs: Iterable[str], option: str, note: Callable[[str], None]) -> None:
    old = sorted({found for pattern in outputs for found in folder.glob(pattern)})
    for path in old:
        try:
            if path.is_dir() and not path.is_symlink():
                shutil.rmtree(path)
            else:
                path.unlink()
        except OSError as error:
            raise InputError(f"{option} {folder}: cannot remove the earlier output {path.name} "
                             f"({error.strerror})") from None
    if old:
        note(f"removed {len(old)} output(s) of an earlier run from {folder}: "
             + ", ".join(p.name for p in old))


@contextmanager
def claim(path, *, outputs: Iterable[str] = (), ready: Callable[[], object] | None = None,
          partial: Iterable[str] = PARTIAL, option: str = "--out",
          note: Callable[[str], None] = _note) -> Iterator[Path]:
    """Check, create, lock and clear the output folder ``path`` for the block (module doc).

    outputs: names or glob patterns of what the command writes there, removed first (pass none
    to keep everything, e.g. to resume). ready: checks the command's input (raises InputError)
    before anything is removed. partial: patterns of half-written files, removed when the block
    is interrupted (Ctrl-C). note: where the one-line note about removed outputs goes.
    """
    folder = check_folder(path, option)
    created = _make(folder, option)
    lock = folder / LOCK_NAME
    try:
        _acquire(lock, option)
    except BaseException:
        _remove_empty(created)
        raise
    try:
        if ready is not None:
            ready()
        _clear(folder, outputs, option, note)
        yield folder
    except BaseException as error:
        if isinstance(error, KeyboardInterrupt):
            _remove_partial(folder, partial)
        lock.unlink(missing_ok=True)
        _remove_empty(created)
        raise
    lock.unlink(missing_ok=True)


def _remove_partial(folder: Path, patterns: Iterable[str]) -> None:
    """Remove the files matching ``patterns`` below ``folder``, then the empty folders below it."""
    for pattern in patterns:
        for path in folder.glob(pattern):
            if path.is_file():
                path.unlink(missing_ok=True)
    for parent, _, _ in sorted(os.walk(folder), key=lambda entry: -len(Path(entry[0]).parts)):
        if Path(parent) != folder and not any(Path(parent).iterdir()):
            Path(parent).rmdir()


def _remove_empty(created: list[Path]) -> None:
    for folder in reversed(created):
        try:
            folder.rmdir()
        except OSError:  # not empty (the command left results there) or already gone
            return


__all__ = ["LOCK_NAME", "check_folder", "claim"]
