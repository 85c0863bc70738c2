"""Where the chunks of a sweep run: in this process, or on a Dask cluster.

Both executors offer the same method, :meth:`imap_unordered`, that runs
``fn(*args)`` for each task and yields ``Outcome`` records as tasks finish. An
exception raised by a task is returned in its outcome, not raised, so that the
other tasks go on; ``KeyboardInterrupt`` stops everything.
"""

from __future__ import annotations

import contextlib
import itertools
import logging
import re
import shutil
import signal
import tempfile
import threading
import traceback
import warnings
from dataclasses import dataclass
from typing import Any, Callable, Hashable, Iterable, Iterator

from .._cores import available_cores
from ..errors import ParameterError

__all__ = ["Outcome", "SerialExecutor", "DaskExecutor", "make_executor", "available_cores", "check_scheduler",
           "check_workers", "WORKERS_PER_CORE"]

#: The most worker processes a local cluster may start per core this process may use: more only
#: share the same cores while each holds its own interpreter and kernels in memory.
WORKERS_PER_CORE = 4


def check_workers(workers) -> int | None:
    """``workers`` (a local cluster's process count) as an int, or :class:`ParameterError`: below 1,
    or more than :data:`WORKERS_PER_CORE` per available core (``--workers 1000`` on 2 cores started
    1000 processes)."""
    if workers is None:
        return None
    if isinstance(workers, bool) or not float(workers).is_integer():
        raise ParameterError(f"`workers` must be a whole number, got {workers!r}")
    n, cores = int(workers), available_cores()
    if n < 1:
        raise ParameterError(f"`workers` must be at least 1, got {workers}")
    most = WORKERS_PER_CORE * cores
    if n > most:
        raise ParameterError(f"`workers` = {n} is more than {most} ({WORKERS_PER_CORE} per core; this process may use "
                             f"{cores}): each worker is a process with its own memory, and more only share the "
                             f"same cores; give at most {most}")
    return n


@dataclass(frozen=True)
class Outcome:
    """Result of one task: its key, and either its value or the error it raised."""

    key: Hashable
    value: Any = None
    error: BaseException | None = None
    traceback: str = ""




class SerialExecutor:
    """Run tasks one after the other in this process (tests, debugging, tiny sweeps)."""

    n_workers = 1
    description = "serial (in this process)"

    def imap_unordered(self, fn: Callable, tasks: Iterable[tuple[Hashable, tuple]]) -> Iterator[Outcome]:
        for key, args in tasks:
            try:
                value = fn(*args)
            except Exception as exc:  # recorded; KeyboardInterrupt propagates
                yield Outcome(key, error=exc, traceback=traceback.format_exc())
            else:
                yield Outcome(key, value)

    def close(self, quiet: bool = False) -> None:
        """Nothing to release."""

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


#: A Dask scheduler address: ``tcp://host:port``, ``host:port``, ``tls://...``, ``inproc://...``.
_SCHEDULER = re.compile(r"^(?:(?:tcp|tls|inproc|ucx|ws|wss)://)?[A-Za-z0-9._\-\[\]:]+(?::\d{1,5})?/?$")


def check_scheduler(address: str) -> str:
    """Refuse a Dask scheduler address that is not one (before any store or cluster is made).

    Raises
    ------
    ParameterError
    """
    text = str(address).strip()
    if not text or not _SCHEDULER.match(text):
        raise ParameterError(f"`scheduler` {address!r} is not a Dask scheduler address; give one such as "
                             "tcp://127.0.0.1:8786 (printed by `dask scheduler`)")
    return text


