"""How the pieces of the compiled integrator are compiled (first call, issue 16).

With an empty numba cache the first ``simulate()`` compiles the integrator
and every function it calls. numba compiles each called function on its own
(typing, lowering, LLVM, machine code) before linking it into its caller, so
the fixed cost of a compiled function is paid once per piece. :func:`piece`
cuts what a piece costs and does not need:

* no CPython and no C-function wrapper (``no_cpython_wrapper``,
  ``no_cfunc_wrapper``): the pieces are called from compiled code only.
  Called from Python such a function would jump to a missing wrapper (a
  crash), so it raises a ``TypeError`` instead (or, ``python=True``, hands
  the call to its twin, below);
* no reference counting (``_nrt=False``): the pieces allocate nothing, so
  their array arguments need no incref/decref (less code to lower and
  optimise, and none of the calls at run time);
* ``forceinline``: LLVM inlines the piece into its caller (the step loop's
  pieces, see :mod:`._radau_newton`);
* no optimisation and no machine code of their own (a *link-only* library,
  :class:`_LinkOnlyLibrary`): numba links a callee's LLVM module into every
  caller and optimises and compiles the caller's module with everything in
  it, so a piece's own optimised module and machine code were built and
  never run. A piece's library now holds its IR as lowered; the entry points
  (which are compiled as before) optimise it once, inside the module that
  runs.

The entry point ``radau.integrate_segment`` (:data:`ENTRY`) and the pieces that another
process may compile into the cache (``piece(cached=True)``, :mod:`._helper`) get a code
library of their own too, :class:`_EntryLibrary`: its module, every piece linked in, is
optimised once, without numba's per-function clean-up, without its "cheap" module pass
(there to inline reference-count operations before pruning them; the pruning pass also ends
the full pipeline) and without vectorisation (the loops run over 2 or 4 states: vector code
and its scalar remainder only add code). The first call 0.3-0.6 s shorter, the runs 5-8 %
faster, answers bitwise unchanged (``benchmarks/bench_ab.py``). :func:`fmin`/:func:`fmax`
replace the builtins ``min``/``max`` in compiled code (numba compiles their overload once per
set of compiler flags: seven times).

They are not cached on their own (``cache=False``; writing ~40 cache files
costs ~0.5 s of the first call): the cached entry point holds their code, so
a process with a warm cache never compiles them. A piece that tests call from
Python (``python=True``) hands such calls to a *twin*: an ordinary ``njit``
of the same source, compiled (and cached) on the first call from Python. ``error_model="numpy"``:
division by zero gives inf/NaN, which the integrator checks, not an
exception. The entry points called from Python
(:func:`~afmforce.dynamics.radau.integrate_segment`, the sampling pass, the
compliance fit) are plain ``njit(cache=True)`` functions.

Measured (``benchmarks/README.md``, "First call"): wrappers and reference
counting off, the first ``simulate()`` with an empty cache takes ~10-20 % less
CPU time than with plain ``njit`` pieces; link-only libraries take another
~15-20 % off (median 14.6 s to 12.7 s on the 2-core machine, interleaved
runs; skipping the per-function clean-up too, another 0.4-0.7 s) and the
Fig-5 run 2.7 to 2.1 ms (LLVM optimises the pieces once, in their caller);
results unchanged (bitwise, the whole Fig-5 trajectory).

The link-only library overrides four internals of numba's CPU code library
(``_optimize_functions``, ``_optimize_final_module``,
``_finalize_final_module``, ``get_pointer_to_function``) and the environment pointer that
``get_executable`` writes (a piece has no Python objects and raises nothing,
so its environment is never read). :data:`LINK_ONLY` says whether this numba
has them; where it does not, the pieces are compiled the ordinary way
(slower first call, same results). ``AFMFORCE_LINK_ONLY=0`` turns it off.
"""

from __future__ import annotations

import hashlib
import os
from functools import partial
from pathlib import Path

from numba import njit
from numba.core.dispatcher import Dispatcher

try:
    from numba.core import codegen as _codegen
    from numba.core.compiler import CompilerBase, DefaultPassBuilder
    from numba.core.compiler_machinery import FunctionPass, register_pass
    from numba.core.typed_passes import NopythonTypeInference

    _BASE = _codegen.JITCodeLibrary
    LINK_ONLY = (os.environ.get("AFMFORCE_LINK_ONLY", "1") != "0"
                 and all(callable(getattr(_BASE, name, None)) for name in (
                     "_optimize_functions", "_optimize_final_module", "_finalize_final_module",
                     "_finalize_dynamic_globals",
                     "_verify_declare_only_symbols", "get_pointer_to_function",
                     "_ensure_finalized", "enable_object_caching"))
                 and isinstance(getattr(_BASE, "codegen", None), property))
except (ImportError, AttributeError):     # pragma: no cover - another numba
    LINK_ONLY = False


