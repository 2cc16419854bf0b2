"""Interface-histories files: round trips and the checks of units, columns and sampling."""

from __future__ import annotations

import numpy as np
import pytest

from mbs.histories_file import (
    InterfaceHistories,
    read_interface_histories,
    write_interface_histories,
)
from reduction.errors import InputError


def _histories(n=40, step=1e-4):
    time = 0.1 + step * np.arange(n)
    wave = np.sin(2 * np.pi * 350.0 * time)
    vector = np.column_stack([wave, 2 * wave, -wave])
    return InterfaceHistories(750.0, time, 1e5 * vector, 78.5 + vector, 1e3 * vector, 0.01 * wave,
                              np.zeros((n, 0)), np.zeros((n, 0)), np.zeros((n, 0)), None)


@pytest.mark.parametrize("suffix", ["h5", "csv"])
def test_histories_written_and_read_back_are_the_same_numbers(tmp_path, suffix):
    written = _histories()
    read = read_interface_histories(write_interface_histories(tmp_path / f"cw.{suffix}", written))
    for name in ("time", "frame_acceleration", "angular_velocity", "angular_acceleration", "wing_torsion"):
        np.testing.assert_array_equal(getattr(read, name), getattr(written, name))
    assert read.speed_rpm == 750.0 and read.modes is None


def _csv(tmp_path, text):
    path = tmp_path / "other_code.csv"
    path.write_text("# format = fretwork-interface-histories\n# format_version = 1\n# speed_rpm = 750\n" + text)
    return path


HEADER = ("time [ms],frame_acceleration:x [m/s^2],frame_acceleration:y [m/s^2],frame_acceleration:z [m/s^2],"
          "angular_velocity:x [rpm],angular_velocity:y [rpm],angular_velocity:z [rpm],"
          "angular_acceleration:x [deg/s^2],angular_acceleration:y [deg/s^2],angular_acceleration:z [deg/s^2],"
          "wing_torsion [um]\n")


def _rows(times):
    return "".join(f"{t:g},1,2,3,0,0,750,0,0,180,5\n" for t in times)


def test_units_of_another_code_are_converted(tmp_path):
    read = read_interface_histories(_csv(tmp_path, HEADER + _rows(np.arange(10) * 0.1)))
    np.testing.assert_allclose(read.time[1], 1e-4)
    np.testing.assert_allclose(read.frame_acceleration[0], [1e3, 2e3, 3e3])
    np.testing.assert_allclose(read.angular_velocity[0, 2], 750 * 2 * np.pi / 60)
    np.testing.assert_allclose(read.angular_acceleration[0, 2], np.pi)
    np.testing.assert_allclose(read.wing_torsion[0], 5e-3)


@pytest.mark.parametrize("header, times, message", [
    (HEADER.replace(",wing_torsion [um]", "").replace("angular_velocity:z [rpm],", ""), None,
     "missing column|components x, y, z"),
    (HEADER.replace("[m/s^2]", "[furlongs]"), None, "unknown unit 'furlongs' of 'frame_acceleration'"),
    (HEADER, np.r_[np.arange(5), np.arange(6, 11)] * 0.1, "non-uniform time step.*between samples 5 and 6"),
])
def test_bad_files_are_one_clear_error(tmp_path, header, times, message):
    times = np.arange(10) * 0.1 if times is None else times
    columns = header.count(",") + 1
    rows = "".join(",".join([f"{t:g}"] + ["1"] * (columns - 1)) + "\n" for t in times)
    with pytest.raises(InputError, match=message):
        read_interface_histories(_csv(tmp_path, header + rows))


def test_a_file_without_wing_torsion_or_modes_is_refused(tmp_path):
    from mbs.histories_file import to_loading

    header = HEADER.replace(",wing_torsion [um]", "")
    rows = "".join(f"{t:g},1,2,3,0,0,750,0,0,180\n" for t in np.arange(10) * 0.1)
    with pytest.raises(InputError, match="needs a 'wing_torsion' column or modal coordinates"):
        to_loading(read_interface_histories(_csv(tmp_path, header + rows)))
