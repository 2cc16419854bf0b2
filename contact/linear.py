"""Linear algebra of one Newton iteration in contact space.

The Jacobian of the contact-space residual is

    J = [[I + W·A·D,  E ],
         [−Eᵀ·A·D,   S_q]]

with A·D the block-diagonal (per point, dim × dim) consistent tangent of the contact law
times the tributary area. Points with a zero tangent (open) have identity columns, so the
system is block lower-triangular in (closed, open) rows: only the closed block, bordered by
the few control DOFs, has to be solved; the open rows follow by one product.

Small closed blocks are factorised directly (dense LU). Large ones are solved by GMRES
preconditioned with a dense single-precision LU of an earlier Jacobian, kept across Newton
iterations and increments: between them the closed set rarely changes and the tangent
changes little, so a few Krylov iterations (each one product with W and one triangular
solve) replace an O(n³) factorisation. The factor is rebuilt when points close that it does
not cover, or when the Krylov work lost to its age exceeds what the last rebuild cost. Up to
16 factors are kept (as many as fit in 1.5 GB) and each solve takes the one formed at the
tangent nearest its own: under a cyclic load that is the one of the same point of an
earlier cycle, not the previous increment's. Work
is counted in floating-point operations, not measured in seconds: a policy driven by the
clock would make the preconditioner, and so the last digits of every result, depend on
the machine's load. The
Newton correction is exact up to the GMRES tolerance; the converged equilibrium is set by
the solver's residual test, not by this module (the condensed-versus-full test checks it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as la
from scipy.linalg.lapack import get_lapack_funcs

from contact.law import Response
from contact.structure import ContactSpace, dense_block, symmetric_product

#: how many times faster per flop the preconditioner's rebuild runs than a Krylov iteration:
#: an iteration streams the dense Jacobian and the factor from memory for 2 flops per entry
#: (memory-bound), the LU is BLAS-3 (compute-bound). A rebuild's work in iteration flops is
#: its flops over this. Measured on the counterweight at 5 mm (1,260 rows, one thread, 150
#: COF and 260 wear cycles): 1.1 ms per iteration and 28 ms per rebuild, a ratio of 25 where
#: the flop counts give 210, so 8. At 1 (the flops alone) aged preconditioners were kept too
#: long: 133,577 Krylov iterations (583 of 11,071 solves failing at max_iterations) and 804
#: rebuilds; at 8, 65,172 iterations (27 failing) and 1,052 rebuilds: 106 instead of 156 s
#: in the two, run side by side; at 4, 80,234 and 772; at 16, 57,899 and 1,587. A constant,
#: not a timing, so that the results do not depend on the machine.
FACTOR_FLOP_RATE = 8.0


def tangent_blocks(response: Response, area: np.ndarray) -> np.ndarray:
    """A·∂[p, τ]/∂[h, Δs] per point, (n, dim, dim) in N/mm (forces per mm of kinematics)."""
    return response.tangent() * area[:, None, None]


@dataclass(frozen=True)
class KrylovSettings:
    """When the iterative path is used and how hard it works.

    direct_below: closed rows below which the closed block is factorised every iteration.
    relative_tolerance: GMRES stops at ‖J·x − b‖ ≤ this × ‖b‖ (rows in mm) ...
    final_tolerance: ... or this × ‖b‖ for the last Newton steps (the caller says which):
        there the inexact correction sets where Newton stops inside its tolerance, and a
        tight one lands it where the exact LU does (within 1e-9 instead of 1e-8 relative).
    fresh_iterations: Krylov iterations a solve needs with a fresh preconditioner. Every
        iteration beyond it is work lost to an aged one, and the preconditioner is rebuilt
        once that has cost as much as a rebuild (:class:`Ageing`, counted in flops).
    max_iterations: Krylov space size; if GMRES has not converged by then, the
        preconditioner is rebuilt from the current tangent and the solve repeated.
    single_precision: factorise the preconditioner and multiply by W in float32 inside
        GMRES (half the memory traffic; 1e-7 relative error, far below the Krylov tolerance);
        the Krylov vectors and the solver's residuals stay float64.
    factors_kept: preconditioners kept at most (the most recently used), and only as many as
        fit in ``factors_bytes`` (at least one). Each solve takes the one formed at the tangent nearest
        the current one. Under a cyclic load the tangent at one point of the cycle is much
        nearer the tangent at the same point one cycle earlier than the previous increment's
        (the slip zones move with the load, and reverse): the counterweight at 5 mm needed
        38 % fewer Krylov iterations and 60 % fewer factorisations with 16 than with one.
        With one kept, a rebuilt preconditioner replaces the only one and ages as fast as it:
        at 2.5 mm (4,800 rows, 92 MB a factor), over 20 COF and 10 wear cycles, 8 kept took
        8,157 Krylov iterations and 42 rebuilds, one 11,595 and 83. The pool must hold one
        factor per load step of the cycle (12 in the shipped scenes) or the least recently
        used is always the one needed next. The loosening extreme at 2.5 mm, in its late wear
        blocks with 8 kept, failed a quarter of its solves (each 40 iterations and a
        rebuild) and took 13.0 s a block; with 16 kept, and a factor that fails kept too,
        5.6 s, side by side. Hence 1.5 GB: 16 factors at 2.5 mm.
    """

    direct_below: int = 300
    relative_tolerance: float = 1e-3
    final_tolerance: float = 1e-7
    fresh_iterations: int = 3
    max_iterations: int = 40
    single_precision: bool = True
    factors_kept: int = 16
    factors_bytes: float = 1.5e9


@dataclass
class Ageing:
    """When a kept preconditioner is worth rebuilding: the one rule of the dense and the
    sparse Krylov paths.

    Every Krylov iteration a solve needs beyond a fresh preconditioner's is work lost to its
    age; once the lost work exceeds what its rebuild cost, it is rebuilt (pay for a rebuild
    only after having wasted as much: never worse than twice the best policy).
    iteration_work: flops of one Krylov iteration; rebuild_work: the rebuild's flops over
    how many times faster per flop it runs (a path's ``FACTOR_FLOP_RATE``: the rebuild is
    compute-bound, an iteration memory-bound). Counted in flops, not seconds, so that the
    policy, and the last digits of the results, do not depend on the machine's load."""

    iteration_work: float
    rebuild_work: float
    lost_work: float = 0.0

    def charge(self, iterations: int, fresh_iterations: int) -> bool:
        """Charge one solve's iterations; True once a rebuild pays (the count starts again)."""
        self.lost_work += max(iterations - fresh_iterations, 0) * self.iteration_work
        due = self.lost_work > self.rebuild_work
        if due:
            self.lost_work = 0.0
        return due


