"""Independent cases (sweep speeds, study settings, limit amplitudes) as dask.distributed tasks.

``map_cases(function, cases)`` calls ``function(**kwargs)`` once per case and returns one
:class:`CaseOutcome` per case, in the order of ``cases``:

- default: an embedded ``LocalCluster`` sized to the machine (one single-threaded worker process
  per core, BLAS pinned to one thread in the workers so two workers do not fight over a core),
  started for the call and closed afterwards; nothing to configure;
- ``scheduler="tcp://HOST:PORT"``: the same work on an existing dask cluster (its workers need
  fretwork installed); an address that does not answer within ``CONNECT_TIMEOUT_S``, or a
  scheduler without workers, is an InputError naming it;
- ``workers=0``: in this process, one case after the other, without dask (debugging; a single
  case on the embedded cluster also runs here, a cluster start-up would cost more than it).

Each call starts and closes its own local cluster (a few seconds); a caller that maps cases
round after round (a bisection) keeps one up with ``with cluster(scheduler, workers) as where:``
and passes ``**where`` to every ``map_cases`` call.

A case that raises is reported in its outcome (``"ExceptionType: message"``) and the others
complete; it is not re-run, the error would repeat. A case whose worker process dies (crash,
out of memory, killed) is re-run on another worker up to ``retries`` times (dask's
``allowed-failures``; on an existing cluster its own setting applies). Results travel back to
the client only: the caller writes the result files, workers never do.

Workers are started with the spawn method: a script (not the ``fretwork`` command) that calls
``map_cases`` must do so under ``if __name__ == "__main__":``.
"""

from __future__ import annotations

import logging
import os
import re
import signal
import sys
import threading
import uuid
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass

from tqdm import tqdm

from reduction.errors import InputError

#: Seconds to wait for an existing scheduler to answer before giving up.
CONNECT_TIMEOUT_S = 10.0
#: One BLAS/OpenMP thread per worker: the workers already fill the cores.
SINGLE_THREAD_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
_ADDRESS = re.compile(r"^(tcp|tls|ucx)://[^\s:/]+:\d+$")


@dataclass(frozen=True)
class CaseOutcome:
    """What one case gave back.

    key: what identifies the case (a speed in rpm, an amplitude in mm, a label);
    value: the function's return value (None if the case failed);
    error: ``"ExceptionType: message"`` if the case failed, else None;
    attempts: how many times the case was started (1 unless a worker died under it; None when
    the scheduler could not tell).
    """

    key: object
    value: object | None
    error: str | None
    attempts: int | None

    @property
    def ok(self) -> bool:
        return self.error is None


def add_cluster_arguments(parser) -> None:
    """Add ``--scheduler tcp://HOST:PORT`` and ``--workers N`` to an argparse parser."""
    group = parser.add_argument_group("parallel cases (dask.distributed)")
    group.add_argument("--scheduler", default=None, metavar="tcp://HOST:PORT",
                       help="run the cases on an existing dask cluster (default: an embedded local cluster)")
    group.add_argument("--workers", type=int, default=None, metavar="N",
                       help="worker processes of the embedded cluster (default: one per core; 0: run the "
                            "cases one after the other in this process)")


def map_cases(function: Callable, cases: Sequence[tuple[object, dict]], *, scheduler: str | None = None,
              workers: int | None = None, label: str = "cases", progress: bool = True, retries: int = 2,
              shared: dict | None = None) -> list[CaseOutcome]:
    """Run ``function(**kwargs, **shared)`` for every ``(key, kwargs)`` of ``cases``; outcomes in case order.

    function: a module-level (picklable) function. scheduler: address of an existing dask
    scheduler, or None for the embedded local cluster. workers: processes of the embedded
    cluster (None: one per core, never more than cases; 0: serially in this process).
    label: name of the tqdm bar (stderr) over completed cases, shown when ``progress``.
    retries: re-runs of a case whose worker died. shared: keyword arguments common to every
    case (a reduced model, ...), sent to each worker once instead of with every case.
    """
    cases = [(key, dict(kwargs)) for key, kwargs in cases]
    shared = dict(shared or {})
    _check_cluster_arguments(scheduler, workers, retries)
    if not cases:
        return []
    if workers == 0 or (scheduler is None and len(cases) == 1):
        return _serial(function, cases, shared, label, progress)
    with _client(scheduler, workers, len(cases), retries) as client:
        return _distributed(client, function, cases, shared, label, progress)


def _call(function: Callable, kwargs: dict, **shared) -> tuple[bool, object]:
    """Run one case on a dask worker; an exception comes back as text so that dask does not retry it."""
    from reduction.threads import pin_process

    pin_process()  # a worker of a cluster we did not start has the default thread count
    return _run_case(function, kwargs, **shared)


