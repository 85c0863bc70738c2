"""How the pieces of the compiled integrator are compiled (first call, issue 16).

With an empty numba cache the first ``simulate()`` compiles the integrator
and every function it calls. numba compiles each called function on its own
(typing, lowering, LLVM, machine code) before linking it into its caller, so
the fixed cost of a compiled function is paid once per piece. :func:`piece`
cuts what a piece costs and does not need:

* no CPython and no C-function wrapper (``no_cpython_wrapper``,
  ``no_cfunc_wrapper``): the pieces are called from compiled code only (pass
  ``python=True`` for the few that tests call from Python). Called from Python
  such a function would jump to a missing wrapper (a crash), so it raises a
  ``TypeError`` instead;
* no reference counting (``_nrt=False``): the pieces allocate nothing, so
  their array arguments need no incref/decref (less code to lower and
  optimise, and none of the calls at run time);
* ``forceinline``: LLVM inlines the piece into its caller (the step loop's
  pieces, see :mod:`._radau_newton`).

They are not cached on their own (``cache=False``; writing ~40 cache files
costs ~0.5 s of the first call): the cached entry point holds their code, so
a process with a warm cache never compiles them. ``error_model="numpy"``:
division by zero gives inf/NaN, which the integrator checks, not an
exception. The entry points called from Python
(:func:`~afmforce.dynamics.radau.integrate_segment`, the sampling pass, the
compliance fit) are plain ``njit(cache=True)`` functions.

Measured (``benchmarks/README.md``, "First call"): the first ``simulate()`` with
an empty cache ~10-20 % less CPU time than with plain ``njit`` pieces; run
times and results unchanged (bitwise).
"""

from __future__ import annotations

from functools import partial

from numba import njit
from numba.core.dispatcher import Dispatcher


def _keep_overload(disp, cres) -> None:
    # Dispatcher.add_overload without registering the entry point for calls from
    # Python (there is none without the CPython wrapper): such calls then reach
    # _compile_for_args, which refuses them
    disp.overloads[tuple(cres.signature.args)] = cres


def _refuse_python_call(disp, *args, **kws):
    raise TypeError(f"{disp.py_func.__module__}.{disp.py_func.__qualname__} is compiled for "
                    "calls from compiled code only (no Python wrapper, see "
                    "afmforce.dynamics._jit)")


def piece(*, inline: bool = False, python: bool = False):
    """``njit`` decorator for a function of the integrator called from compiled code.

    Parameters
    ----------
    inline : bool
        ``forceinline``: LLVM inlines the function into every caller.
    python : bool
        Keep the CPython wrapper (the function is also called from Python, e.g. tests).
    """
    jit = njit(cache=python, error_model="numpy", _nrt=False, forceinline=inline,
               no_cpython_wrapper=not python, no_cfunc_wrapper=True)
    if python:
        return jit

    def decorate(func):
        disp = jit(func)
        if isinstance(disp, Dispatcher):        # not with NUMBA_DISABLE_JIT
            disp.add_overload = partial(_keep_overload, disp)
            disp._compile_for_args = partial(_refuse_python_call, disp)
        return disp

    return decorate
