"""Volume meshes in: meshio files (Abaqus .inp, Gmsh .msh, ...) and scikit-fem meshes.

A ``MeshModel`` holds the scikit-fem mesh with its named node sets and element sets.
Supported solid cells: Tet4, Hex8, Tet10, Hex20 (3D); Tri3, Quad4 (2D, plane strain). Hex20 files
become the trilinear mesh of their corners carrying 20-node serendipity elements
(``MeshModel.quadratic``): their mid-edge nodes must lie at the edge midpoints. Node sets come
from Abaqus *NSET, Abaqus *SURFACE blocks (element faces ``ELSET, S1`` … or node-based; meshio
drops them, :mod:`reduction.mesh.abaqus` reads them: the nodes of their faces), Gmsh physical
groups of lower dimension (nodes of those faces/edges) and scikit-fem boundaries; element sets
from *ELSET, volume physical groups and subdomains. Node sets of quadratic meshes (Tet10, Hex20)
keep the file's mid-edge nodes; a scene's selections add those of edges whose corners a set holds
(:func:`reduction.mesh.selection.select_body_nodes`). Coordinates in mm.

Abaqus element types are read as the element of the same displacement interpolation
(:data:`ABAQUS_SOLIDS`): the hybrid (H) variants carry an extra pressure unknown per element
that enforces near-incompressibility; for the linear-elastic, compressible materials of a
condensation it only restates the displacement solution, so C3D4H is read as Tet4, C3D10H and
C3D10MH as Tet10, C3D8H as Hex8, C3D20H as Hex20. Reduced integration (R) changes the
quadrature, not the interpolation: C3D8R is read as Hex8 (fully integrated), C3D20R as Hex20.
Any other solid type (incompatible modes C3D8I, wedges, ...) is refused, naming the type and file.
"""

from __future__ import annotations

import io
import re
from contextlib import redirect_stderr, redirect_stdout
from dataclasses import dataclass, field
from pathlib import Path

import meshio
import numpy as np
import skfem
from skfem.io.meshio import INV_HEX_MAPPING

from reduction.elasticity import ElasticBody
from reduction.errors import InputError
from reduction.mesh.selection import nodes_at_points

# meshio cell type -> (scikit-fem mesh, dimension)
_SOLID_CELLS = {
    "tetra": (skfem.MeshTet1, 3),
    "hexahedron": (skfem.MeshHex1, 3),
    "tetra10": (skfem.MeshTet2, 3),
    "hexahedron20": (skfem.MeshHex1, 3),
    "triangle": (skfem.MeshTri1, 2),
    "quad": (skfem.MeshQuad1, 2),
}
#: Abaqus solid element types read (as the meshio type of the base element, said in their
#: names): the type -> the base type of the same displacement interpolation (module doc)
ABAQUS_SOLIDS = {
    **dict.fromkeys(("C3D4", "C3D4H"), "C3D4"),
    **dict.fromkeys(("C3D10", "C3D10H", "C3D10M", "C3D10MH", "C3D10I"), "C3D10"),
    **dict.fromkeys(("C3D8", "C3D8H", "C3D8R", "C3D8RH"), "C3D8"),
    **dict.fromkeys(("C3D20", "C3D20H", "C3D20R", "C3D20RH"), "C3D20"),
    **dict.fromkeys(("CPE3", "CPE3H"), "CPS3"),  # meshio reads plane-strain elements as these cells
    **dict.fromkeys(("CPE4", "CPE4H", "CPE4R", "CPE4RH"), "CPS4"),
}
#: meshio reads these as Hex8, but their displacement field is not Hex8's
_ENRICHED_HEX8 = ("C3D8I", "C3D8IH")
_ABAQUS_ELEMENT = re.compile(r"^(\*\s*ELEMENT\s*,.*?\bTYPE\s*=\s*)([^,\s]+)", re.IGNORECASE | re.MULTILINE)
_UNSUPPORTED_SOLIDS = {"wedge", "wedge15", "pyramid", "pyramid13", "hexahedron27",
                       "triangle6", "quad8", "quad9"}
_SURFACE_CELLS = {"triangle", "quad", "triangle6", "quad8", "quad9", "line", "line3", "vertex"}

