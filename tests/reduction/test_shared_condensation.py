"""The counterweight's one factorisation, end to end: wing-mode normalisation and condensation
from one :class:`reduction.condensation.BoundarySchur` (pipelines.coupling.wing_mode_schur),
handed to :func:`contact.assembly.assemble` as the CW's condenser, give the structure of the
two-factor path."""

import numpy as np
import pytest

from contact.assembly import Body, ReferencePoint, assemble
from pipelines.coupling import SharedCondenser, wing_mode_schur
from reduction.elasticity import assemble_elastic_body
from reduction.factorization import factorize
from reduction.mesh.generators import counterweight_block, web_block
from reduction.modal_loads import wing_tip_dofs, wing_torsion

STEEL = {"youngs_modulus": 210_000.0, "poisson_ratio": 0.3, "density": 7.85e-9}
LAYOUT = {"hub_width": 140.0, "screw_x": 50.0, "hole_half_size": 8.0, "contact_size": 10.0,
          "coarse_size": 20.0, "relief_half_width": 30.0}


def _joint():
    """Small CW (heads coupled to two reference points) on a web held at its far face; the CW's
    spin load and a torsion-like wing load (N), the web's and CW's pads as contact surfaces."""
    cw_mesh = counterweight_block(300.0, 80.0, 30.0, hub_height=15.0, **LAYOUT)
    web_mesh = web_block(160.0, 40.0, 30.0, hole_depth=25.0, **LAYOUT)
    cw, web = assemble_elastic_body(cw_mesh, **STEEL), assemble_elastic_body(web_mesh, **STEEL)
    x, y = cw.coordinates[:, 0], cw.coordinates[:, 1]
    heads = {f"head_{k}": ReferencePoint(np.flatnonzero((np.abs(y - 80.0) < 1e-9) & (s * x >= 30.0 - 1e-9)
                                                        & (s * x <= 70.0 + 1e-9)), np.array([s * 50.0, 80.0, 0.0]), True)
             for k, s in ((1, 1), (2, -1))}
    field = np.zeros(cw.n_dofs)
    field[cw.node_dofs[:, 2]] = x * y / 80.0
    spin = np.zeros(cw.n_dofs)
    spin[cw.node_dofs[:, 1]] = 1e7 * (y + 230.0)
    loads = {"spin": cw.mass @ spin}
    bottom = np.flatnonzero(np.abs(web.coordinates[:, 1] + 40.0) < 1e-9)
    bodies = [Body("cw", cw, reference_points=heads, body_loads=loads),
              Body("web", web, fixed_nodes=bottom, fixed_components=(0, 1, 2))]

    def pads(mesh):
        return mesh.facets_satisfying(lambda p: (np.abs(p[1]) < 1e-9) & (np.abs(p[0]) >= 30.0 - 1e-9)
                                      & (np.abs(p[0]) <= 70.0 + 1e-9), boundaries_only=True)

    return bodies, ("cw", pads(cw_mesh)), ("web", pads(web_mesh)), 1e6 * (cw.mass @ field)


def test_shared_condenser_gives_the_two_factor_structure():
    bodies, slave, master, wing = _joint()
    cw = bodies[0].elastic
    face = np.flatnonzero(np.abs(cw.coordinates[:, 1]) < 1e-9)
    # two-factor path: the clamped CW's own factor for the torsion, then assemble's condense
    held = cw.node_dofs[face].ravel()
    free = np.setdiff1d(np.arange(cw.n_dofs), held)
    u = np.zeros(cw.n_dofs)
    u[free] = factorize(cw.stiffness[free][:, free]).solve(wing[free])
    minus, plus = wing_tip_dofs(cw)
    reference_pattern = wing / wing_torsion(u[minus], u[plus])
    two = [Body(b.name, b.elastic, b.fixed_nodes, b.fixed_components, b.reference_points,
                {**b.body_loads, "wing_mode": reference_pattern} if b.name == "cw" else b.body_loads) for b in bodies]
    before = assemble(two, slave, master).structure
    # one factorisation
    shared = wing_mode_schur(bodies[0], face, bodies[0].body_loads, wing)
    pattern = wing / shared.torsion
    assert np.linalg.norm(pattern - reference_pattern) < 1e-10 * np.linalg.norm(reference_pattern)
    one = [Body(b.name, b.elastic, b.fixed_nodes, b.fixed_components, b.reference_points,
                {**b.body_loads, "wing_mode": pattern} if b.name == "cw" else b.body_loads) for b in bodies]
    condenser = SharedCondenser(shared.schur)
    after = assemble(one, slave, master, condensers={"cw": condenser}).structure
    scale = np.abs(before.stiffness).max()
    assert np.abs(after.stiffness - before.stiffness).max() < 1e-10 * scale
    for name, vector in before.loads.items():
        assert np.linalg.norm(after.loads[name] - vector) <= 1e-10 * np.linalg.norm(vector), name
    with pytest.raises(RuntimeError, match="once"):  # the dense complement is not kept for the run
        condenser(None, None, None, None, None)
