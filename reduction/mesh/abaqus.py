"""The ``*SURFACE`` blocks of an Abaqus input file, which meshio drops.

meshio reads nodes, elements, ``*NSET`` and ``*ELSET``, but skips ``*SURFACE``: this small
parser reads the keywords a surface needs (``*NODE`` labels, ``*ELEMENT`` connectivity,
``*NSET``/``*ELSET`` with ``GENERATE``, ``*SURFACE`` of ``TYPE=ELEMENT`` (the default) or
``TYPE=NODE``) and gives each surface as the nodes of its faces. Element faces follow the Abaqus
numbering (S1 … S4 of tetrahedra, S1 … S6 of hexahedra, mid-edge nodes of C3D10/C3D20 included).
Nodes are returned as indices in the order of the file's ``*NODE`` lines (meshio's point order).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from reduction.errors import InputError

# 0-based node positions of each face of an element, by the number of nodes of the element
_TET_FACES = {"S1": (0, 1, 2, 4, 5, 6), "S2": (0, 3, 1, 7, 8, 4), "S3": (1, 3, 2, 8, 9, 5), "S4": (2, 3, 0, 9, 7, 6)}
_HEX_FACES = {"S1": (0, 1, 2, 3, 8, 9, 10, 11), "S2": (4, 7, 6, 5, 15, 14, 13, 12),
              "S3": (0, 4, 5, 1, 16, 12, 17, 8), "S4": (1, 5, 6, 2, 17, 13, 18, 9),
              "S5": (2, 6, 7, 3, 18, 14, 19, 10), "S6": (3, 7, 4, 0, 19, 15, 16, 11)}
_FACES = {4: (_TET_FACES, 3), 10: (_TET_FACES, 6), 8: (_HEX_FACES, 4), 20: (_HEX_FACES, 8)}


def _options(line: str) -> tuple[str, dict]:
    """Keyword (upper case) and its options {NAME: value or ""} of a '*KEYWORD, A=b, C' line."""
    keyword, *parts = [part.strip() for part in line[1:].split(",")]
    options = {}
    for part in parts:
        key, _, value = part.partition("=")
        options[key.strip().upper()] = value.strip()
    return keyword.upper(), options


def _labels(lines: list[str], generate: bool) -> list:
    """Integer labels or set names of a data block (with GENERATE: start, stop, step triples)."""
    items = [item.strip() for line in lines for item in line.split(",") if item.strip()]
    if generate:
        numbers = [int(item) for item in items]
        return [label for k in range(0, len(numbers), 3)
                for label in range(numbers[k], numbers[k + 1] + 1, numbers[k + 2] if k + 2 < len(numbers) else 1)]
    return [int(item) if item.lstrip("-").isdigit() else item for item in items]


def _blocks(path: Path):
    """(keyword line, data lines) of every keyword of the file (comments and blank lines dropped)."""
    current, data = None, []
    for raw in path.read_text(errors="replace").splitlines():
        line = raw.strip()
        if not line or line.startswith("**"):
            continue
        if line.startswith("*"):
            if current is not None:
                yield current, data
            current, data = line, []
        else:
            data.append(line)
    if current is not None:
        yield current, data


def read_surfaces(path) -> dict[str, np.ndarray]:
    """Surface name → sorted node indices (file *NODE order) of its faces or nodes."""
    path = Path(path)
    node_index: dict[int, int] = {}
    elements: dict[int, list[int]] = {}
    node_sets: dict[str, list[int]] = {}
    element_sets: dict[str, list[int]] = {}
    surfaces = []
    for line, data in _blocks(path):
        keyword, options = _options(line)
        if keyword == "NODE":
            for row in data:
                node_index.setdefault(int(row.split(",")[0]), len(node_index))
        elif keyword == "ELEMENT":
            numbers = [int(item) for row in data for item in row.split(",") if item.strip()]
            block = _element_rows(numbers, options.get("TYPE", ""), path)
            elements.update(block)
            if "ELSET" in options:
                element_sets.setdefault(options["ELSET"].upper(), []).extend(block)
        elif keyword in ("NSET", "ELSET"):
            name = options.get(keyword, "").upper()
            target = node_sets if keyword == "NSET" else element_sets
            for member in _labels(data, "GENERATE" in options):
                target.setdefault(name, []).extend(target.get(str(member).upper(), []) if isinstance(member, str)
                                                   else [member])
        elif keyword == "SURFACE":
            surfaces.append((options.get("NAME", "").upper(), options.get("TYPE", "ELEMENT").upper(), data))
    out = {}
    for name, kind, data in surfaces:
        nodes = []
        for row in data:
            target, _, face = (item.strip() for item in row.partition(","))
            if kind == "NODE":
                nodes += node_sets.get(target.upper(), []) if not target.lstrip("-").isdigit() else [int(target)]
                continue
            labels = [int(target)] if target.lstrip("-").isdigit() else element_sets.get(target.upper())
            if labels is None:
                raise InputError(f"{path}: *SURFACE {name} names element set '{target}', which is not defined")
            for label in labels:
                nodes += _face_nodes(elements, label, face.upper(), name, path)
        missing = sorted(set(nodes) - set(node_index))
        if missing:
            raise InputError(f"{path}: *SURFACE {name} refers to node {missing[0]}, which no *NODE line defines")
        out[name] = np.unique([node_index[label] for label in nodes]).astype(np.int64)
    return out


def _element_rows(numbers: list[int], element_type: str, path: Path) -> dict[int, list[int]]:
    """Element label → node labels of one *ELEMENT block (the node count from its TYPE)."""
    digits = "".join(c for c in element_type.upper().removeprefix("C3D") if c.isdigit())
    width = int(digits) if element_type.upper().startswith("C3D") and digits else None
    if width is None:
        return {}  # shells, beams, 2D elements carry no solid faces
    return {numbers[k]: numbers[k + 1:k + 1 + width] for k in range(0, len(numbers), width + 1)}


def _face_nodes(elements: dict, label: int, face: str, surface: str, path: Path) -> list[int]:
    if label not in elements:
        raise InputError(f"{path}: *SURFACE {surface} names element {label}, which is not a solid element")
    nodes = elements[label]
    table, corners = _FACES.get(len(nodes), (None, 0))
    if table is None or face not in table:
        raise InputError(f"{path}: *SURFACE {surface}: face '{face}' of element {label} "
                         f"({len(nodes)} nodes) is not a face label (S1 … S{4 if len(nodes) in (4, 10) else 6})")
    positions = table[face] if len(nodes) in (10, 20) else table[face][:corners]
    return [nodes[k] for k in positions]
