"""The output folder of a command: checked before any work, held with a lock, cleared of old outputs.

:func:`claim` is what every command does with its ``--out`` folder before it computes anything:

- the folder must be a place for results: given (not empty), not a file, not below a file, not
  in or below a system folder (/proc, /sys, /dev, /usr, /etc, /bin, /sbin, /lib, /lib64, /boot),
  not itself a folder that holds other people's folders (/, /var, /root, /home, the user's home:
  a folder below them is fine), writable; anything else is an :class:`InputError` naming the
  option;
- a lock file (``.fretwork.lock``, holding the process id) marks the folder in use: a second
  command into the same folder is refused while the first runs; the lock of a process that no
  longer exists (killed, machine restarted) is stale and taken over;
- fretwork removes only what provably came from fretwork. Whatever a command wrote into the
  folder (the files below its ``outputs``: names or glob patterns) is listed, when the command
  ends in any way, in the folder's manifest ``.fretwork-outputs`` (one file a line: its
  modification time and size, its path relative to the folder). A file is fretwork's when the
  manifest lists it and it is unchanged since (a file the user wrote over is not), or when it
  says so itself: an HDF5 file whose root attribute ``fretwork_format`` starts with "fretwork-"
  (results, checkpoint, multibody and sweep files), a file named ``*.part`` or ``checkpoint.h5``
  that is empty or an HDF5 file that cannot be read (a results file half-written when its run was
  killed, a checkpoint truncated after it was written: fretwork's names, nothing in them readable),
  or a page of ``fretwork report``. Where the
  command writes, a file that is not fretwork's is never removed: the command is refused, naming
  the files and the way out (another folder, or remove them yourself);
- the outputs an earlier run of the command left there are then set aside (moved into
  ``.fretwork-earlier`` in the folder), once the command's input has been checked (``ready``).
  They are removed, said in one note line, when the command ends having written outputs of its
  own, so that old plots never stand beside new ones; a command that fails before it wrote any
  (an input refused only as the command runs: a scene that does not mesh or build, a selection
  that finds nothing, a cluster option, a checkpoint that cannot be resumed) puts them back: a
  refused input loses nothing. Outputs set aside by a command that was killed are put back by
  the next claim of the folder, unless the killed command had written outputs of its own;
- when the command is interrupted (Ctrl-C), its half-written files (``*.part``, ``*.tmp``
  written since the claim) go;
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
#: The list of the files fretwork wrote into the folder: the only ones, with the files that say
#: they are fretwork's, that a command removes.
MANIFEST_NAME = ".fretwork-outputs"
#: Kernel, device and system-software folders: neither they nor anything below them is a place
#: for results.
SYSTEM_FOLDERS = tuple(Path(p) for p in ("/proc", "/sys", "/dev", "/usr", "/etc", "/bin", "/sbin", "/lib",
                                         "/lib64", "/boot"))
#: Folders that hold other folders: a place for results may lie below them, never be one of them
#: (the user's home is one too, see :func:`_shared_folders`).
SHARED_FOLDERS = tuple(Path(p) for p in ("/", "/var", "/root", "/home"))
#: Where a claim keeps the outputs an earlier run left in the folder until the command has
#: written its own (then they are removed) or has failed without writing any (then they go back).
EARLIER_NAME = ".fretwork-earlier"
#: Names of files only fretwork writes where its commands write, which are fretwork's even when
#: damaged (empty, or HDF5 that cannot be read): a run's half-written results file and its
#: checkpoint; a new run replaces them (--resume says the checkpoint is damaged).
DAMAGED_OURS = ("*.part", "checkpoint.h5")
#: Half-written files, removed when a command is interrupted: a results file being written
#: (results.h5.part: the run's whole files are its results.h5 and checkpoint.h5) and the
#: temporary files of atomic writes.
PARTIAL = ("**/*.part", "**/*.tmp")
#: The title that begins every page of ``fretwork report`` (pipelines.output.report): what
#: makes a report.html provably fretwork's.
REPORT_TITLE = "fretwork report: "
_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
#: A lock file younger than this without a process id is being written by its owner.
_FRESH_LOCK_S = 10.0


def _note(text: str) -> None:
    print(f"fretwork: note: {text}", file=sys.stderr)


def _shared_folders() -> list[Path]:
    folders = [folder.resolve() for folder in SHARED_FOLDERS]
    try:
        folders.append(Path.home().resolve())
    except RuntimeError:  # no home folder known
        pass
    return folders


def check_folder(path, option: str = "--out") -> Path:
    """``path`` as a folder results can be written to (it may not exist yet); InputError if not."""
    if not str(path).strip():
        raise InputError(f"{option} is empty: give a folder for the results (it is created if missing), "
                         f"e.g. {option} results")
    path = Path(path)
    resolved = path.expanduser().resolve()
    for system in SYSTEM_FOLDERS:
        system = system.resolve()
        if resolved == system or system in resolved.parents:
            raise InputError(f"{option} {path}: {system} is a system folder, not a place for results; "
                             "give a folder of your own")
    if resolved in _shared_folders():
        raise InputError(f"{option} {path}: {resolved} holds other folders, not a place for results; give a "
                         f"folder of its own, e.g. {option} {resolved / 'fretwork-results'}")
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


def _stamp(path: Path) -> str:
    """What a file was when fretwork recorded it: its modification time (ns) and size."""
    status = path.lstat()
    return f"{status.st_mtime_ns} {status.st_size}"


def _recorded(folder: Path) -> dict[str, str]:
    """The files the manifest lists (paths relative to ``folder``) with their stamps."""
    try:
        lines = (folder / MANIFEST_NAME).read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError):  # none yet, or unreadable: nothing is recorded
        return {}
    entries = [line.split(" ", 2) for line in lines if line and not line.startswith("#")]
    return {entry[2]: f"{entry[0]} {entry[1]}" for entry in entries if len(entry) == 3}


def _record(folder: Path, entries: dict[str, str]) -> None:
    """Write the manifest (atomically); none when nothing is recorded."""
    manifest = folder / MANIFEST_NAME
    try:
        if not entries:
            manifest.unlink(missing_ok=True)
            return
        temporary = manifest.with_name(MANIFEST_NAME + ".tmp")
        temporary.write_text("# the files fretwork wrote here (modified ns, bytes, path): its commands remove only\n"
                             "# these, as they were written, and the files that say they are fretwork's\n"
                             + "".join(f"{entries[name]} {name}\n" for name in sorted(entries)), encoding="utf-8")
        os.replace(temporary, manifest)
    except OSError:  # the folder went read-only: a later command then refuses to clear, nothing is lost
        pass


def _ours(folder: Path, name: str, recorded: dict[str, str]) -> bool:
    """Whether the file ``name`` is provably fretwork's: recorded, and unchanged since, or it says so."""
    path = folder / name
    return recorded.get(name) == _stamp(path) or _says_fretwork(path)