def cache_index_fresh(disp) -> bool | None:
    """Whether numba's cache on disk holds a current index for the ``cache=True``
    dispatcher ``disp`` (one written for this source file as it is now: an index left from
    another version of the file is stale); None where this cannot be told."""
    try:
        cache_file = disp._cache._cache_file               # numba internals
    except AttributeError:
        return None
    try:
        return bool(cache_file._load_index())              # {} when missing or stale
    except Exception:                                      # noqa: BLE001 - unreadable: unsure
        return None


#: Name of the file, beside the dynamics' numba cache files, that holds the digest of the sources
#: they were compiled from (:func:`purge_stale_cache`).
SOURCES_DIGEST = "afmforce-sources.digest"


def cache_sources() -> tuple[Path, Path]:
    """The folders whose sources the integrator's cache depends on: the dynamics and the
    surface force laws (their kernels are inlined into the vector field; issue 31)."""
    here = Path(__file__).parent
    return here, here.parent / "surface_laws"


def sources_digest(folder) -> str:
    """Digest of every ``*.py`` file in ``folder`` (a folder or a sequence of folders; names and
    contents) [hex]."""
    folders = [folder] if isinstance(folder, (str, os.PathLike)) else list(folder)
    h = hashlib.blake2b(digest_size=16)
    for d in folders:
        for f in sorted(Path(d).glob("*.py")):
            h.update(f.name.encode())
            h.update(f.read_bytes())
    return h.hexdigest()


def purge_stale_cache(disp, folder) -> bool:
    """Delete the numba cache files beside ``disp``'s when the sources in ``folder`` changed.

    numba keys a function's cache on its own source file only, but the integrator
    (``radau.integrate_segment``) inlines the vector field of ``models.py`` and the pieces of
    the other modules: after an edit or an upgrade that leaves ``radau.py`` as it was, the
    cache would silently return the old model. ``folder`` may be a sequence of folders (the
    dynamics and the surface force laws, whose kernels the vector field inlines: issue 31). A digest of all the package's sources, kept
    beside the cache files, makes any change of any of them recompile everything (once).
    Returns whether files were deleted. Never raises (an unwritable cache is numba's affair).
    """
    try:
        cache_dir = Path(disp._cache._cache_path)            # numba internals
    except AttributeError:
        return False
    try:
        digest = sources_digest(folder)
        stamp = cache_dir / SOURCES_DIGEST
        if stamp.is_file() and stamp.read_text().strip() == digest:
            return False
        purged = False
        if cache_dir.is_dir():
            for f in list(cache_dir.glob("*.nbi")) + list(cache_dir.glob("*.nbc")):
                f.unlink(missing_ok=True)
                purged = True
        cache_dir.mkdir(parents=True, exist_ok=True)
        tmp = cache_dir / f".{SOURCES_DIGEST}.{os.getpid()}"
        tmp.write_text(digest)
        os.replace(tmp, stamp)
        return purged
    except OSError:
        return False


def cache_missing(disp) -> bool:
    """Whether calling the ``cache=True`` dispatcher ``disp`` will compile it: nothing compiled
    in this process and no current numba cache index for it on disk (missing, or stale: e.g.
    after an upgrade). False when unsure."""
    if getattr(disp, "signatures", None):
        return False
    return cache_index_fresh(disp) is False


def _keep_overload(disp, cres) -> None:
    # Dispatcher.add_overload without registering the entry point for calls from
    # Python (there is none without the CPython wrapper): such calls then reach
    # _compile_for_args, which refuses them
    disp.overloads[tuple(cres.signature.args)] = cres


def _refuse_python_call(disp, *args, **kws):
    raise TypeError(f"{disp.py_func.__module__}.{disp.py_func.__qualname__} is compiled for "
                    "calls from compiled code only (no Python wrapper, see "
                    "afmforce.dynamics._jit)")


