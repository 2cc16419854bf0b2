"""Run the hard cases with single-threaded BLAS.

The contact-space systems of these small models are dense and tiny (≤ 150 unknowns); with
OpenBLAS threads on a loaded 2-core machine each LU solve waits for the other thread
(11 ms instead of 0.3 ms per solve), which made the folder 5× slower without changing any
result. The limit is the library's own (:func:`reduction.threads.single_threaded_blas`).
"""

import pytest

from reduction.threads import single_threaded_blas


@pytest.fixture(autouse=True, scope="module")
def one_blas_thread():
    with single_threaded_blas():
        yield