# right-handed corner triples (corner, edge neighbours) in meshio/VTK/Abaqus node order
_HEX_CORNERS = np.array([[0, 1, 3, 4], [1, 2, 0, 5], [2, 3, 1, 6], [3, 0, 2, 7],
                         [4, 7, 5, 0], [5, 4, 6, 1], [6, 5, 7, 2], [7, 6, 4, 3]])


@dataclass(frozen=True)
class MeshModel:
    """A scikit-fem mesh with named sets.

    points: (n_points, dim) all element nodes, mm, numbered as the nodes of the elastic body on
    ``mesh`` (:class:`reduction.elasticity.ElasticBody`: the vertices, then for Tet10 and Hex20
    one mid-edge node per mesh edge; ``mesh`` of a Hex20 file holds only the corners).
    node_sets: name -> indices into ``points``; element_sets: name -> element indices (mesh.t columns).
    """

    mesh: skfem.Mesh
    points: np.ndarray
    node_sets: dict[str, np.ndarray] = field(default_factory=dict)
    element_sets: dict[str, np.ndarray] = field(default_factory=dict)
    source: str = "scikit-fem"

    serendipity: bool = False

    @property
    def quadratic(self) -> bool:
        """Quadratic elements: Tet10 (a MeshTet2) or Hex20 (serendipity elements on the corner mesh)."""
        return isinstance(self.mesh, skfem.MeshTet2) or self.serendipity

    def node_set(self, name: str) -> np.ndarray:
        if name not in self.node_sets:
            raise InputError(f"{self.source}: no node set '{name}'; available: {sorted(self.node_sets) or 'none'}")
        if self.node_sets[name].size == 0:
            raise InputError(f"{self.source}: node set '{name}' has no nodes on the solid elements")
        return self.node_sets[name]

    def element_set(self, name: str) -> np.ndarray:
        if name not in self.element_sets:
            available = sorted(self.element_sets) or "none"
            raise InputError(f"{self.source}: no element set '{name}'; available: {available}")
        return self.element_sets[name]

    def body_nodes(self, body: ElasticBody, name: str) -> np.ndarray:
        """Rows of ``body.node_dofs`` for the named node set (matched by position)."""
        return nodes_at_points(body.coordinates, self.points[self.node_set(name)])

    def per_element(self, values_by_set: dict[str, float], quantity: str) -> np.ndarray:
        """(n_elements,) array from one value per element set; every element must be covered once."""
        n_elements = self.mesh.t.shape[1]
        values = np.full(n_elements, np.nan)
        for name, value in values_by_set.items():
            elements = self.element_set(name)
            if np.any(~np.isnan(values[elements]) & (values[elements] != value)):
                raise InputError(
                    f"{self.source}: element set '{name}' overlaps another set with a different {quantity}")
            values[elements] = value
        missing = np.flatnonzero(np.isnan(values))
        if missing.size:
            raise InputError(f"{self.source}: {missing.size} elements have no {quantity} "
                             f"(first element index {missing[0]}); sets given: {sorted(values_by_set)}")
        return values


def from_skfem(mesh: skfem.Mesh) -> MeshModel:
    """Wrap a scikit-fem mesh: named boundaries become node sets, subdomains element sets."""
    node_sets = {name: np.unique(mesh.facets[:, np.asarray(facets)].ravel())
                 for name, facets in (mesh.boundaries or {}).items()}
    element_sets = {name: np.asarray(elements) for name, elements in (mesh.subdomains or {}).items()}
    points = mesh.doflocs.T if isinstance(mesh, skfem.MeshTet2) else mesh.p.T
    return MeshModel(mesh=mesh, points=np.ascontiguousarray(points), node_sets=node_sets,
                     element_sets=element_sets, source="scikit-fem mesh")


