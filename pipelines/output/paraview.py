"""Interface fields as an XDMF time series (meshio) that opens in ParaView.

The contact surface is written as its facets (lines in 2D, quadrilaterals or triangles in
3D) with one time step per recorded cycle; time is the equivalent cycle number.
"""

from __future__ import annotations

import os
from pathlib import Path

import h5py
import meshio
import numpy as np

CELL_TYPES = {2: "line", 3: "triangle", 4: "quad"}


def _point_data(fields: h5py.Group, row: int | None) -> dict:
    data = {}
    for name, dataset in fields.items():
        if name == "cycle":
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


def write_interface_series(results_path: str | Path, out_path: str | Path) -> Path:
    """Write ``out_path`` (.xdmf, with its .h5 beside it) from a results file."""
    out_path = Path(out_path)
    with h5py.File(results_path, "r") as file:
        points = file["points/coordinates"][()]
        facets = file["points/facets"][()]
        if points.shape[1] == 2:
            points = np.column_stack([points, np.zeros(len(points))])
        cells = [(CELL_TYPES[facets.shape[1]], facets)]
        fields = file["cycles/fields"]
        cycles = file["cycles/cycle"][()]
        equivalent = dict(zip(cycles, file["cycles/equivalent_cycles"][()]))
        steps = [(float(equivalent.get(cycle, cycle)), _point_data(fields, row))
                 for row, cycle in enumerate(fields["cycle"][()])]
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


def write_final_vtu(results_path: str | Path, out_path: str | Path) -> Path:
    """The final interface fields as one .vtu file."""
    with h5py.File(results_path, "r") as file:
        points = file["points/coordinates"][()]
        facets = file["points/facets"][()]
        if points.shape[1] == 2:
            points = np.column_stack([points, np.zeros(len(points))])
        mesh = meshio.Mesh(points, [(CELL_TYPES[facets.shape[1]], facets)],
                           point_data=_point_data(file["final"], None))
    mesh.write(out_path)
    return Path(out_path)
