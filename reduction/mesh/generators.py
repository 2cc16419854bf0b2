"""Generators for the shipped, documented geometries (structured, graded meshes).

Every generator returns a scikit-fem mesh in mm. Grading puts the contact-zone element size
where the contact is and grows geometrically away from it, so that closed forms (Hertz,
Cattaneo-Mindlin) are resolved without paying for a uniformly fine body.

:func:`least_nodes` counts, before any meshing, the nodes that the fine contact zone of a
generated mesh alone would have: a scene whose mesh would exceed :data:`MAX_GENERATED_NODES`
is refused (a contact size typed in metres, 0.01 for 10 mm, asks for hundreds of millions).
"""

from __future__ import annotations

from itertools import pairwise

import numpy as np
import skfem

from reduction.errors import InputError
from reduction.mesh.layers import layered_block


def graded_coordinates(fine_half_width: float, fine_size: float, total_half_width: float,
                       growth: float = 1.25) -> np.ndarray:
    """Symmetric 1D coordinates: uniform ``fine_size`` on |x| ≤ fine_half_width, then growing.

    All lengths in mm. The last interval is stretched to end exactly at total_half_width.
    """
    if not 0 < fine_size <= fine_half_width < total_half_width:
        raise InputError(f"a graded mesh needs 0 < fine size <= fine half-width < total half-width, got fine "
                         f"size {fine_size:g}, fine half-width {fine_half_width:g} and total half-width "
                         f"{total_half_width:g} mm (contact_size, contact_half_width and the block's half-width, "
                         f"depth or height)")
    n_fine = max(1, int(round(fine_half_width / fine_size)))
    inner = np.linspace(0.0, fine_half_width, n_fine + 1)
    outer, x, h = [], fine_half_width, fine_size
    while x < total_half_width - 1e-12:
        h *= growth
        x = min(x + h, total_half_width)
        if total_half_width - x < 0.5 * h:
            x = total_half_width
        outer.append(x)
    half = np.concatenate([inner, outer])
    return np.concatenate([-half[:0:-1], half])


def one_sided_coordinates(fine_depth: float, fine_size: float, total_depth: float,
                          growth: float = 1.25) -> np.ndarray:
    """Coordinates 0 … total_depth, uniform ``fine_size`` up to fine_depth, then growing (mm)."""
    full = graded_coordinates(fine_depth, fine_size, total_depth, growth)
    return full[full >= 0.0]


def _check_contact_zone(contact_size: float, contact_half_width: float, **outer: float) -> None:
    """A 2D block's graded zone, elements of ``contact_size`` over ±``contact_half_width``, lies
    inside the block (``outer``: its half-width and its depth or height), said by the keys' names."""
    if contact_size > contact_half_width:
        raise InputError(f"contact_size ({contact_size:g} mm) must not exceed contact_half_width "
                         f"({contact_half_width:g} mm): the contact zone ±contact_half_width is meshed with "
                         "elements of contact_size")
    for key, length in outer.items():
        if contact_half_width >= length:
            raise InputError(f"contact_half_width ({contact_half_width:g} mm) must be smaller than {key} "
                             f"({length:g} mm): the refined contact zone lies inside the block")


def plane_block(half_width: float, depth: float, contact_half_width: float, contact_size: float,
                growth: float = 1.25) -> skfem.MeshQuad:
    """2D rectangle x ∈ [−half_width, half_width], y ∈ [−depth, 0]; contact face at y = 0."""
    _check_contact_zone(contact_size, contact_half_width, half_width=half_width, depth=depth)
    x = graded_coordinates(contact_half_width, contact_size, half_width, growth)
    y = -one_sided_coordinates(contact_half_width, contact_size, depth, growth)[::-1]
    return skfem.MeshQuad.init_tensor(x, y)


