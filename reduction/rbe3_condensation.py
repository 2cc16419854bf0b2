"""Condensation onto RBE3 reference points (bolt bearing areas) without stiffening them.

An RBE3 reference point moves with the weighted rigid fit of its node set, u_ref = R u_c, and
its load spreads as R^T F. Starting from a condensation whose retained DOFs include the
coupled DOFs c, a second, dense stage eliminates u_c under that constraint (Lagrange
multipliers, exact):

    [ S_kk   0    S_kc   0  ] [u_k  ]   [f_k]
    [ 0      0    0     -I  ] [u_ref] = [F  ]     (F = -lambda: the force on the reference)
    [ S_ck   0    S_cc  R^T ] [u_c  ]   [f_c]
    [ 0     -I    R     0   ] [lambda]  [0  ]

Units: N/mm, N, mm (rad for rotations, N mm for moments).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from reduction.condensation import Condensation
from reduction.coupling import DistributingCoupling
from reduction.errors import InputError


@dataclass(frozen=True)
class ReferencedCondensation:
    """A condensation whose retained vector is [kept retained DOFs, RBE3 reference DOFs].

    kept: mesh DOF indices still retained (order of the first rows of ``stiffness``).
    reference_dofs: (n_points, n_ref) positions of each reference point's DOFs in the retained vector.
    stiffness: dense (n_r, n_r), N/mm. loads: condensed load vectors, N.
    """

    kept: np.ndarray
    reference_dofs: np.ndarray
    stiffness: np.ndarray
    loads: dict[str, np.ndarray]
    base: Condensation
    coupled_positions: np.ndarray
    kept_positions: np.ndarray
    inner_matrix_factor: tuple
    inner_coupling: np.ndarray
    inner_loads: dict[str, np.ndarray]

    def expand(self, retained_displacement, load_factors: dict[str, float] | None = None) -> np.ndarray:
        """Full displacement vector (mm) from [u_kept, u_ref] (shape (n_r,) or (n_r, m))."""
        x = np.asarray(retained_displacement, dtype=float)
        if x.shape[0] != self.stiffness.shape[0]:
            raise InputError(f"retained displacement has {x.shape[0]} entries, expected {self.stiffness.shape[0]}")
        rhs = -self.inner_coupling @ x
        for name, factor in (load_factors or {}).items():
            if name not in self.inner_loads:
                raise InputError(f"load '{name}' was not condensed; known loads: {sorted(self.loads)}")
            load = self.inner_loads[name]
            rhs = rhs + factor * (load if x.ndim == 1 else load[:, None])
        inner = sla.lu_solve(self.inner_matrix_factor, rhs)
        base_retained = np.zeros((self.base.retained.size,) + x.shape[1:])
        base_retained[self.kept_positions] = x[: self.kept_positions.size]
        base_retained[self.coupled_positions] = inner[: self.coupled_positions.size]
        return self.base.expand(base_retained, load_factors)


def _split_positions(condensation: Condensation,
                     couplings: list[DistributingCoupling]) -> tuple[np.ndarray, np.ndarray]:
    """Positions, in ``condensation.retained``, of the coupled DOFs and of the DOFs kept as they are."""
    position_of = np.full(condensation.n_dofs, -1, dtype=np.int64)
    position_of[condensation.retained] = np.arange(condensation.retained.size)
    coupled = np.concatenate([c.coupled_dofs for c in couplings])
    if np.unique(coupled).size != coupled.size:
        raise InputError("RBE3 couplings share nodes; give each bearing area its own nodes")
    coupled_positions = position_of[coupled]
    if np.any(coupled_positions < 0):
        raise InputError("an RBE3 coupled DOF is not retained in the condensation: retain the bearing-area DOFs")
    is_kept = np.ones(condensation.retained.size, dtype=bool)
    is_kept[coupled_positions] = False
    return coupled_positions, np.flatnonzero(is_kept)


def _stacked_averaging(couplings: list[DistributingCoupling], n_c: int) -> np.ndarray:
    """Block-diagonal averaging matrix: reference DOFs (rows) from the coupled DOFs (columns)."""
    sizes = [c.averaging.shape[0] for c in couplings]
    if len(set(sizes)) > 1:
        raise InputError("RBE3 couplings mix reference points with and without rotations; use one kind")
    averaging = np.zeros((sum(sizes), n_c))
    row = column = 0
    for coupling, size in zip(couplings, sizes):
        width = coupling.coupled_dofs.size
        averaging[row:row + size, column:column + width] = coupling.averaging[:, coupling.coupled_dofs].toarray()
        row, column = row + size, column + width
    return averaging


def _factor_saddle_point(inner: np.ndarray):
    """LU factor of the saddle-point block; InputError when the block is singular."""
    with np.errstate(all="ignore"):
        factor = sla.lu_factor(inner, check_finite=True)
        probe = np.cos(np.arange(inner.shape[0]))
        solution = sla.lu_solve(factor, probe)
    # a singular saddle-point block shows as a non-finite or inaccurate solve, not as an exception
    if not np.all(np.isfinite(solution)) or \
            np.linalg.norm(inner @ solution - probe) > 1e-8 * np.linalg.norm(probe):
        raise InputError("RBE3 elimination is singular: a bearing area can move without strain; "
                         "clamp or retain more of the body, or couple without rotations")
    return factor


def attach_rbe3(condensation: Condensation, couplings: list[DistributingCoupling]) -> ReferencedCondensation:
    """Replace the coupled DOFs of each RBE3 coupling by its reference DOFs.

    Every coupled DOF must be retained in ``condensation``; node sets must not overlap.
    """
    if not couplings:
        raise InputError("attach_rbe3 needs at least one distributing coupling")
    coupled_positions, kept_positions = _split_positions(condensation, couplings)
    n_k, n_c = kept_positions.size, coupled_positions.size
    averaging = _stacked_averaging(couplings, n_c)
    n_ref = averaging.shape[0]

    s = condensation.stiffness
    s_kk = s[np.ix_(kept_positions, kept_positions)]
    s_kc = s[np.ix_(kept_positions, coupled_positions)]
    s_cc = s[np.ix_(coupled_positions, coupled_positions)]
    inner = np.block([[s_cc, averaging.T], [averaging, np.zeros((n_ref, n_ref))]])
    coupling_inner = np.block([[s_kc.T, np.zeros((n_c, n_ref))], [np.zeros((n_ref, n_k)), -np.eye(n_ref)]])
    outer = np.zeros((n_k + n_ref, n_k + n_ref))
    outer[:n_k, :n_k] = s_kk
    factor = _factor_saddle_point(inner)
    schur = outer - coupling_inner.T @ sla.lu_solve(factor, coupling_inner)

    inner_loads, loads = {}, {}
    for name, vector in condensation.loads.items():
        inner_load = np.concatenate([vector[coupled_positions], np.zeros(n_ref)])
        outer_load = np.concatenate([vector[kept_positions], np.zeros(n_ref)])
        inner_loads[name] = inner_load
        loads[name] = outer_load - coupling_inner.T @ sla.lu_solve(factor, inner_load)
    return ReferencedCondensation(
        kept=condensation.retained[kept_positions],
        reference_dofs=(n_k + np.arange(n_ref)).reshape(len(couplings), -1),
        stiffness=0.5 * (schur + schur.T),
        loads=loads,
        base=condensation,
        coupled_positions=coupled_positions,
        kept_positions=kept_positions,
        inner_matrix_factor=factor,
        inner_coupling=coupling_inner,
        inner_loads=inner_loads,
    )
