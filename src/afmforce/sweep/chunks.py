"""The chunk runner shared by sweeps and batches: chunks, executors, store, failures.

:func:`execute` runs chunk tasks on an executor (a local Dask cluster, or the
in-process :class:`~afmforce.sweep.executors.SerialExecutor`), writes each
finished chunk to a :class:`~afmforce.sweep.store.SweepStore` as it arrives,
skips the chunks a store holds already, records a chunk that fails as a whole
(:class:`ChunkFailure`, retried by a rerun) and reports
:class:`~afmforce.progress.Progress`. What a chunk is comes from its caller:
:func:`~afmforce.sweep.parametric.run_sweep` (rows of a parameter table) and
:func:`~afmforce.sweep.batch.run_batch` (items: files, curves). :func:`flatten`
turns one call's result into a row.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Mapping

import numpy as np

from ..errors import ParameterError
from ..progress import Progress
from .executors import make_executor
from .store import SweepStore

__all__ = ["ChunkFailure", "execute", "default_chunk_size", "flatten"]

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
    try:
        ex, owned = make_executor(executor, workers=workers, scheduler=scheduler, warmup=warmup)
    except BaseException:
        if store is not None:
            store.discard_if_empty()      # a new store with no work in it: no manifest left behind
        raise
    try:
        if store is not None:
            store.lock()
            if before is not None:
                before(store)
        skipped = store.completed() if store is not None else set()
        frames, failures, ran = _drive(task_fn, make_tasks(skipped), executor=ex, store=store, totals=totals,
                                       skipped=skipped, progress=progress, describe=describe)
        description = ex.description if ran else "none (all chunks stored)"
    except BaseException:
        if owned:
            ex.close(quiet=True)
            owned = False
        if store is not None:
            store.unlock()
            store.discard_if_empty()
            store = None
        raise
    finally:
        if owned:
            ex.close()
        if store is not None:
            store.unlock()
    if store is not None:  # failures of this run and of earlier runs not since completed
        fields = ("chunk", "items", "parameters", "error", "traceback")
        failures = [ChunkFailure(**{k: r[k] for k in fields}) for r in store.failures()]
    return _Execution(frames, failures, ran, len(skipped), description, time.perf_counter() - t0)