def cylinder_block(radius: float, half_width: float, height: float, contact_half_width: float,
                   contact_size: float, growth: float = 1.25) -> skfem.MeshQuad:
    """2D lower part of a cylinder of ``radius`` resting on y = 0, cut flat at y = height.

    The bottom follows y = R − √(R² − x²); the top face is where a reference point is coupled.
    """
    if half_width >= radius:
        metres = f"; if the radius was meant in metres, write {1e3 * radius:g}" if 1e3 * radius > half_width else ""
        raise InputError(f"half_width ({half_width:g} mm) must be smaller than radius ({radius:g} mm): the block is "
                         f"the lower part of the cylinder, narrower than it{metres}")
    _check_contact_zone(contact_size, contact_half_width, half_width=half_width, height=height)
    x = graded_coordinates(contact_half_width, contact_size, half_width, growth)
    eta = one_sided_coordinates(contact_half_width, contact_size, height, growth) / height
    mesh = skfem.MeshQuad.init_tensor(x, eta)
    px, pe = mesh.p
    profile = radius - np.sqrt(radius ** 2 - px ** 2)
    return skfem.MeshQuad(np.vstack([px, profile + pe * (height - profile)]), mesh.t)


def flat_block(size_x: float, size_y: float, height: float, n_x: int, n_y: int, n_z: int,
               z0: float = 0.0, z_growth: float = 1.0, top_fine: bool = False) -> skfem.MeshHex:
    """3D box [−sx/2, sx/2]×[−sy/2, sy/2]×[z0, z0+height] of hexahedra, n per direction.

    z_growth > 1 grades the layers away from the face at z0 (or from the top with top_fine).
    """
    x = np.linspace(-0.5 * size_x, 0.5 * size_x, n_x + 1)
    y = np.linspace(-0.5 * size_y, 0.5 * size_y, n_y + 1)
    steps = z_growth ** np.arange(n_z)
    z = np.concatenate([[0.0], np.cumsum(steps)]) / steps.sum() * height
    if top_fine:
        z = height - z[::-1]
    return skfem.MeshHex.init_tensor(x, y, z0 + z)


def graded_flat_block(size_x: float, size_y: float, height: float, n_x: int, n_y: int,
                      z0: float = 0.0, top_fine: bool = False,
                      coarse_size: float | None = None) -> skfem.MeshHex:
    """3D box [−sx/2, sx/2]×[−sy/2, sy/2]×[z0, z0+height] of hexahedra, fine on one face and
    coarsening in plane with depth (an engineer's contact mesh, not a tensor grid).

    The face at z0 (at z0 + height with ``top_fine``) has the n_x × n_y cells of
    :func:`flat_block` (its nodes are bit for bit those of the same face of ``flat_block``),
    and so have the two layers under it (each one cell size thick); then rounds of an x and a
    y transition (:mod:`reduction.mesh.layers`: 3:1, conforming, no hanging nodes), each
    2·(cell size) thick, triple the in-plane cell size while it stays ≤ ``coarse_size`` (mm;
    no limit by default) and the rounds fit in the height; layers growing ×1.3 fill the rest
    of the height. Cells that do not group by three stay single (at the ends of a row). When
    no round fits, the tensor grid of the fine face is kept through the height. Lengths mm.
    """
    hx, hy = size_x / n_x, size_y / n_y
    x = np.linspace(-0.5 * size_x, 0.5 * size_x, n_x + 1)
    y = np.linspace(-0.5 * size_y, 0.5 * size_y, n_y + 1)
    coarse = np.inf if coarse_size is None else max(float(coarse_size), hx, hy)
    cell = max(hx, hy)
    transitions = _transition_plan(cell, coarse, height)
    if transitions is None:
        plan, depth = [("regular", 0.0, cell), ("regular", cell, 2.0 * cell)], 2.0 * cell
        if depth > height - 1e-9:
            plan, depth = [("regular", 0.0, height)], height
    else:
        plan, depth, cell = transitions
    plan += _graded_layers(depth, [height], cell, coarse)
    keep_x, keep_y = x[[0, -1]], y[[0, -1]]
    layered = layered_block(x, y, plan, keep_x, keep_y, [tuple(keep_x)], [tuple(keep_y)])
    # layers.py rounds its corners to 1e-9 mm; every in-plane coordinate lies on a fine line
    # and every depth on a layer's bottom, middle or top: snap them back to the exact values.
    levels = np.unique([v for _, a, b in plan for v in (a, 0.5 * (a + b), b)])
    px, depths, py = (_snap(values, lines) for values, lines in zip(layered.p, (x, levels, y)))
    # layered (x, depth, y) → (x, y, z): one axis swap, a mirror; with top_fine a second
    # mirror (z = z0 + height − depth) restores the orientation.
    z = z0 + height - depths if top_fine else z0 + depths
    t = layered.t if top_fine else layered.t[[1, 0, 4, 5, 2, 3, 7, 6]]  # swap the two depth faces
    return skfem.MeshHex(np.vstack([px, py, z]), np.ascontiguousarray(t))


