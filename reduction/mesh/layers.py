"""Hexahedral blocks built layer by layer along y, coarsening 3:1 away from a fine face.

A tensor grid keeps its fine lines through the whole body. Here the x and z lines of a layer
may be coarser than those of the layer below: a transition layer joins three fine cells to
one coarse cell with four hexahedra (the 2D template below, extruded along the other
direction), so the mesh stays conforming (every face shared whole by its two cells, no
hanging nodes)::

    t0 ─────────── t1        bottom b0..b3: the three fine cells' lines (y = ya)
    │  ╲   Q4    ╱  │        mid m1, m2 at the two inner lines, half-way up (y = ym)
    │ Q1 m1 ─── m2 Q3│       top t0, t1: the coarse cell (y = yb)
    │    │  Q2  │   │
    b0 ─ b1 ─── b2 ─ b3

Cells that do not group by three (a stretch between two break lines whose count is not a
multiple of 3, graded cells) go through a transition layer as single hexahedra. All lengths mm.
"""

from __future__ import annotations

from itertools import pairwise

import numpy as np
import skfem

# skfem's hexahedron corner order, as (i, j, k) offsets along (x, y, z) (MeshHex.init_tensor)
_CORNERS = np.array([(0, 0, 0), (0, 1, 0), (1, 0, 0), (0, 0, 1), (1, 1, 0), (0, 1, 1), (1, 0, 1), (1, 1, 1)])


def coarsen(lines: np.ndarray, keep, fine) -> tuple[np.ndarray, list[np.ndarray]]:
    """Join the cells of ``lines`` three by three where they are uniform, inside a fine
    interval (one of ``fine``, each (low, high)) and between two lines of ``keep`` (breaks
    that must stay: ends, hole edges).

    Returns the coarse lines and, per coarse cell, the fine lines it spans (2 or 4 values).
    Only the widest uniform run of each stretch is joined (a second call joins the coarse
    cells of the first); its cells left over (count mod 3) stay single, one at each end.
    """
    keep = np.asarray(sorted(keep))
    is_kept = np.any(np.abs(lines[:, None] - keep[None, :]) < 1e-9, axis=1)
    is_kept[[0, -1]] = True
    kept = np.flatnonzero(is_kept)
    cells: list[np.ndarray] = []
    for a, b in pairwise(kept):
        stretch = lines[a:b + 1]
        inside = any(low - 1e-9 <= stretch[0] and stretch[-1] <= high + 1e-9 for low, high in fine)
        widths = np.diff(stretch)
        uniform = np.abs(widths - widths.max()) <= 1e-9 * widths.max()
        grouped = np.zeros(widths.size, dtype=bool)
        if inside and uniform.sum() >= 3:
            run = np.flatnonzero(uniform)
            start = run[0] + (run.size % 3) // 2
            if np.all(uniform[run[0]:run[-1] + 1]):  # one contiguous run of the widest cells
                grouped[start:start + 3 * (run.size // 3)] = True
        k = 0
        while k < widths.size:
            if grouped[k]:
                cells.append(stretch[k:k + 4])
                k += 3
            else:
                cells.append(stretch[k:k + 2])
                k += 1
    coarse = np.array([cell[0] for cell in cells] + [lines[-1]])
    return coarse, cells


def _template(lo: np.ndarray, ya: float, yb: float) -> list[np.ndarray]:
    """The 2D cells (each (2, 2, 2): [i][j] → (s, y)) between fine lines ``lo`` (2 or 4 values of
    the transition direction s) at y = ya and its coarse cell at y = yb."""
    if lo.size == 2:
        return [np.array([[[lo[0], ya], [lo[0], yb]], [[lo[1], ya], [lo[1], yb]]])]
    ym = 0.5 * (ya + yb)
    s0, s1, s2, s3 = lo
    quads = [((s0, ya), (s0, yb), (s1, ya), (s1, ym)),   # Q1: (0,0), (0,1), (1,0), (1,1)
             ((s1, ya), (s1, ym), (s2, ya), (s2, ym)),   # Q2
             ((s2, ya), (s2, ym), (s3, ya), (s3, yb)),   # Q3
             ((s1, ym), (s0, yb), (s2, ym), (s3, yb))]   # Q4
    return [np.array(q, dtype=float).reshape(2, 2, 2) for q in quads]


def _extrude(quads: list[np.ndarray], across: np.ndarray, direction: str) -> np.ndarray:
    """Hexahedra (n, 8, 3) of the 2D cells ``quads`` (in the (s, y) plane, s = x or z by
    ``direction``) extruded over every cell of the lines ``across`` (the other direction)."""
    hexes = []
    for quad in quads:
        for c0, c1 in pairwise(across):
            cube = np.empty((2, 2, 2, 3))  # [i][j][k] → (x, y, z)
            for t, c in enumerate((c0, c1)):
                if direction == "x":  # s = x (index i), extruded along z (index k)
                    cube[:, :, t, 0] = quad[:, :, 0]
                    cube[:, :, t, 1] = quad[:, :, 1]
                    cube[:, :, t, 2] = c
                else:  # s = z (index k), extruded along x (index i)
                    cube[t, :, :, 0] = c
                    cube[t, :, :, 1] = quad[:, :, 1].T
                    cube[t, :, :, 2] = quad[:, :, 0].T
            hexes.append(cube[_CORNERS[:, 0], _CORNERS[:, 1], _CORNERS[:, 2]])
    return np.array(hexes)


def _regular(x: np.ndarray, z: np.ndarray, ya: float, yb: float) -> np.ndarray:
    """Hexahedra (n, 8, 3) of the tensor layer x × [ya, yb] × z."""
    i, k = np.meshgrid(np.arange(x.size - 1), np.arange(z.size - 1), indexing="ij")
    i, k = i.ravel(), k.ravel()
    corners = np.empty((i.size, 8, 3))
    corners[:, :, 0] = x[i[:, None] + _CORNERS[None, :, 0]]
    corners[:, :, 1] = np.where(_CORNERS[:, 1] == 0, ya, yb)[None, :]
    corners[:, :, 2] = z[k[:, None] + _CORNERS[None, :, 2]]
    return corners


def layered_block(x: np.ndarray, z: np.ndarray, plan, keep_x, keep_z, fine_x, fine_z) -> skfem.MeshHex:
    """Hexahedral mesh of the layers of ``plan`` (each (kind, ya, yb), ya < yb, in order along
    y): kind "regular" keeps the current x and z lines, "x" and "z" coarsen that direction's
    lines (:func:`coarsen` with its breaks ``keep_*`` and fine intervals ``fine_*``) from the
    layer's bottom to its top. ``x``, ``z``: the lines of the first layer (mm)."""
    hexes = []
    for kind, ya, yb in plan:
        if kind == "regular":
            hexes.append(_regular(x, z, ya, yb))
        elif kind == "x":
            x, cells = coarsen(x, keep_x, fine_x)
            hexes.extend(_extrude(_template(cell, ya, yb), z, "x") for cell in cells)
        else:
            z, cells = coarsen(z, keep_z, fine_z)
            hexes.extend(_extrude(_template(cell, ya, yb), x, "z") for cell in cells)
    corners = np.concatenate(hexes)
    points, index = np.unique(np.round(corners.reshape(-1, 3), 9), axis=0, return_inverse=True)
    return skfem.MeshHex(np.ascontiguousarray(points.T), np.ascontiguousarray(index.reshape(-1, 8).T))
