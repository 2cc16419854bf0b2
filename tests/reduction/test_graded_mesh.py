"""The counterweight joint's graded meshes: conforming, the right volume, fine only where the contact is."""

import numpy as np
import pytest
import skfem

from reduction.errors import InputError
from reduction.mesh.generators import counterweight_block, grid_lines, web_block
from tests.reduction.patch import interior_residual

# a small CW–web joint (mm): the shipped layout scaled down, so that a 2.5 mm mesh is quick
CW = {"width": 300.0, "height": 80.0, "thickness": 30.0, "hub_width": 140.0, "hub_height": 15.0,
      "screw_x": 50.0, "hole_half_size": 8.0}
WEB = {"width": 160.0, "depth": 40.0, "thickness": 30.0, "hub_width": 140.0, "screw_x": 50.0,
       "hole_half_size": 8.0, "hole_depth": 25.0}
RELIEF = 30.0  # the pads are 30 ≤ |x| ≤ 70 on the hub face y = 0


def _volume(mesh) -> float:
    basis = skfem.Basis(mesh, skfem.ElementHex1())
    return float(skfem.Functional(lambda w: 1.0 + 0.0 * w.x[0]).assemble(basis))


def _facet_counts(mesh) -> np.ndarray:
    """How many cells hold each distinct facet (node set) of a hexahedral mesh."""
    faces = np.array([[0, 1, 4, 2], [0, 1, 5, 3], [0, 2, 6, 3], [1, 4, 7, 5], [2, 4, 7, 6], [3, 5, 7, 6]])
    keys = np.sort(mesh.t[faces].transpose(2, 0, 1).reshape(-1, 4), axis=1)
    return np.unique(keys, axis=0, return_counts=True)[1]


def _on_boundary(points: np.ndarray, planes) -> np.ndarray:
    """Whether each point (n, 3) lies on one of the axis planes (axis, value)."""
    return np.any([np.abs(points[:, axis] - value) < 1e-9 for axis, value in planes], axis=0)


@pytest.mark.parametrize("size", [5.0, 2.5])
def test_graded_counterweight_is_conforming_with_its_volume_and_fine_pads(size):
    mesh = counterweight_block(**CW, contact_size=size, coarse_size=20.0, relief_half_width=RELIEF)
    # conforming: no facet in three cells, and every facet held by one cell lies on the solid's
    # outside (a hanging node would leave unmatched facets inside the body)
    counts = _facet_counts(mesh)
    assert counts.max() == 2
    boundary = mesh.p[:, mesh.facets[:, mesh.boundary_facets()]].mean(axis=1).T
    hub, t, h = 0.5 * CW["hub_width"], 0.5 * CW["thickness"], CW["hole_half_size"]
    planes = [(0, -0.5 * CW["width"]), (0, 0.5 * CW["width"]), (0, -hub), (0, hub), (1, 0.0),
              (1, CW["hub_height"]), (1, CW["height"]), (2, -t), (2, t)]
    planes += [(0, s * CW["screw_x"] + d * h) for s in (-1, 1) for d in (-1, 1)] + [(2, -h), (2, h)]
    assert np.all(_on_boundary(boundary, planes))
    assert mesh.boundary_facets().size == np.sum(counts == 1)
    expected = (CW["hub_width"] * CW["hub_height"] + CW["width"] * (CW["height"] - CW["hub_height"])) \
        * CW["thickness"] - 2 * (2 * h) ** 2 * CW["height"]
    assert _volume(mesh) == pytest.approx(expected, rel=1e-12)
    # the pads carry the contact size, the relief and the far body are coarser
    x = np.unique(mesh.p[0][np.abs(mesh.p[1]) < 1e-9])
    spacing, middle = np.diff(x), 0.5 * (x[:-1] + x[1:])
    on_pads = (np.abs(middle) > RELIEF) & (np.abs(middle) < hub)
    assert spacing[on_pads].max() <= size + 1e-9
    assert spacing[np.abs(middle) < RELIEF].max() > 1.5 * size
    y = np.unique(mesh.p[1])
    assert np.diff(y)[:2].max() <= size + 1e-9 and np.diff(y).max() > 3 * size


def test_graded_web_matches_the_counterweight_face():
    cw = counterweight_block(**CW, contact_size=2.5, coarse_size=20.0, relief_half_width=RELIEF)
    web = web_block(**WEB, contact_size=2.5, coarse_size=20.0, relief_half_width=RELIEF)
    assert _facet_counts(web).max() == 2
    expected = WEB["width"] * WEB["depth"] * WEB["thickness"] - 2 * (2 * WEB["hole_half_size"]) ** 2 * WEB["hole_depth"]
    assert _volume(web) == pytest.approx(expected, rel=1e-12)

    def face(mesh):
        p = mesh.p[:, np.abs(mesh.p[1]) < 1e-9]
        on_hub = np.abs(p[0]) <= 0.5 * CW["hub_width"] + 1e-9
        return {tuple(point) for point in np.round(p[:, on_hub].T, 9)}

    assert face(cw) == face(web)


def test_fine_mesh_grades_instead_of_refining_the_whole_body():
    """The graded 2.5 mm mesh has the pads of the uniform 2.5 mm mesh and a fraction of its nodes."""
    graded = counterweight_block(**CW, contact_size=2.5, coarse_size=20.0, relief_half_width=RELIEF).p
    uniform = counterweight_block(**CW, contact_size=2.5, coarse_size=2.5, relief_half_width=RELIEF).p

    def pads(p):
        on = (np.abs(p[1]) < 1e-9) & (np.abs(p[0]) >= RELIEF) & (np.abs(p[0]) <= 0.5 * CW["hub_width"])
        return {tuple(point) for point in np.round(p[:, on].T, 9)}

    assert pads(graded) == pads(uniform)
    assert graded.shape[1] < 0.25 * uniform.shape[1]


def test_grid_lines_grade_between_two_fine_intervals():
    lines = grid_lines(-100.0, 100.0, [], [(-70.0, -30.0), (30.0, 70.0)], 2.0, 20.0)
    step = np.diff(lines)
    middle = 0.5 * (lines[:-1] + lines[1:])
    assert step[(np.abs(middle) > 30) & (np.abs(middle) < 70)].max() <= 2.0 + 1e-12
    relief = step[np.abs(middle) < 30]
    np.testing.assert_allclose(relief, relief[::-1], rtol=1e-12)  # symmetric: finest at both pads
    assert relief[0] < relief[len(relief) // 2]
    assert lines[0] == -100.0 and lines[-1] == 100.0 and np.all(step > 0)


def test_relief_must_leave_the_holes_on_the_pads():
    with pytest.raises(InputError, match="relief_half_width"):
        counterweight_block(**CW, contact_size=5.0, relief_half_width=45.0)


def test_layered_counterweight_passes_the_patch_test():
    """A linear displacement field is in equilibrium at every interior node of a conforming mesh
    (the 3:1 transitions included); a hanging node would carry an unbalanced force."""
    mesh = counterweight_block(**CW, contact_size=2.5, coarse_size=20.0, relief_half_width=RELIEF)
    assert interior_residual(mesh) < 1e-9
