"""Batches: one function over many items (files, curves, map pixels), in chunks.

The same chunking, executors, resumable store, progress and failure listing as
sweeps (:mod:`afmforce.sweep.chunks`); items may come from a generator, which
is consumed one chunk at a time, so that a large batch (a 128 x 128 map) is
never held in memory whole and its results go to disk as chunks finish.
"""

from __future__ import annotations

import hashlib
import itertools
import math
import os
import sys
import traceback
from pathlib import Path
from typing import Any, Callable, Iterable

from .._files import display_path
from ..errors import ParameterError
from ..progress import Progress
from .chunks import _check_errors, _error_text, _func_name, _open_store, execute, flatten
from .results import BatchResult

__all__ = ["run_batch", "batch_key", "error_record"]


def _item_chunk(func: Callable, start: int, items: list, labels: list[str], record_errors: bool):
    """Run one chunk of a batch (executes on a worker). One row per returned record."""
    import pandas as pd

    rows = []
    for offset, (item, label) in enumerate(zip(items, labels)):
        base = {"item": start + offset, "source": label}
        try:
            out = func(item)
            records = out if isinstance(out, (list, tuple)) else [out]
            flat = [{"error": None, **flatten(r)} for r in records]  # a record may carry its own error
        except Exception as exc:
            if not record_errors:
                raise
            flat = [error_record(exc)]
        for k, r in enumerate(flat):
            rows.append({**base, "record": k, **r})
    return pd.DataFrame(rows)


def error_record(exc: BaseException) -> dict[str, str]:
    """The columns of a failed item's (or curve's) row: ``error`` (``Type: message``), ``error_type``
    (the exception's class name) and ``traceback`` (shown with ``--debug``)."""
    return {"error": display_path(_error_text(exc)), "error_type": type(exc).__name__,
            "traceback": traceback.format_exc() if exc is sys.exc_info()[1] else
            "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))}


def _default_label(item: Any, index: int) -> str:
    if isinstance(item, (str, os.PathLike)):
        return display_path(item)
    for attr in ("path", "name", "label"):
        value = getattr(item, attr, None)
        if isinstance(value, (str, os.PathLike)):
            return display_path(value)
    return f"item {index}"


def batch_key(func: Callable, paths: list) -> str:
    """Hash of the function's name and each file's path, size and modification time."""
    h = hashlib.sha256(_func_name(func).encode())
    for p in paths:
        path = Path(p).resolve()
        st = path.stat() if path.exists() else None
        line = f"{path}|{st.st_size if st else -1}|{st.st_mtime_ns if st else -1}\n"
        h.update(line.encode("utf-8", "surrogateescape"))      # a file name that is not UTF-8 too
    return h.hexdigest()


def run_batch(items: Iterable, func: Callable[[Any], Any], *, chunk_size: int | None = None, executor=None,
              workers: int | None = None, scheduler: str | None = None, store=None, key: str | None = None,
              progress: Callable[[Progress], None] | None = None, errors: str = "record",
              label: Callable[[Any, int], str] | None = None) -> BatchResult:
    """Run ``func(item)`` for every item (file paths, curves, ...), in chunks.

    ``func`` returns a mapping of scalars, or a list of them (e.g. one per
    curve of a map file); each becomes a row with ``item`` (position in
    ``items``), ``source`` (``label(item, position)``: the path by default),
    ``record`` (position in the list) and ``error`` (None, or the error the
    call raised: that item gets one row and the batch goes on; ``error_type`` and
    ``traceback`` beside it). A record may carry its own ``error`` (and
    ``error_type``, ``traceback``: :func:`error_record`): one failed curve of a
    file's many, the others kept.

    ``items`` may be a generator: it is consumed chunk by chunk and never held
    whole, and finished chunks go to the store (when given) as they arrive. A
    rerun with the same store skips the stored chunks (their items are still
    drawn from ``items`` but not processed). ``key`` identifies the work in the
    store; for a list of file paths it defaults to a hash of ``func``'s name and
    the files' paths, sizes and modification times, otherwise it is required
    with ``store``. Other arguments as in :func:`~afmforce.sweep.run_sweep`.
    """
    _check_errors(errors)
    label = label or _default_label
    n = len(items) if hasattr(items, "__len__") else None
    if store is not None and key is None:
        if n is None or not all(isinstance(p, (str, os.PathLike)) for p in items):
            raise ParameterError("a stored batch of items other than file paths needs key=... to resume")
        key = batch_key(func, list(items))
    store, size = _open_store(store, key, {"function": _func_name(func), "n_items": n}, "batch", chunk_size, n)
    in_flight: dict[int, list[str]] = {}

    def make_tasks(skipped: set[int]):
        it = iter(items)
        for i in itertools.count():
            group = list(itertools.islice(it, size))
            if not group:
                return
            if i not in skipped:
                labels = [display_path(label(x, i * size + j)) for j, x in enumerate(group)]
                in_flight[i] = labels
                yield i, (func, i * size, group, labels, errors == "record"), len(group)

    def describe(i: int, failed: bool):
        labels = in_flight.pop(i, [])
        return list(range(i * size, i * size + len(labels))), [{"source": s} for s in labels]

    n_chunks = None if n is None else math.ceil(n / size)
    done = execute(_item_chunk, make_tasks, executor=executor, workers=workers, scheduler=scheduler,
                   store=store, totals=(n_chunks, n), progress=progress, describe=describe)
    return BatchResult(store=store, frames=None if store is not None else done.frames,
                       failures=tuple(done.failures), chunks_total=n_chunks, chunks_run=done.chunks_run,
                       chunks_skipped=done.chunks_skipped, wall_time=done.wall_time, executor=done.executor)
