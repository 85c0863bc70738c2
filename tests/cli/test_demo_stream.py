"""afmforce demo prints each part when it is done and draws its figures in a forked child
(issue 35 item 4). No wall-clock verdicts: what runs where, and what a first run prints first."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from afmforce.cli import _firstrun
from afmforce.cli import demo

SRC = Path(__file__).resolve().parents[2] / "src"
fork = pytest.mark.skipif(not hasattr(os, "fork"), reason="no os.fork here: the work is done in-process")


@fork
def test_aside_runs_in_a_child_and_returns_its_value(monkeypatch):
    import afmforce._cores as cores

    monkeypatch.setattr(cores, "available_cores", lambda: 2)
    assert demo._Aside(os.getpid).result() != os.getpid()
    assert demo._Aside(lambda: {"a": [1.5, "x"]}).result() == {"a": [1.5, "x"]}
    assert demo._Aside(os.getpid, inline=True).result() == os.getpid()
    monkeypatch.setattr(cores, "available_cores", lambda: 1)
    assert demo._Aside(os.getpid).result() == os.getpid()       # one core: no child


@fork
def test_aside_failure_is_raised_here(monkeypatch, tmp_path):
    """A child that fails: the work is done again in this process, whose error the CLI reports."""
    import afmforce._cores as cores

    monkeypatch.setattr(cores, "available_cores", lambda: 2)
    runs = tmp_path / "runs"

    def work():
        with open(runs, "a") as f:
            f.write(f"{os.getpid()}\n")
        raise ValueError("no figure")

    with pytest.raises(ValueError, match="no figure"):
        demo._Aside(work).result()
    pids = runs.read_text().split()
    assert len(pids) == 2 and pids[1] == str(os.getpid()) and pids[0] != pids[1]


@fork
def test_aside_cancel_ends_the_child(monkeypatch):
    import time

    import afmforce._cores as cores

    monkeypatch.setattr(cores, "available_cores", lambda: 2)
    aside = demo._Aside(lambda: time.sleep(600))
    pid = aside._pid
    aside.cancel()
    with pytest.raises(ChildProcessError):
        os.waitpid(pid, 0)          # reaped: gone


def test_first_run_prints_the_closed_form_checks_first(tmp_path, monkeypatch):
    """A first run (empty numba cache, no stamps): the demo compiles, but the first rows of the
    paper's table, which need no integrator, are printed before it does; they are the numbers
    of the paper's closed-form and static checks. The process is stopped (SIGINT) once they are
    read: the rest compiles for a minute (benchmarks/bench_coldstart.py)."""
    from afmforce.paper.numbers import all_checks, evaluate_checks

    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_DISABLE_JIT", _firstrun.ENV)}
    env.update(PYTHONPATH=str(SRC), AFMFORCE_STATE_DIR=str(tmp_path / "state"),
               NUMBA_CACHE_DIR=str(tmp_path / "numba"), AFMFORCE_COMPILE_HELPER="0")
    # the analysis' warmup counts as done: no detached compiler is left behind by this test
    monkeypatch.setenv("AFMFORCE_STATE_DIR", env["AFMFORCE_STATE_DIR"])
    monkeypatch.setenv("NUMBA_CACHE_DIR", env["NUMBA_CACHE_DIR"])
    _firstrun.write_stamp("analysis")
    assert not _firstrun.is_warm("demo")
    first = evaluate_checks([c for c in all_checks() if c.group in demo.FIRST_GROUPS])
    proc = subprocess.Popen([sys.executable, "-m", "afmforce.cli.main", "demo", "--out", str(tmp_path / "p")],
                            env=env, cwd=tmp_path, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    lines = []
    try:
        for line in proc.stdout:
            lines.append(line.rstrip("\n"))
            if len(lines) == 4 + len(first):     # title, blank, head, rule, the first rows
                break
    finally:
        proc.send_signal(signal.SIGINT)
        try:  # a SIGINT waits for the compiler's current function (up to ~100 s in CI): no need to wait
            proc.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()
    assert lines[0].startswith("afmforce demo: Attard, Carambassis & Rutland") and lines[2].startswith("quantity")
    assert lines[4:] == demo._check_rows(first)
    assert not list(Path(env["AFMFORCE_STATE_DIR"]).glob("warm-demo-*"))
