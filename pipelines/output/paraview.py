"""Interface fields as an XDMF time series (meshio) that opens in ParaView.

The contact surface is written as its facets (lines in 2D, quadrilaterals or triangles in
3D). ``interface.xdmf`` has one time step per recorded cycle, time the equivalent cycle number.
``interface_increments.xdmf`` (a run with ``[procedure] field_output``) has one per written
increment, time (cycle − 1) + fraction of the cycle in simulated cycles: the end of cycle 3 is
at 3.0, its peak load (fraction 0.25 of a sine cycle) at 2.25. In finite sliding the master
body's own final wear field is written on the master surface by :func:`write_master_final_vtu`.
"""

from __future__ import annotations

import os
from pathlib import Path

import h5py
import meshio
import numpy as np

CELL_TYPES = {2: "line", 3: "triangle", 4: "quad"}


#: a fields group up to this size (bytes) is read whole before a series is written from it
_READ_WHOLE = 256 << 20


def _loaded(fields: h5py.Group):
    """Every dataset of a fields group read whole (a dict by name), so that the series slices
    its rows in memory: one h5py read per row and field cost 0.23 ms of the cylinder's 2.9 ms
    per increment. A group larger than ``_READ_WHOLE`` stays
    on disk and is read row by row."""
    if sum(dataset.nbytes for dataset in fields.values()) > _READ_WHOLE:
        return fields
    return {name: dataset[()] for name, dataset in fields.items()}


def _point_data(fields, row: int | None) -> dict:
    """Point data of one row of ``fields`` (an h5py group, or a mapping of arrays by name), or
    of all of it (row None: the final fields)."""
    data = {}
    for name, dataset in fields.items():
        if name in ("cycle", "master_wear_depth"):  # the master's own field lives on its own surface
            continue
        value = dataset[()] if row is None else dataset[row]
        if name == "wear_depth":
            data["wear_depth_total"] = value.sum(axis=0)
            for body, depth in enumerate(value):
                data[f"wear_depth_body{body}"] = depth
        elif name == "shear":
            data["shear_magnitude"] = np.linalg.norm(value.reshape(value.shape[0], -1), axis=1)
        else:
            data[name] = np.asarray(value, dtype=float)
    return data


def _surface(file: h5py.File, group: str = "points") -> tuple[np.ndarray, list]:
    """Points (n, 3) mm and cells of the contact surface of a results file (``group`` points),
    or of the master surface (master_surface)."""
    points = file[f"{group}/coordinates"][()]
    facets = file[f"{group}/facets"][()]
    if points.shape[1] == 2:
        points = np.column_stack([points, np.zeros(len(points))])
    return points, [(CELL_TYPES[facets.shape[1]], facets)]


def _write_series(out_path: Path, points, cells, steps) -> Path:
    # meshio 5.3 writes the heavy-data .h5 into the current directory (it keeps only the
    # file stem), so write from inside the target folder.
    previous = Path.cwd()
    os.chdir(out_path.resolve().parent)
    try:
        with meshio.xdmf.TimeSeriesWriter(out_path.name) as writer:
            writer.write_points_cells(points, cells)
            for time_value, point_data in steps:
                writer.write_data(time_value, point_data=point_data)
    finally:
        os.chdir(previous)
    return out_path


def write_interface_series(results_path: str | Path, out_path: str | Path) -> Path:
    """Write ``out_path`` (.xdmf, with its .h5 beside it) from a results file."""
    with h5py.File(results_path, "r") as file:
        points, cells = _surface(file)
        fields = _loaded(file["cycles/fields"])
        cycles = file["cycles/cycle"][()]
        equivalent = dict(zip(cycles, file["cycles/equivalent_cycles"][()]))
        steps = [(float(equivalent.get(cycle, cycle)), _point_data(fields, row))
                 for row, cycle in enumerate(fields["cycle"][()])]
    return _write_series(Path(out_path), points, cells, steps)


def write_increment_series(results_path: str | Path, out_path: str | Path) -> Path:
    """Write ``out_path`` (.xdmf) from the ``/increment_fields`` of a results file: one time step
    per written increment at (cycle − 1) + fraction."""
    with h5py.File(results_path, "r") as file:
        points, cells = _surface(file)
        group = file["increment_fields"]
        fields = _loaded(group["fields"])
        steps = [(float(time), _point_data(fields, row)) for row, time in enumerate(group["time"][()])]
    return _write_series(Path(out_path), points, cells, steps)


def write_final_vtu(results_path: str | Path, out_path: str | Path) -> Path:
    """The final interface fields as one .vtu file."""
    with h5py.File(results_path, "r") as file:
        points, cells = _surface(file)
        mesh = meshio.Mesh(points, cells, point_data=_point_data(file["final"], None))
    mesh.write(out_path)
    return Path(out_path)


def write_master_final_vtu(results_path: str | Path, out_path: str | Path) -> Path | None:
    """The master body's own final wear depth (``master_wear_depth``, mm) on the master surface as
    one .vtu file; None (nothing written) for a run whose master's wear has no field of its own
    (small sliding: row 1 of ``wear_depth`` in ``interface_final.vtu`` holds it)."""
    with h5py.File(results_path, "r") as file:
        if "final/master_wear_depth" not in file:
            return None
        points, cells = _surface(file, "master_surface")
        depth = file["final/master_wear_depth"][()]
    meshio.Mesh(points, cells, point_data={"master_wear_depth": depth}).write(out_path)
    return Path(out_path)
