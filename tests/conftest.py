"""Every test runs as the command line runs: BLAS (and MKL, PARDISO's) on one thread for the
whole process (`reduction.threads.pin_process`, as `fretwork` calls it first). Unpinned, MKL's
threads change the last digits of the coupled counterweight's condensed inertia patterns, and a
scene at the edge of sliding off (the counterweight extreme at full vibration after a two-cycle
run-up, tests/pipelines/test_checkpoint.py) slid off alone and passed only after some earlier
test had called the command line in the same process."""

import pytest


@pytest.fixture(autouse=True, scope="session")
def _one_blas_thread_as_the_command_line():
    from reduction.threads import pin_process

    pin_process()
