"""Independent cases on dask.distributed: same results as in-process, a worker killed mid-sweep
costs a re-run and nothing else, a failing case is reported while the rest complete, an
unreachable scheduler is bad input."""

import argparse
import math
import os
import time

import numpy as np
import pytest

import pipelines.parallel as distributed
from pipelines.cli.mbs import add_sweep_parser
from mbs.parameters import ModelParams, SolverParams
from pipelines.jobs.sweep import speed_sweep
from pipelines.parallel import CaseOutcome, add_cluster_arguments, cluster, map_cases
from reduction.errors import InputError


def cubic(x, offset=0.0):
    """A case that takes long enough (0.2 s) for both workers to hold cases at once."""
    time.sleep(0.2)
    return x ** 3 + offset


def cubic_killing_its_worker_once(x, victim, marker):
    """The first time case `victim` runs, its worker process dies abruptly (no cleanup)."""
    if x == victim and not os.path.exists(marker):
        with open(marker, "w"):
            pass
        os._exit(1)
    return cubic(x)


def ignores_ctrl_c_after_killing_its_worker_once(x, victim, marker):
    """Whether this case's worker ignores SIGINT; case `victim` kills its worker the first time."""
    import signal

    if x == victim and not os.path.exists(marker):
        with open(marker, "w"):
            pass
        os._exit(1)
    time.sleep(0.2)
    # ignored once the worker has joined (the plugin), and blocked since the process was born:
    # a Ctrl-C while a restarted worker still imports must not reach it either
    return signal.getsignal(signal.SIGINT) == signal.SIG_IGN and signal.SIGINT in signal.pthread_sigmask(
        signal.SIG_BLOCK, [])


def cubic_refusing_two(x):
    if x == 2:
        raise ValueError("x = 2 is out of range")
    return cubic(x)


def test_two_workers_give_the_serial_results_in_case_order():
    cases = [(f"case {x}", {"x": x}) for x in (3, 1, 4, 1, 5)]
    parallel = map_cases(cubic, cases, workers=2, progress=False, shared={"offset": 0.5})
    serial = map_cases(cubic, cases, workers=0, progress=False, shared={"offset": 0.5})
    assert parallel == serial
    assert [o.key for o in parallel] == [key for key, _ in cases]
    assert [o.value for o in parallel] == [27.5, 1.5, 64.5, 1.5, 125.5]


def test_a_worker_killed_mid_sweep_has_its_case_rerun_and_every_case_is_there_once(tmp_path):
    marker = tmp_path / "killed"
    cases = [(x, {"x": x, "victim": 4, "marker": str(marker)}) for x in range(8)]
    outcomes = map_cases(cubic_killing_its_worker_once, cases, workers=2, progress=False)
    assert marker.exists()  # a worker did die
    assert [o.key for o in outcomes] == list(range(8))
    assert all(o.error is None for o in outcomes)
    assert [o.value for o in outcomes] == [x ** 3 for x in range(8)]
    assert outcomes[4].attempts == 2  # the scheduler saw the death and re-ran the case


@pytest.mark.parametrize("kept", [False, True], ids=["map_cases' own cluster", "one cluster for rounds"])
def test_a_worker_started_anew_ignores_ctrl_c_too(tmp_path, kept):
    """Ctrl-C goes to the client alone, which closes the cluster: a worker the nanny restarts
    after its process died must ignore SIGINT like the first ones (it printed a
    KeyboardInterrupt traceback when a limit search, whose rounds share one cluster, was
    interrupted), and from its start (SIGINT blocked), not only once it has joined."""
    marker = tmp_path / "killed"
    cases = [(x, {"x": x, "victim": 1, "marker": str(marker)}) for x in range(6)]
    if kept:
        with cluster(workers=2) as where:
            outcomes = map_cases(ignores_ctrl_c_after_killing_its_worker_once, cases, progress=False, **where)
    else:
        outcomes = map_cases(ignores_ctrl_c_after_killing_its_worker_once, cases, workers=2, progress=False)
    assert marker.exists() and outcomes[1].attempts == 2  # a worker did die and was replaced
    assert [o.value for o in outcomes] == [True] * 6


def test_a_failing_case_is_reported_and_the_others_complete():
    with cluster(workers=2) as where:  # one cluster for two calls, reached by its address
        assert where["scheduler"].startswith("tcp://127.0.0.1:")
        outcomes = map_cases(cubic_refusing_two, [(x, {"x": x}) for x in range(4)], progress=False, **where)
        again = map_cases(cubic_refusing_two, [(5, {"x": 5})], progress=False, **where)
    assert outcomes[2] == CaseOutcome(2, None, "ValueError: x = 2 is out of range", 1)
    assert [o.value for o in outcomes if o.key != 2] == [0, 1, 27]
    assert again == [CaseOutcome(5, 125, None, 1)]
    serial = map_cases(cubic_refusing_two, [(2, {"x": 2})], workers=0, progress=False)
    assert serial[0].error == "ValueError: x = 2 is out of range"