def _snap(values: np.ndarray, lines: np.ndarray) -> np.ndarray:
    """Each of ``values`` replaced by the nearest of the sorted ``lines`` (mm)."""
    right = np.clip(np.searchsorted(lines, values), 1, lines.size - 1)
    left = right - 1
    return np.where(np.abs(values - lines[left]) <= np.abs(lines[right] - values), lines[left], lines[right])


def _plan_with_hole(length: float, width: float, hole_x: float, hole_radius: float, size: float,
                    fine_from: float, fine_to: float, coarse_size: float, block_half: float):
    """2D quads of the rectangle [0, length] × [−width/2, width/2] with a round hole.

    An O-grid fills the square block of half-size ``block_half`` around the hole; a tensor
    grid (uniform ``size`` on [fine_from, fine_to], growing to ``coarse_size``) fills the rest.
    Returns node coordinates (n, 2) and CCW quads (m, 4).
    """
    half_cells = width / (2.0 * size)
    block_cells = block_half / size
    if abs(half_cells - round(half_cells)) > 1e-9 or abs(block_cells - round(block_cells)) > 1e-9:
        raise InputError(f"beam mesh: half the width ({width / 2:g} mm) and the hole block half-size "
                         f"({block_half:g} mm) must be multiples of the contact element size ({size:g} mm)")
    if not hole_radius < block_half <= width / 2:
        raise InputError(f"beam mesh: the hole (radius {hole_radius:g} mm) must fit inside its block (half-size "
                         f"{block_half:g} mm), and the block inside the width ({width:g} mm)")
    n_fine = int(round((fine_to - fine_from) / size))
    fine = hole_x + size * np.arange(int(round((fine_from - hole_x) / size)),
                                     int(round((fine_from - hole_x) / size)) + n_fine + 1)
    xs = np.unique(np.round(np.concatenate([_graded_points(fine[0], 0.0, size, coarse_size)[::-1], fine,
                                            _graded_points(fine[-1], length, size, coarse_size)]), 9))
    ys = np.linspace(-width / 2, width / 2, 2 * int(round(half_cells)) + 1)
    grid_nodes, grid_quads = _grid_outside_block(xs, ys, hole_x, block_half)
    ring_nodes, ring_quads = _o_grid(hole_x, hole_radius, block_half, block_cells, size, grid_nodes.shape[0])
    return _merge_coincident([grid_nodes, ring_nodes], [grid_quads, *ring_quads])


def _graded_points(start: float, end: float, step: float, coarse_size: float) -> list[float]:
    """Points from ``start`` (excluded) to ``end`` (included), spacing growing ×1.3 up to coarse_size."""
    points, x, h = [], start, step
    while abs(end - x) > 1e-9:
        h = min(h * 1.3, coarse_size)
        x = x + np.sign(end - x) * min(h, abs(end - x))
        if abs(end - x) < 0.5 * h:
            x = end
        points.append(x)
    return points


def _grid_outside_block(xs: np.ndarray, ys: np.ndarray, hole_x: float, block_half: float):
    """Tensor grid on xs × ys: all its nodes (n, 2) and the quads (m, 4) outside the hole block."""
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    nodes = np.column_stack([gx.ravel(), gy.ravel()])
    index = np.arange(gx.size).reshape(gx.shape)
    cx = 0.5 * (xs[:-1, None] + xs[1:, None]) + 0 * ys[None, :-1]
    cy = 0.5 * (ys[None, :-1] + ys[None, 1:]) + 0 * xs[:-1, None]
    keep = ~((np.abs(cx - hole_x) < block_half) & (np.abs(cy) < block_half))
    quads = np.stack([index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]], axis=-1)[keep]
    return nodes, quads


