"""One BLAS thread for fretwork's own dense linear algebra: the same scene gives the same bits.

Measured (issue 13): the cylinder-on-plane scene run with ``OPENBLAS_NUM_THREADS=1`` and
``=2`` differed in the last digits of every field (pressure by 2.7e-11 MPa, dissipation by
3.6e-12 mJ/mm²). OpenBLAS splits its dense products and factorisations over threads in
blocks whose number sets the order of the floating-point sums, and OpenBLAS has no switch for
reproducible reductions (MKL's ``MKL_CBWR`` has no OpenBLAS counterpart). The contact
solver's matrices are small to medium (hundreds to a few thousand rows), where a second
thread gains little and loses much on a busy machine (the same run took 33 s on one thread
and 73 s on two with other jobs on the cores). So every fretwork process, the command line
and each dask worker, runs NumPy's and SciPy's OpenBLAS on one thread; parallelism comes from
running cases side by side (:mod:`pipelines.distributed`).

MKL (PARDISO, the sparse condensation) keeps its threads: its factorisation of a large body
pays for them, and its conditional numerical reproducibility is switched on where MKL is
loaded (:mod:`reduction.pardiso`).

Reproducible means: the same scene, the same fretwork, NumPy, SciPy and MKL builds, on the
same kind of CPU. Another CPU model may select other OpenBLAS kernels (FMA or not, other
block sizes) and so other last digits.
"""

from __future__ import annotations


def pin_blas_threads() -> None:
    """Limit every OpenBLAS loaded by NumPy and SciPy to one thread, for the whole process.

    Both are imported first: threadpoolctl limits only the libraries loaded when it is called,
    and NumPy and SciPy each bring their own OpenBLAS build.
    """
    import importlib

    from threadpoolctl import ThreadpoolController

    for module in ("numpy", "scipy.linalg", "scipy.sparse.linalg"):
        importlib.import_module(module)

    ThreadpoolController().select(internal_api="openblas").limit(limits=1)