def read_mesh(path, where: str | None = None) -> MeshModel:
    """Read a volume (or 2D) mesh file with meshio; format from the file extension (.inp Abaqus,
    .msh Gmsh, others as meshio deduces them). ``where``: the scene key that names the file, said
    in every error about it."""
    path = Path(path)
    label = f"'{where}': {path}" if where else f"mesh file {path}"
    if path.is_dir():
        raise InputError(f"{label} is a folder, not a mesh file: name a mesh file in it (Abaqus .inp, Gmsh .msh)")
    if not path.is_file():
        raise InputError(f"{label} does not exist")
    raw = _read_raw(path, label)
    model = from_meshio(raw, source=f"'{where}': {path}" if where else str(path))
    if path.suffix.lower() == ".inp":
        from reduction.mesh.abaqus import read_surfaces

        compact = _file_to_mesh_nodes(raw, model)
        for name, nodes in read_surfaces(path).items():
            model.node_sets.setdefault(name, _compact(compact, nodes))
    return model


#: readers of the formats the extension names for sure (meshio would try several for .msh)
_READERS = {".inp": ("an Abaqus", meshio.abaqus.read), ".msh": ("a Gmsh", meshio.gmsh.read)}


def _read_raw(path: Path, label: str) -> meshio.Mesh:
    """The meshio mesh of a file, or an InputError naming ``label``. meshio prints its readers'
    complaints and ends the process (SystemExit) when no reader accepts a file: its output is
    kept out of the terminal and its exit becomes the error."""
    kind, reader = _READERS.get(path.suffix.lower(), ("a mesh", meshio.read))
    source = _abaqus_base_types(path, label) if path.suffix.lower() == ".inp" else path
    noise = io.StringIO()
    try:
        with redirect_stdout(noise), redirect_stderr(noise):
            return reader(source)
    except SystemExit:
        raise InputError(f"{label} is not {kind} file that meshio can read; write it from the mesher as "
                         "Abaqus .inp or Gmsh .msh") from None
    except KeyError as error:  # a node or element number that the file does not define
        raise InputError(f"{label}: {_undefined_number(path, error.args[0] if error.args else None)}") from None
    except Exception as error:  # meshio raises bare exceptions of many kinds for bad files
        detail = f" ({error})" if str(error) else ""
        raise InputError(f"{label} is not {kind} file that meshio can read{detail}; check that it is "
                         "complete (not truncated) and written in that format") from None


def _abaqus_base_types(path: Path, label: str) -> io.StringIO:
    """The text of an Abaqus file with each solid element type written as its base type
    (:data:`ABAQUS_SOLIDS`), for meshio (which reads C3D4H as a cell type it does not know); an
    InputError naming a type that is neither such a solid nor one meshio reads (surfaces, beams:
    sets only). The buffer is named as the file: meshio finds *INCLUDE files next to it."""
    text = path.read_text(errors="replace")
    _refuse_non_plane_strain(text, label)

    def base_type(match: re.Match) -> str:
        kind = match.group(2).upper()
        if kind in ABAQUS_SOLIDS:
            return match.group(1) + ABAQUS_SOLIDS[kind]
        if kind in meshio.abaqus._abaqus.abaqus_to_meshio_type and kind not in _ENRICHED_HEX8:
            return match.group(0)
        line = text.count("\n", 0, match.start()) + 1
        why = (" (its incompatible modes enrich the displacement field beyond Hex8's: write the mesh as C3D8R, "
               "C3D8 or C3D20R)" if kind in _ENRICHED_HEX8 else "")
        raise InputError(f"{label}: unsupported element type {match.group(2)} (line {line}){why}; supported: "
                         f"{', '.join(ABAQUS_SOLIDS)}")

    buffer = io.StringIO(_ABAQUS_ELEMENT.sub(base_type, text))
    buffer.name = str(path)
    return buffer


#: Abaqus plane-stress elements: meshio reads them as the plane-strain ones' cells
_PLANE_STRESS = ("CPS3", "CPS4", "CPS4R")
_PLANE_STRAIN = frozenset(kind for kind in ABAQUS_SOLIDS if kind.startswith("CPE"))
#: meshio's cell types of 2D elements (of solids, shells, membranes or rigid surfaces alike)
_CELLS_2D = frozenset({"triangle", "quad", "triangle6", "quad8", "quad9"})