def _o_grid(hole_x: float, hole_radius: float, block_half: float, block_cells: float, size: float,
            offset: int):
    """O-grid from the hole's circle to the block's square: nodes (n, 2) numbered from
    ``offset``, and one (n_perimeter, 4) quad array per ring."""
    n_side = int(round(2 * block_cells))
    edge = np.linspace(-block_half, block_half, n_side + 1)[:-1]
    square = np.concatenate([np.column_stack([edge, -block_half + 0 * edge]),
                             np.column_stack([block_half + 0 * edge, edge]),
                             np.column_stack([-edge, block_half + 0 * edge]),
                             np.column_stack([-block_half + 0 * edge, -edge])])
    angle = np.arctan2(square[:, 1], square[:, 0])
    circle = hole_radius * np.column_stack([np.cos(angle), np.sin(angle)])
    n_rings = max(2, int(np.ceil((block_half - hole_radius) / size)))
    rho = np.linspace(0.0, 1.0, n_rings + 1)
    ring_nodes = circle[None] + rho[:, None, None] * (square - circle)[None]  # (rings, perimeter, 2)
    nodes = ring_nodes.reshape(-1, 2) + np.array([hole_x, 0.0])
    n_perimeter = square.shape[0]
    k = np.arange(n_perimeter)
    ring_index = offset + np.arange(ring_nodes.shape[0] * n_perimeter).reshape(ring_nodes.shape[:2])
    quads = []
    for layer in range(n_rings):
        inner, outer = ring_index[layer], ring_index[layer + 1]
        quads.append(np.stack([inner[k], outer[k], outer[(k + 1) % n_perimeter],
                               inner[(k + 1) % n_perimeter]], axis=-1))
    return nodes, quads


def _merge_coincident(nodes: list[np.ndarray], quads: list[np.ndarray]):
    """Merge nodes that coincide to 1e-9 mm and drop nodes no quad uses; returns (points, quads)."""
    points = np.concatenate(nodes)
    unique, inverse = np.unique(np.round(points, 9), axis=0, return_inverse=True)
    cells = inverse.ravel()[np.concatenate(quads)]
    used, renumbered = np.unique(cells, return_inverse=True)  # drop grid nodes inside the hole block
    return unique[used], renumbered.reshape(cells.shape)


def beam_with_hole(length: float, width: float, thickness: float, hole_x: float, hole_radius: float,
                   contact_size: float, pad_half_length: float, side: str, gap: float = 0.5,
                   coarse_size: float = 4.0, layers: int = 6, block_half: float | None = None) -> skfem.MeshHex:
    """3D hexahedral beam [0, length] × [−width/2, width/2] with a vertical bolt hole at x = hole_x.

    side = "lower": the beam occupies z ∈ [−thickness, 0]; "upper": z ∈ [0, thickness]. The face at
    z = 0 touches the other beam only on the pad |x − hole_x| ≤ pad_half_length; elsewhere it is
    recessed by ``gap`` (mm), so the bolted pad is the contact interface.
    """
    if side not in ("lower", "upper"):
        raise InputError(f"beam side must be 'lower' or 'upper', got {side!r}")
    block_half = block_half or contact_size * np.ceil((hole_radius + 2.5 * contact_size) / contact_size)
    plan, quads = _plan_with_hole(length, width, hole_x, hole_radius, contact_size,
                                  hole_x - pad_half_length - 2 * contact_size,
                                  hole_x + pad_half_length + 2 * contact_size, coarse_size, block_half)
    depth = np.linspace(0.0, 1.0, layers + 1)  # 0 at the contact face, 1 at the outer face
    n_plan = plan.shape[0]
    x = np.tile(plan[:, 0], layers + 1)
    y = np.tile(plan[:, 1], layers + 1)
    s = np.repeat(depth, n_plan)
    outside = np.clip((np.abs(x - hole_x) - pad_half_length) / contact_size, 0.0, 1.0)
    face = outside * gap
    z = face + s * (thickness - face)
    if side == "lower":
        z = -z
    a, b, c, d = quads.T
    hexes = []
    for layer in range(layers):
        lo, hi = layer * n_plan, (layer + 1) * n_plan
        hexes.append(np.stack([a + lo, d + lo, b + lo, a + hi, c + lo, d + hi, b + hi, c + hi]))
    t = np.concatenate(hexes, axis=1)
    if side == "lower":
        t = t[[3, 5, 6, 0, 7, 1, 2, 4]]  # mirror in z: swap the two layers to keep volumes positive
    return skfem.MeshHex(np.vstack([x, y, z]), t)


