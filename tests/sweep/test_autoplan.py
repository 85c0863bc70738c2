"""Automatic choice of executor and chunk size from the measured cost of one run (issue 16)."""

from __future__ import annotations

import functools
import os
import time

import pytest
import sweep_funcs as f

from afmforce.sweep import build_spec, run_sweep
from afmforce.sweep.autoplan import (CLUSTER_START_SECONDS, MIN_RUNS_PER_THREAD, PARALLEL_EFFICIENCY,
                                     TARGET_CHUNK_SECONDS, plan_execution)
from afmforce.sweep.executors import DaskExecutor


def _sleeper(seconds: float) -> None:
    time.sleep(seconds)


def test_cheap_runs_stay_in_this_process():
    plan = plan_execution(functools.partial(_sleeper, 0.002), 500, workers=2, default_chunk_size=8)
    assert plan.executor == "serial" and plan.chunk_size == 8
    # the estimates are the model in the module docstring, evaluated on the measured cost
    assert plan.serial_estimate == pytest.approx(500 * plan.seconds_per_run)
    assert plan.cluster_estimate == pytest.approx(
        CLUSTER_START_SECONDS + 500 * plan.seconds_per_run / (PARALLEL_EFFICIENCY * 2))
    assert plan.serial_estimate < plan.cluster_estimate
    assert plan.seconds_per_run >= 0.002


def _raiser() -> None:
    raise ValueError("a file without its calibration")


def test_a_call_that_raises_is_left_out_of_the_timing():
    """Before: one failing item among the three timed (a folder's uncalibrated file) left the cost
    unknown ("the timing run raised") and the plan took the cluster whatever the others cost."""
    calls = [_raiser, functools.partial(_sleeper, 0.002), functools.partial(_sleeper, 0.002)]
    plan = plan_execution(calls, 500, workers=2, default_chunk_size=8)
    assert plan.seconds_per_run is not None and 0.002 <= plan.seconds_per_run < 0.2
    assert plan.executor == "serial" and "raised" not in plan.reason
    assert plan_execution([_raiser, _raiser], 500, workers=2).seconds_per_run is None