def test_bad_cluster_settings_are_named(monkeypatch):
    from distributed import LocalCluster

    monkeypatch.setattr(distributed, "CONNECT_TIMEOUT_S", 0.5)
    with LocalCluster(n_workers=0, dashboard_address=None,
                      scheduler_kwargs={"dashboard_address": "127.0.0.1:0"}) as empty:
        with pytest.raises(InputError, match="the scheduler has no workers"):
            map_cases(cubic, [(1, {"x": 1}), (2, {"x": 2})], scheduler=empty.scheduler_address)
    with pytest.raises(InputError, match="--workers -1"):
        map_cases(cubic, [(1, {"x": 1})], workers=-1)
    with pytest.raises(InputError, match="tcp://HOST:PORT"):
        map_cases(cubic, [(1, {"x": 1})], scheduler="localhost")
    with pytest.raises(InputError, match="give one of the two"):
        map_cases(cubic, [(1, {"x": 1})], scheduler="tcp://127.0.0.1:1", workers=2)
    parser = argparse.ArgumentParser()
    add_cluster_arguments(parser)
    args = parser.parse_args(["--scheduler", "tcp://10.0.0.5:8786", "--workers", "3"])
    assert (args.scheduler, args.workers) == ("tcp://10.0.0.5:8786", 3)


TINY_SCENE = '[mbs]\nn_modes = 2\neffects = ["gear_mesh"]\n[mbs.solver]\nrevolutions = 0.5\ntime_step = 1e-4\n'


def test_cli_sweep_with_an_unreachable_scheduler_exits_2_naming_it(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(distributed, "CONNECT_TIMEOUT_S", 1.0)
    scene = tmp_path / "scene.toml"
    scene.write_text(TINY_SCENE)
    parser = argparse.ArgumentParser()
    add_sweep_parser(parser.add_subparsers())
    out = tmp_path / "sweep.h5"
    args = parser.parse_args(["sweep", str(scene), "--speeds", "700,750", "--out", str(out),
                              "--scheduler", "tcp://127.0.0.1:1"])
    assert args.handler(args) == 2
    error = capsys.readouterr().err
    assert "--scheduler tcp://127.0.0.1:1: no dask scheduler answered" in error
    assert "Traceback" not in error and not out.exists()


def test_mbs_sweep_on_two_workers_equals_the_serial_sweep():
    params = ModelParams(n_modes=2, effects=frozenset({"gear_mesh"}),
                         solver=SolverParams(revolutions=0.5, time_step=1e-4))
    parallel = speed_sweep(params, [700.0, 750.0], workers=2)
    serial = speed_sweep(params, [700.0, 750.0], workers=0)
    assert not parallel.failures and not serial.failures
    for name in ("wing_amplitude", "dominant_frequencies", "dominant_orders", "system_frequencies"):
        np.testing.assert_array_equal(getattr(parallel, name), getattr(serial, name), err_msg=name)
    assert np.all(parallel.wing_amplitude > 0)


def test_accuracy_study_records_do_not_depend_on_where_the_runs_ran(coarse_cylinder):
    from pipelines.studies.accuracy import accuracy_study

    sweeps = {"contact_size": [0.2], "increments_per_cycle": [12, 6], "normal_stiffness": [4.0e6, 4.0e5],
              "critical_slip": [1.0e-3], "cycle_jump": [1000.0]}
    parallel = accuracy_study(coarse_cylinder, quick=True, sweeps=sweeps, workers=2)
    serial = accuracy_study(coarse_cylinder, quick=True, sweeps=sweeps, workers=0)
    assert len(parallel.records) == len(serial.records) == 3
    for ours, theirs in zip(parallel.records, serial.records):
        for costs in (ours, theirs):
            del costs["wall_time_s"], costs["cpu_time_s"]
        assert_same(ours, theirs)
    assert parallel.recommendation["label"] == serial.recommendation["label"]


def assert_same(ours, theirs, where="record"):
    """Equal to the bit: a case gives the same bits in a worker as in this process (issue 13;
    before it, the clock-driven preconditioner and BLAS threads changed the last digits)."""
    if isinstance(ours, dict):
        assert ours.keys() == theirs.keys(), where
        for key in ours:
            assert_same(ours[key], theirs[key], f"{where}.{key}")
    elif isinstance(ours, float):
        assert ours == theirs or (math.isnan(ours) and math.isnan(theirs)), f"{where}: {ours!r} != {theirs!r}"
    else:
        assert ours == theirs, where


def test_the_cluster_logs_are_silenced_unless_asked_for(monkeypatch):
    import logging

    from pipelines.parallel import _cluster_log_level

    monkeypatch.delenv("FRETWORK_DASK_LOGS", raising=False)
    assert _cluster_log_level() > logging.CRITICAL  # the scheduler's CRITICAL lines at a Ctrl-C too
    monkeypatch.setenv("FRETWORK_DASK_LOGS", "1")
    assert _cluster_log_level() == logging.WARNING


def test_a_case_the_cluster_gave_up_on_without_an_exception_is_said_in_words():
    """A future that did not finish and has no exception read 'NoneType: None' in the limit
    search's error (QA, 2026-11-28); the search then stops as a stopped simulation (exit 1)."""
    from contact.solver import ConvergenceError
    from pipelines.jobs import limit
    from pipelines.parallel import _describe

    said = _describe(None, "lost")
    assert said.startswith("it did not finish on the cluster (its state: lost)") and "None" not in said
    assert _describe(ValueError("x = 2 is out of range")) == "ValueError: x = 2 is out of range"

    def lost(function, cases, **_):  # every case comes back as the cluster gave up on it
        return [CaseOutcome(key, None, said, 1) for key, _ in cases]

    with pytest.raises(ConvergenceError, match="the run at 100.0 µm failed \\(it did not finish on the cluster"):
        limit._search("scene.toml", 0.1, 0.4, 0.05, 3, None, None, None, {}, False, lost)
