"""Parameter sweeps: one run of a function per row of a parameter table, in chunks.

:func:`run_sweep` groups the rows into chunks (one task per chunk, not per
run) and runs them with the shared chunk runner (:func:`~afmforce.sweep.chunks.execute`):
in this process or on Dask, chosen from the measured cost of a run
(:mod:`~afmforce.sweep.autoplan`), stored as they finish, resumed from the
store. A run that raises is recorded in its row (``error`` column) while the
others go on; a chunk that fails as a whole (worker lost, or
``errors="raise"``) is recorded with its parameters and retried by a rerun.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import os
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ..errors import ParameterError
from ..progress import Progress
from .autoplan import ExecutionPlan, plan_execution
from .chunks import _check_errors, _error_text, _func_name, _open_store, default_chunk_size, execute, flatten
from .executors import available_cores
from .results import SweepResult
from .spec import SweepSpec
from .store import SweepStore

__all__ = ["run_sweep", "table_key"]

#: Rows timed by the automatic plan of a long sweep (first, middle, last).
TIMED_ROWS = 3


def _call_row(func: Callable, kwargs: dict, record_errors: bool) -> dict:
    try:
        row = flatten(func(**kwargs))
        clash = sorted(set(row) & set(kwargs))
        if clash:
            raise ParameterError(f"output(s) {clash} have the name of a parameter; rename them")
    except Exception as exc:
        if not record_errors:
            raise
        return {"error": _error_text(exc)}
    row["error"] = None
    return row


def _stored(result) -> Callable:
    """A function of any kwargs returning (or raising) a result already computed."""
    def call(**_):
        if isinstance(result, BaseException):
            raise result
        return result
    return call


def _parameter_chunk(func: Callable, runs: list[int], columns: dict[str, list], record_errors: bool):
    """Run one chunk of a sweep (executes on a worker). Returns a DataFrame indexed by run.

    A ``func`` with a ``batch`` attribute (e.g. :func:`~afmforce.sweep.simulation.simulate_run`)
    runs the whole chunk in one ``func.batch(list of kwargs)`` call, which returns one
    result (or the exception of a failed run) per row.
    """
    import pandas as pd

    kwargs_list = [{name: values[i] for name, values in columns.items()} for i in range(len(runs))]
    batch = getattr(func, "batch", None)
    calls = [_stored(r) for r in batch(kwargs_list)] if batch is not None else [func] * len(runs)
    outs = [_call_row(call, kwargs, record_errors) for call, kwargs in zip(calls, kwargs_list)]
    rows = [{"run": run, **kwargs, **out} for run, kwargs, out in zip(runs, kwargs_list, outs)]
    return pd.DataFrame(rows).set_index("run")


def _table(parameters):
    import pandas as pd

    if isinstance(parameters, SweepSpec):
        return parameters.table()
    if isinstance(parameters, pd.DataFrame):
        table = parameters.reset_index(drop=True)
    elif isinstance(parameters, Mapping):
        table = pd.DataFrame(dict(parameters))
    else:
        table = pd.DataFrame(list(parameters))
    table.index.name = "run"
    if table.empty:
        raise ParameterError("the parameter table has no runs")
    return table


def table_key(func: Callable, table) -> str:
    """Hash of the function's name and the parameter table (values, columns, dtypes)."""
    import pandas as pd

    h = hashlib.sha256(_func_name(func).encode())
    h.update(json.dumps([list(map(str, table.columns)), [str(t) for t in table.dtypes]]).encode())
    h.update(pd.util.hash_pandas_object(table, index=True).to_numpy().tobytes())
    return h.hexdigest()


def _warm_call(func: Callable, kwargs: dict) -> None:
    """One run on a worker before its first chunk (loads compiled code); errors are ignored.
    The workers compile side by side already: no compile helper process each
    (:mod:`afmforce.dynamics._helper`)."""
    os.environ["AFMFORCE_COMPILE_HELPER"] = "0"
    try:
        func(**kwargs)
    except Exception:
        pass


def _resumed(store, key: str) -> tuple[int | None, int]:
    """(chunk size, chunks done) of a store that already exists for ``key``, else (None, 0)."""
    if store is None:
        return None, 0
    opened = store if isinstance(store, SweepStore) else SweepStore(Path(store) / f"sweep-{key[:12]}")
    manifest = opened.manifest()
    if manifest is None:
        return None, 0
    return int(manifest["chunk_size"]), len(opened.completed())


