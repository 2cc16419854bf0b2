"""Interface-histories files: the load histories of one counterweight (CW) interface, written by
any multibody code (ours: ``fretwork mbs --interface-histories``) and read as the scene's
``coupling.histories`` instead of running the exudyn model.

The format (``fretwork-interface-histories``, version 1) is documented in
``docs/histories_format.md``: HDF5 or CSV, every column (dataset) naming its quantity,
component and unit. It holds time; the frame acceleration, angular velocity and angular
acceleration of the CW interface frame; optionally the wing torsion and the CW's modal
coordinates (velocities and accelerations derived when left out) with their mode shapes on the
CW mesh. Units are converted to mm, t, s, rad on reading (:data:`UNITS`); a missing column, an
unknown unit or a non-uniform time step is an :class:`InputError` naming the file and the column.

:func:`read_interface_histories` gives an :class:`InterfaceHistories` (the file's content in
our units), :func:`to_loading` the :class:`mbs.loading.MultibodyLoading` the contact model
takes, :func:`from_loading` and :func:`write_interface_histories` the way back. A loading
written and read back is the same, bit for bit (float64 throughout; CSV with 17 digits).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np
import skfem
from scipy.spatial import cKDTree
from skfem.io.meshio import HEX_MAPPING, INV_HEX_MAPPING

from mbs.counterweight import corner_tetrahedra, torsion_mode_index, wing_tip_points
from mbs.loading import MultibodyLoading
from reduction.errors import InputError
from reduction.mesh.io import HEX20_EDGES

FORMAT = "fretwork-interface-histories"
MODES_FORMAT = "fretwork-mode-shapes"
FORMAT_VERSION = 1
FRAME = ("counterweight interface frame: origin at the centre of the contact face, x tangential, "
         "y radial outward, z along the crank axis")
XYZ = ("x", "y", "z")

#: unit families: accepted unit → factor to ours (mm, t, s, rad)
_LENGTH = {"mm": 1.0, "m": 1e3, "um": 1e-3, "µm": 1e-3}
_ACCELERATION = {"mm/s^2": 1.0, "m/s^2": 1e3, "g": 9806.65}
_ANGULAR_VELOCITY = {"rad/s": 1.0, "deg/s": math.pi / 180.0, "rpm": math.pi / 30.0}
_ANGULAR_ACCELERATION = {"rad/s^2": 1.0, "deg/s^2": math.pi / 180.0}
#: mode shapes × modal coordinates must give mm: mass-normalised shapes (1/sqrt(t)) with
#: coordinates in mm·sqrt(t), or shapes in a length with dimensionless coordinates ("1")
_SHAPE = {"1/sqrt(t)": ("mm*sqrt(t)", 1.0), "mm": ("1", 1.0), "m": ("1", 1e3)}

#: quantity → (components or None for a scalar, units, required)
QUANTITIES = {
    "time": (None, {"s": 1.0, "ms": 1e-3}, True),
    "frame_acceleration": (XYZ, _ACCELERATION, True),
    "angular_velocity": (XYZ, _ANGULAR_VELOCITY, True),
    "angular_acceleration": (XYZ, _ANGULAR_ACCELERATION, True),
    "wing_torsion": (None, _LENGTH, False),
    "modal_coordinate": ("modes", None, False),
    "modal_velocity": ("modes", None, False),
    "modal_acceleration": ("modes", None, False),
}
_MODAL_SUFFIX = {"modal_coordinate": "", "modal_velocity": "/s", "modal_acceleration": "/s^2"}
#: a step may differ from the median step by this fraction (fixed-step output rounded in time)
STEP_TOLERANCE = 1e-6
MIN_SAMPLES = 8
#: a step longer than this fraction of a revolution cannot resolve the engine's own orders (4th
#: and up); a file's time in ms labelled [s] lands far beyond it (a step of 1,000 times the true one)
MAX_STEP_REVOLUTIONS = 1.0 / 8.0
#: the mean spin about the crank axis may differ from ``speed_rpm`` by this fraction (the
#: torsional vibration of the crankshaft stays well inside it)
SPEED_TOLERANCE = 0.05
#: cell types of the mode shapes' elements → nodes per cell (meshio/Abaqus node order)
CELL_TYPES = {"tetra": 4, "tetra10": 10, "hexahedron": 8, "hexahedron20": 20}


@dataclass(frozen=True)
class ModeShapes:
    """The CW's mode shapes in our units: node_coordinates (n, 3) mm in the CW frame, shapes
    (n, 3, m) mm per unit modal coordinate, frequencies (m,) Hz (fixed interface), torsion_mode
    (0-based index, or -1: found from the wing tips), cells (n_c, 4, 10, 8 or 20) node indices of
    tetra, tetra10, hexahedron or hexahedron20 elements (:data:`CELL_TYPES`), or None: the
    elements are those of the scene's CW mesh;
    coordinate_unit: the unit of the modal coordinates these shapes take (:data:`_SHAPE`)."""

    node_coordinates: np.ndarray
    shapes: np.ndarray
    frequencies: np.ndarray
    torsion_mode: int = -1
    cells: np.ndarray | None = None
    coordinate_unit: str = "mm*sqrt(t)"


@dataclass(frozen=True)
class InterfaceHistories:
    """One CW interface's histories in our units (module doc), samples along the first axis.

    speed_rpm: engine speed; time (n,) s; frame_acceleration (n, 3) mm/s²; angular_velocity
    (n, 3) rad/s; angular_acceleration (n, 3) rad/s²; wing_torsion (n,) mm or None;
    modal_coordinates, modal_velocities, modal_accelerations (n, m) (m = 0 without modes);
    modes: :class:`ModeShapes` or None. source: the file, for messages.
    """

    speed_rpm: float
    time: np.ndarray
    frame_acceleration: np.ndarray
    angular_velocity: np.ndarray
    angular_acceleration: np.ndarray
    wing_torsion: np.ndarray | None
    modal_coordinates: np.ndarray
    modal_velocities: np.ndarray
    modal_accelerations: np.ndarray
    modes: ModeShapes | None
    source: str = "interface histories"


# ---------------------------------------------------------------- loading <-> histories

def from_loading(loading: MultibodyLoading) -> InterfaceHistories:
    """The histories of a multibody loading (ours), with its mode shapes on its P2 mesh."""
    modes = None
    if loading.n_modes:
        mesh = skfem.MeshTet1(loading.mesh_points, loading.mesh_cells)
        basis = skfem.Basis(mesh, skfem.ElementVector(skfem.ElementTetP2()), intorder=1)
        coordinates = basis.doflocs[:, 0::3].T  # node-interleaved DOFs: one row per node
        modes = ModeShapes(coordinates, loading.mode_shapes.reshape(len(coordinates), 3, -1),
                           loading.mode_frequencies_hz, loading.torsion_mode, _tetra10_cells(mesh))
    return InterfaceHistories(loading.speed_rpm, loading.time, loading.frame_acceleration, loading.angular_velocity,
                              loading.angular_acceleration, loading.wing_torsion, loading.modal_coordinates,
                              loading.modal_velocities, loading.modal_accelerations, modes)


def _tetra10_cells(mesh: skfem.MeshTet1) -> np.ndarray:
    """(n_t, 10) tetra10 connectivity (Abaqus C3D10 / meshio order: vertices, then the edges 01, 12,
    20, 03, 13, 23) of the P2 nodes of ``mesh`` (vertices, then one node per edge)."""
    n_v = mesh.p.shape[1]
    keys = np.minimum(*mesh.edges) * n_v + np.maximum(*mesh.edges)
    order = np.argsort(keys)
    t = mesh.t
    columns = [n_v + order[np.searchsorted(keys[order], np.minimum(t[a], t[b]) * n_v + np.maximum(t[a], t[b]))]
               for a, b in ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))]
    return np.column_stack([t.T, *columns]).astype(np.int64)


def to_loading(histories: InterfaceHistories, cw_mesh: skfem.Mesh | None = None) -> MultibodyLoading:
    """The multibody loading of a CW from its interface histories.

    cw_mesh: the scene's CW mesh (scikit-fem, CW frame), which gives the elements when the file's
    mode shapes come without cells; its nodes must then be those of the mode shapes."""
    modes = histories.modes
    n = len(histories.time)
    if modes is None:
        points, cells, shapes = np.zeros((3, 0)), np.zeros((4, 0), dtype=np.int64), np.zeros((0, 0))
        frequencies, torsion = np.zeros(0), -1
    else:
        mesh, shapes = _p2_field(modes, cw_mesh, histories.source)
        points, cells = mesh.p, mesh.t
        frequencies, torsion = modes.frequencies, modes.torsion_mode
        if torsion < 0:
            tips = _wing_tips(mesh)
            torsion = torsion_mode_index(shapes[3 * tips + 2, :], shapes)
    wing = histories.wing_torsion
    if wing is None:
        if modes is None:
            raise InputError(f"{histories.source}: needs a 'wing_torsion' column or modal coordinates with "
                             "mode shapes (the wing torsion is the amplitude the contact loading is scaled by)")
        tips = _wing_tips(skfem.MeshTet1(points, cells))
        wing = 0.5 * (histories.modal_coordinates @ (shapes[3 * tips[1] + 2] - shapes[3 * tips[0] + 2]))
    size = np.ptp(points, axis=1) if points.size else np.full(3, np.nan)
    return MultibodyLoading(
        speed_rpm=histories.speed_rpm, time=histories.time, frame_acceleration=histories.frame_acceleration,
        angular_velocity=histories.angular_velocity, angular_acceleration=histories.angular_acceleration,
        modal_coordinates=histories.modal_coordinates.reshape(n, -1),
        modal_velocities=histories.modal_velocities.reshape(n, -1),
        modal_accelerations=histories.modal_accelerations.reshape(n, -1),
        wing_torsion=wing, mesh_points=points, mesh_cells=cells, mode_shapes=shapes,
        geometry={"width": float(size[0]), "height": float(points[1].max()) if points.size else float("nan"),
                  "thickness": float(size[2])},
        mode_frequencies_hz=frequencies, torsion_mode=int(torsion), wall_time_s=0.0)


def _wing_tips(mesh: skfem.MeshTet1) -> np.ndarray:
    """The P2 nodes nearest to the wing tips (:func:`mbs.counterweight.wing_tip_points`)."""
    basis = skfem.Basis(mesh, skfem.ElementVector(skfem.ElementTetP2()), intorder=1)
    coordinates = basis.doflocs[:, 0::3].T
    return cKDTree(coordinates).query(wing_tip_points(coordinates))[1]


def _p2_field(modes: ModeShapes, cw_mesh, source: str) -> tuple[skfem.MeshTet1, np.ndarray]:
    """The linear tetrahedral mesh of the mode shapes and the shapes (3·n_nodes, m) in the
    node-interleaved P2 DOF order of that mesh (:class:`reduction.modal_loads.ModeField`).

    Hexahedra (the file's cells, or the scene's CW mesh) are split into tetrahedra; the P2 nodes
    the shapes are not given at (midpoints of the split's diagonals, and of the edges of Hex8)
    take the value of the hexahedron's own field (trilinear, or serendipity for Hex20)."""
    hexes = None
    if modes.cells is not None and modes.cells.shape[1] in (8, 20):
        hexes = modes.cells
        vertices = np.unique(hexes[:, :8])
        compact = np.full(len(modes.node_coordinates), -1)
        compact[vertices] = np.arange(vertices.size)
        mesh = corner_tetrahedra(skfem.MeshHex1(np.ascontiguousarray(modes.node_coordinates[vertices].T),
                                                np.ascontiguousarray(compact[hexes[:, :8]].T[INV_HEX_MAPPING[:8]])))
    elif modes.cells is not None:
        corners = modes.cells[:, :4]
        vertices = np.unique(corners)
        compact = np.full(len(modes.node_coordinates), -1)
        compact[vertices] = np.arange(vertices.size)
        mesh = skfem.MeshTet1(np.ascontiguousarray(modes.node_coordinates[vertices].T),
                              np.ascontiguousarray(compact[corners].T))
    elif cw_mesh is None:
        raise InputError(f"{source}: the mode shapes come without cells; the CW mesh of the scene "
                         "('coupling.body', a mesh file) must give their elements")
    else:
        mesh = corner_tetrahedra(cw_mesh)
        if isinstance(cw_mesh, skfem.MeshHex1):
            hexes = _hexes_at_nodes(cw_mesh, modes.node_coordinates)
    basis = skfem.Basis(mesh, skfem.ElementVector(skfem.ElementTetP2()), intorder=1)
    nodes = basis.doflocs[:, 0::3].T
    n_vertices = mesh.p.shape[1]
    span = float(np.ptp(nodes, axis=0).max())
    distance, index = cKDTree(modes.node_coordinates).query(nodes)
    found = distance <= 1e-6 * span
    m = modes.shapes.shape[2]
    if hexes is not None and found[:n_vertices].all() and not found.all():
        field = np.empty((len(nodes), 3, m))
        field[found] = modes.shapes[index[found]]
        missing = np.flatnonzero(~found)
        ends = index[mesh.edges[:, missing - n_vertices]]
        field[missing] = _hexahedron_values(hexes, ends, modes.shapes, source)
    elif found.all():
        field = modes.shapes[index]
    elif found[:n_vertices].all():
        # linear shapes at the vertices: the P2 field of the same (linear) shape takes edge means
        field = np.empty((len(nodes), 3, m))
        field[:n_vertices] = modes.shapes[index[:n_vertices]]
        field[n_vertices:] = 0.5 * (field[mesh.edges[0]] + field[mesh.edges[1]])
    else:
        missing = nodes[np.flatnonzero(~found)[0]]
        raise InputError(f"{source}: the mode shapes are given at {len(modes.node_coordinates)} nodes, but "
                         f"{int((~found[:n_vertices]).sum())} of the {n_vertices} CW mesh nodes have none "
                         f"(first at {missing.round(3).tolist()} mm): give them on the nodes of the CW mesh")
    return mesh, np.ascontiguousarray(field.reshape(-1, m))


def _hexes_at_nodes(mesh: skfem.MeshHex1, coordinates: np.ndarray) -> np.ndarray | None:
    """The hexahedra of ``mesh`` (meshio/Abaqus node order) as indices of the shape nodes at
    ``coordinates``: 20 nodes when the shapes are given at every mid-edge point, 8 when only at
    the corners, None when not even at the corners (the caller names the missing nodes)."""
    span = float(np.ptp(coordinates, axis=0).max())
    corners = mesh.p.T[mesh.t.T[:, HEX_MAPPING[:8]]]
    points = np.concatenate([corners, 0.5 * (corners[:, HEX20_EDGES[:, 0]] + corners[:, HEX20_EDGES[:, 1]])], axis=1)
    distance, index = cKDTree(coordinates).query(points.reshape(-1, 3))
    distance, index = distance.reshape(-1, 20), index.reshape(-1, 20)
    found = distance <= 1e-6 * span
    if found.all():
        return index
    return index[:, :8] if found[:, :8].all() else None


#: reference coordinates of the nodes of a meshio/Abaqus hexahedron20 (the first 8: hexahedron)
_HEX_REFERENCE = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                           [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)
_HEX_REFERENCE = np.vstack([_HEX_REFERENCE, 0.5 * (_HEX_REFERENCE[HEX20_EDGES[:, 0]] + _HEX_REFERENCE[HEX20_EDGES[:, 1]])])


def hexahedron_shape_functions(xi: np.ndarray, n_nodes: int) -> np.ndarray:
    """(k, n_nodes) shape functions of the trilinear (8) or serendipity (20) hexahedron at the
    reference points ``xi`` (k, 3) in [-1, 1]³, meshio/Abaqus node order."""
    corners = _HEX_REFERENCE[:8]
    linear = np.prod(1.0 + xi[:, None, :] * corners[None], axis=2) / 8.0
    if n_nodes == 8:
        return linear
    corner = linear * (np.sum(xi[:, None, :] * corners[None], axis=2) - 2.0)
    middle = _HEX_REFERENCE[8:]
    mid_edge = np.prod(np.where(middle[None] == 0.0, 1.0 - xi[:, None, :] ** 2, 1.0 + xi[:, None, :] * middle[None]),
                       axis=2) / 4.0
    return np.hstack([corner, mid_edge])


def _hexahedron_values(hexes: np.ndarray, ends: np.ndarray, shapes: np.ndarray, source: str) -> np.ndarray:
    """(k, 3, m) shapes at the midpoints of k segments between two corners of one hexahedron
    (``ends`` (2, k) node indices), from that hexahedron's field at the reference midpoint."""
    pairs = np.array([(a, b) for a in range(8) for b in range(a + 1, 8)])
    first, second = hexes[:, pairs[:, 0]], hexes[:, pairs[:, 1]]
    size = int(hexes.max()) + 1
    keys = (np.minimum(first, second) * size + np.maximum(first, second)).ravel()
    order = np.argsort(keys, kind="stable")
    wanted = np.minimum(*ends) * size + np.maximum(*ends)
    position = np.minimum(np.searchsorted(keys[order], wanted), keys.size - 1)
    if np.any(keys[order][position] != wanted):
        raise InputError(f"{source}: the tetrahedra split from the hexahedral cells do not lie in the cells")
    cell, pair = np.divmod(order[position], len(pairs))
    xi = 0.5 * (_HEX_REFERENCE[pairs[pair, 0]] + _HEX_REFERENCE[pairs[pair, 1]])
    weights = hexahedron_shape_functions(xi, hexes.shape[1])
    return np.einsum("kn,knam->kam", weights, shapes[hexes[cell]])


# ---------------------------------------------------------------- writing

def _columns(histories: InterfaceHistories):
    """(quantity, component labels or None, unit, (n, k) or (n,) values) of every history."""
    yield "time", None, "s", histories.time
    yield "frame_acceleration", XYZ, "mm/s^2", histories.frame_acceleration
    yield "angular_velocity", XYZ, "rad/s", histories.angular_velocity
    yield "angular_acceleration", XYZ, "rad/s^2", histories.angular_acceleration
    if histories.wing_torsion is not None:
        yield "wing_torsion", None, "mm", histories.wing_torsion
    m = histories.modal_coordinates.shape[1] if histories.modal_coordinates.ndim == 2 else 0
    if m:
        labels = tuple(str(k + 1) for k in range(m))
        for quantity, values in (("modal_coordinate", histories.modal_coordinates),
                                 ("modal_velocity", histories.modal_velocities),
                                 ("modal_acceleration", histories.modal_accelerations)):
            yield quantity, labels, "mm*sqrt(t)" + _MODAL_SUFFIX[quantity], values


def write_interface_histories(path, histories: InterfaceHistories, *, producer: str = "fretwork") -> Path:
    """Write ``histories`` to ``path``: HDF5 for .h5/.hdf5, CSV for .csv (the mode shapes then go
    to ``<stem>_modes.csv`` beside it). Mode shapes are written mass-normalised (1/sqrt(t))."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.suffix.lower() in (".h5", ".hdf5"):
        _write_hdf5(path, histories, producer)
    elif path.suffix.lower() == ".csv":
        _write_csv(path, histories, producer)
    else:
        raise InputError(f"{path}: an interface-histories file ends in .h5, .hdf5 or .csv")
    return path


def _write_hdf5(path: Path, histories: InterfaceHistories, producer: str) -> None:
    with h5py.File(path, "w") as root:
        root.attrs.update({"format": FORMAT, "format_version": FORMAT_VERSION, "speed_rpm": histories.speed_rpm,
                           "frame": FRAME, "producer": producer})
        for quantity, labels, unit, values in _columns(histories):
            dataset = root.create_dataset(quantity, data=np.asarray(values, dtype=np.float64))
            dataset.attrs["unit"] = unit
            if labels is not None:
                dataset.attrs["components"] = list(labels)
        modes = histories.modes
        if modes is not None:
            group = root.create_group("modes")
            group.attrs["torsion_mode"] = modes.torsion_mode + 1
            for name, values, unit in (("node_coordinate", modes.node_coordinates, "mm"),
                                       ("mode_shape", modes.shapes, "1/sqrt(t)"),
                                       ("frequency", modes.frequencies, "Hz")):
                group.create_dataset(name, data=np.asarray(values, dtype=np.float64)).attrs["unit"] = unit
            if modes.cells is not None:
                cells = group.create_dataset("cells", data=modes.cells)
                cells.attrs["cell_type"] = {width: name for name, width in CELL_TYPES.items()}[modes.cells.shape[1]]


def _header(quantity, labels, unit) -> list[str]:
    return [f"{quantity} [{unit}]"] if labels is None else [f"{quantity}:{c} [{unit}]" for c in labels]


def _write_csv(path: Path, histories: InterfaceHistories, producer: str) -> None:
    header, blocks = [], []
    for quantity, labels, unit, values in _columns(histories):
        header += _header(quantity, labels, unit)
        blocks.append(np.asarray(values, dtype=np.float64).reshape(len(histories.time), -1))
    meta = [f"format = {FORMAT}", f"format_version = {FORMAT_VERSION}", f"speed_rpm = {histories.speed_rpm!r}",
            f"frame = {FRAME}", f"producer = {producer}"]
    modes = histories.modes
    if modes is not None:
        modes_path = path.with_name(f"{path.stem}_modes.csv")
        meta.append(f"mode_shapes = {modes_path.name}")
        m = modes.shapes.shape[2]
        mode_header = _header("node_coordinate", XYZ, "mm") + [
            f"mode_shape:{k + 1}.{c} [1/sqrt(t)]" for k in range(m) for c in XYZ]
        table = np.column_stack([modes.node_coordinates, modes.shapes.transpose(0, 2, 1).reshape(len(modes.shapes), -1)])
        mode_meta = [f"format = {MODES_FORMAT}", f"format_version = {FORMAT_VERSION}",
                     "frequency_hz = " + ", ".join(repr(float(f)) for f in modes.frequencies),
                     f"torsion_mode = {modes.torsion_mode + 1}"]
        _save_csv(modes_path, mode_meta, mode_header, table)
    _save_csv(path, meta, header, np.column_stack(blocks))


def _save_csv(path: Path, meta: list[str], header: list[str], table: np.ndarray) -> None:
    text = "".join(f"# {line}\n" for line in meta) + ",".join(header) + "\n"
    with path.open("w") as stream:
        stream.write(text)
        np.savetxt(stream, table, delimiter=",", fmt="%.17g")


# ---------------------------------------------------------------- reading

def read_interface_histories(path) -> InterfaceHistories:
    """Read and check an interface-histories file (HDF5 or CSV by its suffix), in our units."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"interface-histories file {path} does not exist")
    if path.suffix.lower() in (".h5", ".hdf5"):
        meta, columns, modes = _read_hdf5(path)
    elif path.suffix.lower() == ".csv":
        meta, columns, modes = _read_csv(path)
    else:
        raise InputError(f"{path}: an interface-histories file ends in .h5, .hdf5 or .csv")
    return _checked(path, meta, columns, modes)


def _read_hdf5(path: Path):
    """(metadata, {quantity: (labels, unit, values)}, ModeShapes or None) of an HDF5 file."""
    try:
        root = h5py.File(path, "r")
    except OSError as error:
        raise InputError(f"{path}: not a readable HDF5 file ({error})") from None
    with root:
        meta = {key: (value.decode() if isinstance(value, bytes) else value) for key, value in root.attrs.items()}
        columns = {}
        for name, dataset in root.items():
            if name == "modes" or not isinstance(dataset, h5py.Dataset):
                continue
            labels = dataset.attrs.get("components")
            labels = None if labels is None else tuple(str(c.decode() if isinstance(c, bytes) else c) for c in labels)
            columns[name] = (labels, _text(dataset.attrs.get("unit")), dataset[()])
        modes = None
        if "modes" in root:
            group = root["modes"]
            modes = _mode_shapes(path, {key: _text(value) if isinstance(value, (str, bytes)) else value
                                        for key, value in group.attrs.items()},
                                 {name: (_text(group[name].attrs.get("unit")), group[name][()])
                                  for name in group if name != "cells"},
                                 group["cells"][()] if "cells" in group else None,
                                 _text(group["cells"].attrs.get("cell_type")) if "cells" in group else None)
    return meta, columns, modes


def _text(value):
    return value.decode() if isinstance(value, bytes) else value


def _parse_csv(path: Path) -> tuple[dict, list[str], int, np.ndarray]:
    """('# key = value' metadata, header fields, the header's line number, (n, k) values) of a
    CSV file. A UTF-8 byte-order mark (Excel's "CSV UTF-8") is dropped."""
    meta, header, header_line, rows = {}, None, 0, []
    with path.open(encoding="utf-8-sig") as stream:
        for number, line in enumerate(stream, 1):
            line = line.strip()
            if not line:
                continue
            if line.startswith("#"):
                key, _, value = line[1:].partition("=")
                meta[key.strip()] = value.strip()
            elif header is None:
                header, header_line = [field.strip() for field in line.split(",")], number
            else:
                try:
                    rows.append([float(value) for value in line.split(",")])
                except ValueError:
                    raise InputError(f"{path}, line {number}: not a row of numbers: {line[:80]!r}") from None
                if len(rows[-1]) != len(header):
                    raise InputError(f"{path}, line {number}: {len(rows[-1])} values for {len(header)} columns")
    if header is None or not rows:
        raise InputError(f"{path}: no header line and samples found")
    return meta, header, header_line, np.array(rows)


def _split_header(path: Path, field: str) -> tuple[str, str | None, str]:
    """'quantity:component [unit]' → (quantity, component or None, unit)."""
    name, bracket, unit = field.partition("[")
    if not bracket or not unit.endswith("]"):
        raise InputError(f"{path}: column '{field}' has no unit; write 'quantity:component [unit]'")
    quantity, _, component = name.strip().partition(":")
    return quantity.strip(), component.strip() or None, unit[:-1].strip()


def _grouped(path: Path, header: list[str], line: int, table: np.ndarray) -> dict:
    """{quantity: (labels or None, unit, values)} from CSV columns; ``line``: the header's line
    number, for messages."""
    columns: dict = {}
    seen: dict = {}
    for k, field in enumerate(header):
        quantity, component, unit = _split_header(path, field)
        if (quantity, component) in seen:
            raise InputError(f"{path}, line {line}: column '{field}' appears twice (columns "
                             f"{seen[quantity, component]} and {k + 1}); give each column once")
        seen[quantity, component] = k + 1
        labels, units, values = columns.setdefault(quantity, ([], set(), []))
        labels.append(component)
        units.add(unit)
        values.append(table[:, k])
    out = {}
    for quantity, (labels, units, values) in columns.items():
        if len(units) > 1:
            raise InputError(f"{path}: the columns of '{quantity}' mix units {sorted(units)}")
        scalar = labels == [None]
        out[quantity] = (None if scalar else tuple(labels), units.pop(),
                         values[0] if scalar else np.column_stack(values))
    return out


def _read_csv(path: Path):
    meta, header, line, table = _parse_csv(path)
    columns = _grouped(path, header, line, table)
    modes = None
    if "mode_shapes" in meta:
        modes_path = path.parent / meta["mode_shapes"]
        if not modes_path.is_file():
            raise InputError(f"{path}: its mode-shape file {modes_path} does not exist")
        mode_meta, mode_header, mode_line, mode_table = _parse_csv(modes_path)
        grouped = _grouped(modes_path, mode_header, mode_line, mode_table)
        if "mode_shape" not in grouped:
            raise InputError(f"{modes_path}: missing columns 'mode_shape:K.x [unit]' …")
        labels, unit, values = grouped["mode_shape"]
        parsed = [label.partition(".") for label in labels]
        order = sorted(range(len(parsed)), key=lambda i: (int(parsed[i][0]) if parsed[i][0].isdigit() else -1,
                                                          XYZ.index(parsed[i][2]) if parsed[i][2] in XYZ else -1))
        if any(not parsed[i][0].isdigit() or parsed[i][2] not in XYZ for i in order) or len(order) % 3:
            raise InputError(f"{modes_path}: mode-shape columns must read 'mode_shape:K.x', '.y', '.z' (K = 1, 2, …)")
        shapes = values[:, order].reshape(len(values), -1, 3).transpose(0, 2, 1)
        frequencies = mode_meta.get("frequency_hz")
        attrs = {"torsion_mode": int(mode_meta["torsion_mode"]) if "torsion_mode" in mode_meta else 0}
        datasets = {"node_coordinate": grouped.get("node_coordinate", (None, "mm", None))[1:],
                    "mode_shape": (unit, shapes)}
        if frequencies is not None:
            datasets["frequency"] = ("Hz", np.array([float(f) for f in frequencies.split(",")]))
        if "node_coordinate" not in grouped:
            raise InputError(f"{modes_path}: missing columns 'node_coordinate:x [mm]', ':y', ':z'")
        modes = _mode_shapes(modes_path, attrs, datasets, None, None)
    return meta, columns, modes


def _mode_shapes(path: Path, attrs: dict, datasets: dict, cells, cell_type) -> ModeShapes:
    """Mode shapes in our units from the file's datasets {name: (unit, values)}."""
    for name in ("node_coordinate", "mode_shape", "frequency"):
        if name not in datasets:
            raise InputError(f"{path}: the mode shapes need '{name}'")
    unit, coordinates = datasets["node_coordinate"]
    coordinates = np.asarray(coordinates, float) * _factor(path, "node_coordinate", unit, _LENGTH)
    shape_unit, shapes = datasets["mode_shape"]
    if shape_unit not in _SHAPE:
        raise InputError(f"{path}: unknown unit '{shape_unit}' of 'mode_shape'; known: {', '.join(_SHAPE)}")
    shapes = np.asarray(shapes, float) * _SHAPE[shape_unit][1]
    unit, frequencies = datasets["frequency"]
    frequencies = np.asarray(frequencies, float).ravel() * _factor(path, "frequency", unit, {"Hz": 1.0})
    if coordinates.ndim != 2 or coordinates.shape[1] != 3 or shapes.shape[:2] != coordinates.shape \
            or shapes.ndim != 3 or frequencies.shape != (shapes.shape[2],):
        raise InputError(f"{path}: mode shapes must be (nodes, 3, modes) at node coordinates (nodes, 3) with one "
                         f"frequency per mode; got {shapes.shape}, {coordinates.shape}, {frequencies.shape}")
    if cells is not None:
        cells = np.asarray(cells, dtype=np.int64)
        if cells.ndim != 2 or cells.shape[1] != CELL_TYPES.get(cell_type):
            raise InputError(f"{path}: mode-shape cells must be tetra (n, 4), tetra10 (n, 10), hexahedron (n, 8) or "
                             f"hexahedron20 (n, 20), got {cell_type!r} {cells.shape}")
        if cells.min() < 0 or cells.max() >= len(coordinates):
            raise InputError(f"{path}: mode-shape cells refer to nodes outside 0 … {len(coordinates) - 1}")
    torsion = int(attrs.get("torsion_mode", 0))
    if not 0 <= torsion <= shapes.shape[2]:
        raise InputError(f"{path}: 'torsion_mode' is {torsion}, but there are {shapes.shape[2]} modes (1 … or 0: find it)")
    return ModeShapes(coordinates, shapes, frequencies, torsion - 1, cells, _SHAPE[shape_unit][0])


def _factor(path: Path, quantity: str, unit, known: dict) -> float:
    if unit not in known:
        raise InputError(f"{path}: unknown unit '{unit}' of '{quantity}'; known: {', '.join(known)}")
    return known[unit]


def _checked(path: Path, meta: dict, columns: dict, modes: ModeShapes | None) -> InterfaceHistories:
    """The histories in our units after every check (module doc)."""
    if meta.get("format") != FORMAT:
        raise InputError(f"{path}: not an interface-histories file (format = {meta.get('format')!r}, "
                         f"expected '{FORMAT}')")
    version = int(meta.get("format_version", -1))
    if version != FORMAT_VERSION:
        raise InputError(f"{path}: format_version {version} is not supported (this fretwork reads {FORMAT_VERSION})")
    try:
        speed = float(meta["speed_rpm"])
    except (KeyError, ValueError):
        speed = math.nan
    if not speed > 0.0 or not math.isfinite(speed):
        raise InputError(f"{path}: needs the engine speed 'speed_rpm' (rpm, > 0) in its metadata")
    for quantity, (components, _, required) in QUANTITIES.items():
        if required and quantity not in columns:
            expected = quantity if components is None else ", ".join(f"{quantity}:{c}" for c in components)
            raise InputError(f"{path}: missing column(s) {expected}")
    values = {}
    for quantity, (labels, unit, data) in columns.items():
        if quantity not in QUANTITIES:
            raise InputError(f"{path}: unknown quantity '{quantity}'; known: {', '.join(QUANTITIES)}")
        components, units, _ = QUANTITIES[quantity]
        data = np.asarray(data, dtype=float)
        if components == "modes":
            values[quantity] = data.reshape(len(data), -1) * _modal_factor(path, quantity, unit, modes)
            continue
        if components is not None and tuple(labels or ()) != components:
            raise InputError(f"{path}: '{quantity}' must have the components {', '.join(components)} in this "
                             f"order, got {labels}")
        values[quantity] = _shaped(path, quantity, components, data) * _factor(path, quantity, unit, units)
    _, time_unit, stored = columns["time"]
    time = values["time"] = _sampled_time(path, values["time"], _resolution(stored) * QUANTITIES["time"][1][time_unit])
    for quantity, data in values.items():
        if len(data) != len(time):
            raise InputError(f"{path}: '{quantity}' has {len(data)} samples, 'time' has {len(time)}")
        if not np.all(np.isfinite(data)):
            raise InputError(f"{path}: '{quantity}' holds non-finite values")
    _check_speed(path, speed, values["angular_velocity"][:, 2])
    _check_revolution_sampling(path, speed, time, time_unit)
    _check_frame_radius(path, values["frame_acceleration"], values["angular_velocity"][:, 2],
                        columns["frame_acceleration"][1])
    q = values.get("modal_coordinate")
    if (q is None) != (modes is None):
        raise InputError(f"{path}: modal coordinates and mode shapes go together: give both or neither")
    if q is not None and q.shape[1] != modes.shapes.shape[2]:
        raise InputError(f"{path}: {q.shape[1]} modal coordinates but {modes.shapes.shape[2]} mode shapes")
    if q is None:
        q = np.zeros((len(time), 0))
    step = float(np.mean(np.diff(time)))
    velocity = values.get("modal_velocity", np.gradient(q, step, axis=0) if q.size else q)
    acceleration = values.get("modal_acceleration", np.gradient(velocity, step, axis=0) if q.size else q)
    return InterfaceHistories(speed, time, values["frame_acceleration"], values["angular_velocity"],
                              values["angular_acceleration"], values.get("wing_torsion"), q, velocity,
                              acceleration, modes, str(path))


#: the largest distance (mm) of a CW interface frame from the spin axis that an engine has: the
#: largest crank radii are about 1.5 m
_LARGEST_RADIUS_MM = 10000.0


def _check_frame_radius(path: Path, frame_acceleration: np.ndarray, spin: np.ndarray, unit: str) -> None:
    """InputError when the mean frame acceleration (mm/s²) over the mean spin squared puts the
    frame farther than :data:`_LARGEST_RADIUS_MM` from the axis: a unit mistake, most likely
    (QA, 2026-11-28: mm/s² labelled m/s² ran into a Newton failure at 1000 ω²r). The centripetal
    acceleration ω²·r dominates the mean; a file that hardly spins is not judged."""
    omega = float(np.mean(np.abs(spin)))
    if omega < 1.0:  # rad/s: a static or slow case says nothing about its radius
        return
    radius = float(np.linalg.norm(np.mean(frame_acceleration, axis=0))) / omega ** 2
    if radius > _LARGEST_RADIUS_MM:
        raise InputError(f"{path}: the mean frame_acceleration ({np.linalg.norm(np.mean(frame_acceleration, axis=0)):.3g} "
                         f"mm/s², read as {unit}) over the mean spin squared ({omega:.4g} rad/s) puts the CW frame "
                         f"{radius / 1000:.3g} m from the spin axis: check the unit of frame_acceleration (values in "
                         "mm/s² labelled m/s² are read 1000 times too large)")


def _modal_factor(path: Path, quantity: str, unit: str, modes: ModeShapes | None) -> float:
    """Modal coordinates keep their unit, which must match the mode shapes' (:data:`_SHAPE`)."""
    suffix = _MODAL_SUFFIX[quantity]
    known = sorted({coordinate + suffix for coordinate, _ in _SHAPE.values()})
    if unit not in known:
        raise InputError(f"{path}: unknown unit '{unit}' of '{quantity}'; known: {', '.join(known)}")
    if modes is not None and unit != modes.coordinate_unit + suffix:
        raise InputError(f"{path}: '{quantity}' is in {unit}, but the mode shapes' unit takes coordinates in "
                         f"{modes.coordinate_unit + suffix} (shape × coordinate must be mm)")
    return 1.0


def _shaped(path: Path, quantity: str, components, data: np.ndarray) -> np.ndarray:
    """The samples of one quantity: (n,) for a scalar (an HDF5 dataset of shape (n, 1) or (1, n)
    taken as (n,)), (n, 3) for a vector."""
    if components is None:
        if data.ndim == 2 and 1 in data.shape:
            data = data.ravel()
        if data.ndim != 1:
            raise InputError(f"{path}: '{quantity}' must hold one value per sample, shape (samples,), "
                             f"got shape {data.shape}")
    elif data.ndim != 2 or data.shape[1] != len(components):
        raise InputError(f"{path}: '{quantity}' must have the shape (samples, {len(components)}), got {data.shape}")
    return data


def _resolution(stored) -> float:
    """The spacing of the stored numbers at their largest magnitude, in their unit, when they are
    stored with less precision than float64 (an HDF5 float32 dataset), else 0."""
    stored = np.asarray(stored)
    if stored.dtype.kind != "f" or stored.dtype.itemsize >= 8 or not stored.size:
        return 0.0
    return float(np.spacing(np.max(np.abs(stored))))


def _sampled_time(path: Path, time: np.ndarray, resolution: float) -> np.ndarray:
    """The time (s) after the sampling checks (:func:`_check_sampling`). Time stored with less
    precision than float64 (``resolution`` s > 0: the spacing of its numbers) is checked to within
    that spacing and rebuilt as the fixed-step samples it stands for, in float64."""
    _check_sampling(path, time, resolution)
    if resolution == 0.0:
        return time
    step = (time[-1] - time[0]) / (len(time) - 1)
    return time[0] + step * np.arange(len(time))


def _check_sampling(path: Path, time: np.ndarray, resolution: float) -> None:
    """Fixed-step samples: at least MIN_SAMPLES, increasing, every step the median step (to within
    STEP_TOLERANCE, and two spacings ``resolution`` of numbers stored with less precision)."""
    if len(time) < MIN_SAMPLES:
        raise InputError(f"{path}: needs at least {MIN_SAMPLES} samples of 'time', got {len(time)}")
    steps = np.diff(time)
    step = float(np.median(steps))
    if resolution > 0.01 * abs(step):
        raise InputError(f"{path}: 'time' is stored in single precision (float32), whose numbers are "
                         f"{resolution:.3g} s apart at t = {np.max(np.abs(time)):.6g} s, too coarse for the "
                         f"step {step:.6g} s: store it as float64")
    bad = np.flatnonzero(~(np.abs(steps - step) <= STEP_TOLERANCE * step + 2.0 * resolution))
    if step <= 0 or bad.size:
        k = int(bad[0]) if bad.size else 0
        raise InputError(f"{path}: non-uniform time step: {steps[k]:.6g} s between samples {k + 1} and {k + 2} "
                         f"(t = {time[k]:.6g} s), the median step is {step:.6g} s; give fixed-step samples "
                         "without gaps (resample the file)")


def _check_speed(path: Path, speed_rpm: float, spin: np.ndarray) -> None:
    """The mean spin about the crank axis (rad/s, either sense) is the engine speed
    ``speed_rpm``, to within SPEED_TOLERANCE."""
    mean_rpm = abs(float(np.mean(spin))) * 30.0 / math.pi
    if abs(mean_rpm - speed_rpm) > SPEED_TOLERANCE * speed_rpm:
        raise InputError(f"{path}: speed_rpm = {speed_rpm:g}, but the mean angular velocity about the crank axis "
                         f"(angular_velocity:z) is {mean_rpm * math.pi / 30.0:.6g} rad/s = {mean_rpm:.6g} rpm; they "
                         f"must agree within {SPEED_TOLERANCE:.0%} (check speed_rpm and the unit of angular_velocity)")


def _check_revolution_sampling(path: Path, speed_rpm: float, time: np.ndarray, unit: str) -> None:
    """At least 1/MAX_STEP_REVOLUTIONS samples per revolution at ``speed_rpm``."""
    revolution = 60.0 / speed_rpm
    step = float(np.median(np.diff(time)))
    if step <= MAX_STEP_REVOLUTIONS * revolution:
        return
    advice = "sample the histories more finely"
    if unit == "s" and step * 1e-3 <= MAX_STEP_REVOLUTIONS * revolution:
        advice = "if the time is in ms, label the column 'time [ms]'"
    raise InputError(f"{path}: the time step {step:.6g} s is {step / revolution:.3g} "
                     f"revolutions at speed_rpm = {speed_rpm:g} (one revolution: {revolution:.6g} s); a history "
                     f"needs at least {1.0 / MAX_STEP_REVOLUTIONS:.0f} samples per revolution: {advice}")