def _refuse_non_plane_strain(text: str, label: str) -> None:
    """InputError for a 2D Abaqus mesh (no C3D solids) whose elements are not plane-strain
    solids: plane-stress elements, whose bodies are softer (E against E/(1 − ν²)), or, in a
    mesh with no plane-strain element, shells, membranes and rigid elements that meshio reads as
    the same triangles and quads. fretwork's 2D bodies are plane strain; read as such, they gave
    a plane-strain answer without a word."""
    found = [(match.group(2).upper(), match.start()) for match in _ABAQUS_ELEMENT.finditer(text)]
    kinds = {kind for kind, _ in found}
    if any(kind.startswith("C3D") for kind in kinds):
        return  # a 3D mesh: other elements only give sets
    plane_strain = bool(kinds & _PLANE_STRAIN)
    for kind, start in found:
        line = text.count("\n", 0, start) + 1  # *ELEMENT lines are few: one a block
        if kind in _PLANE_STRESS:
            raise InputError(f"{label}: plane-stress element type {kind} (line {line}): fretwork's 2D bodies are "
                             "plane strain (CPE3, CPE4, CPE4R), which are stiffer; write the mesh with plane-strain "
                             "elements, or model the body in 3D")
        if not plane_strain and meshio.abaqus._abaqus.abaqus_to_meshio_type.get(kind) in _CELLS_2D:
            raise InputError(f"{label}: element type {kind} (line {line}) is a shell, membrane or rigid element, "
                             "not a plane-strain solid; fretwork's 2D bodies are plane strain (CPE3, CPE4, CPE4R) "
                             "and its 3D ones solids (C3D4, C3D10, C3D8, C3D20)")


def _undefined_number(path: Path, number) -> str:
    """Say which number a file refers to without defining it: a node (of an element or a node set)
    or an element (of an element set)."""
    if path.suffix.lower() != ".inp" or number is None:
        return f"it refers to number {number}, which the file does not define"
    if not str(number).lstrip("-").isdigit():  # meshio's cell type of an element type it lists but cannot read
        return f"unsupported element type (meshio reads it as '{number}', a cell type it does not know)"
    if int(number) in _abaqus_node_numbers(path):
        return (f"an element set refers to element {number}, which the file does not define "
                "(no *ELEMENT line has that number)")
    return (f"an element (or node set) refers to node {number}, which the file does not define "
            "(no *NODE line has that number); export the mesh again with its nodes")


def _abaqus_node_numbers(path: Path) -> set[int]:
    """The node numbers of the *NODE blocks of an Abaqus file."""
    numbers, in_nodes = set(), False
    with path.open(errors="replace") as stream:
        for line in stream:
            if line.startswith("*"):
                in_nodes = line[1:].split(",")[0].strip().upper() == "NODE" and not line.startswith("**")
                continue
            head = line.split(",", 1)[0].strip()
            if in_nodes and head.lstrip("-").isdigit():
                numbers.add(int(head))
    return numbers


def _file_to_mesh_nodes(raw: meshio.Mesh, model: MeshModel) -> np.ndarray:
    """Map from the file's point order to ``model.points`` (-1: not a node of the solid mesh)."""
    from scipy.spatial import cKDTree

    points = np.asarray(raw.points, dtype=float)[:, :model.points.shape[1]]
    distance, index = cKDTree(model.points).query(points)
    span = float(np.ptp(model.points, axis=0).max()) or 1.0
    return np.where(distance <= 1e-9 * span, index, -1)


