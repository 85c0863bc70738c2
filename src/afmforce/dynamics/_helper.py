"""A second process compiles part of the integrator on the first call (issue 16).

With an empty numba cache the first :func:`~afmforce.dynamics.simulate` compiles about ten
seconds of code on one core. Part of it are functions the rest only calls, compiled as
cached pieces (``piece(cached=True)``, :mod:`._jit`) or cached entry points (:func:`tasks`):
the event location (``_locate._terminal_event``, ``_locate._events``), the error norms, the
dense output and the sampling step of an accepted step, and the two passes after the
integration (``_sampling.sample_columns``, ``events.fit_compliance``). When this process is
about to compile the integrator, :func:`start` launches ``python -m
afmforce.dynamics._helper``, which compiles them into numba's cache, in the order the
integrator needs them, and prints one line per task. The dispatcher of a task waits for that
line before it compiles (:func:`_compile`); numba then loads the task from the cache. The
helper runs ahead: this process, compiling the pieces before them, has never had to wait.
numba caches a function's LLVM IR with its machine code, so the integrator still inlines the
tasks: the answers are those of a compilation in one process (``benchmarks/bench_ab.py``:
all 616 identical).

The helper is launched only where it can help: the integrator is not in numba's cache
(:func:`~afmforce.dynamics._jit.cache_missing`), numba compiles (not ``NUMBA_DISABLE_JIT``),
this process may use two CPUs or more (:func:`afmforce._cores.available_cores`: a
container's CPU quota counts), and ``AFMFORCE_COMPILE_HELPER`` is not ``0`` (the
workers of a Dask sweep set it: they compile side by side already). Where none runs, the
tasks are compiled here as link-only pieces, as before (:func:`~._jit.compile_link_only`).
It loses nothing when it fails: if it cannot start, reports a failure, dies or stays silent
for :data:`WAIT_S`, this process compiles the task itself. It is stopped when this process
exits; a forked child forgets it.

Measured (``benchmarks/README.md``, "First call"): the first ``simulate()`` with an empty
cache takes ~7 s of wall time instead of ~10.5 s (the helper: ~4.5 s on the other core).
"""

from __future__ import annotations

import atexit
import os
import subprocess
import sys
import threading
from functools import partial
from pathlib import Path

from numba.core.dispatcher import Dispatcher

from . import _locate as _L
from . import _radau_control as _C
from . import _radau_newton as _N
from . import _sampling as _S
from . import models as _M
from . import events as _E
from . import radau as _R
from .._cores import available_cores
from ._jit import cache_index_fresh, cache_missing, compile_link_only

__all__ = ["WAIT_S", "in_cache", "start", "tasks"]

#: Longest wait for one task's line [s] before compiling it here.
WAIT_S = 60.0
ENV = "AFMFORCE_COMPILE_HELPER"


def tasks() -> list[tuple[str, Dispatcher, tuple]]:
    """``(name, dispatcher, numba signature)`` of every task, in the order the integrator
    needs them: the argument types ``simulate`` passes (``tests/dynamics/test_helper.py``
    checks them)."""
    from numba import typeof
    from numba import types as T

    f8, i8, b1 = T.float64, T.int64, T.boolean
    m = typeof(_M.PLAIN(0))      # the model id of a run with the paper's terms only (issue 35)
    a1, a2, i1 = T.Array(f8, 1, "C"), T.Array(f8, 2, "C"), T.Array(i8, 1, "C")
    a1a, i1a, c1 = T.Array(f8, 1, "A"), T.Array(i8, 1, "A"), T.Array(T.int8, 1, "C")
    drive = typeof(_R.Drive(0, 0.0, 0.0, 0.0, 0.0, 0, 0.0))
    table = [
        (_C, "error_norm", (f8, a1, a1, a2, a2, f8, a2, a1, f8, a1, a1, a1, a1)),
        (_C, "improved_error_norm", (m, a1, drive, f8, f8, a1, a2, a2, f8, a2, a1, a1, a1,
                                     a1, i1, f8)),
        (_C, "left_hard_contact", (m, a1, drive, f8, a1, f8)),
        (_N, "dense_coefficients", (a1, a2, a1, a2)),
        (_L, "_terminal_event", (m, a1, f8, f8, f8, f8, f8, a1, a2, f8, a1, i8, f8, a1, a1, a1)),
        (_S, "sample_step", (f8, f8, f8, a1, a2, f8, f8, b1, i1, a2, a1)),
        (_L, "_events", (m, a1, i8, f8, f8, f8, f8, f8, a1, a2, a1, a1, a1, a1)),
        (_S, "sample_columns", (m, a1, a2, i8, b1, f8, i1a, i1a, c1, a1a, a1a, a1a, b1, f8,
                                a1, a1, c1, a2, a1, a1)),
        (_E, "fit_compliance", (a1, a1, a1a, c1, f8, f8, f8, f8)),
    ]
    return [(name, getattr(module, name), sig) for module, name, sig in table]