def _files(entry: Path, folder: Path) -> list[str]:
    """The files at or below ``entry`` (links as files, never followed), relative to ``folder``."""
    if entry.is_symlink() or not entry.is_dir():
        return [entry.relative_to(folder).as_posix()]
    found = []
    for parent, folders, names in os.walk(entry):
        base = Path(parent)
        found += [(base / name).relative_to(folder).as_posix() for name in names]
        found += [(base / name).relative_to(folder).as_posix() for name in folders if (base / name).is_symlink()]
    return found


def _says_fretwork(path: Path) -> bool:
    """Whether the file says it was written by fretwork: an HDF5 file whose root attribute
    ``fretwork_format`` starts with "fretwork-", or a page of ``fretwork report``."""
    if path.is_symlink() or not path.is_file():
        return False
    try:
        with path.open("rb") as stream:
            head = stream.read(1024)
    except OSError:
        return False
    if not head:
        return _damaged_ours(path)  # a checkpoint emptied: nothing in it to lose
    if head.startswith(_HDF5_SIGNATURE):
        import h5py

        try:
            with h5py.File(path, "r") as file:
                tag = file.attrs.get("fretwork_format", "")
        except (OSError, KeyError, ValueError):
            # a damaged file proves nothing, but for fretwork's own names: the half-written
            # results file of a run killed in the middle of a write, which its --resume must
            # take over, and a checkpoint truncated after it was written, which a new run replaces
            return _damaged_ours(path)
        return (tag.decode(errors="replace") if isinstance(tag, bytes) else str(tag)).startswith("fretwork-")
    return f"<title>{REPORT_TITLE}".encode() in head


def _damaged_ours(path: Path) -> bool:
    return any(path.match(pattern) for pattern in DAMAGED_OURS)


def _outputs(folder: Path, outputs: Iterable[str]) -> list[Path]:
    return sorted({found for pattern in outputs for found in folder.glob(pattern)})


def _written(folder: Path, outputs: Iterable[str]) -> set[str]:
    return {name for entry in _outputs(folder, outputs) for name in _files(entry, folder)}


def _refuse_foreign(folder: Path, outputs: Iterable[str], recorded: dict[str, str], option: str) -> None:
    """InputError naming the files where the command writes that are not provably fretwork's."""
    foreign = sorted(name for name in _written(folder, outputs) if not _ours(folder, name, recorded))
    if foreign:
        shown = ", ".join(foreign[:5]) + (f" and {len(foreign) - 5} more" if len(foreign) > 5 else "")
        raise InputError(f"{option} {folder} holds files that fretwork did not write, where this command "
                         f"writes its outputs: {shown}; they are left alone: give another {option}, or move "
                         "or remove them yourself")


def _set_aside(folder: Path, outputs: Iterable[str], option: str) -> None:
    """Move the outputs of an earlier run (all fretwork's: :func:`_refuse_foreign` first) into
    :data:`EARLIER_NAME`, where :func:`_settle` removes them or puts them back."""
    earlier = folder / EARLIER_NAME
    for path in _outputs(folder, outputs):
        target = earlier / path.relative_to(folder)
        try:
            target.parent.mkdir(parents=True, exist_ok=True)
            path.rename(target)
        except OSError as error:
            _put_back(earlier, folder)
            raise InputError(f"{option} {folder}: cannot set aside the earlier output {path.name} "
                             f"({error.strerror})") from None


