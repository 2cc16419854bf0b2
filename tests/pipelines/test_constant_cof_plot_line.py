"""The constant-COF plot's profile along an oblique line through two probes: its abscissa is the
distance from the line's start, and the label gives the line's direction as a direction (and its
angle), not as a second point."""

from types import SimpleNamespace

import matplotlib.pyplot as plt
import matplotlib.tri
import numpy as np

from pipelines.output.constant_cof_plot import _line_panel, _probe_line


def test_an_oblique_line_is_labelled_by_its_direction_and_angle():
    x, y = np.meshgrid(np.linspace(0.0, 4.0, 5), np.linspace(0.0, 2.0, 3))
    points = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    mesh = matplotlib.tri.Triangulation(points[:, 0], points[:, 1])
    shear = points[:, 0] + points[:, 1]
    comparison = SimpleNamespace(
        coordinates=points,
        probes=[SimpleNamespace(name="P1", position_mm=(0.0, 0.0, 0.0)),
                SimpleNamespace(name="P2", position_mm=(2.0, 1.0, 0.0))],
        models=[SimpleNamespace(name="variable", max_shear=shear), SimpleNamespace(name="constant", max_shear=shear)])
    start, direction, length = _probe_line(comparison, 0, 1)
    np.testing.assert_allclose(direction, np.array([2.0, 1.0]) / np.sqrt(5.0))
    figure, ax = plt.subplots()
    try:
        _line_panel(ax, comparison, mesh, (0, 1), (start, direction, length))
        label = ax.get_xlabel()
    finally:
        plt.close(figure)
    assert "along direction (0.894, 0.447)" in label and "26.6° from the x axis" in label
    assert "(x, y) = (0, 0) mm" in label and "towards" not in label