@dataclass
class KrylovCounters:
    """What the iterative path did, for benchmarks: solves, Krylov iterations, factorisations."""

    solves: int = 0
    krylov_iterations: int = 0
    factorisations: int = 0
    direct_solves: int = 0


class NewtonLinearSolver:
    """Newton corrections for one :class:`ContactSpace`, keeping a preconditioner between calls."""

    def __init__(self, space: ContactSpace, settings: KrylovSettings = KrylovSettings()):
        self.space = space
        self.settings = settings
        self.counters = KrylovCounters()
        self._control_scale = np.ones(space.n_control)
        self._compliance: dict = {}  # dtype → (closed rows, W on them)
        self._coupling: tuple | None = None  # (closed rows, by open rows?, W on open × closed)
        self._single: np.ndarray | None = None  # W in single precision (_whole_compliance)
        self._pool = _Pool()  # the preconditioners kept
        self._stale = True
        self._last_points: np.ndarray | None = None  # the points the last solve worked on
        itemsize = 4 if settings.single_precision else 8
        fitting = int(settings.factors_bytes // (itemsize * (space.n_rows + space.n_control) ** 2))
        self._pool.size = max(1, min(settings.factors_kept, fitting))

    def description(self) -> str:
        """Which path solves this interface's Newton systems, in words (for run summaries)."""
        exact = f"exact LU of the bordered closed system below {self.settings.direct_below:g} closed rows"
        if self.space.n_rows < self.settings.direct_below:
            return f"dense W ({self.space.n_rows} rows): exact LU of the bordered closed system"
        precision = "single" if self.settings.single_precision else "double"
        return (f"dense W ({self.space.n_rows} rows): GMRES preconditioned by a {precision}-precision "
                f"LU of an earlier Jacobian; {exact}")

    def solve(self, blocks: np.ndarray, r_kin: np.ndarray, r_ctl: np.ndarray,
              final: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Newton correction (Δg mm, Δq mm) for residuals r_kin (mm) and r_ctl (N); ``final``:
        Newton is one step from its tolerance (the Krylov path then solves to
        ``final_tolerance``)."""
        n, dim, _ = blocks.shape
        closed_points = np.flatnonzero(blocks[:, 0, 0] > 0.0)
        if closed_points.size * dim < self.settings.direct_below:
            self.counters.direct_solves += 1
            return self._direct(blocks, closed_points, r_kin, r_ctl)
        # Rows of open points may stay in the system: their tangent is zero, so their columns
        # are the identity and the equations stay exact. Solving on the points the
        # preconditioner was built for keeps it usable when points open.
        chosen = None if self._stale else self._pool.nearest(blocks, closed_points)
        if chosen is None:
            working = self._points_to_cover(closed_points)
        else:
            working = chosen.points
            self._control_scale = chosen.control_scale
        self._last_points = working
        closed = _rows(working, dim)
        closed_blocks = blocks[working]
        dtype = np.float32 if self.settings.single_precision else np.float64
        W_cc = self._closed_compliance(closed, dtype)
        E_c = self.space.E[closed]
        matvec = self._bordered_product(closed_blocks, W_cc, E_c)
        tolerance = self.settings.final_tolerance if final else self.settings.relative_tolerance
        if chosen is None:
            chosen = self._refactor(working, closed_blocks, W_cc, E_c)
        solution, iterations = self._krylov(matvec, chosen, r_kin[closed], r_ctl, tolerance)
        # Rebuild for the next solve once the nearest preconditioner has wasted as much as it
        # cost. The old one stays in the pool (least recently used goes first) for the
        # tangents it is nearer to; here the new one will be nearer.
        self._stale = solution is not None and chosen.age.charge(iterations, self.settings.fresh_iterations)
        if solution is None:
            # The factor stays in the pool: it failed on this tangent, not on the one it was
            # formed at. Under a cyclic load that is the same step of the next cycle, and a
            # factor dropped here is missing there (see KrylovSettings.factors_kept).
            chosen = self._refactor(working, closed_blocks, W_cc, E_c)
            solution, more = self._krylov(matvec, chosen, r_kin[closed], r_ctl, tolerance)
            iterations += more
            if solution is None:
                raise np.linalg.LinAlgError("GMRES did not converge with a fresh preconditioner")
        self.counters.solves += 1
        self.counters.krylov_iterations += iterations
        n_c = closed.size
        return self._with_open_rows(blocks, working, solution[:n_c], solution[n_c:], r_kin)

    def _points_to_cover(self, closed_points: np.ndarray) -> np.ndarray:
        """The points a new preconditioner is built on: the closed ones, and those the last
        solve worked on while that costs little (a contact zone that moves away should not
        drag all its history along)."""
        reference = self._last_points
        grown = closed_points if reference is None else np.union1d(reference, closed_points)
        return grown if grown.size <= 1.25 * closed_points.size else closed_points

    def _bordered_product(self, closed_blocks, W_cc, E_c):
        """x ↦ J·x for the bordered closed Jacobian (see :func:`_bordered`), with the control
        rows scaled as the preconditioner in use was (read at each call: a rebuild sets it)."""
        space, n_c = self.space, W_cc.shape[0]
        buffer = np.empty(n_c + space.n_control)

        def matvec(x):
            x_c, x_q = x[:n_c], x[n_c:]
            tangent_x = _apply_blocks(closed_blocks, x_c)
            top = buffer[:n_c]
            np.add(x_c, symmetric_product(W_cc, tangent_x), out=top)
            if x_q.size:
                top += E_c @ x_q
                buffer[n_c:] = self._control_scale * (space.Sq @ x_q - E_c.T @ tangent_x)
            return buffer.copy()

        return matvec

    def _krylov(self, matvec, factor, r_closed, r_ctl, tolerance):
        """GMRES on the bordered closed system preconditioned by ``factor``: (solution or None,
        iterations)."""
        rhs = np.concatenate([-r_closed, -self._control_scale * r_ctl])
        return _gmres(matvec, factor.precondition, rhs, tolerance, self.settings.max_iterations)

    def _with_open_rows(self, blocks, closed_points, delta_closed, delta_q, r_kin):
        """The full Δg from its closed rows: open rows follow by one product with W."""
        n, dim, _ = blocks.shape
        closed = _rows(closed_points, dim)
        delta_g = np.empty(n * dim)
        delta_g[closed] = delta_closed
        if closed.size == n * dim:
            return delta_g, delta_q
        is_open = np.ones(n * dim, dtype=bool)
        is_open[closed] = False
        open_rows = np.flatnonzero(is_open)
        contact_force = _apply_blocks(blocks[closed_points], delta_closed)
        coupling = self._open_coupling(closed, open_rows, contact_force)
        delta_g[open_rows] = -r_kin[open_rows] - coupling - self.space.E[open_rows] @ delta_q
        return delta_g, delta_q

    def _open_coupling(self, closed, open_rows, contact_force):
        """(W·f)[open] for forces f on the closed rows; W on (open, closed) gathered once while
        the closed rows stay the same (a small interface solved directly changes them rarely
        between Newton iterations: the cylinder, 0.08 ms a solve)."""
        cached = self._coupling
        if cached is None or not np.array_equal(cached[0], closed):
            W = self.space.W
            # W is symmetric: (W·f)[open] = f_c·W[closed, open]; gather the smaller row set.
            if open_rows.size <= closed.size:
                cached = self._coupling = (closed, True, _block(W, open_rows, closed))
            else:
                cached = self._coupling = (closed, False, _block(W, closed, open_rows))
        _, by_rows, block = cached
        return block @ contact_force if by_rows else contact_force @ block

    def _direct(self, blocks, closed_points, r_kin, r_ctl):
        """Exact solve: float64 LU of the bordered closed Jacobian of this iteration."""
        n, dim, _ = blocks.shape
        closed = _rows(closed_points, dim)
        E_c = self.space.E[closed]
        W_cc = self._closed_compliance(closed, np.float64)
        matrix, scale = _bordered(W_cc, blocks[closed_points], E_c, self.space.Sq, np.float64)
        rhs = np.concatenate([-r_kin[closed], -scale * r_ctl])
        if rhs.size:
            lu, pivots, info = _getrf(matrix)
            if info > 0:
                raise np.linalg.LinAlgError("singular Newton system")
            solution, _ = _getrs(lu, pivots, rhs)
        else:
            solution = rhs
        return self._with_open_rows(blocks, closed_points, solution[:closed.size],
                                    solution[closed.size:], r_kin)

    def _closed_compliance(self, closed: np.ndarray, dtype) -> np.ndarray:
        """W on the closed rows, in ``dtype``; cached while they stay closed."""
        key = np.dtype(dtype).char
        cached = self._compliance.get(key)
        if cached is None or not np.array_equal(cached[0], closed):
            self._compliance.pop(key, None)  # free the old copy before making the new one
            W = self._whole_compliance(dtype)
            block = W if closed.size == W.shape[0] else _block(W, closed, closed)
            self._compliance[key] = cached = (closed, block)
        return cached[1]

    def _whole_compliance(self, dtype) -> np.ndarray:
        """W in ``dtype``: the space's own in double precision; in single, one copy kept for
        the solver's life. The Krylov path gathers W on the working rows of whichever kept
        preconditioner it takes, and gathering from the single-precision copy reads half the
        bytes of W (the same values: rounding commutes with gathering)."""
        W = self.space.W
        if np.dtype(dtype) == W.dtype:
            return W
        if self._single is None or self._single.dtype != np.dtype(dtype):
            self._single = W.astype(dtype)
        return self._single

    def _refactor(self, closed_points, closed_blocks, W_cc, E_c) -> _Factor:
        """LU of the bordered closed Jacobian in the Krylov working precision, kept in the pool."""
        factor = self._factor(closed_points, closed_blocks.copy(), W_cc, E_c)
        self._control_scale = factor.control_scale
        self._pool.add(factor, self.space.structure.n_points)
        self._stale = False
        self.counters.factorisations += 1
        return factor

    def _factor(self, points, blocks, W_cc, E_c) -> _Factor:
        """The preconditioner formed at the tangent ``blocks`` (N/mm) of ``points``."""
        matrix, control_scale = _bordered(W_cc, blocks, E_c, self.space.Sq, W_cc.dtype)
        lu, pivots, info = _getrf(matrix)
        if info > 0:
            raise np.linalg.LinAlgError("singular preconditioner")
        size = matrix.shape[0]
        return _Factor(lu, pivots, points, blocks, control_scale,
                       Ageing(_krylov_iteration_flops(size), _rebuild_flops(size) / FACTOR_FLOP_RATE))

    def memory(self) -> dict[str, np.ndarray]:
        """The kept preconditioners as the tangents they were formed at, for a checkpoint
        (:meth:`recall`): per factor its points (``points``, ``counts`` of each), tangent
        blocks (N/mm), lost work (flops) and last use, and the pool's clock, whether the next
        solve rebuilds (``stale``) and the points the last solve worked on (empty for none).
        About 100 kB a factor at 1,500 points, where a factor itself is 90 MB: a resumed run
        forms the factors again from W, to the same bits, instead of reading them."""
        factors = self._pool.factors
        dim = self.space.structure.dim
        return {"points": np.concatenate([f.points for f in factors]) if factors else np.zeros(0, int),
                "counts": np.array([f.points.size for f in factors], dtype=int),
                "blocks": (np.concatenate([f.blocks for f in factors]) if factors
                           else np.zeros((0, dim, dim))),
                "lost_work": np.array([f.age.lost_work for f in factors], dtype=float),
                "last_used": np.array([f.last_used for f in factors], dtype=int),
                "clock": np.array(self._pool._clock), "stale": np.array(self._stale),
                "last_points": np.zeros(0, int) if self._last_points is None else self._last_points}

    def recall(self, memory: dict[str, np.ndarray]) -> None:
        """Take up a :meth:`memory` (a resumed run): form its factors again, in its order,
        from W and their tangents; the next solves then go as an uninterrupted run's."""
        dim = self.space.structure.dim
        dtype = np.float32 if self.settings.single_precision else np.float64
        ends = np.cumsum(memory["counts"])
        factors = []
        for end, count, lost, used in zip(ends, memory["counts"], memory["lost_work"], memory["last_used"]):
            points, blocks = memory["points"][end - count:end], memory["blocks"][end - count:end]
            closed = _rows(points, dim)
            factor = self._factor(points.copy(), blocks.copy(), self._closed_compliance(closed, dtype),
                                  self.space.E[closed])
            factor.age.lost_work, factor.last_used = float(lost), int(used)
            factors.append(factor)
        self._pool.take(factors, int(memory["clock"]), self.space.structure.n_points)
        self._stale = bool(memory["stale"])
        # a solve on the Krylov path works on some points, so empty stands for none
        self._last_points = memory["last_points"].copy() if memory["last_points"].size else None


@dataclass(eq=False)
class _Factor:
    """One preconditioner: the LU (single or double precision) of the bordered closed
    Jacobian of an earlier tangent, the closed points it covers and their tangent blocks
    then (N/mm), the control rows' scale it was formed with, and its age (cost and waste)."""

    lu: np.ndarray
    pivots: np.ndarray
    points: np.ndarray
    blocks: np.ndarray
    control_scale: np.ndarray
    age: Ageing
    last_used: int = 0

    def precondition(self, vector: np.ndarray) -> np.ndarray:
        solution, _ = _getrs_for(self.lu.dtype)(self.lu, self.pivots, vector.astype(self.lu.dtype))
        return solution.astype(float, copy=False)


class _Pool:
    """The preconditioners kept (at most ``size``), and which one suits a tangent.

    Beside the list, the reference tangents of all of them stand in one array (factor,
    point, dim, dim), zero at the points a factor does not cover, so that choosing is two
    array operations however many are kept."""

    def __init__(self):
        self.size = 1
        self.factors: list[_Factor] = []
        self._clock = 0
        self._stack = self._covers = None

    def add(self, factor: _Factor, n_points: int) -> None:
        """Keep ``factor``; the least recently used goes when more than ``size`` are kept."""
        self.factors.append(factor)
        self._touch(factor)
        while len(self.factors) > self.size:
            self.factors.remove(min(self.factors, key=lambda kept: kept.last_used))
        self._stack_tangents(n_points)

    def take(self, factors: list[_Factor], clock: int, n_points: int) -> None:
        """Keep ``factors`` (in this order, with their last uses) as a resumed run's pool."""
        self.factors, self._clock = list(factors), clock
        if factors:
            self._stack_tangents(n_points)

    def _stack_tangents(self, n_points: int) -> None:
        dim = self.factors[0].blocks.shape[1]
        self._stack = np.zeros((len(self.factors), n_points, dim, dim))
        self._covers = np.zeros((len(self.factors), n_points), dtype=bool)
        for row, kept in enumerate(self.factors):
            self._stack[row, kept.points] = kept.blocks
            self._covers[row, kept.points] = True

    def nearest(self, blocks: np.ndarray, closed_points: np.ndarray) -> _Factor | None:
        """The factor formed at the tangent nearest ``blocks`` (sum of squared differences of
        the per-point blocks) among those covering every closed point, the most recently used
        on a tie; None if none covers them. Deterministic: it depends only on the tangents."""
        if not self.factors:
            return None
        usable = self._covers[:, closed_points].all(axis=1)
        if not usable.any():
            return None
        gaps = np.where(usable, np.sum((self._stack - blocks[None]) ** 2, axis=(1, 2, 3)), np.inf)
        best = np.flatnonzero(gaps == gaps.min())
        chosen = max((self.factors[row] for row in best), key=lambda kept: kept.last_used)
        self._touch(chosen)
        return chosen

    def _touch(self, factor: _Factor) -> None:
        self._clock += 1
        factor.last_used = self._clock


def _block(W: np.ndarray, rows: np.ndarray, columns: np.ndarray) -> np.ndarray:
    """W[rows][:, columns] of a symmetric W, in the Fortran order that two-step gather gives,
    in one pass: W[columns, rows]ᵀ (measured at 4,728 rows, 4,500 of them gathered: 230 ms
    for the two steps and the cast to single precision, 54 ms from a single-precision copy)."""
    return dense_block(W, columns, rows).T


def _rows(points: np.ndarray, dim: int) -> np.ndarray:
    """Rows (normal, tangents) of ``points`` in the contact kinematics."""
    return (points[:, None] * dim + np.arange(dim)).ravel()


def _apply_blocks(blocks: np.ndarray, vector: np.ndarray) -> np.ndarray:
    """blockdiag(blocks)·vector for per-point (dim, dim) blocks."""
    n, dim, _ = blocks.shape
    return np.matmul(blocks, vector.reshape(n, dim, 1)).reshape(-1)


def _bordered(W_cc, closed_blocks, E_c, Sq, dtype) -> tuple[np.ndarray, np.ndarray]:
    """The bordered closed Jacobian in Fortran order, and the scale of its control rows.

        [[I + W_cc·A·D,   E_c ],
         [−s·E_cᵀ·A·D,  s·S_q]]

    Control rows are forces (N). S_q alone may vanish (a body floating until it touches),
    so they are divided by the stiffness the closed contacts give each control DOF,
    diag(Eᵀ·A·D·E) + |diag(S_q)|: then they read as mm like the kinematic rows. The floor
    keeps a DOF that no contact holds yet (tangential, before any pressure) well scaled.
    """
    n_c, m = W_cc.shape[0], Sq.shape[0]
    dim = closed_blocks.shape[1]
    matrix = np.empty((n_c + m, n_c + m), dtype=dtype, order="F")
    # W·blockdiag(D) = (blockdiag(Dᵀ)·W)ᵀ since W is symmetric: the row-block product is
    # contiguous, and its transpose is the Fortran-ordered array LAPACK factorises in place.
    transposed = matrix.T
    if n_c:
        # W_cc gathered on some rows is Fortran-ordered (_block): its transpose, the same
        # values, is the C-ordered array the row blocks are read from without a copy
        # (4,728 rows in single precision: 66 → 42 ms)
        rows = W_cc.T if W_cc.flags.f_contiguous and not W_cc.flags.c_contiguous else W_cc
        np.matmul(closed_blocks.transpose(0, 2, 1).astype(dtype),
                  rows.astype(dtype, copy=False).reshape(-1, dim, n_c),
                  out=transposed[:n_c, :n_c].reshape(-1, dim, n_c))
        transposed[np.diag_indices(n_c)] += 1.0
    # Eᵀ·blockdiag(D) = (blockdiag(Dᵀ)·E)ᵀ; the points' count is given, not inferred (-1):
    # with no control DOFs (every reference-point DOF prescribed) E_c is empty
    points = closed_blocks.shape[0]
    tangent_E = np.einsum("pji,pjm->pim", closed_blocks, E_c.reshape(points, dim, m)).reshape(n_c, m)
    stiffness = np.abs(np.einsum("rm,rm->m", E_c, tangent_E)) + np.abs(np.diag(Sq))
    floor = 1e-3 * stiffness.max(initial=0.0)
    scale = 1.0 / (np.maximum(stiffness, floor) if floor > 0.0 else np.ones(m))
    matrix[:n_c, n_c:] = E_c
    matrix[n_c:, :n_c] = -(scale[:, None] * tangent_E.T)
    matrix[n_c:, n_c:] = scale[:, None] * Sq
    return matrix, scale


def _getrf(matrix: np.ndarray):
    """LAPACK LU in place (no checks, no copies): (lu, pivots, info)."""
    getrf, = get_lapack_funcs(("getrf",), (matrix,))
    return getrf(matrix, overwrite_a=True)


def _getrs_for(dtype):
    getrs, = get_lapack_funcs(("getrs",), dtype=dtype)
    return getrs


def _getrs(lu, pivots, rhs):
    return _getrs_for(lu.dtype)(lu, pivots, rhs)


def _krylov_iteration_flops(size: int) -> float:
    """One preconditioned Krylov iteration on ``size`` rows: a product with the dense
    Jacobian and two triangular solves, each about 2·size² flops."""
    return 4.0 * size**2


def _rebuild_flops(size: int) -> float:
    """Forming (2·size²·dim, bounded by 6·size²) and LU-factorising (2/3·size³) the dense
    bordered Jacobian of ``size`` rows."""
    return 2.0 / 3.0 * size**3 + 6.0 * size**2


def _gmres(matvec, precondition, rhs: np.ndarray, tolerance: float, max_iterations: int):
    """Right-preconditioned GMRES from zero; (solution, iterations), solution None if not converged."""
    beta = float(np.linalg.norm(rhs))
    if beta == 0.0:
        return np.zeros_like(rhs), 0
    basis = np.empty((max_iterations + 1, rhs.size))
    directions = np.empty((max_iterations, rhs.size))
    hessenberg = np.zeros((max_iterations + 1, max_iterations))
    cosines, sines = np.zeros(max_iterations), np.zeros(max_iterations)
    residual = np.zeros(max_iterations + 1)
    residual[0] = beta
    basis[0] = rhs / beta
    for j in range(max_iterations):
        directions[j] = precondition(basis[j])
        w = matvec(directions[j])
        # Classical Gram-Schmidt twice: two BLAS products instead of j vector operations.
        for _ in range(2):
            h = basis[:j + 1] @ w
            w -= basis[:j + 1].T @ h
            hessenberg[:j + 1, j] += h
        hessenberg[j + 1, j] = np.linalg.norm(w)
        if hessenberg[j + 1, j] > 0.0:
            basis[j + 1] = w / hessenberg[j + 1, j]
        for i in range(j):
            upper = cosines[i] * hessenberg[i, j] + sines[i] * hessenberg[i + 1, j]
            hessenberg[i + 1, j] = -sines[i] * hessenberg[i, j] + cosines[i] * hessenberg[i + 1, j]
            hessenberg[i, j] = upper
        radius = np.hypot(hessenberg[j, j], hessenberg[j + 1, j])
        cosines[j], sines[j] = hessenberg[j, j] / radius, hessenberg[j + 1, j] / radius
        hessenberg[j, j], hessenberg[j + 1, j] = radius, 0.0
        residual[j + 1] = -sines[j] * residual[j]
        residual[j] *= cosines[j]
        if abs(residual[j + 1]) <= tolerance * beta:
            k = j + 1
            coefficients = la.solve_triangular(hessenberg[:k, :k], residual[:k], check_finite=False)
            return directions[:k].T @ coefficients, k
    return None, max_iterations
