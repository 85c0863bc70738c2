"""The compiled pieces of the integrator (:mod:`afmforce.dynamics._jit`, issue 16)."""

from __future__ import annotations

import types

import numpy as np
import pytest

from afmforce.dynamics import _locate as L
from afmforce.dynamics import models as M
from afmforce.dynamics._jit import piece


def test_piece_refuses_calls_from_python_instead_of_crashing():
    """A piece has no Python wrapper: a call from Python is a TypeError, before and after
    a compiled caller has compiled it (a call to the missing wrapper would crash)."""

    @piece()
    def twice(x):
        return 2.0 * x

    from numba import njit

    @njit
    def caller(x):
        return twice(x) + 1.0

    with pytest.raises(TypeError, match="compiled code only"):
        twice(1.5)
    assert caller(1.5) == 4.0                  # compiled from a compiled caller
    assert len(twice.overloads) == 1
    with pytest.raises(TypeError, match="compiled code only"):
        twice(1.5)
    with pytest.raises(TypeError, match="compiled code only"):
        L._dense(np.zeros(2), np.zeros((2, 3)), 0.5, np.zeros(2))


def test_piece_with_python_wrapper_is_callable():
    """``piece(python=True)`` (rhs, jac, the Schur solves: called by tests) hands calls from
    Python to its twin, an ordinary njit of the same source."""
    y = np.array([2e-9, 0.0])
    out = np.zeros(2)
    p = M.pack_spring(spring_constant=0.1, mass=1e-11, radius=1e-7, hamaker=1e-20, z0=1.6e-10,
                      viscosity=0.0, h_guard=1e-10)
    assert M.rhs(M.MODEL_SPRING, p, 0.0, 0.0, y, out)
    assert out[0] == 0.0 and out[1] == pytest.approx(1e11 * (-0.1 * 2e-9 + M.surface_force.py_func(
        2e-9, 1e-27, 1.6e-10)[0]), rel=1e-12)


def test_pieces_compute_what_their_python_source_does():
    """observe (a piece without wrapper, with observables and surface_force inside) through
    the compiled observe_array equals the same functions run as Python (to rounding: numba's
    x**3 may round differently from Python's)."""
    rng = np.random.default_rng(3)
    for model, n in ((M.MODEL_SPRING, 2), (M.MODEL_BEAM, 4)):
        p = rng.uniform(0.5, 2.0, M.P_SIZE) * 1e-3
        Y = rng.uniform(0.5, 1.0, (5, n)) * 1e-8
        zd = -rng.uniform(1.0, 2.0, 5) * 1e-8
        vd = rng.uniform(-1.0, 1.0, 5) * 1e-6
        got = M.observe_array(model, p, zd, vd, Y)
        want = np.empty_like(got)
        # the pure-Python source, with the pure-Python force law
        src = M.observe.py_func
        sf = M.surface_force.py_func
        static = M.static_force.py_func      # (issue 25: eq 2 + double layer; drainage with slip)
        static = types.FunctionType(static.__code__, dict(static.__globals__, surface_force=sf))
        py = dict(src.__globals__, surface_force=sf, static_force=static,
                  drainage=M.drainage.py_func)
        # observe writes what the scalar piece observables computes (issue 35.5, fifth pass)
        py["observables"] = types.FunctionType(M.observables.py_func.__code__, py)
        observe = types.FunctionType(src.__code__, py)
        for i in range(5):
            observe(model, p, zd[i], vd[i], Y[i], want[i])
        np.testing.assert_allclose(got, want, rtol=1e-14, atol=0.0)


def _inner(x, out):
    s = 0.0
    for i in range(out.size):
        out[i] = np.sin(x * (i + 1)) / (1.0 + x * x)
        s += out[i] ** 3
    return s


def _outer(x, out):
    return inner(x, out) + inner(-0.5 * x, out) * out[0]  # noqa: F821 (given below)


def _entry(xs, out):
    acc = np.zeros(xs.size)
    for j in range(xs.size):
        acc[j] = outer(xs[j], out)  # noqa: F821 (given below)
    return acc