def grid_lines(start: float, end: float, breaks, fine, fine_size: float,
               coarse_size: float, growth: float = 1.3) -> np.ndarray:
    """Sorted 1D grid coordinates on [start, end] (mm) through every point of ``breaks``.

    ``fine``: one interval (low, high) or a list of them. Uniform spacing of at most
    ``fine_size`` on each fine interval; elsewhere the spacing grows by ``growth`` away from the
    fine intervals (from both sides between two of them) up to ``coarse_size``. Two meshes built
    with the same breaks and fine intervals share their lines there (matching faces).
    """
    intervals = [fine] if np.isscalar(fine[0]) else list(fine)
    intervals = [(max(start, low), min(end, high)) for low, high in intervals]
    ends = [value for interval in intervals for value in interval]
    points = np.unique(np.round(np.concatenate([[start, end], ends,
                                                [b for b in breaks if start <= b <= end]]), 9))
    lines = [points[:1]]
    for low, high in zip(points[:-1], points[1:]):
        length = high - low
        if any(a - 1e-9 <= low and high <= b + 1e-9 for a, b in intervals):
            n = int(np.ceil(length / fine_size - 1e-9))
            lines.append(np.linspace(low, high, n + 1)[1:])
            continue
        fine_left = any(b <= low + 1e-9 for _, b in intervals)
        fine_right = any(a >= high - 1e-9 for a, _ in intervals)
        sizes = _graded_sizes(length, fine_size, coarse_size, growth, both=fine_left and fine_right)
        if fine_right and not fine_left:  # finest next to the fine interval on the right
            sizes = sizes[::-1]
        graded = low + np.cumsum(sizes)
        graded[-1] = high  # exactly on the break, not a rounding off it
        lines.append(graded)
    return np.concatenate(lines)


def _graded_sizes(length: float, fine_size: float, coarse_size: float, growth: float,
                  both: bool = False) -> np.ndarray:
    """Cell sizes (mm) filling ``length``: fine_size·growth^k capped at coarse_size, growing from
    the left end (or from both ends towards the middle), scaled to sum to ``length``."""
    left, right, total, h = [], [], 0.0, fine_size
    while total < length - 1e-9:
        h = min(h * growth, coarse_size)
        left.append(h)
        total += h
        if both and total < length - 1e-9:
            right.append(h)
            total += h
    return np.asarray(left + right[::-1]) * length / total


def cells_inside(mesh, boxes) -> np.ndarray:
    """Boolean mask of the cells of ``mesh`` whose centroid lies strictly inside one of ``boxes``
    (each ((x0, y0, z0), (x1, y1, z1)) in mm)."""
    centroid = mesh.p[:, mesh.t].mean(axis=1).T
    mask = np.zeros(len(centroid), dtype=bool)
    for low, high in boxes:
        mask |= np.all((centroid > np.asarray(low)) & (centroid < np.asarray(high)), axis=1)
    return mask


def union_of_boxes(x: np.ndarray, y: np.ndarray, z: np.ndarray, solids, voids=()) -> skfem.MeshHex:
    """Hexahedral mesh of the tensor grid x × y × z restricted to the union of ``solids`` minus
    ``voids`` (each box ((x0, y0, z0), (x1, y1, z1)) in mm; box faces should lie on grid lines)."""
    mesh = skfem.MeshHex.init_tensor(x, y, z)
    keep = cells_inside(mesh, solids) & ~cells_inside(mesh, voids)
    if not keep.any():
        raise InputError("the boxes of the mesh contain no grid cell")
    return mesh.remove_elements(np.flatnonzero(~keep))


def counterweight_solids(width: float, height: float, thickness: float, hub_width: float, hub_height: float):
    """The generic counterweight's shape in its own frame, as two boxes (mm): the hub
    |x| ≤ hub_width/2, 0 ≤ y ≤ hub_height under the contact face y = 0, and the wing plate
    |x| ≤ width/2, hub_height ≤ y ≤ height; thickness along z. The one definition of the CW's
    shape: the multibody mesh (mbs.counterweight) and the contact mesh (:func:`counterweight_block`)
    are both cut from it."""
    half_hub, half_t = 0.5 * hub_width, 0.5 * thickness
    return [((-half_hub, 0.0, -half_t), (half_hub, hub_height, half_t)),
            ((-0.5 * width, hub_height, -half_t), (0.5 * width, height, half_t))]


