"""Choose where a sweep runs and how big its chunks are, from the measured cost of one run.

A local Dask cluster costs seconds to start and to load the compiled (numba)
code in every worker; a sweep that finishes in this process sooner than that
should not start one. :func:`plan_execution` times runs of the swept function
in this process: one row, or a few rows spread over the table (run costs vary
with the parameters: a Fig-5 run at 0.1 um/s takes twice one at 2 um/s), the
first call once more (it may load or compile code: 2.3 s in a fresh process
for a 20 ms run) unless it was long and the sweep short; the cost of a run is
their mean. It then compares

* serial:  ``n_runs * t_run`` (divided by ``PARALLEL_EFFICIENCY * threads`` for a
  batched function that integrates on threads, e.g. ``simulate_run``)
* cluster: ``CLUSTER_START_SECONDS + n_runs * t_run / (PARALLEL_EFFICIENCY * workers)``

and picks the faster. Chunks are sized from the measured cost as well: on a
cluster, about ``TARGET_CHUNK_SECONDS`` each (so that scheduling overhead stays
small and a killed sweep loses little) with at least ``MIN_CHUNKS_PER_WORKER``
chunks per worker (so that the load balances); in this process a batched
function gets chunks of about ``TARGET_CHUNK_SECONDS`` of work on its threads
and at least ``MIN_RUNS_PER_THREAD`` runs per thread (a chunk is one batch: with
3 runs on 2 threads one thread idles a third of the time), an unbatched one the
default size (progress granularity). The timing runs are done once more than
the sweep asks for; their results are discarded (the swept function must be
pure, which :func:`~afmforce.sweep.run_sweep` already requires). They also
leave the numba cache written, so that cluster workers load it instead of each
compiling the same code.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any, Callable, Sequence

__all__ = ["ExecutionPlan", "plan_execution", "CLUSTER_START_SECONDS", "TARGET_CHUNK_SECONDS",
           "MIN_RUNS_PER_THREAD"]

#: Seconds to start a local cluster and warm its workers: measured 4.2 s to start 2 workers
#: plus about 0.7 s per worker to load the dynamics' numba cache on the 2-core development
#: machine (benchmarks/bench_sweep.py prints the figure of the machine it runs on).
CLUSTER_START_SECONDS = 5.0
#: Fraction of ideal speed-up a local cluster reaches (1.84x on 2 workers measured for issue 7).
PARALLEL_EFFICIENCY = 0.9
#: Wall time aimed at per chunk on a cluster [s].
TARGET_CHUNK_SECONDS = 1.0
#: At least this many chunks per worker on a cluster.
MIN_CHUNKS_PER_WORKER = 4
#: Largest chunk (runs).
MAX_CHUNK = 256
#: At least this many runs per thread in a chunk of a batched function run in this process.
MIN_RUNS_PER_THREAD = 4
#: A first call longer than this [s] is taken as the cost of a run (no second timing call) ...
_RETIME_BELOW = 2.0
#: ... in a sweep of fewer runs than this (in a longer one, one extra run is a small share of it and
#: the first call may have been mostly loading compiled code: 2.3 s for a 20 ms Fig-5 run).
_RETIME_RUNS = 20


@dataclass(frozen=True)
class ExecutionPlan:
    """Where a sweep runs and with which chunk size, and why.

    Attributes
    ----------
    executor : {"serial", "dask"}
        In this process, or on a local Dask cluster.
    chunk_size : int
        Runs per chunk.
    seconds_per_run : float or None
        Measured cost of one run [s]; None when the timing run raised.
    serial_estimate, cluster_estimate : float or None
        Predicted wall time [s] of the two choices.
    reason : str
        One line for the user.
    """

    executor: str
    chunk_size: int
    seconds_per_run: float | None
    serial_estimate: float | None
    cluster_estimate: float | None
    reason: str


def _time_calls(calls: Sequence[Callable[[], Any]], n_runs: int) -> float | None:
    """Mean seconds of one call over ``calls``, over the calls that did not raise (None: all raised).

    The first call may load or compile code (seconds in a fresh process: the numba cache), so
    it is timed again, unless it took ``_RETIME_BELOW`` or more and the sweep is so short
    (fewer than ``_RETIME_RUNS`` runs) that an extra run would cost a noticeable share of it.
    A call that raises (a file without its calibration among a folder's) says nothing of the
    others' cost: it is left out (the sweep itself records the error of each run).
    """
    def timed(call) -> float | None:
        t0 = time.perf_counter()
        try:
            call()
        except Exception:
            return None
        return time.perf_counter() - t0

    first = timed(calls[0])
    if first is not None and first >= _RETIME_BELOW and n_runs < _RETIME_RUNS:
        return first
    times = [t for t in map(timed, calls) if t is not None]
    return sum(times) / len(times) if times else None


def plan_execution(call: Callable[[], Any] | Sequence[Callable[[], Any]], n_runs: int, workers: int, *,
                   chunk_size: int | None = None, default_chunk_size: int = 1,
                   serial_threads: int = 1, cluster_start: float = CLUSTER_START_SECONDS) -> ExecutionPlan:
    """Time ``call()`` (representative runs) and plan the sweep of ``n_runs`` runs.

    Parameters
    ----------
    call : callable or sequence of callables
        One run of the swept function, or a few (e.g. on rows spread over the
        table); the cost of a run is their mean.
    n_runs : int
        Runs still to do.
    workers : int
        Worker processes a local cluster would have.
    chunk_size : int, optional
        Chunk size fixed by the user or by a resumed store; kept as it is.
    default_chunk_size : int
        Chunk size to use in this process (progress granularity).
    serial_threads : int
        Threads a run in this process uses (a batched function, e.g.
        :func:`~afmforce.sweep.simulation.simulate_run`, integrates on one thread
        per core): the serial estimate is divided by
        ``PARALLEL_EFFICIENCY * serial_threads`` when above 1.
    cluster_start : float
        Seconds to start the cluster and warm its workers (default
        :data:`CLUSTER_START_SECONDS`, the dynamics'; an analysis imports more).

    Returns
    -------
    ExecutionPlan
    """
    t_run = _time_calls([call] if callable(call) else list(call), n_runs)
    if t_run is None:
        size = chunk_size or default_chunk_size
        return ExecutionPlan("serial" if workers <= 1 else "dask", size, None, None, None,
                             "the timing run raised; errors are recorded per run")
    serial = n_runs * t_run / (PARALLEL_EFFICIENCY * serial_threads if serial_threads > 1 else 1.0)
    cluster = cluster_start + n_runs * t_run / (PARALLEL_EFFICIENCY * max(1, workers))
    if workers <= 1 or serial <= cluster:
        why = ("one worker" if workers <= 1 else
               f"{n_runs} runs x {t_run * 1e3:.3g} ms" + (
                   f" on {serial_threads} threads" if serial_threads > 1 else "") +
               f" = {serial:.3g} s serial <= {cluster:.3g} s on a "
               f"{workers}-worker cluster (incl. {cluster_start:g} s start)")
        if chunk_size is None:
            chunk_size = default_chunk_size
            if serial_threads > 1:  # a chunk is one batch on the threads: keep them all busy
                by_time = round(TARGET_CHUNK_SECONDS * PARALLEL_EFFICIENCY * serial_threads / max(t_run, 1e-9))
                chunk_size = max(default_chunk_size, MIN_RUNS_PER_THREAD * serial_threads, by_time)
                chunk_size = int(min(MAX_CHUNK, n_runs, chunk_size))
        return ExecutionPlan("serial", chunk_size, t_run, serial, cluster,
                             f"in this process: {why}; {chunk_size} runs per chunk")
    if chunk_size is None:
        by_time = max(1, round(TARGET_CHUNK_SECONDS / max(t_run, 1e-9)))
        balance = max(1, math.ceil(n_runs / (MIN_CHUNKS_PER_WORKER * workers)))
        chunk_size = int(min(MAX_CHUNK, by_time, balance))
    return ExecutionPlan("dask", chunk_size, t_run, serial, cluster,
                         f"local Dask cluster of {workers} workers: {n_runs} runs x {t_run * 1e3:.3g} ms = "
                         f"{serial:.3g} s serial, about {cluster:.3g} s on the cluster; "
                         f"{chunk_size} runs per chunk")
