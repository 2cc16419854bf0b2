"""Moving a mesh's surface nodes with the interior following smoothly (mm).

Used to build the geometry that wear would leave (the paper's check that wear as a gap gives
the same profile as moving the surface): the interior nodes follow a harmonic extension of
the surface motion, so the elements stay valid for small moves.
"""

from __future__ import annotations

import numpy as np
import skfem
from skfem.models.poisson import laplace


def move_surface(mesh, nodes: np.ndarray, displacement: np.ndarray):
    """Move ``nodes`` by ``displacement`` (n, dim) mm; the interior follows harmonically (the
    other boundary nodes stay). 2D meshes of quads or triangles."""
    element = skfem.ElementQuad1() if isinstance(mesh, skfem.MeshQuad) else skfem.ElementTriP1()
    basis = skfem.Basis(mesh, element)
    stiffness = skfem.asm(laplace, basis)
    boundary = mesh.boundary_nodes()
    moved = np.zeros_like(mesh.p)
    for component in range(mesh.dim()):
        prescribed = np.zeros(mesh.p.shape[1])
        prescribed[nodes] = displacement[:, component]
        moved[component] = skfem.solve(*skfem.condense(stiffness, np.zeros(mesh.p.shape[1]), x=prescribed,
                                                       D=np.union1d(boundary, nodes)))
    return type(mesh)(mesh.p + moved, mesh.t)
