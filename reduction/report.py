"""Accuracy of a Craig-Bampton body against its full sparse model.

Reports relative eigenfrequency errors (interfaces free: the body with only its clamps, which
is free-free when it has none; and interfaces fixed), the MAC of expanded modes, the static
interface displacement error for a unit load at each interface DOF, and the time to reduce.
Frequencies in Hz, times in s.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from reduction.coupling import rigid_couplings
from reduction.craig_bampton import CraigBampton, craig_bampton
from reduction.elasticity import assemble_elastic_body
from reduction.errors import InputError
from reduction.factorization import factorize
from reduction.mesh.io import read_mesh

#: eigenvalues below this fraction of the largest computed one are rigid-body modes
_RIGID_TOLERANCE = 1e-8
#: at most this many interface DOFs get a unit-load static check (evenly spread)
_MAX_STATIC_CASES = 60


@dataclass(frozen=True)
class AccuracyReport:
    """Accuracy of a reduction for several numbers of fixed-interface modes.

    mode_counts: (k,). full_hz: (f,) first elastic frequencies of the body with its clamps
    (interfaces free). reduced_hz, mac: (k, f). interface_fixed_full_hz and
    interface_fixed_reduced_hz: (g,) with the interfaces held too. static_dofs: interface DOFs
    loaded one at a time; static_error: their relative interface displacement errors (empty
    for an unclamped body). rigid_modes: zero-frequency modes skipped.
    """

    n_dofs: int
    n_interface: int
    mode_counts: np.ndarray
    full_hz: np.ndarray
    reduced_hz: np.ndarray
    mac: np.ndarray
    interface_fixed_full_hz: np.ndarray
    interface_fixed_reduced_hz: np.ndarray
    static_dofs: np.ndarray
    static_error: np.ndarray
    rigid_modes: int
    reduction_time_s: float
    full_model_time_s: float

    @property
    def frequency_error(self) -> np.ndarray:
        """(k, f) relative frequency errors, reduced / full - 1."""
        return self.reduced_hz / self.full_hz - 1.0

    @property
    def interface_fixed_error(self) -> np.ndarray:
        return self.interface_fixed_reduced_hz / self.interface_fixed_full_hz - 1.0

    @property
    def max_error_by_modes(self) -> np.ndarray:
        """(k,) largest |relative frequency error| for each mode count."""
        return np.nanmax(np.abs(self.frequency_error), axis=1)

    @property
    def error_never_grows(self) -> bool:
        """Whether the largest frequency error is non-increasing with the mode count."""
        errors = self.max_error_by_modes
        return bool(np.all(errors[1:] <= errors[:-1] * (1 + 1e-9)))

    def summary(self) -> dict:
        """Headline figures (JSON-ready) for a one-screen report."""
        return {
            "n_dofs": self.n_dofs,
            "n_interface": self.n_interface,
            "modes": int(self.mode_counts[-1]),
            "rigid_modes": self.rigid_modes,
            "max_frequency_error": float(self.max_error_by_modes[-1]),
            "error_never_grows": self.error_never_grows,
            "min_mac": float(np.nanmin(self.mac[-1])),
            "max_static_interface_error": float(self.static_error.max()) if self.static_error.size else None,
            "reduction_time_s": self.reduction_time_s,
            "full_model_time_s": self.full_model_time_s,
        }

    def to_records(self) -> list[dict]:
        """Flat rows (JSON-ready) of every compared quantity."""
        records = []
        for row, modes in enumerate(self.mode_counts):
            for index, full in enumerate(self.full_hz):
                records.append({
                    "quantity": "frequency", "case": "interfaces free", "modes": int(modes), "index": index + 1,
                    "full_hz": float(full), "reduced_hz": float(self.reduced_hz[row, index]),
                    "relative_error": float(self.frequency_error[row, index]), "mac": float(self.mac[row, index]),
                })
        for index, (full, reduced) in enumerate(zip(self.interface_fixed_full_hz, self.interface_fixed_reduced_hz)):
            records.append({
                "quantity": "frequency", "case": "interfaces fixed", "modes": int(self.mode_counts[-1]),
                "index": index + 1, "full_hz": float(full), "reduced_hz": float(reduced),
                "relative_error": float(reduced / full - 1.0),
            })
        for dof, error in zip(self.static_dofs, self.static_error):
            records.append({"quantity": "static interface displacement", "case": "unit load",
                            "interface_dof": int(dof), "relative_error": float(error)})
        records.append({"quantity": "time", "case": "reduction", "seconds": self.reduction_time_s,
                        "n_dofs": self.n_dofs, "n_interface": self.n_interface})
        records.append({"quantity": "time", "case": "full model eigenvalues and statics",
                        "seconds": self.full_model_time_s})
        return records


def _lowest_eigenpairs(stiffness, mass, count: int, solver: str):
    """Lowest ``count`` eigenpairs of a sparse pencil that may be singular (rigid modes)."""
    diagonal_ratio = stiffness.diagonal() / np.maximum(mass.diagonal(), np.finfo(float).tiny)
    shift = -1e-6 * float(np.median(diagonal_ratio))
    shifted = factorize(stiffness - shift * mass, solver=solver, label="shifted full-model stiffness")
    inverse = spla.LinearOperator(stiffness.shape, matvec=shifted.solve, dtype=float)
    values, vectors = spla.eigsh(stiffness.tocsc(), k=count, M=mass.tocsc(), sigma=shift, which="LM",
                                 OPinv=inverse, v0=np.cos(np.arange(stiffness.shape[0])))
    order = np.argsort(values)
    return values[order], vectors[:, order]


def _hz(eigenvalues: np.ndarray) -> np.ndarray:
    return np.sqrt(np.maximum(eigenvalues, 0.0)) / (2 * np.pi)


def _mac(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Column-wise modal assurance criterion of equal-shaped mode matrices."""
    return np.einsum("ij,ij->j", a, b) ** 2 / (np.einsum("ij,ij->j", a, a) * np.einsum("ij,ij->j", b, b))