def _far_size(contact_size: float, coarse_size: float | None) -> float:
    """Element size (mm) far from the contact: ``coarse_size``, by default 4 × contact_size but
    at least 40 mm (the shipped 10 mm meshes unchanged; a fine mesh grades to 40 mm, instead of
    refining the whole body)."""
    if coarse_size is not None:
        return max(float(coarse_size), contact_size)
    return max(4.0 * contact_size, 40.0)


def _hub_lines(width: float, hub_width: float, screw_x: float, hole_half_size: float,
               relief_half_width: float, contact_size: float, coarse: float):
    """x lines of the CW–web joint: fine on the hub face, or only on its two pads
    relief_half_width ≤ |x| ≤ hub_width/2 when the central relief is given (> 0); with the
    breaks they keep and their fine intervals: (lines, breaks, fine intervals)."""
    half_hub = 0.5 * hub_width
    if not 0.0 <= relief_half_width < screw_x - hole_half_size:
        raise InputError(f"relief_half_width ({relief_half_width:g} mm) must be >= 0 and leave the screw holes on "
                         f"the pads (relief_half_width < screw_x − hole_half_size = {screw_x - hole_half_size:g} mm)")
    holes_x = [s * screw_x + d * hole_half_size for s in (-1, 1) for d in (-1, 1)]
    fine = [(-half_hub, half_hub)]
    if relief_half_width > 0:
        fine = [(-half_hub, -relief_half_width), (relief_half_width, half_hub)]
    breaks = holes_x + [-half_hub, half_hub, -0.5 * width, 0.5 * width] + [end for interval in fine for end in interval]
    return grid_lines(-0.5 * width, 0.5 * width, holes_x + [-half_hub, half_hub], fine, contact_size, coarse), \
        breaks, fine


def _transition_plan(size: float, coarse: float, room: float):
    """Layers from the contact face (depth 0 … ``room`` mm): two of ``size``, then rounds of an x
    and a z transition (:mod:`reduction.mesh.layers`), each 2·(cell size) thick, tripling the cell
    size while it stays ≤ ``coarse`` and the rounds fit in ``room``. Returns (plan, depth
    reached, cell size reached), or None when no round fits or the far size is at most 4 × the
    contact size (the tensor grid is kept: the shipped 10 mm meshes are unchanged)."""
    if coarse <= 4.0 * size + 1e-9:
        return None
    plan, depth, cell = [("regular", 0.0, size), ("regular", size, 2.0 * size)], 2.0 * size, size
    while 3.0 * cell <= coarse + 1e-9 and depth + 4.0 * cell <= room + 1e-9:
        plan += [("x", depth, depth + 2.0 * cell), ("z", depth + 2.0 * cell, depth + 4.0 * cell)]
        depth, cell = depth + 4.0 * cell, 3.0 * cell
    return None if len(plan) == 2 else (plan, depth, cell)


def _graded_layers(depth: float, stops, cell: float, coarse: float) -> list:
    """Regular layers from ``depth`` through every depth of ``stops`` (ascending, the last the
    block's end), their thickness growing ×1.3 from ``cell`` up to ``coarse`` in each stretch."""
    layers = []
    for stop in stops:
        if stop <= depth + 1e-9:
            continue
        edges = depth + np.concatenate([[0.0], np.cumsum(_graded_sizes(stop - depth, cell, coarse, 1.3))])
        edges[-1] = stop
        layers += [("regular", a, b) for a, b in pairwise(edges)]
        depth = stop
    return layers


def _layered(x, z, plan, keep_x, keep_z, fine_x, fine_z, solids, voids, mirror: bool) -> skfem.MeshHex:
    """The layered mesh (y = depth, or y = −depth with ``mirror``) cut to the solids minus voids."""
    mesh = layered_block(x, z, plan, keep_x, keep_z, fine_x, fine_z)
    if mirror:  # y → −y, and the corner order with it (swap the two y faces) to keep volumes positive
        mesh = skfem.MeshHex(mesh.p * np.array([[1.0], [-1.0], [1.0]]), np.ascontiguousarray(mesh.t[[1, 0, 4, 5, 2, 3, 7, 6]]))
    keep = cells_inside(mesh, solids) & ~cells_inside(mesh, voids)
    return mesh.remove_elements(np.flatnonzero(~keep))