if LINK_ONLY:
    class _NoEnv:
        """The codegen as the piece's library shows it: ``set_env`` does nothing (the
        piece has no module in the execution engine to write the pointer into)."""

        def __init__(self, codegen):
            self._codegen = codegen

        def set_env(self, env_name, env) -> None:
            pass

        def __getattr__(self, name):
            return getattr(self._codegen, name)

    class _LinkOnlyLibrary(_BASE):
        """A code library that is only linked into callers: no optimisation, no
        execution engine, no machine code (see the module docstring)."""

        def _optimize_functions(self, ll_module) -> None:
            # the per-function clean-up after lowering: the caller's module pipeline
            # (which holds this IR) runs the same simplification passes
            ll_module.data_layout = self._codegen._data_layout

        def _optimize_final_module(self) -> None:
            pass

        def _finalize_final_module(self) -> None:
            self._finalize_dynamic_globals()
            self._verify_declare_only_symbols()
            self._finalized = True

        def get_pointer_to_function(self, name) -> int:
            self._ensure_finalized()
            return 0                    # no code; the piece is never called through it

        @property
        def codegen(self):
            return _NoEnv(self._codegen)

    class _EntryLibrary(_BASE):
        """The code library of the integrator's entry point (:data:`ENTRY`): its module
        (with every piece linked in) is optimised once, without vectorisation."""

        def _optimize_functions(self, ll_module) -> None:
            # the per-function clean-up after lowering: the module pipeline runs it again
            ll_module.data_layout = self._codegen._data_layout

        def _optimize_final_module(self) -> None:
            # numba runs a "cheap" module pipeline first, to inline reference-count
            # operations before pruning them; the pruning pass also ends the full pipeline
            mpm, mpb = self._codegen._module_pass_manager(loop_vectorize=False,
                                                          slp_vectorize=False)
            mpm.run(self._final_module, mpb)

    def _compiler_with(library_class, name: str):
        """numba's nopython pipeline with a pass that gives the function a
        ``library_class`` code library before it is lowered."""

        @register_pass(mutates_CFG=False, analysis_only=True)
        class _UseLibrary(FunctionPass):
            _name = name

            def __init__(self):
                FunctionPass.__init__(self)

            def run_pass(self, state) -> bool:
                if state.library is None:
                    state.library = library_class(state.targetctx.codegen(),
                                                  state.func_id.func_qualname)
                    state.library.enable_object_caching()
                return False

        class _Compiler(CompilerBase):
            def define_pipelines(self):
                pm = DefaultPassBuilder.define_nopython_pipeline(self.state)
                pm.add_pass_after(_UseLibrary, NopythonTypeInference)
                pm.finalize()
                return [pm]

        return _Compiler

    _PieceCompiler = _compiler_with(_LinkOnlyLibrary, "afmforce_link_only_library")
    _EntryCompiler = _compiler_with(_EntryLibrary, "afmforce_entry_library")
    _PIPELINE = dict(pipeline_class=_PieceCompiler)
    #: ``njit`` options of the integrator's entry point (``radau.integrate_segment``)
    ENTRY = dict(pipeline_class=_EntryCompiler)
else:                                   # pragma: no cover - another numba
    _PIPELINE = {}
    ENTRY = {}


def _call_twin(disp, twin, *args, **kws):
    # a call from Python: numba's dispatcher calls what _compile_for_args returns with the
    # arguments, here the ordinary njit of the same source (made on the first call)
    if not twin:
        twin.append(njit(cache=True, error_model="numpy")(disp.py_func))
    return twin[0]


def piece(*, inline: bool = False, python: bool = False, cached: bool = False):
    """``njit`` decorator for a function of the integrator called from compiled code.

    Parameters
    ----------
    inline : bool
        ``forceinline``: LLVM inlines the function into every caller.
    python : bool
        The function is also called from Python (tests): such calls go to its twin, an
        ordinary ``njit`` of the same source.
    cached : bool
        Compiled to machine code (not link-only; optimised as the entry point is, see
        :data:`ENTRY`) and cached, so that another process can compile it into numba's
        cache (:mod:`._helper`); callers still inline it (numba caches its LLVM IR too).
    """
    jit = njit(cache=cached, error_model="numpy", _nrt=False, forceinline=inline,
               no_cpython_wrapper=True, no_cfunc_wrapper=True,
               **(ENTRY if cached else _PIPELINE))

    def decorate(func):
        disp = jit(func)
        if isinstance(disp, Dispatcher):        # not with NUMBA_DISABLE_JIT
            disp._afmforce_cached_piece = cached
            disp.add_overload = partial(_keep_overload, disp)
            disp._compile_for_args = (partial(_call_twin, disp, []) if python
                                      else partial(_refuse_python_call, disp))
        return disp

    return decorate


def compile_link_only(disp) -> None:
    """Compile the ``cached=True`` piece ``disp`` link-only and uncached after all (no other
    process compiles it into the cache: its own machine code would never run, and the
    entry point that inlines it is cached). Only before it is compiled; numba internals."""
    if LINK_ONLY and getattr(disp, "_afmforce_cached_piece", False) and not disp.overloads:
        from numba.core.caching import NullCache

        disp._compiler.pipeline_class = _PieceCompiler
        disp._cache = NullCache()


@piece(inline=True, python=True)
def fmin(a, b):
    """``min(a, b)`` with numba's semantics (``b if b < a else a``: the first argument on
    ties and NaN comparisons), without numba's ``min`` overload, which is compiled once per
    argument types *and* per set of compiler flags (four times on the first call)."""
    return b if b < a else a


@piece(inline=True, python=True)
def fmax(a, b):
    """``max(a, b)`` with numba's semantics (``b if b > a else a``); see :func:`fmin`."""
    return b if b > a else a
