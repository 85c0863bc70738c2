"""Chunked, resumable execution of sweeps and batches.

:func:`run_sweep` calls ``func(**parameters)`` once per row of a parameter
table; :func:`~afmforce.sweep.run_batch` calls ``func(item)`` once per item (file paths,
curves, ...). Both group the calls into chunks (one task per chunk, not per
call), run the chunks on an executor (a local Dask cluster by default, or the
in-process :class:`~afmforce.sweep.executors.SerialExecutor`), write each
finished chunk to a :class:`~afmforce.sweep.store.SweepStore` as it arrives,
skip the chunks a store holds already, and report progress through a
callback. A call that raises is recorded in its row (``error`` column) while
the others go on; a chunk that fails as a whole (worker lost, or
``errors="raise"``) is recorded with its parameters and retried by a rerun.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping

import numpy as np

from ..errors import ParameterError
from ..progress import Progress
from .autoplan import ExecutionPlan, plan_execution
from .executors import available_cores, make_executor
from .results import SweepResult
from .spec import SweepSpec
from .store import SweepStore

__all__ = ["Progress", "ChunkFailure", "run_sweep", "execute", "default_chunk_size", "flatten", "table_key"]

#: Arrays longer than this are refused as outputs (a sweep stores summaries).
MAX_ARRAY_OUTPUT = 16


@dataclass(frozen=True)
class ChunkFailure:
    """A chunk that raised as a whole: which items, their parameters, the error."""

    chunk: int
    items: list
    parameters: list[dict]
    error: str
    traceback: str = ""


def default_chunk_size(n_items: int | None) -> int:
    """About 64 chunks, between 1 and 256 items each (32 for an unknown length)."""
    if n_items is None:
        return 32
    return int(min(256, max(1, math.ceil(n_items / 64))))


def _plain(value: Any, name: str):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (list, tuple, np.ndarray)):
        arr = np.asarray(value)
        if arr.ndim == 0:
            return arr.item()
        if arr.size > MAX_ARRAY_OUTPUT:
            raise ParameterError(f"output {name!r} is an array of {arr.size} values; "
                                 "return scalar summaries from the swept function")
        return json.dumps(arr.tolist())
    return value


def flatten(result: Any, prefix: str = "") -> dict[str, Any]:
    """Flatten nested mappings (and dataclasses) into ``{"a.b": scalar}``."""
    if dataclasses.is_dataclass(result) and not isinstance(result, type):
        result = result.to_dict() if hasattr(result, "to_dict") else {
            f.name: getattr(result, f.name) for f in dataclasses.fields(result)}
    if not isinstance(result, Mapping):
        return {prefix or "value": _plain(result, prefix or "value")}
    out: dict[str, Any] = {}
    for key, value in result.items():
        name = f"{prefix}.{key}" if prefix else str(key)
        if isinstance(value, Mapping) or (dataclasses.is_dataclass(value) and not isinstance(value, type)):
            out.update(flatten(value, name))
        else:
            out[name] = _plain(value, name)
    return out


def _error_text(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}"


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


def _func_name(func: Callable) -> str:
    """``module:qualname`` of a function (of its class for a callable object)."""
    target = func if hasattr(func, "__qualname__") else type(func)
    return f"{getattr(target, '__module__', '?')}:{target.__qualname__}"


def _drive(task_fn, tasks, *, executor, store, totals, skipped, progress, describe):
    """Run ``tasks`` (``(index, args, n_items)``) and store each finished chunk.

    ``describe(index, failed)`` is called once per finished chunk; for a failed
    one it returns the chunk's items and their parameters (the failure record).

    Returns ``(frames kept in memory when there is no store, failures, chunks_run)``.
    """
    chunks_total, items_total = totals
    state = {"done": len(skipped), "items": 0, "failed": 0}
    sizes: dict[int, int] = {}
    frames: dict[int, Any] = {}
    failures: list[ChunkFailure] = []

    def report() -> None:
        if progress is not None:
            progress(Progress(done=state["done"], total=chunks_total, unit="chunk",
                              failed=state["failed"], skipped=len(skipped),
                              items_done=state["items"], items_total=items_total))

    def submit():
        for index, args, n in tasks:
            sizes[index] = n
            yield index, args

    report()
    for outcome in executor.imap_unordered(task_fn, submit()):
        index = outcome.key
        state["done"] += 1
        state["items"] += sizes.pop(index)
        items, params = describe(index, outcome.error is not None)
        if outcome.error is None:
            if store is not None:
                store.write_chunk(index, outcome.value)
            else:
                frames[index] = outcome.value
        else:
            failure = ChunkFailure(index, items, params, _error_text(outcome.error), outcome.traceback)
            failures.append(failure)
            state["failed"] += 1
            if store is not None:
                store.write_failure(index, dataclasses.asdict(failure))
        report()
    return frames, failures, state["done"] - len(skipped)


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


def _open_store(store, key, manifest, kind, chunk_size, n_items):
    """Open (or resume) the store; returns ``(store or None, chunk size)``."""
    if chunk_size is not None and (int(chunk_size) != chunk_size or chunk_size < 1):
        raise ParameterError(f"chunk size must be a positive integer, got {chunk_size}")
    default = default_chunk_size(n_items)
    if store is None:
        return None, chunk_size or default
    if isinstance(store, SweepStore):
        if store.manifest() is None:
            raise ParameterError(f"{store.root} has no manifest; pass the parent folder instead")
        return store, store.chunk_size
    opened = SweepStore.open(store, key, manifest, kind=kind, chunk_size=chunk_size, default_chunk_size=default)
    return opened, opened.chunk_size


def _check_errors(errors: str) -> None:
    if errors not in ("record", "raise"):
        raise ParameterError(f"errors must be 'record' or 'raise', got {errors!r}")


@dataclass(frozen=True)
class _Execution:
    frames: dict
    failures: list
    chunks_run: int
    chunks_skipped: int
    executor: str
    wall_time: float


def execute(task_fn: Callable, make_tasks: Callable[[set[int]], Iterable], *, executor, workers, scheduler,
            store: SweepStore | None, totals, progress, describe, before=None, warmup=None) -> _Execution:
    """Run chunk tasks on an executor with a locked store (shared by sweeps and batches).

    ``make_tasks(skipped)`` yields ``(index, args, n_items)`` for the chunks
    not in ``skipped``; ``before(store)`` runs once the store is locked;
    ``warmup()`` runs once on every worker of a Dask cluster before the first chunk.
    """
    t0 = time.perf_counter()
    ex, owned = make_executor(executor, workers=workers, scheduler=scheduler, warmup=warmup)
    try:
        if store is not None:
            store.lock()
            if before is not None:
                before(store)
        skipped = store.completed() if store is not None else set()
        frames, failures, ran = _drive(task_fn, make_tasks(skipped), executor=ex, store=store, totals=totals,
                                       skipped=skipped, progress=progress, describe=describe)
        description = ex.description if ran else "none (all chunks stored)"
    finally:
        if owned:
            ex.close()
        if store is not None:
            store.unlock()
    if store is not None:  # failures of this run and of earlier runs not since completed
        fields = ("chunk", "items", "parameters", "error", "traceback")
        failures = [ChunkFailure(**{k: r[k] for k in fields}) for r in store.failures()]
    return _Execution(frames, failures, ran, len(skipped), description, time.perf_counter() - t0)


def _warm_call(func: Callable, kwargs: dict) -> None:
    """One run on a worker before its first chunk (loads compiled code); errors are ignored."""
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
    row0 = {c: table[c].iloc[0] for c in table.columns}
    row0 = {k: (v.item() if isinstance(v, np.generic) else v) for k, v in row0.items()}
    # a batched function says how many threads its runs use in this process
    threads = int(func.batch_threads()) if callable(getattr(func, "batch_threads", None)) else 1
    return plan_execution(functools.partial(func, **row0), max(1, remaining), workers or available_cores(),
                          chunk_size=fixed, default_chunk_size=default_chunk_size(n),
                          serial_threads=threads)


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
        ``"auto"`` (default): time one run here and run in this process when that
        finishes sooner than starting a local cluster, else on a local Dask cluster
        of ``workers`` processes (one per core) with chunks sized from the measured
        cost (:func:`~afmforce.sweep.autoplan.plan_execution`; one run is done once
        more to time it). ``"dask"``: always a local cluster, or the cluster at
        ``scheduler`` (``tcp://host:port``, also the choice when a scheduler is given).
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
