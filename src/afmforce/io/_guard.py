"""Run a reader with a time budget: a damaged file must never hang afmforce.

Some third-party parsers (h5py on a corrupted attribute, struct-heavy readers on
a huge declared size) can spin in compiled code that holds the GIL, so a thread
cannot be stopped. :func:`run_with_timeout` therefore runs the call in a forked
child process (POSIX) and kills it when the budget is spent; the result comes back
pickled. Where ``fork`` does not exist the call runs in this process, unguarded.

Guarded calls nest (``load(..., timeout=)`` detects an HDF5 file in a child of its
own): on Linux every child asks to be killed when its parent dies
(``PR_SET_PDEATHSIG``), so killing a child takes its children with it instead of
leaving them spinning in h5py as orphans (elsewhere only the direct child is killed).
"""

from __future__ import annotations

import os
import pickle
import select
import signal
import time
from typing import Any, Callable

from ..errors import AfmforceError, FileFormatError

__all__ = ["FileTimeoutError", "run_with_timeout"]


class FileTimeoutError(FileFormatError):
    """Reading a file took longer than its time budget (``file_timeout``)."""


def _child(write_fd: int, func: Callable, args, kwargs) -> None:
    try:
        try:
            payload = pickle.dumps(("ok", func(*args, **kwargs)), protocol=pickle.HIGHEST_PROTOCOL)
        except BaseException as exc:  # everything goes back to the parent, which re-raises it
            try:
                payload = pickle.dumps(("err", exc), protocol=pickle.HIGHEST_PROTOCOL)
            except Exception:
                payload = pickle.dumps(("err", FileFormatError(f"{type(exc).__name__}: {str(exc)[:200]}")))
        view = memoryview(payload)
        while view:
            n = os.write(write_fd, view[:1 << 20])
            view = view[n:]
    finally:
        os._exit(0)


def run_with_timeout(func: Callable, *args: Any, timeout: float | None, path: str = "",
                     **kwargs: Any) -> Any:
    """``func(*args, **kwargs)`` with at most ``timeout`` [s] of wall time.

    Raises
    ------
    FileTimeoutError
        The call ran past ``timeout``; the child process was killed.
    Whatever ``func`` raised, re-raised here.
    """
    if timeout is None or not hasattr(os, "fork"):
        return func(*args, **kwargs)
    if not timeout > 0:
        raise ValueError(f"timeout must be positive [s], got {timeout!r}")
    read_fd, write_fd = os.pipe()
    parent = os.getpid()
    pid = os.fork()
    if pid == 0:  # child
        _die_with_parent(parent)
        os.close(read_fd)
        _child(write_fd, func, args, kwargs)
    os.close(write_fd)
    chunks: list[bytes] = []
    deadline = time.monotonic() + timeout
    finished = False
    try:
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise FileTimeoutError(
                    f"{path}: reading took longer than {timeout:g} s (`file_timeout`); the file is damaged "
                    "or very large: skipped")
            ready, _, _ = select.select([read_fd], [], [], min(left, 0.5))
            if ready:
                block = os.read(read_fd, 1 << 20)
                if not block:
                    finished = True
                    break
                chunks.append(block)
    finally:
        os.close(read_fd)
        if not finished:  # budget spent, or interrupted
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:  # already gone
                pass
        os.waitpid(pid, 0)
    if not chunks:
        raise FileFormatError(f"{path}: the reader process died without an answer (crash in a parser)")
    status, value = pickle.loads(b"".join(chunks))
    if status == "ok":
        return value
    if isinstance(value, (AfmforceError, KeyboardInterrupt)):
        raise value
    raise value



def _die_with_parent(parent: int) -> None:
    """Linux: SIGKILL this (child) process when its parent dies (no orphans of a killed reader)."""
    try:
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG = 1
    except (OSError, AttributeError):  # not Linux: the direct child is still killed by its parent
        return
    if os.getppid() != parent:  # the parent died before the request took effect
        os._exit(0)
