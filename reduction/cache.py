"""HDF5 cache of reductions, keyed by a hash of mesh, material, retained sets and mode count.

A scene that changes only contact parameters finds its reduced bodies here and skips the
reduction. One file per key, ``<cache_dir>/<key>.h5``; root attrs fretwork_format =
"fretwork-reduction", format_version = 1, kind ("craig-bampton" or "condensation").
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Callable

import h5py
import numpy as np
import scipy.sparse as sp
import skfem

from reduction.condensation import Condensation, lazy_interior_solver
from reduction.craig_bampton import CraigBampton
from reduction.errors import InputError

FORMAT = "fretwork-reduction"
FORMAT_VERSION = 1


def reduction_key(mesh: skfem.Mesh, materials: dict, retained: dict, n_modes: int = 0,
                  extra: dict | None = None) -> str:
    """Hex SHA-256 of everything a reduction depends on.

    materials: name -> scalar or per-element array (E in MPa, nu, density in t/mm^3);
    retained: name -> DOF or node index arrays (interfaces, clamps, couplings); extra: any
    further JSON-like settings (e.g. solver tolerances, reference points).
    """
    digest = hashlib.sha256()

    def add(label: str, value) -> None:
        digest.update(label.encode())
        array = np.ascontiguousarray(np.asarray(value))
        digest.update(str(array.dtype).encode() + str(array.shape).encode())
        digest.update(array.tobytes())

    add("format", FORMAT_VERSION)
    add("mesh type", type(mesh).__name__)
    add("points", mesh.doflocs.astype(np.float64))
    add("elements", mesh.t.astype(np.int64))
    for name in sorted(materials):
        add(f"material {name}", np.asarray(materials[name], dtype=np.float64))
    for name in sorted(retained):
        add(f"retained {name}", np.asarray(retained[name], dtype=np.int64))
    add("modes", int(n_modes))
    for name in sorted(extra or {}):
        add(f"extra {name}", repr(extra[name]))
    return digest.hexdigest()


def _file(cache_dir, key: str) -> Path:
    return Path(cache_dir) / f"{key}.h5"


def _open_valid(path: Path, kind: str):
    handle = h5py.File(path, "r")
    if handle.attrs.get("fretwork_format") != FORMAT or handle.attrs.get("format_version") != FORMAT_VERSION \
            or handle.attrs.get("kind") != kind:
        handle.close()
        raise InputError(f"{path} is not a fretwork {kind} cache file of format version {FORMAT_VERSION}")
    return handle


def _write_header(handle: h5py.File, key: str, kind: str) -> None:
    handle.attrs["fretwork_format"] = FORMAT
    handle.attrs["format_version"] = FORMAT_VERSION
    handle.attrs["kind"] = kind
    handle.attrs["key"] = key


def _dataset(handle, name: str, data, units: str, description: str) -> None:
    dataset = handle.create_dataset(name, data=data)
    dataset.attrs["units"] = units
    dataset.attrs["description"] = description


def save_craig_bampton(cache_dir, key: str, reduction: CraigBampton) -> Path:
    path = _file(cache_dir, key)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_suffix(".h5.partial")
    with h5py.File(partial, "w") as handle:
        _write_header(handle, key, "craig-bampton")
        _dataset(handle, "interface_dofs", reduction.interface_dofs, "-", "retained boundary DOF indices")
        _dataset(handle, "fixed", reduction.fixed, "-", "DOF indices held at zero")
        _dataset(handle, "basis", reduction.basis, "mm", "constraint modes then mass-normalised normal modes")
        _dataset(handle, "stiffness", reduction.stiffness, "N/mm", "reduced stiffness")
        _dataset(handle, "mass", reduction.mass, "t", "reduced mass")
        _dataset(handle, "fixed_interface_eigenvalues", reduction.fixed_interface_eigenvalues, "rad^2/s^2",
                 "squared circular frequencies of the normal modes")
        handle.attrs["reduction_time_s"] = reduction.reduction_time_s
    partial.replace(path)  # a crash mid-write never leaves a readable half file
    return path


def load_craig_bampton(cache_dir, key: str) -> CraigBampton | None:
    path = _file(cache_dir, key)
    if not path.is_file():
        return None
    with _open_valid(path, "craig-bampton") as handle:
        return CraigBampton(
            interface_dofs=handle["interface_dofs"][()],
            fixed=handle["fixed"][()],
            basis=handle["basis"][()],
            stiffness=handle["stiffness"][()],
            mass=handle["mass"][()],
            fixed_interface_eigenvalues=handle["fixed_interface_eigenvalues"][()],
            reduction_time_s=float(handle.attrs["reduction_time_s"]),
        )


def cached_craig_bampton(cache_dir, key: str, compute: Callable[[], CraigBampton]) -> tuple[CraigBampton, bool]:
    """The cached reduction for ``key`` (and True), or ``compute()`` stored now (and False)."""
    found = load_craig_bampton(cache_dir, key)
    if found is not None:
        return found, True
    reduction = compute()
    save_craig_bampton(cache_dir, key, reduction)
    return reduction, False


def save_condensation(cache_dir, key: str, condensation: Condensation) -> Path:
    path = _file(cache_dir, key)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_suffix(".h5.partial")
    with h5py.File(partial, "w") as handle:
        _write_header(handle, key, "condensation")
        _dataset(handle, "retained", condensation.retained, "-", "retained DOF indices")
        _dataset(handle, "interior", condensation.interior, "-", "eliminated DOF indices")
        _dataset(handle, "fixed", condensation.fixed, "-", "DOF indices held at zero")
        _dataset(handle, "stiffness", condensation.stiffness, "N/mm", "Schur complement on the retained DOFs")
        loads = handle.create_group("loads")
        responses = handle.create_group("interior_load_response")
        for name, vector in condensation.loads.items():
            _dataset(loads, name, vector, "N", f"condensed load '{name}'")
            _dataset(responses, name, condensation.interior_load_response[name], "mm",
                     f"interior displacement under load '{name}' with retained DOFs held")
        handle.attrs["n_dofs"] = condensation.n_dofs
        handle.attrs["solver"] = condensation.solver
    partial.replace(path)
    return path


def load_condensation(cache_dir, key: str, stiffness=None, *, solver: str = "auto") -> Condensation | None:
    """A cached condensation; pass the full stiffness (N/mm) to be able to ``expand`` it
    (the interior is factorised on first use only)."""
    path = _file(cache_dir, key)
    if not path.is_file():
        return None
    with _open_valid(path, "condensation") as handle:
        retained = handle["retained"][()]
        interior = handle["interior"][()]
        n_dofs = int(handle.attrs["n_dofs"])
        condensed_stiffness = handle["stiffness"][()]
        loads = {name: handle["loads"][name][()] for name in handle["loads"]}
        responses = {name: handle["interior_load_response"][name][()] for name in handle["interior_load_response"]}
        fixed = handle["fixed"][()]
        solver_name = str(handle.attrs["solver"])
    if stiffness is None:
        coupling = sp.csr_matrix((interior.size, retained.size))

        def solve(rhs):
            raise InputError("this cached condensation was loaded without the stiffness matrix; pass it to expand")
    else:
        matrix = sp.csr_matrix(stiffness)
        if matrix.shape != (n_dofs, n_dofs):
            raise InputError(f"stiffness has shape {matrix.shape}, the cached condensation has {n_dofs} DOFs")
        coupling = matrix[interior][:, retained]
        solve = lazy_interior_solver(matrix[interior][:, interior], solver, eager=False)
    return Condensation(
        retained=retained, stiffness=condensed_stiffness, loads=loads, interior=interior, fixed=fixed,
        n_dofs=n_dofs, solver=solver_name, interior_load_response=responses,
        interior_retained_coupling=coupling, solve_interior=solve,
    )


def cached_condensation(cache_dir, key: str, stiffness, compute: Callable[[], Condensation],
                        *, solver: str = "auto") -> tuple[Condensation, bool]:
    """The cached condensation for ``key`` (and True), or ``compute()`` stored now (and False).

    stiffness: the full matrix (N/mm) the condensation came from, kept for ``expand``. Put the
    load vectors into the key (``reduction_key(..., extra={...})``) when they may change.
    """
    found = load_condensation(cache_dir, key, stiffness, solver=solver)
    if found is not None:
        return found, True
    condensation = compute()
    save_condensation(cache_dir, key, condensation)
    return condensation, False