@contextlib.contextmanager
def _workers_ignore_sigint():
    """Start worker processes with Ctrl-C (SIGINT) ignored: the terminal sends it to the whole
    process group, and only this process should stop (with one line), not print a traceback
    per worker. Spawned processes inherit an ignored signal; the main thread only can set it."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


class DaskExecutor:
    """Run tasks on a ``dask.distributed`` cluster.

    Without ``scheduler`` or ``client`` a :class:`distributed.LocalCluster` of
    ``workers`` single-threaded processes (default: one per available core) is
    started on the loopback interface when first needed and closed by
    :meth:`close`; its workers' scratch space is a folder of its own in the temporary
    folder (``TMPDIR``), removed by :meth:`close`. ``scheduler="tcp://host:port"`` connects to a running
    cluster instead; ``client`` uses an existing :class:`distributed.Client`
    (which is left open).

    At most ``window`` tasks are in flight at once (default: three per worker
    thread), so that a long iterable of tasks is never held in memory whole.
    ``warmup()`` runs once on every worker before the first task is submitted.
    """

    def __init__(self, workers: int | None = None, scheduler: str | None = None, client=None,
                 window: int | None = None, warmup: Callable[[], Any] | None = None) -> None:
        workers = check_workers(workers)
        if client is not None and scheduler is not None:
            raise ParameterError("give a scheduler address or a client, not both")
        if scheduler is not None:
            check_scheduler(scheduler)
        self.workers = None if workers is None else int(workers)
        self.scheduler = scheduler
        self._client = client
        self._own_client = client is None
        self._cluster = None
        self._scratch: str | None = None
        self._window = window
        self._warmup = warmup

    @property
    def client(self):
        """The :class:`distributed.Client`, started on first use."""
        if self._client is None:
            from distributed import Client, LocalCluster

            if self.scheduler:
                try:
                    self._client = Client(self.scheduler, timeout="20s")
                except (OSError, TimeoutError, ValueError, TypeError) as exc:
                    raise ParameterError(
                        f"`scheduler` {self.scheduler}: cannot reach the Dask scheduler ({exc}); "
                        "check the address or start one with `dask scheduler`"
                    ) from None
            else:
                import dask

                # no dashboard, so no statistical profiler either: it samples the
                # task thread every 10 ms and slows short compiled runs measurably
                # the scratch of the scheduler (made here) and the workers in a folder of its own, removed by
                # close(): dask's default, <tmp>/dask-scratch-space, outlived every sweep
                self._scratch = tempfile.mkdtemp(prefix="afmforce-dask-")
                with dask.config.set({"distributed.worker.profile.enabled": False,
                                      "temporary-directory": self._scratch}), _workers_ignore_sigint(), \
                        warnings.catch_warnings():
                    # another cluster on this machine holds the HTTP port: dask takes another one itself
                    warnings.filterwarnings("ignore", message="Port .* is already in use")
                    try:
                        self._cluster = LocalCluster(
                            n_workers=self.workers or available_cores(), threads_per_worker=1, processes=True,
                            host="127.0.0.1", dashboard_address=None, silence_logs=logging.ERROR,
                            local_directory=self._scratch,
                        )
                    except BaseException:
                        shutil.rmtree(self._scratch, ignore_errors=True)
                        self._scratch = None
                        raise
                self._client = Client(self._cluster)
        return self._client

    @property
    def n_workers(self) -> int:
        """Number of worker threads in the cluster."""
        return max(1, sum(self.client.nthreads().values()))

    @property
    def description(self) -> str:
        if self.scheduler:
            return f"Dask cluster at {self.scheduler} ({self.n_workers} worker threads)"
        if not self._own_client:
            return f"Dask client {self.client.scheduler.address} ({self.n_workers} worker threads)"
        return f"local Dask cluster ({self.n_workers} worker processes)"

    def imap_unordered(self, fn: Callable, tasks: Iterable[tuple[Hashable, tuple]]) -> Iterator[Outcome]:
        from distributed import as_completed

        pending = iter(tasks)
        try:
            first = next(pending)
        except StopIteration:
            return  # nothing to run: do not start a cluster
        pending = itertools.chain([first], pending)
        client = self.client
        if self._warmup is not None:
            # every worker loads the compiled code once before its first chunk (the run that
            # timed the sweep in this process has written the numba cache it loads)
            client.run(self._warmup)
            self._warmup = None
        window = self._window or 3 * self.n_workers
        keys: dict[str, Hashable] = {}
        done = as_completed()

        def submit_next() -> bool:
            try:
                key, args = next(pending)
            except StopIteration:
                return False
            future = client.submit(fn, *args, pure=False)
            keys[future.key] = key
            done.add(future)
            return True

        for _ in range(window):
            if not submit_next():
                break
        try:
            for future in done:
                key = keys.pop(future.key)
                try:
                    value = future.result()
                except Exception as exc:
                    tb = future.traceback()
                    text = "".join(traceback.format_tb(tb)) if tb is not None else ""
                    yield Outcome(key, error=exc, traceback=text + f"{type(exc).__name__}: {exc}\n")
                else:
                    yield Outcome(key, value)
                finally:
                    future.release()
                submit_next()
        finally:
            for future in list(done.futures):
                future.cancel()

    def close(self, quiet: bool = False) -> None:
        """Close the client and the local cluster this executor started.

        ``quiet``: after an interruption (Ctrl-C) or an error, the cluster's own log
        lines about the tasks it cancels are not printed (the caller reports one line).
        """
        loggers = [logging.getLogger(n) for n in ("distributed", "tornado", "asyncio")] if quiet else []
        levels = [lg.level for lg in loggers]
        for lg in loggers:
            lg.setLevel(logging.CRITICAL + 1)
        try:   # a second Ctrl-C (every worker's, or the user's again) must not break the shutdown half-way
            with _workers_ignore_sigint() if quiet else contextlib.nullcontext():
                # after an interruption a worker may still be busy in its task (workers ignore
                # SIGINT): a close that times out must not replace the one-line report, and the
                # cluster is closed (its worker processes ended) all the same
                def shut(part) -> None:
                    try:
                        part.close(**({"timeout": 10} if quiet else {}))
                    except (TimeoutError, OSError):
                        if not quiet:
                            raise

                if self._own_client and self._client is not None:
                    shut(self._client)
                    self._client = None
                if self._cluster is not None:
                    shut(self._cluster)
                    self._cluster = None
        finally:
            if self._scratch is not None:
                shutil.rmtree(self._scratch, ignore_errors=True)
                self._scratch = None
            for lg, level in zip(loggers, levels):
                lg.setLevel(level)

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def make_executor(executor=None, *, workers: int | None = None, scheduler: str | None = None,
                  warmup: Callable[[], Any] | None = None):
    """Resolve an executor argument; returns ``(executor, owned)``.

    ``executor`` may be an executor object, ``"serial"``, ``"dask"``/``"local"``/None
    (a Dask cluster: local unless ``scheduler`` is given) or a
    :class:`distributed.Client`. ``owned`` says whether the caller must close it.
    ``warmup`` is passed to a cluster this function creates.
    """
    if workers is not None and scheduler:
        raise ParameterError("`workers` sizes the local cluster; a `scheduler` cluster has its own workers")
    if executor is None or executor in ("dask", "local"):
        return DaskExecutor(workers=workers, scheduler=scheduler, warmup=warmup), True
    if executor == "serial":
        if scheduler:
            raise ParameterError("`serial` and `scheduler` exclude each other")
        return SerialExecutor(), True
    if hasattr(executor, "imap_unordered"):
        return executor, False
    try:
        from distributed import Client
    except ImportError:  # pragma: no cover - dask is a dependency
        Client = ()
    if isinstance(executor, Client):
        return DaskExecutor(client=executor), False
    raise ParameterError(f"unknown executor {executor!r}; use 'serial', 'dask' or a distributed.Client")
