"""Craig-Bampton reduction (constraint modes + fixed-interface normal modes) of sparse K, M.

Units: stiffness N/mm, mass t, so eigenvalues are omega^2 in (rad/s)^2 and frequencies Hz.

How the pieces fit (API for the multibody model):

    body = assemble_elastic_body(mesh, E, nu, density)                 # reduction.elasticity
    coupling = rigid_couplings(body.n_dofs, body.node_dofs, body.coordinates,
                               [(nodes_a, point_a), (nodes_b, point_b)], rotations=True)
    k, m = coupling.reduce_matrix(body.stiffness), coupling.reduce_matrix(body.mass)
    cb = craig_bampton(k, m, coupling.reference_dofs.ravel(), n_modes=20, fixed=clamped_dofs)
    cb.stiffness, cb.mass          # (n_q, n_q) reduced matrices, q = [interface DOFs, modal amplitudes]
    u = coupling.expand(cb.expand(q))                                    # full nodal displacements, mm

``interface_dofs`` are DOF indices of the matrices passed in: mesh DOFs (``body.node_dofs[...]``)
or RBE2 reference-point DOFs of a ``Coupling``. Generalised coordinates q are the interface
displacements (mm, rad) followed by the amplitudes of the mass-normalised fixed-interface modes.

For exudyn's floating-frame body (``ObjectFFRFreducedOrder``) use ``reduction.exudyn_bridge``,
which builds the mode basis in exudyn's convention (rigid motion carried by the frame, first
interface clamped) and a ready ``exudyn.FEM.FEMinterface``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from reduction.condensation import as_dof_index
from reduction.errors import InputError
from reduction.factorization import factorize


@dataclass(frozen=True)
class CraigBampton:
    """A Craig-Bampton reduced body.

    interface_dofs: (n_b,) retained DOF indices (into the matrices that were reduced).
    fixed: DOFs held at zero. basis: (n, n_b + n_m) columns = constraint modes (unit displacement
    of one interface DOF, interior in static equilibrium) then fixed-interface normal modes
    (mass-normalised, zero at interface and fixed DOFs).
    stiffness (N/mm) and mass (t): (n_q, n_q) reduced matrices, n_q = n_b + n_m.
    fixed_interface_eigenvalues: (n_m,) omega^2 of the normal modes, (rad/s)^2.
    reduction_time_s: wall time of the reduction, s.
    """

    interface_dofs: np.ndarray
    fixed: np.ndarray
    basis: np.ndarray
    stiffness: np.ndarray
    mass: np.ndarray
    fixed_interface_eigenvalues: np.ndarray
    reduction_time_s: float

    @property
    def n_interface(self) -> int:
        return int(self.interface_dofs.size)

    @property
    def n_modes(self) -> int:
        return int(self.fixed_interface_eigenvalues.size)

    @property
    def constraint_modes(self) -> np.ndarray:
        return self.basis[:, : self.n_interface]

    @property
    def normal_modes(self) -> np.ndarray:
        return self.basis[:, self.n_interface:]

    @property
    def fixed_interface_frequencies_hz(self) -> np.ndarray:
        return np.sqrt(np.maximum(self.fixed_interface_eigenvalues, 0.0)) / (2 * np.pi)

    def expand(self, generalized: np.ndarray) -> np.ndarray:
        """Full displacement vector(s), mm, from q of shape (n_q,) or (n_q, m)."""
        return self.basis @ np.asarray(generalized, dtype=float)

    def truncated(self, n_modes: int) -> "CraigBampton":
        """The same reduction keeping only the first ``n_modes`` normal modes."""
        if not 0 <= n_modes <= self.n_modes:
            raise InputError(f"can keep 0..{self.n_modes} normal modes, asked for {n_modes}")
        keep = self.n_interface + n_modes
        return CraigBampton(
            interface_dofs=self.interface_dofs,
            fixed=self.fixed,
            basis=self.basis[:, :keep],
            stiffness=self.stiffness[:keep, :keep],
            mass=self.mass[:keep, :keep],
            fixed_interface_eigenvalues=self.fixed_interface_eigenvalues[:n_modes],
            reduction_time_s=self.reduction_time_s,
        )


def fixed_interface_modes(
    stiffness_interior: sp.spmatrix, mass_interior: sp.spmatrix, n_modes: int, solve_interior
) -> tuple[np.ndarray, np.ndarray]:
    """Lowest ``n_modes`` eigenpairs of K_ii phi = omega^2 M_ii phi (shift-invert about 0).

    Returns omega^2 ascending, (rad/s)^2, and M-normalised modes (n_i, n_modes).
    """
    n = stiffness_interior.shape[0]
    if n_modes == 0:
        return np.zeros(0), np.zeros((n, 0))
    if n_modes >= n - 1:
        raise InputError(f"asked for {n_modes} normal modes but the interior has only {n} DOFs")
    inverse = spla.LinearOperator((n, n), matvec=solve_interior, dtype=float)
    eigenvalues, modes = spla.eigsh(
        sp.csr_matrix(stiffness_interior), k=n_modes, M=sp.csr_matrix(mass_interior), sigma=0.0,
        OPinv=inverse, which="LM", v0=np.cos(np.arange(n)),
    )
    order = np.argsort(eigenvalues)
    modes = modes[:, order]
    # eigsh returns M-orthonormal vectors; normalise again against round-off of the shift-invert
    modes /= np.sqrt(np.einsum("ij,ij->j", modes, mass_interior @ modes))
    return eigenvalues[order], modes


def craig_bampton(stiffness, mass, interface_dofs, n_modes: int, *, fixed=(), solver: str = "auto") -> CraigBampton:
    """Craig-Bampton reduction of sparse symmetric K (N/mm) and M (t).

    interface_dofs: retained boundary DOFs (their order is kept in q). n_modes: number of
    fixed-interface normal modes. fixed: DOFs held at zero (clamps). The interior K_ii must be
    non-singular (interface + fixed DOFs stop all rigid motion of the interior).
    """
    start = time.perf_counter()
    k = sp.csr_matrix(stiffness)
    m = sp.csr_matrix(mass)
    n = k.shape[0]
    if k.shape != (n, n) or m.shape != (n, n):
        raise InputError(f"stiffness {k.shape} and mass {m.shape} must be square and of equal size")
    interface = as_dof_index(interface_dofs, n, "interface")
    fixed = as_dof_index(fixed, n, "fixed")
    if np.intersect1d(interface, fixed).size:
        raise InputError("a DOF is both an interface DOF and fixed")
    if n_modes < 0:
        raise InputError(f"number of normal modes must be >= 0, got {n_modes}")
    is_interior = np.ones(n, dtype=bool)
    is_interior[interface] = False
    is_interior[fixed] = False
    interior = np.flatnonzero(is_interior)

    k_ii = k[interior][:, interior]
    k_ib = k[interior][:, interface]
    factor = factorize(k_ii, solver=solver, label="interior stiffness K_ii (interface and clamps fixed)")
    static_interior = -factor.solve(k_ib.toarray())
    eigenvalues, modes_interior = fixed_interface_modes(k_ii, m[interior][:, interior], n_modes, factor.solve)

    n_b = interface.size
    basis = np.zeros((n, n_b + n_modes))
    basis[interface, np.arange(n_b)] = 1.0
    basis[interior, :n_b] = static_interior
    basis[interior, n_b:] = modes_interior

    reduced_stiffness = np.zeros((n_b + n_modes,) * 2)
    schur = k[interface][:, interface].toarray() + k_ib.T @ static_interior
    reduced_stiffness[:n_b, :n_b] = 0.5 * (schur + schur.T)
    reduced_stiffness[n_b:, n_b:] = np.diag(eigenvalues)
    reduced_mass = basis.T @ (m @ basis)
    reduced_mass = 0.5 * (reduced_mass + reduced_mass.T)
    return CraigBampton(
        interface_dofs=interface,
        fixed=fixed,
        basis=basis,
        stiffness=reduced_stiffness,
        mass=reduced_mass,
        fixed_interface_eigenvalues=eigenvalues,
        reduction_time_s=time.perf_counter() - start,
    )