def _auto_plan(func, table, key: str, store, chunk_size, workers) -> ExecutionPlan:
    n = len(table)
    fixed, done = _resumed(store, key)
    fixed = chunk_size or fixed
    remaining = n - done * (fixed or 0) if fixed else n
    if remaining <= 0:  # everything stored: nothing to time
        return ExecutionPlan("serial", fixed or default_chunk_size(n), None, 0.0, None, "all chunks stored")
    # time rows spread over the table (costs vary with the parameters) when the sweep is long
    # enough for the extra timing runs not to matter (at most ~5 % of its runs)
    positions = sorted({0, n // 2, n - 1}) if remaining >= 20 * TIMED_ROWS else [0]
    calls = [functools.partial(func, **_row(table, i)) for i in positions]
    # a batched function says how many threads its runs use in this process
    threads = int(func.batch_threads()) if callable(getattr(func, "batch_threads", None)) else 1
    return plan_execution(calls, max(1, remaining), workers or available_cores(),
                          chunk_size=fixed, default_chunk_size=default_chunk_size(n),
                          serial_threads=threads)


def _row(table, i: int) -> dict:
    row = {c: table[c].iloc[i] for c in table.columns}
    return {k: (v.item() if isinstance(v, np.generic) else v) for k, v in row.items()}


def run_sweep(func: Callable[..., Any], parameters, *, chunk_size: int | None = None, executor="auto",
              workers: int | None = None, scheduler: str | None = None, store=None,
              progress: Callable[[Progress], None] | None = None, errors: str = "record",
              key: str | None = None) -> SweepResult:
    """Run ``func(**row)`` for every row of a parameter table, in chunks.

    Parameters
    ----------
    func : callable
        A pure, module-level (picklable) function returning a mapping of
        scalars (nested mappings are flattened to ``"a.b"`` columns).
    parameters : SweepSpec, DataFrame, mapping of columns or list of dicts
        One row per run.
    chunk_size : int, optional
        Runs per chunk (default :func:`default_chunk_size`; a resumed store keeps its own).
    executor : "auto", "serial", "dask", SerialExecutor, DaskExecutor, distributed.Client, optional
        ``"auto"`` (default): time runs here (one, or three spread over a long
        table: they are done once more than asked) and run in this process when
        that finishes sooner than starting a local cluster, else on a local Dask
        cluster of ``workers`` processes (one per core); chunks are sized from the
        measured cost in both cases (:func:`~afmforce.sweep.autoplan.plan_execution`).
        ``"dask"``: always a local cluster, or the cluster at ``scheduler``
        (``tcp://host:port``, also the choice when a scheduler is given).
    store : path or SweepStore, optional
        Parent folder of the resumable store (a sub-folder keyed by a hash of
        ``func`` and the table is created); without it nothing is written.
    progress : callable, optional
        Called with a :class:`~afmforce.progress.Progress` (unit ``"chunk"``,
        runs as items) at the start and after every chunk.
    errors : {"record", "raise"}
        ``"record"``: a run that raises gets its error in the ``error`` column.
        ``"raise"``: it fails its whole chunk (recorded, retried by a rerun).
    key : str, optional
        Store key; default a hash of ``func``'s name and the table.

    Returns
    -------
    SweepResult
    """
    _check_errors(errors)
    spec = parameters if isinstance(parameters, SweepSpec) else None
    table = _table(parameters)
    n = len(table)
    key = key or table_key(func, table)
    plan = None
    if executor is None or executor == "auto":
        if scheduler is None:
            plan = _auto_plan(func, table, key, store, chunk_size, workers)
            executor, chunk_size = plan.executor, plan.chunk_size if chunk_size is None else chunk_size
        else:
            executor = "dask"
    manifest = {"function": _func_name(func), "n_items": n, "spec": spec.to_dict() if spec else None}
    store, size = _open_store(store, key, manifest, "sweep", chunk_size, n)
    n_chunks = math.ceil(n / size)
    columns = {c: table[c].tolist() for c in table.columns}

    def runs(i: int) -> range:
        return range(i * size, min(n, (i + 1) * size))

    def make_tasks(skipped: set[int]):
        for i in range(n_chunks):
            if i not in skipped:
                chunk = {c: v[i * size:(i + 1) * size] for c, v in columns.items()}
                yield i, (func, list(runs(i)), chunk, errors == "record"), len(runs(i))

    def describe(i: int, failed: bool):
        if not failed:
            return None, None
        return list(runs(i)), [{"run": r, **{c: v[r] for c, v in columns.items()}} for r in runs(i)]

    row0 = {c: v[0] for c, v in columns.items()}
    done = execute(_parameter_chunk, make_tasks, executor=executor, workers=workers, scheduler=scheduler,
                   store=store, totals=(n_chunks, n), progress=progress, describe=describe,
                   before=lambda s: s.write_parameters(table), warmup=functools.partial(_warm_call, func, row0))
    described = done.executor
    if plan is not None and done.chunks_run:
        described = f"{done.executor}; chosen automatically: {plan.reason}"
    return SweepResult.assemble(
        table, done.frames if store is None else store, spec=spec, failures=done.failures,
        chunks_total=n_chunks, chunks_run=done.chunks_run, chunks_skipped=done.chunks_skipped,
        wall_time=done.wall_time, executor=described,
    )
