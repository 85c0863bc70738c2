"""``simulate_many()``: many approach-retract cycles in one call.

A fit evaluates the forward model hundreds of times and a sweep thousands;
one :func:`~afmforce.dynamics.simulate` call is a thin layer of Python
around one compiled call. Here every run is prepared in this thread
(validation; the run's setup, cached per configuration and per shared parts;
a few small arrays), its compiled part (:meth:`._Run.integrate`: one
integrator call per drive segment, then the sampled observables and the
constant-compliance fits, compiled pieces that release the GIL) runs on a
pool of threads, one per core, and the finished runs (events,
warnings, the ``Trajectory`` around the arrays) are assembled here while the
pool integrates the next ones. About 5 % of a Fig-6 run holds the GIL. The
results are the same as from separate :func:`simulate` calls: the same code
runs, only the order differs.
"""

from __future__ import annotations

import sys
from collections import deque
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Callable, Iterable, Sequence

from .._cores import available_cores
from ..errors import AfmforceError, ParameterError
from .config import SimulationConfig
from .simulate import _Run
from .trajectory import Trajectory

__all__ = ["simulate_many", "run_many", "default_threads"]

#: ``on_error`` choices of :func:`simulate_many`.
ON_ERROR = ("raise", "return")
#: Runs kept in flight per thread (prepared or integrated, not yet finished).
WINDOW_PER_THREAD = 3


def default_threads() -> int:
    """Threads :func:`simulate_many` uses by default: the usable cores, 1 inside a Dask
    worker (the cluster already runs one process per core)."""
    if "distributed" in sys.modules:
        try:
            from distributed import get_worker

            get_worker()
            return 1
        except (ImportError, ValueError):
            pass
    return available_cores()


def _config(item) -> SimulationConfig:
    """The configuration of one item, with the checks that need a static solve done."""
    cfg = item if isinstance(item, SimulationConfig) else SimulationConfig(**dict(item))
    return cfg.validate()


def simulate_many(configs: Iterable[SimulationConfig | dict], *, threads: int | None = None,
                  check: str = "off", on_error: str = "raise",
                  reduce: Callable[[Trajectory], Any] | None = None) -> list:
    """Simulate many cycles; the same trajectories as ``[simulate(c) for c in configs]``.

    Parameters
    ----------
    configs : iterable of SimulationConfig or dict
        The runs (a dict holds flat names of :class:`SimulationConfig`, e.g. ``{"xi": 0.01}``).
    threads : int, optional
        Integrator threads (default :func:`default_threads`: one per usable core,
        1 inside a Dask worker); 1 runs everything in this thread.
    check : {"off", "auto", "always", "raise"}
        Convergence guard of every run (see :func:`~afmforce.dynamics.simulate`).
    on_error : {"raise", "return"}
        ``"raise"``: the first run that fails (bad configuration, solver failure)
        raises its :class:`~afmforce.errors.AfmforceError`; ``"return"``: its
        place in the result holds the exception and the other runs go on.
    reduce : callable, optional
        Applied to each finished trajectory (in this thread); its result is kept
        instead of the trajectory, so that a long batch need not hold every
        sampled curve in memory (e.g. ``lambda tr: tr.events``).

    Returns
    -------
    list
        One entry per config, in order: the Trajectory (or ``reduce`` of it), or
        with ``on_error="return"`` the AfmforceError of a failed run. Warnings
        (:class:`DynamicsWarning`, :class:`ConvergenceWarning`) are issued as by
        :func:`simulate`.
    """
    def fin(run):
        tr = run.finish(check)
        return tr if reduce is None else reduce(tr)

    return run_many(configs, fin, threads=threads, on_error=on_error)


def run_many(configs: Iterable[SimulationConfig | dict], finish: Callable[[_Run], Any], *,
             threads: int | None = None, on_error: str = "raise") -> list:
    """The pipeline of :func:`simulate_many` with a custom last step.

    ``finish(run)`` turns an integrated :class:`._Run` into the result kept
    (``run.finish(check)`` gives the Trajectory); it runs in this thread, in
    the order of ``configs``, so it may use ``warnings.catch_warnings``.
    """
    if on_error not in ON_ERROR:
        raise ParameterError(f"on_error must be one of {ON_ERROR}, got {on_error!r}")
    items: Sequence = list(configs)
    threads = default_threads() if threads is None else int(threads)
    if threads < 1:
        raise ParameterError(f"threads must be at least 1, got {threads}")
    out: list = [None] * len(items)
    cfgs: list = [None] * len(items)
    for i, item in enumerate(items):          # validate every config before any work
        try:
            cfgs[i] = _config(item)
        except AfmforceError as exc:
            if on_error == "raise":
                raise
            out[i] = exc
    todo = [i for i, c in enumerate(cfgs) if c is not None]

    def start(i):
        """Prepare run i (this thread); an error is returned, not raised."""
        try:
            return _Run(cfgs[i])
        except AfmforceError as exc:
            return exc

    def integrate(run):
        if isinstance(run, BaseException):
            return run
        try:
            return run.integrate()
        except AfmforceError as exc:
            return exc

    def done(i, run):
        try:
            if isinstance(run, BaseException):
                raise run
            out[i] = finish(run)
        except AfmforceError as exc:
            if on_error == "raise":
                raise
            out[i] = exc

    if threads == 1 or len(todo) < 2:
        for i in todo:
            done(i, integrate(start(i)))
        return out
    # a bounded window of runs in flight: memory stays ~WINDOW_PER_THREAD * threads runs
    window = WINDOW_PER_THREAD * threads
    pending: deque = deque()
    with ThreadPoolExecutor(max_workers=threads) as pool:
        try:
            for i in todo:
                pending.append((i, pool.submit(integrate, start(i))))
                if len(pending) >= window:
                    j, fut = pending.popleft()
                    done(j, fut.result())
            while pending:
                j, fut = pending.popleft()
                done(j, fut.result())
        finally:
            for _, fut in pending:
                fut.cancel()
    return out