def accuracy_report(stiffness, mass, interface_dofs, n_modes: int, *, fixed=(), n_frequencies: int = 6,
                    mode_counts=None, solver: str = "auto") -> AccuracyReport:
    """Compare Craig-Bampton reductions with 0..n_modes fixed-interface modes to the full model.

    stiffness (N/mm), mass (t): sparse; interface_dofs and fixed index them. mode_counts default:
    about eight counts from 0 to n_modes.
    """
    k = sp.csr_matrix(stiffness)
    m = sp.csr_matrix(mass)
    fixed = np.asarray(fixed, dtype=np.int64)
    interface = np.asarray(interface_dofs, dtype=np.int64)
    cb = craig_bampton(k, m, interface, n_modes, fixed=fixed, solver=solver)
    counts = _mode_counts(mode_counts, n_modes)
    full = _full_model_reference(k, m, fixed, interface, n_modes, n_frequencies, solver)
    reduced_hz, mac = _reduced_modes(cb, counts, full.free, full.vectors, n_frequencies)
    static_error = _reduced_statics_error(cb, full.static_dofs, full.static)
    return AccuracyReport(
        n_dofs=k.shape[0],
        n_interface=interface.size,
        mode_counts=counts,
        full_hz=_hz(full.values),
        reduced_hz=np.array(reduced_hz),
        mac=np.array(mac),
        interface_fixed_full_hz=_hz(full.interface_fixed_values),
        interface_fixed_reduced_hz=cb.fixed_interface_frequencies_hz[:full.interface_fixed_count],
        static_dofs=full.static_dofs,
        static_error=static_error,
        rigid_modes=full.rigid_modes,
        reduction_time_s=cb.reduction_time_s,
        full_model_time_s=full.time_s,
    )


def _mode_counts(mode_counts, n_modes: int) -> np.ndarray:
    """Sorted distinct mode counts in 0..n_modes; by default about eight of them."""
    counts = np.unique(np.linspace(0, n_modes, 8).round().astype(int)) if mode_counts is None \
        else np.asarray(sorted({int(c) for c in mode_counts}))
    if counts.max() > n_modes or counts.min() < 0:
        raise InputError(f"mode counts must lie in 0..{n_modes}, got {counts.tolist()}")
    return counts


@dataclass(frozen=True)
class _FullModelReference:
    """What the reductions are compared with, from the full sparse model.

    free: (n_free,) DOFs not clamped. values (eigenvalues, (rad/s)^2) and vectors (n_free, f):
    the first elastic modes. interface_fixed_values: the first eigenvalues with the interfaces
    held too, interface_fixed_count of them. static_dofs, static: see :func:`_full_statics`.
    time_s: time to compute all of it, s.
    """

    free: np.ndarray
    values: np.ndarray
    vectors: np.ndarray
    rigid_modes: int
    interface_fixed_values: np.ndarray
    interface_fixed_count: int
    static_dofs: np.ndarray
    static: np.ndarray
    time_s: float


def _full_model_reference(k, m, fixed: np.ndarray, interface: np.ndarray, n_modes: int,
                          n_frequencies: int, solver: str) -> _FullModelReference:
    """Modes (interfaces free and fixed) and interface statics of the full model, timed."""
    start = time.perf_counter()
    free = np.setdiff1d(np.arange(k.shape[0]), fixed)
    k_free, m_free = k[free][:, free], m[free][:, free]
    n_rigid_max = 6 if fixed.size == 0 else 0
    values, vectors = _lowest_eigenpairs(k_free, m_free, n_frequencies + n_rigid_max, solver)
    rigid = int(np.sum(values < _RIGID_TOLERANCE * values.max()))
    full_values, full_vectors = values[rigid:rigid + n_frequencies], vectors[:, rigid:rigid + n_frequencies]
    interior_fixed_count = min(n_frequencies, n_modes)
    held = np.setdiff1d(free, interface)
    fixed_values = (_lowest_eigenpairs(k[held][:, held], m[held][:, held], interior_fixed_count, solver)[0]
                    if interior_fixed_count else np.zeros(0))
    static_dofs, full_static = _full_statics(k_free, free, interface, fixed.size > 0, solver)
    full_time = time.perf_counter() - start
    return _FullModelReference(free, full_values, full_vectors, rigid, fixed_values, interior_fixed_count,
                               static_dofs, full_static, full_time)