def test_costly_sweeps_go_to_a_cluster_with_chunks_sized_by_cost():
    plan = plan_execution(functools.partial(_sleeper, 0.05), 1000, workers=2)
    assert plan.executor == "dask"
    t = plan.seconds_per_run
    assert 0.05 <= t < 0.5
    # about TARGET_CHUNK_SECONDS per chunk, but at least 4 chunks per worker
    assert plan.chunk_size == min(256, round(TARGET_CHUNK_SECONDS / t), -(-1000 // 8))
    assert plan.cluster_estimate < plan.serial_estimate


def test_one_worker_is_always_serial_and_a_raising_run_is_not_timed():
    assert plan_execution(functools.partial(_sleeper, 0.05), 10_000, workers=1).executor == "serial"

    def boom():
        raise ValueError("bad row")

    plan = plan_execution(boom, 100, workers=2, default_chunk_size=4)
    assert plan.seconds_per_run is None and plan.chunk_size == 4 and "raised" in plan.reason


def test_run_sweep_default_runs_a_small_sweep_here_with_the_same_results():
    spec = build_spec(["x=1:4:4", "y=1:3:3"])
    auto = run_sweep(f.counted, spec)  # default executor="auto"
    serial = run_sweep(f.counted, spec, executor="serial")
    assert "chosen automatically" in auto.executor and "in this process" in auto.executor
    assert auto.table.equals(serial.table)


def test_auto_on_a_complete_store_times_nothing(tmp_path):
    spec = build_spec(["x=1:4:4", "y=1:3:3"])
    run_sweep(f.counted, spec, executor="serial", store=tmp_path, key="done", chunk_size=3)
    f.CALLS.clear()
    again = run_sweep(f.counted, spec, store=tmp_path, key="done")
    assert f.CALLS == [] and again.chunks_run == 0


def test_every_dask_worker_runs_the_warmup_once(dask_client, tmp_path):
    ex = DaskExecutor(client=dask_client, warmup=functools.partial(f.mark_pid, str(tmp_path)))
    outcomes = list(ex.imap_unordered(f.counted, [(i, (i, 1)) for i in range(4)]))
    assert sorted(o.value["product"] for o in outcomes) == [0, 1, 2, 3]
    workers = dask_client.run(os.getpid)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(f"pid-{pid}" for pid in workers.values())


def test_a_batched_function_on_threads_counts_them_in_the_serial_estimate():
    one = plan_execution(functools.partial(_sleeper, 0.01), 400, workers=2)
    two = plan_execution(functools.partial(_sleeper, 0.01), 400, workers=2, serial_threads=2)
    assert two.serial_estimate == pytest.approx(
        400 * two.seconds_per_run / (PARALLEL_EFFICIENCY * 2))
    assert one.serial_estimate == pytest.approx(400 * one.seconds_per_run)
    assert "on 2 threads" in two.reason


def test_a_batched_function_in_this_process_gets_chunks_sized_by_its_cost():
    # a chunk is one batch on the threads: 3 runs on 2 threads would leave one idle a third of the time
    plan = plan_execution(functools.partial(_sleeper, 0.01), 400, workers=2, serial_threads=2,
                          default_chunk_size=7)
    assert plan.executor == "serial"
    by_time = round(TARGET_CHUNK_SECONDS * PARALLEL_EFFICIENCY * 2 / plan.seconds_per_run)
    assert plan.chunk_size == min(256, 400, max(7, MIN_RUNS_PER_THREAD * 2, by_time))
    assert plan.chunk_size >= MIN_RUNS_PER_THREAD * 2 and f"{plan.chunk_size} runs per chunk" in plan.reason
    # an unbatched function in this process keeps the default (progress granularity)
    assert plan_execution(functools.partial(_sleeper, 0.01), 400, workers=2, default_chunk_size=7).chunk_size == 7


def test_the_cost_of_a_run_is_the_mean_over_the_timed_rows():
    plan = plan_execution([functools.partial(_sleeper, 0.01), functools.partial(_sleeper, 0.03)], 100, workers=2)
    assert plan.seconds_per_run >= 0.02  # the mean; one row alone would say 0.01


def test_auto_times_first_middle_and_last_row_then_runs_batched_chunks_here():
    spec = build_spec(["x=1:20:20", "y=1:5:5"])  # 100 runs
    auto = run_sweep(f.batched, spec)
    rows = spec.table()
    timed = [(rows["x"][i], rows["y"][i]) for i in (0, 0, 50, 99)]  # the first call timed twice
    assert f.CALLS[:4] == timed and len(f.CALLS) == 104
    assert "in this process" in auto.executor and auto.chunks_total < 100 // 4  # default: 50 chunks of 2
    serial = run_sweep(f.batched, spec, executor="serial", chunk_size=3)
    assert auto.table.equals(serial.table)


class _SlowFirst:
    """A run whose first call loads code (``first`` s), the later ones ``then`` s."""

    def __init__(self, first: float, then: float) -> None:
        self.calls, self.first, self.then = 0, first, then

    def __call__(self) -> None:
        self.calls += 1
        time.sleep(self.first if self.calls == 1 else self.then)


def test_a_long_first_call_is_timed_again_unless_the_sweep_is_short(monkeypatch):
    # a fresh process loads the numba cache in its first run (2.3 s for a 20 ms Fig-5 run): taken as
    # the cost, 10,000 runs looked like 6 hours and cluster chunks shrank to one run
    from afmforce.sweep import autoplan

    monkeypatch.setattr(autoplan, "_RETIME_BELOW", 0.05)
    long_sweep = _SlowFirst(0.1, 0.002)
    plan = plan_execution(long_sweep, 1000, workers=2)
    assert long_sweep.calls == 2 and plan.seconds_per_run < 0.05
    short_sweep = _SlowFirst(0.1, 0.002)
    plan = plan_execution(short_sweep, autoplan._RETIME_RUNS - 1, workers=2)
    assert short_sweep.calls == 1 and plan.seconds_per_run >= 0.1