def in_cache(disp) -> bool:
    """Whether numba's cache on disk has a current index for the ``cache=True`` dispatcher."""
    return cache_index_fresh(disp) is True


class _Helper:
    """The helper process and the lines it printed (read by a thread)."""

    def __init__(self, proc: subprocess.Popen):
        self.proc = proc
        self.lines: dict[str, str] = {}
        self.closed = False
        self.cond = threading.Condition()
        threading.Thread(target=self._read, name="afmforce-compile-helper", daemon=True).start()

    def _read(self) -> None:
        for raw in self.proc.stdout:
            status, _, name = raw.decode("ascii", "replace").strip().partition(" ")
            with self.cond:
                self.lines[name] = status
                self.cond.notify_all()
        self.proc.wait()
        with self.cond:
            self.closed = True
            self.cond.notify_all()

    def wait(self, name: str, timeout: float = WAIT_S) -> str | None:
        """The helper's word on task ``name`` ("done", "fail") or None (it died, or timed
        out)."""
        with self.cond:
            self.cond.wait_for(lambda: name in self.lines or self.closed, timeout)
            return self.lines.get(name)

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()


_HELPER: _Helper | None = None
_TRIED = False
_LOCK = threading.Lock()


#: Callables ``f()`` run once, just before the integrator is compiled (not when it is cached).
BEFORE_COMPILE: list = []


def start() -> bool:
    """Launch the helper if it can help (once per process; cheap after the first call).
    Returns whether one is running."""
    global _HELPER, _TRIED
    if _TRIED:
        return _HELPER is not None
    with _LOCK:
        if _TRIED:
            return _HELPER is not None
        _TRIED = True
        if not (isinstance(_R.integrate_segment, Dispatcher)
                and cache_missing(_R.integrate_segment)):
            return False                # nothing to compile (the usual case: one index read)
        for notice in tuple(BEFORE_COMPILE):  # the command line says why the first run is slow
            notice()
        missing = [disp for _, disp, _ in tasks() if not in_cache(disp)]
        if (missing and os.environ.get(ENV, "1") != "0" and sys.executable
                and available_cores() >= 2):
            _HELPER = _launch()
        if _HELPER is None:             # compiled here: as link-only pieces, like the rest
            for disp in missing:
                compile_link_only(disp)
    return _HELPER is not None


def _launch() -> _Helper | None:
    import afmforce

    root = Path(afmforce.__file__).resolve().parents[1]
    env = dict(os.environ, **{ENV: "0"})
    if env.get("NUMBA_CACHE_DIR"):              # the helper runs in ``root``
        env["NUMBA_CACHE_DIR"] = os.path.abspath(env["NUMBA_CACHE_DIR"])
    try:
        proc = subprocess.Popen([sys.executable, "-m", "afmforce.dynamics._helper"],
                                cwd=root, env=env, stdin=subprocess.DEVNULL,
                                stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    except OSError:
        return None
    helper = _Helper(proc)
    atexit.register(helper.stop)
    return helper


def _forget() -> None:
    # a forked child: the helper (and the thread reading it) belong to the parent
    global _HELPER, _TRIED
    _HELPER, _TRIED = None, False


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget)


def _compile(compile_here, name: str, sig: tuple, args: tuple):
    # the dispatcher's compile(args): waits for the helper first where it compiles this
    # signature, then numba loads it from the cache (or compiles it here)
    helper = _HELPER
    if helper is not None and tuple(args) == sig:
        helper.wait(name)
    return compile_here(args)


if __name__ != "__main__":              # run as the helper: the imported module installs them
    for _name, _disp, _sig in tasks():
        if isinstance(_disp, Dispatcher):
            _disp.compile = partial(_compile, _disp.compile, _name, _sig)


def main() -> int:
    """The helper: compile every task, print ``done NAME`` once numba's cache holds it
    (``fail NAME`` otherwise)."""
    for name, disp, sig in tasks():
        try:
            disp.compile(sig)
            ok = in_cache(disp)
        except Exception:                       # noqa: BLE001 - the caller compiles it
            ok = False
        print(("done " if ok else "fail ") + name, flush=True)
    return 0


if __name__ == "__main__":
    from afmforce.dynamics._helper import main as _main     # the module, not this copy
    sys.exit(_main())