def _reduced_modes(cb: CraigBampton, counts: np.ndarray, free: np.ndarray, full_vectors: np.ndarray,
                   n_frequencies: int) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Per mode count: the reduced model's first elastic frequencies (Hz) and their MAC with
    the full modes; NaN where the reduced model has fewer modes."""
    reduced_hz, mac = [], []
    for count in counts:
        reduced = cb.truncated(int(count))
        r_values, r_vectors = sla.eigh(reduced.stiffness, reduced.mass)
        r_rigid = int(np.sum(r_values < _RIGID_TOLERANCE * r_values.max()))
        chosen = slice(r_rigid, r_rigid + n_frequencies)
        r_hz = np.full(n_frequencies, np.nan)
        r_hz[: len(r_values[chosen])] = _hz(r_values[chosen])
        expanded = (reduced.basis @ r_vectors[:, chosen])[free]
        row_mac = np.full(n_frequencies, np.nan)
        row_mac[: expanded.shape[1]] = _mac(full_vectors[:, : expanded.shape[1]], expanded)
        reduced_hz.append(r_hz)
        mac.append(row_mac)
    return reduced_hz, mac


def _full_statics(k_free, free, interface, clamped: bool, solver: str):
    """Full-model interface displacements for a unit load at each (sampled) interface DOF."""
    if not clamped:
        return np.zeros(0, dtype=np.int64), np.zeros((interface.size, 0))
    chosen = np.unique(np.linspace(0, interface.size - 1, min(interface.size, _MAX_STATIC_CASES)).round().astype(int))
    position = np.searchsorted(free, interface)
    loads = np.zeros((free.size, chosen.size))
    loads[position[chosen], np.arange(chosen.size)] = 1.0
    displacement = factorize(k_free, solver=solver, label="clamped full-model stiffness").solve(loads)
    return interface[chosen], displacement[position]


def _reduced_statics_error(cb: CraigBampton, static_dofs, full_static) -> np.ndarray:
    if static_dofs.size == 0:
        return np.zeros(0)
    loads = np.zeros((cb.basis.shape[0], static_dofs.size))
    loads[static_dofs, np.arange(static_dofs.size)] = 1.0
    q = np.linalg.solve(cb.stiffness, cb.basis.T @ loads)
    reduced = q[: cb.n_interface]
    return np.linalg.norm(reduced - full_static, axis=0) / np.linalg.norm(full_static, axis=0)


def accuracy_report_for_mesh(path, youngs_modulus: float, poisson_ratio: float, density: float,
                             n_modes: int, interface_sets: list[str] | None = None, *, clamp_sets=(),
                             rotations: bool = True, n_frequencies: int = 6) -> AccuracyReport:
    """Report for a mesh file: each named node set is RBE2-coupled to its centroid and becomes an
    interface (default: every node set in the file that is not a clamp set); named clamp sets
    are fixed. E in MPa, density in t/mm^3."""
    model = read_mesh(path)
    body = assemble_elastic_body(model.mesh, youngs_modulus, poisson_ratio, density)
    if interface_sets is None:
        interface_sets = sorted(set(model.node_sets) - set(clamp_sets))
    groups = []
    for name in interface_sets:
        nodes = model.body_nodes(body, name)
        groups.append((nodes, body.coordinates[nodes].mean(axis=0)))
    if not groups:
        raise InputError(f"{path}: no interface node set (the file names none besides the clamps)")
    coupling = rigid_couplings(body.n_dofs, body.node_dofs, body.coordinates, groups, rotations=rotations)
    clamped = [body.node_dofs[model.body_nodes(body, name)].ravel() for name in clamp_sets]
    fixed = coupling.kept[np.concatenate(clamped)] if clamped else np.zeros(0, dtype=np.int64)
    if np.any(fixed < 0):
        raise InputError("a clamp set shares nodes with an interface set")
    return accuracy_report(coupling.reduce_matrix(body.stiffness), coupling.reduce_matrix(body.mass),
                           coupling.reference_dofs.ravel(), n_modes, fixed=fixed, n_frequencies=n_frequencies)


def plot_error_vs_modes(report: AccuracyReport, path) -> Path:
    """Write a PNG of |relative frequency error| (each of the first frequencies) vs number of modes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = Path(path)
    figure, axes = plt.subplots(figsize=(6.0, 4.0))
    error = np.abs(report.frequency_error)
    floor = 1e-12
    for index in range(error.shape[1]):
        axes.semilogy(report.mode_counts, np.maximum(error[:, index], floor), marker="o",
                      label=f"f{index + 1} = {report.full_hz[index]:.1f} Hz")
    axes.axhline(0.005, color="grey", linestyle="--", linewidth=0.8, label="0.5 %")
    axes.set_xlabel("fixed-interface normal modes")
    axes.set_ylabel("|relative frequency error|")
    axes.set_title(f"Craig-Bampton, {report.n_dofs} DOFs, {report.n_interface} interface DOFs")
    axes.legend(fontsize=7)
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path