def _run_case(function: Callable, kwargs: dict, **shared) -> tuple[bool, object]:
    try:
        return True, function(**kwargs, **shared)
    except Exception as error:  # the case fails, the sweep goes on: report it, whatever it is
        return False, _describe(error)


def _describe(error: BaseException | None, status: str = "") -> str:
    if error is None:  # a future the cluster gave up on without an exception (QA: "NoneType: None")
        return (f"it did not finish on the cluster (its state: {status or 'unknown'}): a worker was lost or "
                "the cluster closed; run again, or with --workers 0 in this process")
    return f"{type(error).__name__}: {error}"


def _serial(function, cases, shared, label, progress) -> list[CaseOutcome]:
    from reduction.threads import pinned_while_inside

    outcomes = []
    for key, kwargs in tqdm(cases, desc=label, unit="case", file=sys.stderr, disable=not progress):
        with pinned_while_inside():  # this process is the caller's: its thread settings come back
            ok, value = _run_case(function, kwargs, **shared)
        outcomes.append(CaseOutcome(key, value if ok else None, None if ok else value, 1))
    return outcomes


@contextmanager
def cluster(scheduler: str | None = None, workers: int | None = None, *, retries: int = 2) -> Iterator[dict]:
    """One cluster for several ``map_cases`` calls: yields their ``scheduler`` and ``workers`` keywords.

    With ``scheduler`` or ``workers=0`` nothing is started (the calls go there, or run in this
    process); otherwise an embedded local cluster (``workers`` processes, default one per core)
    is up until the block ends and every call sends its cases to it, a single case included.
    """
    _check_cluster_arguments(scheduler, workers, retries)
    if scheduler is not None or workers == 0:
        yield {"scheduler": scheduler, "workers": workers}
        return
    with _local_cluster(workers, retries) as local:
        yield {"scheduler": local.scheduler_address, "workers": None}


def _check_cluster_arguments(scheduler, workers, retries) -> None:
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 0):
        raise InputError(f"--workers {workers!r}: give a whole number of worker processes, 0 or more")
    if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
        raise InputError(f"retries {retries!r}: give a whole number, 0 or more")
    if scheduler is not None and workers is not None:
        raise InputError(f"--workers {workers} sizes the embedded cluster; with --scheduler {scheduler} "
                         "the cases run on that cluster's workers (give one of the two)")
    if scheduler is not None and not _ADDRESS.match(scheduler):
        raise InputError(f"--scheduler {scheduler!r}: give the dask scheduler's address as tcp://HOST:PORT")


@contextmanager
def _local_cluster(workers: int | None, retries: int, n_cases: int | None = None) -> Iterator:
    """LocalCluster of ``workers`` single-threaded processes (default one per core, at most n_cases)."""
    import dask
    from dask.system import cpu_count
    from distributed import LocalCluster

    n_workers = workers or cpu_count()
    if n_cases is not None:
        n_workers = min(n_workers, n_cases)
    # memory_limit=0: a worker that grows past its share of the RAM would be killed and its
    # case re-run until it counts as failed; one large contact case may use most of the machine.
    # The scheduler serves its health page even without a dashboard: on a free local port, not
    # on 8787 (taken by any other cluster on the machine, with a warning).
    # silence_logs above CRITICAL: a worker's own ERROR lines are about the cluster, not the cases (a
    # case's error comes back as its outcome, a dead worker as a retried case): when Ctrl-C
    # closes the scheduler, a worker still heart-beating printed "Failed to communicate with
    # scheduler during heartbeat" with a traceback before the cluster ended it.
    # The workers' environment is the thread pins only: dask's default adds
    # MALLOC_TRIM_THRESHOLD_=65536 (memory back to the OS sooner), which made the contact
    # solver's cases about 20 % slower (its large temporaries are mapped and unmapped anew).
    settings = {"distributed.scheduler.allowed-failures": retries,
                "distributed.nanny.pre-spawn-environ": dict(SINGLE_THREAD_ENV)}
    with dask.config.set(settings):  # for the cluster's whole life: a worker that died is started anew
        with _workers_ignore_ctrl_c():
            local = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True, dashboard_address=None,
                                 scheduler_kwargs={"dashboard_address": "127.0.0.1:0"}, silence_logs=_cluster_log_level(),
                                 memory_limit=0)
        with local:
            from distributed import Client

            from pipelines.worker_signals import IgnoreCtrlC

            # the scheduler keeps the plugin and hands it to every worker that joins later
            with Client(local, set_as_default=False) as client:
                client.register_plugin(IgnoreCtrlC())
            yield local


