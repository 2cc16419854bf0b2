"""The multibody plots: µm on the axes, the time history over the steady window the wing
amplitude is measured on, a Campbell diagram whose legend names every line kind."""

from dataclasses import replace
import re

import matplotlib.pyplot as plt
import numpy as np
import pytest

from mbs import plots
from mbs.campbell import Campbell
from mbs.histories import RunHistories, steady_part
from mbs.spectra import Spectrum

UNIT = re.compile(r"\((µm|Hz|rpm|rev|cycles per revolution)\)")


@pytest.fixture
def figures(monkeypatch):
    """The figures the plot functions draw, kept open instead of saved."""
    drawn = []
    monkeypatch.setattr(plots, "_save", lambda figure, path: drawn.append(figure) or path)
    yield drawn
    for figure in drawn:
        plt.close(figure)


def histories(n=400, n_cw=2):
    """A run that starts with a large transient and settles to a 2 µm (CW1) wing torsion."""
    time = np.linspace(0.0, 0.16, n)
    angle = 2 * np.pi * 12.5 * time
    decay = 50.0 * np.exp(-time / 0.01)
    torsion = np.array([(2e-3 + decay * 1e-3) * np.sin(2 * np.pi * 300 * time)] * n_cw)
    torsion[1] *= 0.5
    tips = np.stack([-torsion + 1e-3, torsion + 1e-3], axis=-1)
    zeros3 = np.zeros((n_cw, n, 3))
    return RunHistories(time=time, crank_angle=angle, crank_speed=np.full(n, 2 * np.pi * 12.5),
                        cw_interface_displacement=zeros3, cw_interface_rotation=zeros3, cw_interface_force=zeros3,
                        cw_interface_moment=zeros3, cw_modal_coordinates=np.zeros((n_cw, n, 2)),
                        cw_modal_velocities=np.zeros((n_cw, n, 2)), cw_modal_accelerations=np.zeros((n_cw, n, 2)),
                        cw_frame_acceleration=zeros3, cw_angular_velocity=zeros3, cw_angular_acceleration=zeros3,
                        cw_wing_tip_axial=tips, energy_time=None, energy=None, wall_time=1.0)


def campbell(orders):
    speeds = np.linspace(100.0, 1000.0, 10)
    return Campbell(speeds_rpm=speeds, frequencies=np.tile([366.0, 401.0, 860.0], (10, 1)),
                    orders=np.asarray(orders, dtype=float),
                    crossings=[{"order": 30.0, "mode": 0, "speed_rpm": 732.0, "frequency_hz": 366.0}],
                    system_frequencies=np.tile([170.0, 350.0], (10, 1)),
                    system_crossings=[{"order": 30.0, "mode": 0, "speed_rpm": 340.0, "frequency_hz": 170.0}])


def axis_labels(figure):
    return [label for ax in figure.axes for label in (ax.get_xlabel(), ax.get_ylabel())]


def test_the_time_history_shows_the_steady_window_of_the_wing_amplitude(figures):
    run = histories()
    plots.plot_time_history(run, "unused.png")
    (figure,) = figures
    steady = steady_part(len(run.time))
    revolutions = run.crank_angle[steady] / (2 * np.pi)
    for c, ax in enumerate(figure.axes):
        lines = ax.get_lines()
        assert all(np.array_equal(line.get_xdata(), revolutions) for line in lines)
        torsion = lines[2].get_ydata()
        # the black line is the torsion the amplitude is defined on: half its peak-to-peak is it
        assert 0.5 * np.ptp(torsion) == pytest.approx(1e3 * run.wing_amplitude[c], rel=1e-12)
        assert f"raw amplitude {1e3 * run.wing_amplitude[c]:.3g} µm" in lines[2].get_label()
        # the transient (50 µm at the start) is not drawn: the axis is scaled to the steady part
        assert max(abs(v) for v in ax.get_ylim()) < 10.0
    assert "second half" in figure.axes[0].get_title() and "uncalibrated" in figure.axes[0].get_title()
    assert "wing amplitude" in figure.axes[0].get_title()
    # whether that half is steady is said: this synthetic run is too short to tell
    assert run.unsettled_change is None and "NOT STEADY" in figure.axes[0].get_title()


def test_every_axis_of_the_mbs_plots_has_a_unit_and_micrometres_are_µm(figures):
    run = histories()
    spectrum = Spectrum(np.linspace(0.0, 500.0, 50), np.full((50, 2), 1e-3))
    plots.plot_time_history(run, "unused.png")
    plots.plot_spectrum(spectrum, "unused.png")
    plots.plot_spectrum(spectrum, "unused.png", xlabel="engine order (cycles per revolution)")
    plots.plot_campbell(campbell([0.5, 1.0, 30.0]), "unused.png", operating_rpm=750.0)
    plots.plot_sweep([600.0, 700.0], np.array([[1e-3, 2e-3], [3e-3, 1e-3]]), "unused.png")
    labels = [label for figure in figures for label in axis_labels(figure) if label]
    assert len(labels) == 2 * 2 + 2 + 2 + 2 + 2 - 1  # the time history's upper x axis is shared
    assert "raw" in figures[-1].axes[0].get_ylabel()  # the sweep's amplitudes are the model's own
    for label in labels:
        assert UNIT.search(label), label
        assert "um" not in label.replace("µm", ""), label


