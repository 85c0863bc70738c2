"""Test-wide setup: this folder is on ``sys.path`` (pytest inserts a root conftest's folder),
so tests import the shared helper :mod:`realdata`."""

import os

import pytest

# The README's test command (and .ci/run) is `pytest -n auto`: pytest-xdist runs the suite in one
# worker process per usable core, each file on one worker (`--dist loadfile`, pyproject.toml: a
# file's module fixtures are built once). "auto" here is the cores this process may run on (not
# xdist's default, psutil's *physical* cores: a 2-vCPU machine may report 1), and no worker at all
# on a single core (the tests run in this process, as a plain `pytest`); PYTEST_XDIST_AUTO_NUM_WORKERS
# still overrides. A plain `pytest tests/x.py` starts no worker.
@pytest.hookimpl(optionalhook=True)             # a hook of pytest-xdist (the test extra)
def pytest_xdist_auto_num_workers(config):
    if os.environ.get("PYTEST_XDIST_AUTO_NUM_WORKERS"):
        return None                                         # xdist's own hook reads it
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:                                  # pragma: no cover - not Linux
        cores = os.cpu_count() or 1
    return cores if cores >= 2 else 0

# The first `afmforce analyze` after an install runs its kernels as Python and starts a background
# warmup (afmforce.cli._firstrun): a test run is not a user's first run. Commands the tests start
# compile as before, so no test's stderr depends on which test ran first, and no detached warmup
# outlives the suite; tests/cli/test_coldstart.py removes this to test the first run itself.
os.environ.setdefault("AFMFORCE_FIRST_RUN", "compile")


# The whole suite on a fresh checkout (.ci/run) starts with an empty numba cache and leaves one of
# two cores idle while pytest runs single-threaded: compile the kernels of later test folders there
# meanwhile (`afmforce warmup`: the demo's integrators, liquids and virtual AFM, then the default
# simulate), niced, in its own process group. Only for a run of many tests (a single file does not
# wait for it); stopped at the end if still running (numba writes its cache files atomically).
# A test's verdict does not depend on it: a kernel not yet in the cache is compiled where it is used.
# Off by default: measured in .ci/run, 14 min 42 s of tests with it against 13 min 59 s without (no gain:
# the early tests compile the same kernels meanwhile); AFMFORCE_TEST_WARMUP=1 turns it on.
WARMUP_MIN_TESTS = 1000


def pytest_collection_modifyitems(session, config, items):
    import subprocess
    import sys

    if (len(items) < WARMUP_MIN_TESTS or os.environ.get("AFMFORCE_TEST_WARMUP", "0") != "1"
            or os.environ.get("PYTEST_XDIST_WORKER")         # `-n`: every core runs tests already
            or (os.cpu_count() or 1) < 2 or getattr(config, "_afmforce_warmup", None) is not None):
        return
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_DISABLE_JIT"}
    config._afmforce_warmup = subprocess.Popen(
        [sys.executable, "-m", "afmforce.cli.main", "warmup", "--only", "demo", "--only", "simulate"],
        stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env,
        start_new_session=True, preexec_fn=lambda: os.nice(10))
    os.environ["AFMFORCE_TEST_WARMUP_PGID"] = str(config._afmforce_warmup.pid)  # not a worker (tests/web)


def pytest_unconfigure(config):
    import signal

    proc = getattr(config, "_afmforce_warmup", None)
    if proc is not None and proc.poll() is None:
        try:
            os.killpg(proc.pid, signal.SIGTERM)
        except OSError:
            pass
        proc.wait(timeout=30)