def _cluster_log_level() -> int:
    """The level of the local cluster's own log lines on stderr: above CRITICAL (none), or WARNING
    with ``FRETWORK_DASK_LOGS`` set, to see a worker that died and was started anew ("Restarting
    worker"), which a user otherwise sees only as its case run again. Not CRITICAL itself: when
    Ctrl-C closes the client of a long search, the scheduler logs each case that still finishes
    at CRITICAL ("Closed comm ... while trying to write key-in-memory", with a traceback)."""
    return logging.WARNING if os.environ.get("FRETWORK_DASK_LOGS") else logging.CRITICAL + 1


@contextmanager
def _workers_ignore_ctrl_c() -> Iterator[None]:
    """Processes started in the block ignore SIGINT, and so do those that threads started in
    the block start later.

    Ctrl-C reaches every process of the terminal's process group: a worker that took it would
    die in the middle of its case, with a traceback and leaked semaphores. The workers inherit
    the ignored signal (it survives their exec); the client alone is interrupted and closes the
    cluster, which ends the workers. A Ctrl-C while the cluster starts (the block) is ignored.

    A worker started anew after its process died does not inherit the ignored signal: the
    nanny starts it from a thread, after the block. That thread descends from the cluster's
    event-loop thread, started in the block, and a thread inherits its creator's signal mask:
    SIGINT is blocked in the main thread during the block (unblocked after), so the loop thread
    and its descendants keep it blocked, and a process one of them starts is born with it
    blocked (a mask survives fork and exec). Without that, a Ctrl-C while a restarted worker was
    still importing printed its KeyboardInterrupt traceback; once it has joined,
    :class:`pipelines.worker_signals.IgnoreCtrlC` ignores the signal outright. The
    multiprocessing resource tracker is started first: starting it unblocks SIGINT in the thread
    that starts it (``resource_tracker.ensure_running``), which would be the loop thread."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    from multiprocessing import resource_tracker

    resource_tracker.ensure_running()
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
        signal.signal(signal.SIGINT, previous)


@contextmanager
def _client(scheduler: str | None, workers: int | None, n_cases: int, retries: int) -> Iterator:
    from distributed import Client

    if scheduler is not None:
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
        except (OSError, TimeoutError) as error:
            raise InputError(f"--scheduler {scheduler}: no dask scheduler answered within "
                             f"{CONNECT_TIMEOUT_S:g} s ({error}); start one with `dask scheduler` and "
                             "workers with `dask worker ADDRESS`, or leave --scheduler out to use "
                             "this machine") from None
        with client:
            try:  # cases sent to a scheduler without workers would wait for ever
                client.wait_for_workers(1, timeout=CONNECT_TIMEOUT_S)
            except TimeoutError:
                raise InputError(f"--scheduler {scheduler}: the scheduler has no workers (none joined within "
                                 f"{CONNECT_TIMEOUT_S:g} s); start some with `dask worker {scheduler}`") from None
            yield client
        return
    with _local_cluster(workers, retries, n_cases) as local, Client(local, set_as_default=False) as client:
        yield client


def _distributed(client, function, cases, shared, label, progress) -> list[CaseOutcome]:
    from distributed import as_completed

    shared_futures = {name: client.scatter(value, broadcast=True) for name, value in shared.items()}
    run = uuid.uuid4().hex[:8]
    futures = [client.submit(_call, function, kwargs, **shared_futures, key=f"{label}-{run}-{i}", pure=False)
               for i, (_, kwargs) in enumerate(cases)]
    position = {future.key: i for i, future in enumerate(futures)}
    results: list = [None] * len(cases)
    with tqdm(total=len(cases), desc=label, unit="case", file=sys.stderr, disable=not progress) as bar:
        for future in as_completed(futures, loop=client.loop):
            if future.status == "finished":
                results[position[future.key]] = future.result()
            else:  # the worker died more often than allowed, or the cluster went away
                try:
                    error = future.exception()
                except BaseException as cancelled:  # a cancelled future has no exception to give
                    error = cancelled
                results[position[future.key]] = (False, _describe(error, future.status))
            bar.update(1)
    attempts = _attempts(client, [future.key for future in futures])
    return [CaseOutcome(key, value if ok else None, None if ok else value, attempts.get(future.key))
            for (key, _), (ok, value), future in zip(cases, results, futures)]


def _attempts(client, keys: list) -> dict:
    """Starts per task: 1 + the times a worker died while it held the task (scheduler's count)."""
    def count(dask_scheduler):
        return {key: 1 + dask_scheduler.tasks[key].suspicious for key in keys if key in dask_scheduler.tasks}

    try:
        return client.run_on_scheduler(count)
    except Exception:  # a scheduler that cannot run the query: attempts unknown, results unaffected
        return {}


__all__ = ["CONNECT_TIMEOUT_S", "CaseOutcome", "add_cluster_arguments", "cluster", "map_cases"]