def test_the_campbell_legend_names_modes_orders_crossings_and_the_operating_speed(figures):
    plots.plot_campbell(campbell(list(np.arange(1, 13) * 0.5) + [30.0]), "unused.png", operating_rpm=750.0)
    labels = [text.get_text() for text in figures[0].axes[0].get_legend().get_texts()]
    assert labels == ["CW modes, interface held (3)", "coupled multibody model modes (2)",
                      "engine orders 0.5 … 6 (12, no crossing; zoomed below)", "engine order 30 (f = 30 · rpm / 60)",
                      "order crosses a CW mode", "order crosses a coupled mode (a crossing, not a shown resonance)",
                      "operating speed 750 rpm"]


def test_a_few_engine_orders_each_get_their_own_legend_entry(figures):
    plots.plot_campbell(campbell([0.5, 1.0, 30.0]), "unused.png")
    labels = [text.get_text() for text in figures[0].axes[0].get_legend().get_texts()]
    assert [label for label in labels if label.startswith("engine order")] == [
        "engine order 0.5 (f = 0.5 · rpm / 60)", "engine order 1 (f = 1 · rpm / 60)",
        "engine order 30 (f = 30 · rpm / 60)"]


def test_the_campbell_legend_counts_the_coupled_modes_that_were_found(figures):
    # as a sweep stores them: one column per mode, NaN where a speed's solve found fewer; a
    # column no speed found is not a mode (`mbs` and `sweep` counted 23 and 24 of one model)
    diagram = campbell([0.5, 1.0, 30.0])
    system = np.full((10, 4), np.nan)
    system[:, :2] = diagram.system_frequencies
    system[3:, 2] = 500.0  # found at the higher speeds only
    plots.plot_campbell(replace(diagram, system_frequencies=system), "unused.png")
    ax = figures[0].axes[0]
    assert "coupled multibody model modes (3)" in [text.get_text() for text in ax.get_legend().get_texts()]
    assert sum(line.get_color() == "0.6" for line in ax.get_lines()) == 3


def test_many_quiet_engine_orders_are_zoomed_and_each_named(figures):
    """Twelve gas-torque orders under 100 Hz beside modes up to 860 Hz: a panel of their own,
    scaled to them, each line named by its order at its right end."""
    plots.plot_campbell(campbell(list(np.arange(1, 13) * 0.5) + [30.0]), "unused.png", operating_rpm=750.0)
    main, zoom = figures[0].axes
    assert zoom.get_ylim()[1] == pytest.approx(1.1 * 6 * 1000.0 / 60.0)
    named = sorted(float(text.get_text()) for text in zoom.texts)
    assert named[-1] == 6.0 and len(named) >= 6  # every order, or every other when they crowd
    assert zoom.get_xlabel() == "engine speed (rpm)" and main.get_ylim()[1] > 800.0


def test_the_time_history_names_scene_speed_and_the_calibrated_amplitude(figures):
    run = histories()
    plots.plot_time_history(run, "unused.png", scene="user_joint", calibration=1000.0)
    (figure,) = figures
    title = figure.axes[0].get_title()
    assert title.startswith("user_joint: wing tips at 750 rpm") and "calibration" in title  # 12.5 rev/s
    torsion = figure.axes[0].get_lines()[2].get_label()
    assert f"→ {1e3 * 1000.0 * run.wing_amplitude[0]:.3g} µm" in torsion
    legend = figure.axes[0].get_legend()
    assert legend.get_bbox_to_anchor().x0 > figure.axes[0].get_window_extent().x1 - 1  # beside the traces


def test_a_crossing_is_a_resonance_only_where_the_sweep_amplitude_peaks(figures):
    speeds = [600.0, 700.0, 800.0, 900.0]
    amplitude = np.array([[1e-4], [3e-4], [2e-4], [1e-4]])  # mm, a peak at 700 rpm
    plots.plot_sweep(speeds, amplitude, "unused.png", crossings_rpm=[690.0, 880.0], calibration=1000.0)
    ax = figures[0].axes[0]
    labels = [text.get_text() for text in ax.get_legend().get_texts()]
    assert "order/mode crossing at an amplitude peak (resonance)" in labels
    assert "order/mode crossing (no amplitude peak in the sweep)" in labels
    assert "raw" in ax.get_ylabel() and "uncalibrated" in ax.get_title()
    (scene_axis,) = ax.child_axes  # the scene's wing amplitude: the raw one × the calibration
    assert "calibration 1000" in scene_axis.get_ylabel()
    figures[0].canvas.draw()  # a secondary axis takes its limits when drawn
    low, high = ax.get_ylim()
    assert scene_axis.get_ylim() == pytest.approx((1000.0 * low, 1000.0 * high))