def from_meshio(raw: meshio.Mesh, source: str = "meshio mesh") -> MeshModel:
    """Convert a meshio mesh to a MeshModel, with sets; checks cell types and orientation."""
    cell_type = _solid_type(raw, source)
    mesh_type, dim = _SOLID_CELLS[cell_type]
    cells = raw.cells_dict[cell_type]
    points = np.asarray(raw.points, dtype=float)[:, :dim]
    _check_orientation(points, cells, cell_type, source)

    # keep element nodes only: stray points (reference nodes, geometry points) would be unconnected DOFs
    used = np.unique(cells)
    compact = np.full(len(raw.points), -1, dtype=np.int64)
    compact[used] = np.arange(used.size)
    points = np.ascontiguousarray(points[used])
    serendipity = cell_type == "hexahedron20"
    if serendipity:  # the corner mesh carries the 20-node elements; points and sets keep every node
        _check_straight_hex20(np.asarray(raw.points, dtype=float)[:, :dim], cells, source)
        corners = np.unique(cells[:, :8])
        corner_index = np.full(len(raw.points), -1, dtype=np.int64)
        corner_index[corners] = np.arange(corners.size)
        t = corner_index[cells[:, :8]].T
        vertices = np.asarray(raw.points, dtype=float)[corners, :dim]
    else:
        t, vertices = compact[cells].T, points
    if cell_type in ("hexahedron", "hexahedron20"):
        t = t[INV_HEX_MAPPING[:8]]
    mesh = mesh_type(np.ascontiguousarray(vertices.T), np.ascontiguousarray(t))
    if cell_type in ("tetra10", "hexahedron20"):
        order = _body_order(mesh, points, source)
        compact[used] = order
        points = np.ascontiguousarray(points[np.argsort(order)])

    node_sets = {name: _compact(compact, indices) for name, indices in raw.point_sets.items()}
    element_sets: dict[str, np.ndarray] = {}
    for name, by_type in raw.cell_sets_dict.items():
        if name.startswith("gmsh:"):
            continue
        if cell_type in by_type:
            element_sets[name] = np.asarray(by_type[cell_type], dtype=np.int64)
        surface_nodes = [raw.cells_dict[kind][index].ravel() for kind, index in by_type.items() if kind != cell_type]
        if surface_nodes:
            node_sets[name] = _compact(compact, np.concatenate(surface_nodes))
    _gmsh_physical_groups(raw, cell_type, dim, compact, node_sets, element_sets)
    return MeshModel(mesh=mesh, points=points, node_sets=node_sets, element_sets=element_sets, source=source,
                     serendipity=serendipity)


#: mid-edge nodes 8 … 19 of a meshio/Abaqus hexahedron20 (C3D20): the corners of their edges
HEX20_EDGES = np.array([[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4],
                         [0, 4], [1, 5], [2, 6], [3, 7]])


def _check_straight_hex20(points: np.ndarray, cells: np.ndarray, source: str) -> None:
    """The serendipity elements on the corner mesh put mid-edge nodes at the edge midpoints."""
    midpoints = 0.5 * (points[cells[:, HEX20_EDGES[:, 0]]] + points[cells[:, HEX20_EDGES[:, 1]]])
    offset = np.linalg.norm(points[cells[:, 8:20]] - midpoints, axis=-1)
    length = np.linalg.norm(points[cells[:, HEX20_EDGES[:, 1]]] - points[cells[:, HEX20_EDGES[:, 0]]], axis=-1)
    bad = np.flatnonzero(np.any(offset > 1e-6 * length, axis=1))
    if bad.size:
        raise InputError(f"{source}: {bad.size} hexahedron20 elements have curved edges (mid-edge node off the "
                         f"edge midpoint), first element index {bad[0]}; only straight-edged Hex20 are supported")


def _body_order(mesh: skfem.Mesh, points: np.ndarray, source: str) -> np.ndarray:
    """Position of each point of a quadratic mesh in the body's node order (the mesh vertices,
    then one mid-edge node per mesh edge, :class:`reduction.elasticity.ElasticBody`)."""
    from scipy.spatial import cKDTree

    if isinstance(mesh, skfem.MeshTet2):
        body_nodes = mesh.doflocs.T  # the file's own mid-edge nodes (edges may be curved)
    else:
        body_nodes = np.vstack([mesh.p.T, 0.5 * (mesh.p.T[mesh.edges[0]] + mesh.p.T[mesh.edges[1]])])
    order = cKDTree(body_nodes).query(points)[1]
    if len(points) != len(body_nodes) or np.unique(order).size != len(points):
        raise InputError(f"{source}: the mid-edge nodes do not match the element edges one to one "
                         "(each edge of the mesh needs exactly one mid-edge node)")
    return order


def _compact(compact: np.ndarray, file_indices) -> np.ndarray:
    indices = compact[np.unique(np.asarray(file_indices, dtype=np.int64))]
    return indices[indices >= 0]


