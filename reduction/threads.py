"""BLAS threads for steps whose results must not depend on the machine's thread settings.

Threaded BLAS and MKL (PARDISO) split their sums differently for different thread counts,
so the last digits of a factorisation, and after thousands of contact increments every
digit of a field, changed with OPENBLAS_NUM_THREADS / MKL_NUM_THREADS: the same scene gave
different results on a laptop and on a cluster node, and a run resumed in another process
was not bit for bit the uninterrupted one. The contact-space set-up therefore runs its
BLAS on one thread (on the shared 2-core machine a second thread saved little there), as
every contact increment does (:class:`contact.solver.ContactSolver`).

The limit is process-wide: a step that other threads of the same process run concurrently
(the reduction inside dask workers with several threads) must not use it, since one
thread's restore would undo another's limit.

Those limits cover the library's own steps. A whole job touches more: the condensation, the
multibody loading, the inertia patterns of a coupled scene, the energy bookkeeping between
increments. Measured: with only the per-step limits, the counterweight scene (extreme case,
270 cycles) still ended with 37 result datasets different between one and two threads. So
every fretwork process (the command line, each dask worker) also pins its BLAS to one thread
for good (:func:`pin_process`); a limited block then restores one thread on exit.

A program that imports fretwork as a library and calls a job (``run_scene``, ``build``, the
limit scan...) has not pinned its process, and measured: a counterweight scene at the edge of
sliding off then slid off where the command line's run ended ``damage``. Each job is therefore
wrapped in :func:`one_blas_thread`: inside it the process runs as if pinned, and on leaving the
outermost job the caller's thread settings come back.
"""

from __future__ import annotations

import functools
import sys
import threading
from contextlib import contextmanager

from threadpoolctl import ThreadpoolController

_controller: tuple[int, ThreadpoolController] | None = None
#: (modules loaded, threads) when :func:`pin_process` pinned every BLAS of the process
_pinned: tuple[int, int] | None = None


def blas_controller() -> ThreadpoolController:
    """The process's BLAS libraries, as threadpoolctl sees them.

    Finding them walks every loaded shared object (3 ms), more than a small contact
    increment costs, and a finite-sliding run builds a solver and a contact space at every
    re-pairing; so the scan is kept while no module has been imported since (a BLAS comes
    with the extension module that loads it: NumPy, SciPy, MKL with PARDISO).
    """
    global _controller
    if _controller is None or _controller[0] != len(sys.modules):
        _controller = (len(sys.modules), ThreadpoolController())
    return _controller[1]


@contextmanager
def blas_threads(limit: int):
    """BLAS (OpenBLAS, MKL) limited to ``limit`` threads inside the block.

    Nothing to do (and nothing spent: setting a limit costs about 0.1 ms, a tenth of a small
    contact increment) when the process is pinned to that many threads; if modules were
    loaded since, the process is pinned again first (their BLAS too)."""
    global _pinned
    if _pinned is not None and _pinned[1] == limit:
        if _pinned[0] != len(sys.modules):  # a module loaded since may have brought a BLAS
            blas_controller().limit(limits=limit, user_api="blas")
            _pinned = (len(sys.modules), limit)
        yield
        return
    with blas_controller().limit(limits=limit, user_api="blas"):
        yield


def single_threaded_blas():
    """BLAS (OpenBLAS, MKL) limited to one thread inside the block."""
    return blas_threads(1)


def _load_blas_libraries() -> None:
    """Import what brings a BLAS (NumPy, SciPy, MKL where PARDISO is installed), so that a limit
    set now covers each of them."""
    import importlib

    from reduction import pardiso

    for module in ("numpy", "scipy.linalg", "scipy.sparse.linalg"):
        importlib.import_module(module)
    pardiso.available()  # loads MKL where pypardiso is installed


_lent = threading.Lock()
#: (library calls inside, the caller's limits to restore, the caller's record of a pinning)
_lending: list = [0, None, None]


@contextmanager
def pinned_while_inside():
    """The process pinned to one BLAS thread while inside the block, as :func:`pin_process` pins
    it for good; on leaving the outermost such block the caller's thread limits (and record of
    a pinning) come back. Nested blocks share one pinning, released by the outermost. Nothing
    to do in a pinned process.

    Jobs run concurrently on several threads of one process must pin it instead
    (:func:`pin_process`, as each dask worker does): MKL's thread count is the calling
    thread's (measured: a limit set on one thread left MKL at two threads on another)."""
    global _pinned
    with _lent:
        if _lending[0] == 0:
            if _pinned is not None and _pinned[1] == 1:
                _lending[1:] = [None, None]
            else:
                _load_blas_libraries()
                _lending[1:] = [blas_controller().limit(limits=1, user_api="blas"), _pinned]
                _pinned = (len(sys.modules), 1)
        _lending[0] += 1
    try:
        yield
    finally:
        with _lent:
            _lending[0] -= 1
            if _lending[0] == 0 and _lending[1] is not None:
                _lending[1].restore_original_limits()
                _pinned = _lending[2]
                _lending[1:] = [None, None]


def one_blas_thread(function):
    """Decorate a job a library caller may call: it runs inside :func:`pinned_while_inside`."""
    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        with pinned_while_inside():
            return function(*args, **kwargs)
    return wrapper


def pin_process() -> None:
    """Limit every BLAS (NumPy's and SciPy's OpenBLAS, MKL) to one thread for the rest of the
    process. NumPy, SciPy and MKL (PARDISO's, when installed) are loaded first: threadpoolctl
    limits only the libraries that are loaded when it is called, and each brings its own
    build (measured: with MKL loaded later, the coupled counterweight's condensed inertia
    patterns, and so its results, differed between one and two threads)."""
    global _pinned
    _load_blas_libraries()
    blas_controller().limit(limits=1, user_api="blas")
    _pinned = (len(sys.modules), 1)
