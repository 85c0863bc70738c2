"""Automatic choice of executor and chunk size from the measured cost of one run (issue 16)."""

from __future__ import annotations

import functools
import os
import time

import pytest
import sweep_funcs as f

from afmforce.sweep import build_spec, run_sweep
from afmforce.sweep.autoplan import CLUSTER_START_SECONDS, PARALLEL_EFFICIENCY, TARGET_CHUNK_SECONDS, plan_execution
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
