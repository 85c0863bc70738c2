"""The compile helper process of the first call (:mod:`afmforce.dynamics._helper`, issue 16)."""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from afmforce.dynamics import _helper as H

FIRST_CALL = textwrap.dedent("""
    import hashlib, json, warnings
    warnings.simplefilter("ignore")
    import numpy as np
    import afmforce.dynamics as d
    from afmforce.dynamics import _helper as H
    tr = d.simulate()
    h = H._HELPER
    print(json.dumps({
        "helper": None if h is None else dict(h.lines),
        "hits": {n: sum(disp.stats.cache_hits.values()) for n, disp, _ in H.tasks()},
        "misses": {n: sum(disp.stats.cache_misses.values()) for n, disp, _ in H.tasks()},
        "digest": hashlib.sha256(np.stack([tr.deflection, tr.angle, tr.normal_force,
                                           tr.apparent_deflection]).tobytes()).hexdigest(),
    }))
""")


def _digest(tr) -> str:
    return hashlib.sha256(np.stack([tr.deflection, tr.angle, tr.normal_force,
                                    tr.apparent_deflection]).tobytes()).hexdigest()


@pytest.mark.skipif(H.available_cores() < 2, reason="the helper runs only with two CPUs or more")
def test_first_call_loads_every_task_from_the_helper_with_the_same_answers(tmp_path):
    """End to end, empty numba cache: the helper compiles every task into the cache, the
    first simulate() loads each one from there (a hit, no miss: the signatures of
    :func:`tasks` are those simulate passes, else it would compile them itself), and the
    trajectory is bit for bit the one of this process (compiled without helper or loaded)."""
    import afmforce.dynamics as d

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    env.pop("AFMFORCE_COMPILE_HELPER", None)
    r = subprocess.run([sys.executable, "-c", FIRST_CALL], env=env, capture_output=True,
                       text=True, timeout=600, check=True)
    got = json.loads(r.stdout.strip().splitlines()[-1])
    names = [n for n, _, _ in H.tasks()]
    assert got["helper"] == {n: "done" for n in names}
    assert all(got["hits"][n] >= 1 for n in names), got["hits"]
    assert all(got["misses"][n] == 0 for n in names), got["misses"]
    assert got["digest"] == _digest(d.simulate())


def test_no_helper_where_it_cannot_help(monkeypatch):
    """start() launches nothing when turned off, with one CPU, or when the integrator is in
    the cache (as in this test process: then it reads nothing more than that index); where no
    helper runs but the integrator compiles, the tasks compile link-only here. It decides
    once per process."""
    launched, link_only, asked = [], [], []
    monkeypatch.setattr(H, "_launch", lambda: launched.append(1) or None)
    monkeypatch.setattr(H, "compile_link_only", lambda disp: link_only.append(disp))

    def in_cache(disp):
        asked.append(disp)
        return False

    for setup, compiles in ((lambda: monkeypatch.setenv(H.ENV, "0"), True),
                            (lambda: monkeypatch.setattr(H, "available_cores", lambda: 1), True),
                            (lambda: monkeypatch.setattr(H, "cache_missing", lambda d: False),
                             False)):
        monkeypatch.setattr(H, "_TRIED", False)
        monkeypatch.setattr(H, "_HELPER", None)
        monkeypatch.setattr(H, "cache_missing", lambda disp: True)
        monkeypatch.setattr(H, "in_cache", in_cache)
        monkeypatch.delenv(H.ENV, raising=False)
        monkeypatch.setattr(H, "available_cores", lambda: 2)
        link_only.clear()
        asked.clear()
        setup()
        assert H.start() is False
        tasks = [d for _, d, _ in H.tasks()]
        assert link_only == (tasks if compiles else []) and asked == (tasks if compiles else [])
    assert launched == []
    monkeypatch.setattr(H, "_TRIED", False)
    monkeypatch.setattr(H, "cache_missing", lambda disp: True)
    assert H.start() is False and launched == [1]          # useful: launched (stub: failed)
    assert H.start() is False and launched == [1]          # once per process


