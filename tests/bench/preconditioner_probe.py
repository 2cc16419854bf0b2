"""Two other preconditioners and a recycled Krylov space for the dense Krylov path, tried on
the run's own solves (docs/performance.md).

``python tests/bench/preconditioner_probe.py [--size 5] [--cof 20] [--wear 10]`` runs
``examples/counterweight_extreme.toml`` at that contact size for that many COF cycles and wear
blocks. Every Krylov solve is done as the run does it (the kept LU of the Jacobian J₀ = I + W·T₀
of an earlier tangent T₀), then again, on the same right-hand side and tolerance, with

- *scaled*: the same LU corrected by the current tangent T, M⁻¹ = T⁻¹·T₀·J₀⁻¹ on the points
  where both tangents are invertible (stick): J = (T⁻¹ + W)·T, so where W dominates the
  compliance T⁻¹ the corrected preconditioner is the exact one whatever the stick stiffness;
- *diagonal*: a Cholesky factor of I + D^½·W·D^½, D the diagonal of T₀ clipped at zero (and
  at 1e-6 of its largest entry), bordered by the control rows through their Schur complement:
  symmetric positive definite, so half the flops of the LU to form, as the sparse path's
  "diagonal" reference is;
- *recycled*: the shipped LU, with the previous solve's preconditioned directions (at most 8)
  offered first (flexible GMRES): each costs a product with J but no preconditioner solve, and
  in a Newton iteration whose tangent is near the last one's they might span most of the
  correction.

The run itself goes as shipped; the probe prints, per GMRES tolerance, the solves and the
Krylov iterations of the shipped preconditioner and of each variant (for *recycled*, the
preconditioned ones, and in brackets the recycled directions), and how W's diagonal compares
with the stick points' stiffness (W_ii·T_ii, normal and tangential).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np
from scipy.linalg import lapack

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "bench"))

import contact.linear as linear  # noqa: E402
import scene_run  # noqa: E402
from pipelines.jobs.run import run_model  # noqa: E402


def scaled(solver, factor, blocks, previous):
    """M⁻¹ = R·J₀⁻¹ with R = T⁻¹·T₀ per stick point (identity elsewhere)."""
    n, dim, _ = blocks.shape
    correction = np.broadcast_to(np.eye(dim), blocks.shape).copy()
    invertible = (np.linalg.cond(blocks) < 1e12) & (np.linalg.cond(factor.blocks) < 1e12)
    correction[invertible] = np.linalg.solve(blocks[invertible], factor.blocks[invertible])
    # how stiff the stick points are against the bodies: W's diagonal times the tangent's
    rows = linear._rows(factor.points[invertible], dim).reshape(-1, dim)
    product = solver.space.W[rows, rows] * np.diagonal(blocks[invertible], axis1=1, axis2=2)
    STIFFNESS.append(product)

    def precondition(vector):
        x = factor.precondition(vector)
        x[:n * dim] = np.matmul(correction, x[:n * dim].reshape(n, dim, 1)).reshape(-1)
        return x

    return precondition, []


def diagonal(solver, factor, blocks, previous, floor: float = 1e-6):
    """Cholesky of I + D^½·W·D^½ (single precision), the control rows by their Schur complement."""
    dim = factor.blocks.shape[1]
    closed = linear._rows(factor.points, dim)
    d = np.maximum(np.diagonal(factor.blocks, axis1=1, axis2=2).ravel(), 0.0)
    root = np.sqrt(np.maximum(d, floor * d.max()))
    W = solver._closed_compliance(closed, np.float32)
    matrix = (root[:, None] * W * root[None, :]).astype(np.float32)
    matrix[np.diag_indices_from(matrix)] += 1.0
    cholesky, info = lapack.spotrf(matrix, lower=1, overwrite_a=1, clean=0)
    if info:
        raise np.linalg.LinAlgError("I + D^1/2 W D^1/2 not positive definite")
    F = root[:, None] * solver.space.E[closed]
    AF = lapack.spotrs(cholesky, F.astype(np.float32), lower=1)[0].astype(float)
    schur = solver.space.Sq + F.T @ AF
    n_c = closed.size

    def precondition(vector):
        top, control = vector[:n_c], vector[n_c:]
        a = lapack.spotrs(cholesky, (root * top).astype(np.float32), lower=1)[0].astype(float)
        q = np.linalg.solve(schur, control / factor.control_scale + F.T @ a) if control.size else control
        return np.concatenate([(a - AF @ q) / root, q])

    return precondition, []


def recycled(solver, factor, blocks, previous):
    """The shipped LU, the previous solve's directions (if of the same size) offered first."""
    offered = [z for z in previous if z.size == factor.lu.shape[0]][:8]
    calls = iter(range(10**9))

    def precondition(vector):
        k = next(calls)
        return offered[k] if k < len(offered) else factor.precondition(vector)

    return precondition, offered