def counterweight_block(width: float, height: float, thickness: float, hub_width: float, hub_height: float,
                        screw_x: float, hole_half_size: float, contact_size: float,
                        coarse_size: float | None = None, relief_half_width: float = 0.0) -> skfem.MeshHex:
    """Generic counterweight in its own frame (the multibody model's, mbs.counterweight): contact
    face y = 0 of the hub |x| ≤ hub_width/2, wing plate |x| ≤ width/2 over hub_height ≤ y ≤
    height, thickness along z; square through holes (half-size ``hole_half_size``) for two
    screws at x = ±screw_x. Element size ``contact_size`` on the hub face (on its pads
    |x| ≥ relief_half_width when that is > 0) and in the two layers under it, graded to
    ``coarse_size`` (:func:`_far_size`) away from them: in y by growing layers, in x and z by
    3:1 transition layers in the hub (:mod:`reduction.mesh.layers`, conforming hexahedra, no
    hanging nodes) when the far size exceeds 4 × contact_size; otherwise a tensor grid (the
    shipped 10 mm mesh). All lengths mm.
    """
    if not (0 < hub_width < width and 0 < hub_height < height and
            hole_half_size < screw_x < 0.5 * hub_width - hole_half_size and 2 * hole_half_size < thickness):
        raise InputError(f"counterweight_block: needs hub_width < width ({hub_width:g}, {width:g} mm), hub_height < "
                         f"height ({hub_height:g}, {height:g} mm), the screw holes inside the hub face (hole_half_size "
                         f"< screw_x < hub_width/2 − hole_half_size: {hole_half_size:g} < {screw_x:g} < "
                         f"{0.5 * hub_width - hole_half_size:g} mm) and 2 × hole_half_size < thickness "
                         f"({2 * hole_half_size:g}, {thickness:g} mm)")
    coarse = _far_size(contact_size, coarse_size)
    half_t = 0.5 * thickness
    x, keep_x, fine_x = _hub_lines(width, hub_width, screw_x, hole_half_size, relief_half_width, contact_size, coarse)
    z = grid_lines(-half_t, half_t, [-hole_half_size, hole_half_size], (-half_t, half_t), contact_size, coarse)
    voids = [((s * screw_x - hole_half_size, -1.0, -hole_half_size),
              (s * screw_x + hole_half_size, height + 1.0, hole_half_size)) for s in (-1, 1)]
    solids = counterweight_solids(width, height, thickness, hub_width, hub_height)
    transitions = _transition_plan(contact_size, coarse, hub_height)
    if transitions is None:
        y = grid_lines(0.0, height, [hub_height], (0.0, min(2.0 * contact_size, hub_height)), contact_size, coarse)
        return union_of_boxes(x, y, z, solids, voids)
    plan, depth, cell = transitions
    plan += _graded_layers(depth, [hub_height, height], cell, coarse)
    keep_z = [-half_t, -hole_half_size, hole_half_size, half_t]
    return _layered(x, z, plan, keep_x, keep_z, fine_x, [(-half_t, half_t)], solids, voids, mirror=False)


def web_block(width: float, depth: float, thickness: float, hub_width: float, screw_x: float,
              hole_half_size: float, hole_depth: float, contact_size: float,
              coarse_size: float | None = None, relief_half_width: float = 0.0) -> skfem.MeshHex:
    """The crank-web side of a counterweight joint: block |x| ≤ width/2, −depth ≤ y ≤ 0, thickness
    along z, with blind threaded holes (square, half-size ``hole_half_size``, ``hole_depth`` deep)
    at x = ±screw_x. Its face y = 0 matches :func:`counterweight_block` on the hub (same lines,
    same grading: give both the same contact_size, coarse_size and relief_half_width)."""
    if not (hub_width <= width and hole_depth < depth):
        raise InputError(f"web_block: needs hub_width <= width ({hub_width:g}, {width:g} mm) and hole_depth < depth "
                         f"({hole_depth:g}, {depth:g} mm)")
    coarse = _far_size(contact_size, coarse_size)
    half_t = 0.5 * thickness
    x, keep_x, fine_x = _hub_lines(width, hub_width, screw_x, hole_half_size, relief_half_width, contact_size, coarse)
    z = grid_lines(-half_t, half_t, [-hole_half_size, hole_half_size], (-half_t, half_t), contact_size, coarse)
    solids = [((-0.5 * width, -depth, -half_t), (0.5 * width, 0.0, half_t))]
    voids = [((s * screw_x - hole_half_size, -hole_depth, -hole_half_size),
              (s * screw_x + hole_half_size, 1.0, hole_half_size)) for s in (-1, 1)]
    transitions = _transition_plan(contact_size, coarse, hole_depth)
    if transitions is None:
        y = -grid_lines(0.0, depth, [hole_depth], (0.0, min(2.0 * contact_size, hole_depth)), contact_size, coarse)[::-1]
        return union_of_boxes(x, y, z, solids, voids)
    plan, reached, cell = transitions
    plan += _graded_layers(reached, [hole_depth, depth], cell, coarse)
    keep_z = [-half_t, -hole_half_size, hole_half_size, half_t]
    return _layered(x, z, plan, keep_x, keep_z, fine_x, [(-half_t, half_t)], solids, voids, mirror=True)


