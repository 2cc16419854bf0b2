"""Run the hard cases with single-threaded BLAS.

The contact-space systems of these small models are dense and tiny (≤ 150 unknowns); with
OpenBLAS threads on a loaded 2-core machine each LU solve waits for the other thread
(11 ms instead of 0.3 ms per solve), which made the folder 5× slower without changing any
result. threadpoolctl is optional: without it the cases run with the default threads.
"""

import pytest

try:
    from threadpoolctl import threadpool_limits
except ImportError:  # the physics is the same, only slower
    threadpool_limits = None


@pytest.fixture(autouse=True, scope="module")
def single_threaded_blas():
    if threadpool_limits is None:
        yield
        return
    with threadpool_limits(limits=1, user_api="blas"):
        yield
