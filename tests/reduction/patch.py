"""The patch test of a hexahedral mesh, shared by the graded-mesh tests."""

import numpy as np

from reduction.elasticity import assemble_elastic_body


def interior_residual(mesh) -> float:
    """Largest nodal force at an interior node under a linear displacement field, relative to
    the largest force anywhere (steel, mm): a conforming mesh keeps every interior node in
    equilibrium (round-off), a hanging node carries an unbalanced force."""
    body = assemble_elastic_body(mesh, 210_000.0, 0.3)
    strain = np.array([[1e-3, 2e-4, 0.0], [2e-4, -5e-4, 3e-4], [0.0, 3e-4, 7e-4]])
    u = np.zeros(body.n_dofs)
    u[body.node_dofs] = body.coordinates @ strain.T
    force = (body.stiffness @ u)[body.node_dofs]
    boundary = np.zeros(mesh.p.shape[1], dtype=bool)
    boundary[mesh.facets[:, mesh.boundary_facets()].ravel()] = True
    return float(np.abs(force[~boundary]).max() / np.abs(force).max())