#: W_ii·T_ii at the stick points of every solve, (points, dim): normal, tangential
STIFFNESS: list = []

VARIANTS = {"scaled": scaled, "diagonal": diagonal, "recycled": recycled}


def probe(rows: list) -> None:
    """Wrap the Krylov solve: after the shipped one, solve again with each variant."""
    bordered = linear.NewtonLinearSolver._bordered_product
    diagonals: dict = {}  # id → (factor, its diagonal preconditioner), while the pool keeps it
    last: list = []  # the previous solve's preconditioned directions

    def recorded_bordered(solver, closed_blocks, W_cc, E_c):
        solver._probed_blocks = closed_blocks
        return bordered(solver, closed_blocks, W_cc, E_c)

    def diagonal_of(solver, factor):
        pooled = {id(kept) for kept in solver._pool.factors}
        for key in [key for key in diagonals if key not in pooled]:
            del diagonals[key]
        if id(factor) not in diagonals:
            diagonals[id(factor)] = (factor, diagonal(solver, factor, solver._probed_blocks, last))
        return diagonals[id(factor)][1]

    def compared_krylov(solver, matvec, factor, r_closed, r_ctl, tolerance):
        directions = []

        def recorded(vector):
            directions.append(factor.precondition(vector))
            return directions[-1]

        rhs = np.concatenate([-r_closed, -solver._control_scale * r_ctl])
        solution, iterations = linear._gmres(matvec, recorded, rhs, tolerance, solver.settings.max_iterations)
        row = [tolerance, iterations, 0]
        for name, make in VARIANTS.items():
            # the diagonal one is formed once per factor, as a pool would keep it
            precondition, offered = (diagonal_of(solver, factor) if name == "diagonal"
                                     else make(solver, factor, solver._probed_blocks, last))
            row.append(linear._gmres(matvec, precondition, rhs, tolerance, 200)[1] - len(offered))
            row[2] += len(offered)
        last[:] = directions
        rows.append(row)
        return solution, iterations

    linear.NewtonLinearSolver._bordered_product = recorded_bordered
    linear.NewtonLinearSolver._krylov = compared_krylov


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    scene_run.short_extreme_arguments(parser, size=5.0)
    args = parser.parse_args(argv)
    model = scene_run.short_extreme(args)
    rows: list = []
    probe(rows)
    with tempfile.TemporaryDirectory() as out:
        run_model(model, Path(out), progress=False, plots=False)
    table = np.array(rows)
    for tolerance in np.unique(table[:, 0]):
        solves = table[table[:, 0] == tolerance]
        counts = ", ".join(f"{name} {solves[:, k + 3].sum():.0f} ({solves[:, k + 3].mean():.2f})"
                           for k, name in enumerate(VARIANTS))
        print(f"GMRES to {tolerance:g}: {len(solves)} solves; Krylov iterations (per solve): shipped "
              f"{solves[:, 1].sum():.0f} ({solves[:, 1].mean():.2f}), {counts} "
              f"[{solves[:, 2].mean():.2f} directions recycled]")
    stiffness = np.concatenate(STIFFNESS)
    for k, name in enumerate(("normal", "tangential")):
        low, median, high = np.percentile(stiffness[:, min(k, stiffness.shape[1] - 1)], [10, 50, 90])
        print(f"W·T on the {name} diagonal of the stick points: 10th percentile {low:.3g}, "
              f"median {median:.3g}, 90th {high:.3g}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