def _put_back(earlier: Path, folder: Path) -> None:
    """Move what :func:`_set_aside` moved into ``earlier`` back into ``folder``, where the name is
    free (merging folders), and remove ``earlier``."""
    for path in sorted(earlier.iterdir()) if earlier.is_dir() else ():
        target = folder / path.name
        if path.is_dir() and not path.is_symlink() and target.is_dir() and not target.is_symlink():
            _put_back(path, target)
        elif not target.exists() and not target.is_symlink():
            path.rename(target)
    shutil.rmtree(earlier, ignore_errors=True)


def _settle(folder: Path, outputs: Iterable[str], failed: bool, note: Callable[[str], None]) -> None:
    """The end of what :func:`_set_aside` began: a command that failed before writing any of its
    outputs gets the earlier run's back; otherwise they are removed, and said so."""
    earlier = folder / EARLIER_NAME
    if not earlier.is_dir():
        return
    if failed and not _outputs(folder, outputs):
        _put_back(earlier, folder)
        return
    old = sorted(earlier.iterdir())
    shutil.rmtree(earlier, ignore_errors=True)
    if old:
        note(f"removed {len(old)} output(s) of an earlier run from {folder}: " + ", ".join(p.name for p in old))


@contextmanager
def claim(path, *, outputs: Iterable[str] = (), clear: bool = True, ready: Callable[[], object] | None = None,
          partial: Iterable[str] = PARTIAL, option: str = "--out",
          note: Callable[[str], None] = _note) -> Iterator[Path]:
    """Check, create, lock and clear the output folder ``path`` for the block (module doc).

    outputs: names or glob patterns of what the command writes there: refused when not
    fretwork's, set aside first when ``clear`` (false: kept, e.g. to resume, or a single file the
    command writes anew) and removed when the block ends having written outputs, put back when
    it fails before writing any; recorded in the manifest when the block ends. ready: checks the
    command's input (raises InputError) before anything is set aside. partial: patterns of
    half-written files, removed when the block is interrupted (Ctrl-C). note: where the
    one-line note about removed outputs goes.
    """
    outputs = tuple(outputs)
    folder = check_folder(path, option)
    created = _make(folder, option)
    lock = folder / LOCK_NAME
    try:
        _acquire(lock, option)
    except BaseException:
        _remove_empty(created)
        raise
    since = lock.stat().st_mtime_ns
    try:
        # outputs a killed command set aside: its own, if it wrote any, replace them
        _settle(folder, outputs, True, note)
        if ready is not None:
            ready()
        recorded = _recorded(folder)
        _refuse_foreign(folder, outputs, recorded, option)
        if clear:
            _set_aside(folder, outputs, option)
    except BaseException:
        lock.unlink(missing_ok=True)
        _remove_empty(created)
        raise
    failed = True
    try:
        yield folder
        failed = False
    except KeyboardInterrupt:
        _remove_partial(folder, partial, since)
        raise
    finally:
        _settle(folder, outputs, failed, note)
        # what is below the outputs now is fretwork's: it was (else the claim was refused), or the
        # command wrote it; what the manifest holds beside (another command's) stays as recorded
        kept = {name: stamp for name, stamp in recorded.items()
                if (folder / name).is_file() or (folder / name).is_symlink()}
        _record(folder, kept | {name: _stamp(folder / name) for name in _written(folder, outputs)})
        lock.unlink(missing_ok=True)
        if failed:
            _remove_empty(created)


def _remove_partial(folder: Path, patterns: Iterable[str], since: int) -> None:
    """Remove the files matching ``patterns`` below ``folder`` written since ``since`` (ns), then
    the empty folders below it made or emptied since then: an older file, or an empty folder of
    the user's, is not the interrupted command's."""
    def earlier(path: Path) -> bool:  # an earlier run's outputs, set aside: not the command's
        return EARLIER_NAME in path.relative_to(folder).parts

    for pattern in patterns:
        for path in folder.glob(pattern):
            if path.is_file() and not path.is_symlink() and path.stat().st_mtime_ns >= since and not earlier(path):
                path.unlink(missing_ok=True)
    for parent, _, _ in sorted(os.walk(folder), key=lambda entry: -len(Path(entry[0]).parts)):
        below = Path(parent)
        if below != folder and not earlier(below) and not any(below.iterdir()) and below.stat().st_mtime_ns >= since:
            below.rmdir()


def _remove_empty(created: list[Path]) -> None:
    for folder in reversed(created):
        try:
            folder.rmdir()
        except OSError:  # not empty (the command left results there) or already gone
            return


__all__ = ["EARLIER_NAME", "LOCK_NAME", "MANIFEST_NAME", "REPORT_TITLE", "check_folder", "claim"]