def _fake_helper(script: str) -> H._Helper:
    return H._Helper(subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE))


def test_helper_wait_reads_lines_and_gives_up_on_death_or_silence():
    """wait(): the task's status once its line is printed; None at once when the helper
    has exited without it; None after the timeout while it stays silent."""
    h = _fake_helper("import time; print('done a', flush=True); print('fail b', flush=True);"
                     "time.sleep(0.3)")
    assert h.wait("a", timeout=30) == "done"
    assert h.wait("b", timeout=30) == "fail"
    assert h.wait("c", timeout=30) is None and h.closed
    silent = _fake_helper("import time; time.sleep(30)")
    assert silent.wait("a", timeout=0.2) is None and not silent.closed
    silent.stop()
    assert silent.proc.poll() is not None


def test_a_task_compiles_here_after_the_helper_failed(monkeypatch):
    """Every task's dispatcher compiles through :func:`_compile`, which waits for the
    helper's line on the task's own signature only, then compiles (or loads) it in this
    process whatever the helper said."""
    asked, compiled = [], []

    class Stub:
        def wait(self, name, timeout=H.WAIT_S):
            asked.append(name)
            return "fail"

    monkeypatch.setattr(H, "_HELPER", Stub())
    for name, disp, sig in H.tasks():
        assert disp.compile.func is H._compile and disp.compile.args[1:] == (name, sig)
        here = disp.compile.args[0]
        assert here.__self__ is disp                         # numba's own compile, bound
        assert H._compile(lambda a: compiled.append(a) or "cres", name, sig, sig) == "cres"
        other = tuple(reversed(sig))
        H._compile(lambda a: compiled.append(a), name, sig, other)
        assert asked[-1] == name and len(asked) == len(compiled) - len(asked)
    assert compiled[::2] == [sig for _, _, sig in H.tasks()]


def test_cached_piece_compiled_here_is_link_only_and_not_cached(tmp_path, monkeypatch):
    """Without a helper, a ``piece(cached=True)`` is compiled as the other pieces are
    (:func:`compile_link_only`: link-only, no cache file of its own), and its caller still
    computes with it; with the switch left off it is cached."""
    import importlib

    import numba.core.config as nconfig

    from afmforce.dynamics import _jit

    (tmp_path / "cp_mod.py").write_text(textwrap.dedent("""
        from numba import njit
        from afmforce.dynamics._jit import piece

        @piece(cached=True)
        def g(x):
            return 3.0 * x

        @piece(cached=True)
        def g2(x):
            return 3.0 * x

        @njit
        def caller(x):
            return g(x) + 1.0

        @njit
        def caller2(x):
            return g2(x) + 1.0
    """))
    monkeypatch.setattr(nconfig, "CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.syspath_prepend(str(tmp_path))
    mod = importlib.import_module("cp_mod")
    _jit.compile_link_only(mod.g)
    assert mod.caller(2.0) == 7.0 and mod.caller2(2.0) == 7.0
    lib = next(iter(mod.g.overloads.values())).library
    assert isinstance(lib, _jit._LinkOnlyLibrary) == _jit.LINK_ONLY
    assert H.in_cache(mod.g2) and H.in_cache(mod.g) != _jit.LINK_ONLY
    _jit.compile_link_only(mod.g2)                           # compiled already: unchanged
    assert not isinstance(next(iter(mod.g2.overloads.values())).library,
                          _jit._LinkOnlyLibrary)


@pytest.mark.skipif(not hasattr(os, "fork"), reason="fork only")
def test_a_forked_child_forgets_the_parents_helper(monkeypatch):
    """The helper and the thread reading it belong to the parent: a forked child must not
    wait on them (it would wait out WAIT_S)."""
    monkeypatch.setattr(H, "_HELPER", object())
    monkeypatch.setattr(H, "_TRIED", True)
    pid = os.fork()
    if pid == 0:                                             # the child
        os._exit(0 if (H._HELPER is None and H._TRIED is False) else 1)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0
    assert H._HELPER is not None                             # the parent keeps its own