#: the most nodes a generated mesh may have. Assembling a body needs about 5 kB per hexahedron
#: (its element matrices) and factorising it far more, so two million nodes is already beyond a
#: workstation; the shipped meshes have a few thousand, a 1 mm counterweight joint some 10⁵.
MAX_GENERATED_NODES = 2_000_000


def _lines(length: float, size: float) -> float:
    """Grid lines of a stretch of ``length`` cut into cells of at most ``size`` (mm), as a float
    (a contact size typed in metres makes the count too large for an array)."""
    return np.ceil(length / size - 1e-9) + 1.0


def _hub_nodes(hub_width: float, thickness: float, screw_x: float, hole_half_size: float, contact_size: float,
               layers: float, relief_half_width: float = 0.0, **_) -> float:
    """Nodes of the fine hub face of :func:`counterweight_block` or :func:`web_block` (its pads
    when relieved, less the screw holes) in ``layers`` node planes."""
    face = (_lines(hub_width - 2.0 * relief_half_width, contact_size) * _lines(thickness, contact_size)
            - 2.0 * (_lines(2.0 * hole_half_size, contact_size) - 2.0) ** 2)
    return max(face, 0.0) * layers


def _counterweight_nodes(hub_height: float, contact_size: float, **args) -> float:
    return _hub_nodes(contact_size=contact_size, layers=3.0 if 2.0 * contact_size <= hub_height else 2.0, **args)


def _web_nodes(hole_depth: float, contact_size: float, **args) -> float:
    return _hub_nodes(contact_size=contact_size, layers=3.0 if 2.0 * contact_size <= hole_depth else 2.0, **args)


def _block_2d_nodes(contact_half_width: float, contact_size: float, **_) -> float:
    n_half = max(1.0, np.round(contact_half_width / contact_size))
    return (2.0 * n_half + 1.0) * (n_half + 1.0)


def _beam_nodes(width: float, contact_size: float, pad_half_length: float, layers: int = 6, **_) -> float:
    return _lines(2.0 * pad_half_length + 4.0 * contact_size, contact_size) * _lines(width, contact_size) * (layers + 1)


def _flat_nodes(n_x: float, n_y: float, n_z: float, **_) -> float:
    return (n_x + 1.0) * (n_y + 1.0) * (n_z + 1.0)


_FINE_NODES = {"counterweight_block": ("contact_size", _counterweight_nodes),
               "web_block": ("contact_size", _web_nodes),
               "plane_block": ("contact_size", _block_2d_nodes),
               "cylinder_block": ("contact_size", _block_2d_nodes),
               "beam_with_hole": ("contact_size", _beam_nodes),
               "flat_block": ("n_x", _flat_nodes)}


def least_nodes(generator: str, args: dict) -> tuple[float, str] | None:
    """(nodes, key): about how many nodes the fine zone of the mesh that ``generator`` makes
    from ``args`` (its keyword arguments, mm) has, a lower bound of the mesh's count found
    without meshing, and the key that sets it (``contact_size``, or ``n_x`` of a flat block);
    None for a generator without an estimate."""
    if generator not in _FINE_NODES:
        return None
    key, count = _FINE_NODES[generator]
    return float(count(**args)), key