def _solid_type(raw: meshio.Mesh, source: str) -> str:
    kinds = {block.type for block in raw.cells}
    unsupported = sorted(kinds & _UNSUPPORTED_SOLIDS - _SURFACE_CELLS)
    solids3d = sorted(kinds & {"tetra", "hexahedron", "tetra10", "hexahedron20"})
    if unsupported:
        raise InputError(f"{source}: unsupported cell type(s) {', '.join(unsupported)}; "
                         "supported: tetra (Tet4), hexahedron (Hex8), tetra10 (Tet10), hexahedron20 (Hex20), "
                         "triangle, quad")
    if len(solids3d) > 1:
        raise InputError(f"{source}: mixed solid cell types {', '.join(solids3d)} in one body are not supported")
    if solids3d:
        return solids3d[0]
    solids2d = sorted(kinds & {"triangle", "quad"})
    if len(solids2d) == 1:
        return solids2d[0]
    if len(solids2d) > 1:
        raise InputError(f"{source}: mixed 2D cell types {', '.join(solids2d)} are not supported")
    raise InputError(f"{source}: no solid cells found (cell types present: {', '.join(sorted(kinds)) or 'none'})")


def _signed_measures(points: np.ndarray, cells: np.ndarray, cell_type: str) -> np.ndarray:
    """Per element, the smallest signed corner volume (3D) or area (2D); positive when well ordered."""
    if cell_type in ("tetra", "tetra10"):
        corners = np.array([[0, 1, 2, 3]])
    elif cell_type in ("hexahedron", "hexahedron20"):
        corners = _HEX_CORNERS
    elif cell_type == "triangle":
        corners = np.array([[0, 1, 2]])
    else:  # quad
        corners = np.array([[0, 1, 3], [1, 2, 0], [2, 3, 1], [3, 0, 2]])
    origin = points[cells[:, corners[:, 0]]]
    edges = np.stack([points[cells[:, corners[:, k]]] - origin for k in range(1, corners.shape[1])], axis=-2)
    if edges.shape[-1] == 2:
        return np.min(edges[..., 0, 0] * edges[..., 1, 1] - edges[..., 0, 1] * edges[..., 1, 0], axis=1)
    return np.min(np.linalg.det(edges), axis=1)


def _check_orientation(points: np.ndarray, cells: np.ndarray, cell_type: str, source: str) -> None:
    measure = _signed_measures(points, cells, cell_type)
    bad = np.flatnonzero(measure <= 0)
    if bad.size:
        raise InputError(
            f"{source}: {bad.size} of {len(cells)} {cell_type} elements are inverted or degenerate "
            f"(non-positive corner volume), first element index {bad[0]} with nodes {cells[bad[0]].tolist()}"
        )


def _gmsh_physical_groups(raw, cell_type, dim, compact, node_sets, element_sets) -> None:
    """Named Gmsh physical groups: solid-dimension groups become element sets, lower ones node sets."""
    physical = raw.cell_data.get("gmsh:physical")
    if physical is None or not raw.field_data:
        return
    solid_offset = 0
    for block, tags in zip(raw.cells, physical):
        block_dim = 3 if block.type in ("tetra", "hexahedron", "tetra10", "hexahedron20") else \
            2 if block.type in ("triangle", "quad", "triangle6", "quad8", "quad9") else \
            1 if block.type in ("line", "line3") else 0
        for name, (tag, group_dim) in ((n, v[:2]) for n, v in raw.field_data.items()):
            if group_dim != block_dim:
                continue
            hits = np.flatnonzero(np.asarray(tags) == tag)
            if not hits.size:
                continue
            if block.type == cell_type and block_dim == dim:
                previous = element_sets.get(name, np.zeros(0, dtype=np.int64))
                element_sets[name] = np.union1d(previous, hits + solid_offset)
            elif block_dim < dim:
                previous = node_sets.get(name, np.zeros(0, dtype=np.int64))
                node_sets[name] = np.union1d(previous, _compact(compact, block.data[hits].ravel()))
        if block.type == cell_type:
            solid_offset += len(block.data)
