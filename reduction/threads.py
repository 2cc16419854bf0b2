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
"""

from __future__ import annotations

from contextlib import contextmanager

from threadpoolctl import ThreadpoolController


@contextmanager
def single_threaded_blas():
    """BLAS (OpenBLAS, MKL) limited to one thread inside the block."""
    with ThreadpoolController().limit(limits=1, user_api="blas"):
        yield
