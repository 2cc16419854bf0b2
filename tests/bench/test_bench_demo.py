"""Benchmark: the demo's wall time split by stage (make bench; not a pass/fail timing test).

Runs ``fretwork demo``'s job without the stage cache and prints the time of each stage:
multibody (CW reduction and run), contact model (meshing, assembly, condensation), COF and wear
phases of the operating point, amplitude limit, speed sweep.
"""

from __future__ import annotations

import os

import pytest

from pipelines.jobs.demo import run_demo


@pytest.mark.bench
def test_demo_stage_times(tmp_path):
    result = run_demo(tmp_path / "demo", cache_dir=None, progress=False)
    total = sum(result.stage_times.values())
    print(f"\ndemo stage times (machine: {os.cpu_count()} cores), total {total:.1f} s")
    print(f"{'stage':<22} {'s':>8} {'share':>7}")
    for name, seconds in result.stage_times.items():
        print(f"{name.removesuffix('_s'):<22} {seconds:8.2f} {seconds / total:7.1%}")
    print("summary:", {k: result.summary[k] for k in ("verdict", "amplitude_limit_um", "margin_at_operating_point",
                                                      "smallest_margin", "smallest_margin_speed_rpm")})
    assert result.summary["verdict"] == "stick"
    assert result.summary["amplitude_limit_um"] is not None