def test_link_only_pieces_build_no_code_of_their_own_and_compute_the_same():
    """A piece's library is link-only (no machine code, no module optimisation): its
    callers, compiled ordinarily, compute exactly what the same functions compiled with
    plain ``njit`` compute, through two levels of pieces."""
    from numba import njit

    from afmforce.dynamics import _jit

    assert _jit.LINK_ONLY                       # this numba has the internals it overrides

    g_piece = {"np": np}
    g_plain = {"np": np}
    for g, deco in ((g_piece, piece(inline=True)), (g_plain, njit)):
        for f in (_inner, _outer):
            g[f.__name__[1:]] = deco(types.FunctionType(f.__code__, g, f.__name__[1:]))
    e_piece = njit(types.FunctionType(_entry.__code__, g_piece))
    e_plain = njit(types.FunctionType(_entry.__code__, g_plain))
    xs = np.linspace(-3.0, 3.0, 41)
    got = e_piece(xs, np.zeros(5))
    want = e_plain(xs, np.zeros(5))
    assert np.array_equal(got, want)
    assert got[0] != 0.0
    for name in ("inner", "outer"):
        (cres,) = g_piece[name].overloads.values()
        assert isinstance(cres.library, _jit._LinkOnlyLibrary)
        assert cres.library.get_pointer_to_function(cres.fndesc.mangled_name) == 0
        (plain,) = g_plain[name].overloads.values()
        assert plain.library.get_pointer_to_function(plain.fndesc.mangled_name) != 0


def test_fmin_fmax_are_numbas_min_and_max():
    """fmin/fmax (replacing the builtins in the compiled code: numba compiles its min/max
    overload once per flag set) return exactly what numba's builtin min/max return, NaN,
    signed zeros, ties and mixed int/float included, compared bit for bit."""
    from numba import njit

    from afmforce.dynamics._jit import fmax, fmin

    @njit
    def ours(a, b):
        return fmin(a, b), fmax(a, b)

    @njit
    def builtin(a, b):
        return min(a, b), max(a, b)

    vals = [0.0, -0.0, 1.0, -1.0, 2.5, np.inf, -np.inf, np.nan, 1e-300, 3]
    for a in vals:
        for b in vals:
            got, want = ours(a, b), builtin(a, b)
            assert np.array(got, dtype=float).tobytes() == np.array(want, dtype=float).tobytes(), \
                (a, b, got, want)
            # and from Python (the twin), the same as the compiled call
            assert np.array((fmin(a, b), fmax(a, b)), dtype=float).tobytes() \
                == np.array(got, dtype=float).tobytes()


def test_a_change_in_any_dynamics_source_purges_the_numba_cache(tmp_path):
    """numba keys integrate_segment's cache on radau.py alone; it inlines models.py: a change in
    any source of the package must delete the cache files (a stale cache ran the old model)."""
    from types import SimpleNamespace

    from afmforce.dynamics import radau
    from afmforce.dynamics._jit import SOURCES_DIGEST, cache_sources, purge_stale_cache, sources_digest

    src, cache = tmp_path / "src", tmp_path / "cache"
    src.mkdir()
    cache.mkdir()
    (src / "models.py").write_text("x = 1\n")
    disp = SimpleNamespace(_cache=SimpleNamespace(_cache_path=str(cache)))

    def fill():
        for name in ("radau.integrate_segment-150.py311.nbi", "radau.integrate_segment-150.py311.1.nbc"):
            (cache / name).write_bytes(b"old")

    fill()
    assert purge_stale_cache(disp, src)                       # no digest yet: purged
    assert not list(cache.glob("*.nb?"))
    fill()
    assert not purge_stale_cache(disp, src)                   # same sources: kept
    assert len(list(cache.glob("*.nb?"))) == 2
    (src / "models.py").write_text("x = 2\n")                 # another file than the entry's
    assert purge_stale_cache(disp, src)
    assert not list(cache.glob("*.nb?"))
    assert (cache / SOURCES_DIGEST).read_text() == sources_digest(src)
    # the package itself: its cache folder carries the digest of the sources as they are now
    stamp = __import__("pathlib").Path(radau.integrate_segment._cache._cache_path) / SOURCES_DIGEST
    assert stamp.read_text() == sources_digest(cache_sources())
    # issue 31: the surface force laws' sources (their kernels are inlined) are in that digest
    laws = cache_sources()[1]
    assert laws.name == "surface_laws" and (laws / "hydration.py").is_file()
    copy = tmp_path / "laws"
    copy.mkdir()
    for f in laws.glob("*.py"):
        (copy / f.name).write_bytes(f.read_bytes())
    before = sources_digest((cache_sources()[0], copy))
    (copy / "hydration.py").write_text((copy / "hydration.py").read_text() + "\n# edited\n")
    assert sources_digest((cache_sources()[0], copy)) != before
