"""The dense path's floor per increment at a given size (docs/performance.md).

``python tests/bench/dense_floor.py [--rows 4566] [--newton 2.6] [--increments 11410]`` times,
on one BLAS thread (best of 30), the kernels of one increment of the dense Krylov path on a
symmetric matrix of that many rows: the residual's product with W (double precision), the
Krylov product (single), the preconditioner's two triangular solves (single) and a rebuild's
LU (single). The floor is one residual per Newton iteration plus the predictor's and one
Krylov iteration per solve, with no rebuild: what the run would cost with exact, free
preconditioners. Default: the counterweight at 2.5 mm (4,566 contact rows, 2.6 Newton
iterations per increment, 11,410 increments).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.linalg.blas import dsymv, ssymv
from scipy.linalg.lapack import sgetrf, sgetrs
from threadpoolctl import threadpool_limits


def best_ms(call, repeats: int = 30) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return 1e3 * min(times)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=4566)
    parser.add_argument("--newton", type=float, default=2.6, help="Newton iterations per increment")
    parser.add_argument("--increments", type=int, default=11410)
    args = parser.parse_args(argv)
    n = args.rows
    rng = np.random.default_rng(0)
    W = rng.standard_normal((n, n))
    W = np.asfortranarray(W + W.T + n * np.eye(n))
    W32 = np.asfortranarray(W.astype(np.float32))
    x, x32 = rng.standard_normal(n), rng.standard_normal(n).astype(np.float32)
    with threadpool_limits(1, user_api="blas"):
        lu, pivots, _ = sgetrf(W32.copy(order="F"))
        residual = best_ms(lambda: dsymv(1.0, W, x, lower=0))
        product = best_ms(lambda: ssymv(1.0, W32, x32, lower=0))
        triangular = best_ms(lambda: sgetrs(lu, pivots, x32))
        rebuild = best_ms(lambda: sgetrf(W32.copy(order="F")), repeats=3)
    floor = (args.newton + 1.0) * residual + args.newton * (product + triangular)
    print(f"{n} rows, one thread: W product double {residual:.2f} ms, single {product:.2f} ms; "
          f"two triangular solves {triangular:.2f} ms; LU {rebuild / 1e3:.2f} s")
    print(f"floor: {floor:.1f} ms per increment, {floor * args.increments / 6e4:.1f} min for "
          f"{args.increments} increments")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
