"""Write the meshes of the user-style joint (examples/user_joint.toml) as Abaqus input files.

This stands for what an engineer brings from their own preprocessor: a counterweight (CW) and a
crank web meshed with quadratic tetrahedra (C3D10, the paper's element), with node sets for the bolt heads, the thread
engagement and the support, and the contact faces as element-face surfaces (*SURFACE,
TYPE=ELEMENT, "element, Sn" lines). The meshes do not match across the joint (CW 20 mm, web
25 mm elements on the contact face): the contact is paired by mortar.

Geometry (mm), both in the CW frame (origin at the centre of the contact face, x tangential, y
radial outward, z along the crank axis):
  CW: wing plate 560 × 130 × 60 (x, y, z) on a 200 mm wide, 30 mm high hub whose face y = 0 is
  the contact face; screw heads bear on 40 × 60 mm of the top face y = 160 at x = ±60.
  Web: 250 × 75 × 60 block under it, held at its far face y = -75; the screw threads engage in
  the web 15 ... 55 mm deep around x = ±60.

Run: python examples/user_joint/make_meshes.py   (writes cw.inp and web.inp beside this file)
"""

from pathlib import Path

import meshio
import numpy as np
import skfem

HERE = Path(__file__).resolve().parent
# Abaqus faces of a C3D4 or C3D10 element: corner positions (0-based) of S1 … S4
FACES = {"S1": (0, 1, 2), "S2": (0, 3, 1), "S3": (1, 3, 2), "S4": (2, 3, 0)}
# C3D10 mid-edge nodes 5 … 10 (Abaqus and meshio "tetra10" order): the edges' corner positions
EDGES = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))


def tetrahedra(x, y, z, keep):
    """Positively oriented tetrahedra of the tensor grid x × y × z whose centroids satisfy keep."""
    mesh = skfem.MeshTet.init_tensor(np.asarray(x, float), np.asarray(y, float), np.asarray(z, float))
    centroids = mesh.p[:, mesh.t].mean(axis=1)
    mesh = mesh.remove_elements(np.flatnonzero(~keep(*centroids)))
    points, cells = mesh.p.T, mesh.t.T.copy()
    corners = points[cells]
    volume = np.linalg.det(np.stack([corners[:, k] - corners[:, 0] for k in (1, 2, 3)], axis=1))
    cells[volume < 0] = cells[volume < 0][:, [0, 2, 1, 3]]
    used = np.unique(cells)
    compact = np.full(len(points), -1)
    compact[used] = np.arange(used.size)
    return points[used], compact[cells]


def quadratic(points, cells):
    """C3D10 cells of C3D4 ``cells``: a node at the middle of every edge, shared by the cells
    that share the edge (straight edges)."""
    edges = np.sort(cells[:, EDGES], axis=2).reshape(-1, 2)
    unique, index = np.unique(edges, axis=0, return_inverse=True)
    middles = 0.5 * (points[unique[:, 0]] + points[unique[:, 1]])
    mid_nodes = len(points) + index.reshape(len(cells), len(EDGES))
    return np.vstack([points, middles]), np.hstack([cells, mid_nodes])


def node_set(points, low, high):
    inside = np.all((points >= np.asarray(low) - 1e-6) & (points <= np.asarray(high) + 1e-6), axis=1)
    return np.flatnonzero(inside)


def write(path, points, cells, node_sets, surfaces):
    """The .inp file: nodes, C3D10 elements, node sets (meshio), then the *SURFACE blocks."""
    meshio.write(path, meshio.Mesh(points, [("tetra10", cells)], point_sets=node_sets), file_format="abaqus")
    # meshio names its tetra10 the hybrid modified C3D10MH: the plain C3D10 of the same nodes
    path.write_text(path.read_text().replace("*ELEMENT, TYPE=C3D10MH", "*ELEMENT, TYPE=C3D10"))
    with open(path, "a") as stream:
        for name, (low, high) in surfaces.items():
            stream.write(f"*SURFACE, NAME={name}, TYPE=ELEMENT\n")
            for k, cell in enumerate(cells):
                for face, corners in FACES.items():
                    face_points = points[cell[list(corners)]]
                    if np.all((face_points >= np.asarray(low) - 1e-6) & (face_points <= np.asarray(high) + 1e-6)):
                        stream.write(f"{k + 1}, {face}\n")


def counterweight():
    x = np.concatenate([np.linspace(-280, -100, 7)[:-1], np.linspace(-100, 100, 11)[:-1], np.linspace(100, 280, 7)])
    y = np.array([0.0, 30.0, 70.0, 115.0, 160.0])
    z = np.linspace(-30, 30, 3)
    points, cells = quadratic(*tetrahedra(x, y, z, lambda cx, cy, cz: (np.abs(cx) <= 100) | (cy >= 30)))
    sets = {"HEAD_1": node_set(points, [40, 160, -30], [80, 160, 30]),
            "HEAD_2": node_set(points, [-80, 160, -30], [-40, 160, 30])}
    write(HERE / "cw.inp", points, cells, sets, {"CONTACT": ([-100, 0, -30], [100, 0, 30])})


def web():
    x = np.linspace(-125, 125, 11)
    y = np.array([-75.0, -55.0, -35.0, -15.0, 0.0])
    z = np.linspace(-30, 30, 3)
    points, cells = quadratic(*tetrahedra(x, y, z, lambda cx, cy, cz: np.ones_like(cx, dtype=bool)))
    sets = {"BASE": node_set(points, [-125, -75, -30], [125, -75, 30]),
            "THREAD_1": node_set(points, [45, -55, -30], [75, -15, 30]),
            "THREAD_2": node_set(points, [-75, -55, -30], [-45, -15, 30])}
    write(HERE / "web.inp", points, cells, sets, {"CONTACT": ([-100, 0, -30], [100, 0, 30])})


if __name__ == "__main__":
    counterweight()
    web()
