"""The first command after an install answers in seconds (issue 35, item 4).

afmforce's kernels are compiled by numba on their first call and cached on disk
(``cache=True``): with an empty cache the first ``afmforce analyze`` compiled for ~25 s of
one core, the first ``afmforce simulate`` for ~20 s, ``afmforce demo`` for ~45 s. What
happens now:

* ``afmforce warmup`` (:mod:`.warmup`) compiles the kernels of the default commands ahead,
  by running each group's workload (:data:`GROUPS`) on the shipped sample files, and leaves
  a *stamp* per group (:func:`stamp_path`) once numba's cache holds them;
* the first ``afmforce analyze`` of a few small files (:func:`interpretable`) with no stamp
  for the analysis does not wait for the compiler: it starts ``afmforce warmup --only
  analysis`` in the background (a detached process, one at a time: :func:`start_background`)
  and runs its own kernels as the Python they are written in (``NUMBA_DISABLE_JIT``, set
  before numba is imported), with one line on stderr. The answers are those of the compiled
  kernels to rounding (Python and LLVM round differently in the last bits: 1.2e-14 relative
  at most on the shipped sample files, which ``tests/cli/test_coldstart.py`` compares at
  1e-12); the next run loads the compiled kernels from the cache;
* the first ``afmforce simulate`` with no stamp for the integrator runs it as Python too
  while ``afmforce warmup --only simulate`` compiles it in the background: the integrator as
  Python takes the compiled one's steps bitwise (its integer powers are written as numba
  compiles them, ``dynamics.models.surface_force``, ``dynamics._radau_newton._ipow``; tested
  on the default run and the demo's kinds of runs), so its answers are the compiled ones, not
  only to rounding. As Python the integrator is ~10x slower (the default run: ~1 s of
  integration, ~2.4 s in all): a run that is still integrating after
  :data:`INTERPRETED_BUDGET_S` of CPU time (a ``SIGVTALRM`` timer; no timer, no Python run)
  stops before it wrote anything and runs again compiled (``os.execv`` of the same command
  line, one more line on stderr): at most that long lost, never an endless Python run;
* ``demo`` compiles, on two cores (``dynamics._helper``), after one line that names
  ``afmforce warmup``, and prints each part as soon as it is done (``cli/demo.py``): first
  the paper's closed-form, inertia and static checks (31 of the 61 rows of its table: ~0.4 s,
  no integrator, nothing to compile), so that a first run answers in about a second too; then
  the simulated checks, the virtual experiment and the liquid fit, which wait for the compiled
  kernels. Decision: none of them runs as Python. The simulated checks alone take 25 s of CPU
  as Python against ~1 s compiled (measured: ``evaluate_checks`` of the "dynamics" group with
  ``NUMBA_DISABLE_JIT``), more than compiling the integrator (~10-20 s of one core); the liquid
  fit's 112,612 Newton solves as Python would take over a minute; and numba's switch is one
  per process, so a Python part could not share the process with the compiled ones. The demo
  starts the analysis' warmup in the background at once (:data:`COMMAND_LATER`; two cores or
  more), so that its analysis kernels are compiled on the other core while it compiles the
  integrator; its figures (about half its CPU time warm) are drawn in a forked child while
  the experiments run.

A stamp only says that the warmup ran for these sources, this numba and this cache: it is
a hint, never a guarantee of freshness. That is numba's index, whose stamp covers every
source a kernel may reach (:mod:`afmforce._jitcache`): a missing or stale cache entry is
compiled, never run old. The stamp's key (:func:`key`) is cheap (file sizes and times, no
numba import) so that deciding costs ~1 ms. ``AFMFORCE_FIRST_RUN=compile`` turns the
background start and the Python run off (the old behaviour).
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import sys
import time
from pathlib import Path

from .._files import pid_alive
from .._jitcache import kernel_source_files

__all__ = ["GROUPS", "COMMAND_GROUP", "ENV", "key", "stamp_path", "is_warm", "write_stamp",
           "interpretable", "start_background", "prepare", "guard"]

#: Group -> what ``afmforce warmup`` runs to compile its kernels (commands of this CLI).
GROUPS: dict[str, str] = {
    "analysis": "analyze the shipped sample files (every reader and analysis step of the default pipeline)",
    "simulate": "simulate the default run (the integrator, events, sampling)",
    "demo": "afmforce demo (the paper's checks, the virtual AFM, the liquid experiment)",
}
#: Command -> the group whose kernels it needs first.
COMMAND_GROUP = {"analyze": "analysis", "simulate": "simulate", "demo": "demo"}
#: Command -> groups it needs later, compiled by a background warmup on another core while the
#: command compiles and runs what it needs first (``demo``: the integrator, then the analysis).
COMMAND_LATER = {"demo": ("analysis",)}
ENV = "AFMFORCE_FIRST_RUN"
#: analyze runs its kernels as Python on its first run only for this much input [bytes] ...
MAX_INTERPRETED_BYTES = 2_000_000
#: ... and this many inputs (a folder is never run so)
MAX_INTERPRETED_INPUTS = 8
#: analyze's options whose kernels are slow as Python (the indentation and adhesive contact fits:
#: 1-2 s a curve compiled): with any of them the first run compiles
HEAVY_FLAGS = ("indentation_model", "fast_map")
#: simulate's first run gives the command this much CPU time with the integrator as Python [s]
#: (the default run: ~1.5 s, ~0.8 s of it integrating), then runs it again compiled; CPU time,
#: not wall time: on a loaded machine both the Python run and the compiler take longer
INTERPRETED_BUDGET_S = 4.0
#: What the first run's line on stderr calls each group's kernels
KERNELS = {"analysis": "the analysis kernels are", "simulate": "the integrator is"}
#: A background warmup whose lock is older than this is taken for dead [s].
LOCK_STALE_S = 900.0


def _package() -> Path:
    return Path(__file__).resolve().parents[1]


def state_dir() -> Path:
    """Where stamps and locks live: ``$AFMFORCE_STATE_DIR``, else ``$XDG_CACHE_HOME/afmforce``,
    else ``~/.cache/afmforce``."""
    if os.environ.get("AFMFORCE_STATE_DIR"):
        return Path(os.environ["AFMFORCE_STATE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "afmforce"


def key() -> str:
    """What a warm cache depends on, cheaply: this package's place and its kernels' sources
    (names, sizes, modification times: :func:`afmforce._jitcache.kernel_source_files`' list),
    numba's installation, the interpreter and ``NUMBA_CACHE_DIR`` [hex]."""
    root = _package()
    h = hashlib.blake2b(digest_size=12)
    h.update(f"{root}\0{sys.executable}\0{sys.version}\0{os.environ.get('NUMBA_CACHE_DIR', '')}".encode())
    files = kernel_source_files(root)
    spec = importlib.util.find_spec("numba")
    if spec is not None and spec.origin:
        files.append(Path(spec.origin))
    for f in files:
        try:
            st = f.stat()
        except OSError:
            continue
        h.update(f"{f}\0{st.st_size}\0{st.st_mtime_ns}\0".encode())
    return h.hexdigest()


def stamp_path(group: str, k: str | None = None) -> Path:
    return state_dir() / f"warm-{group}-{k or key()}"


def is_warm(group: str, k: str | None = None) -> bool:
    """Whether ``afmforce warmup`` compiled ``group`` for these sources and this cache."""
    return stamp_path(group, k).is_file()


def write_stamp(group: str, k: str | None = None) -> Path | None:
    """Leave the stamp of ``group`` (None when the state folder is not writable)."""
    path = stamp_path(group, k)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(time.strftime("%Y-%m-%dT%H:%M:%S\n"))
    except OSError:
        return None
    return path


def start_background(group: str, k: str | None = None) -> str:
    """Start ``afmforce warmup --only GROUP`` as a detached process unless one runs already
    (a lock file with its pid). Returns "started", "running" (another one holds the lock) or
    "failed" (no state folder, no process)."""
    k = k or key()
    folder = state_dir()
    lock = folder / f"warming-{group}-{k}.lock"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        if lock.exists():
            try:
                pid = int(lock.read_text().split()[0])
            except (OSError, ValueError, IndexError):
                pid = 0
            if pid and pid_alive(pid) and time.time() - lock.stat().st_mtime < LOCK_STALE_S:
                return "running"
            lock.unlink(missing_ok=True)
        fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
    except FileExistsError:
        return "running"                # another command took it a moment ago
    except OSError:
        return "failed"
    import subprocess

    env = {name: value for name, value in os.environ.items() if name != "NUMBA_DISABLE_JIT"}
    if env.get("NUMBA_CACHE_DIR"):
        env["NUMBA_CACHE_DIR"] = os.path.abspath(env["NUMBA_CACHE_DIR"])
    env[ENV] = "compile"
    try:
        log = open(folder / f"warmup-{group}.log", "wb")
        proc = subprocess.Popen([sys.executable, "-m", "afmforce.cli.main", "warmup", "--only", group,
                                 "--lock", str(lock)],
                                cwd=str(folder), env=env, stdin=subprocess.DEVNULL, stdout=log,
                                stderr=subprocess.STDOUT, start_new_session=True)
        log.close()
    except OSError:
        os.close(fd)
        lock.unlink(missing_ok=True)
        return "failed"
    os.write(fd, f"{proc.pid}\n".encode())
    os.close(fd)
    return "started"


def _cores() -> int:
    from .._cores import available_cores

    return available_cores()


def interpretable(command: str, args) -> bool:
    """Whether this run may use the kernels as Python (numba not imported yet): ``simulate``
    where a timer can stop it (:func:`guard`), ``analyze`` of a few small files (or shipped
    examples), in this process (no cluster), without a contact fit (:data:`HEAVY_FLAGS`)."""
    if "numba" in sys.modules:
        return False
    if command == "simulate":
        import signal

        return hasattr(signal, "setitimer") and hasattr(signal, "SIGVTALRM")
    if command != "analyze":
        return False
    if getattr(args, "scheduler", None) or getattr(args, "workers", None):
        return False
    if any(getattr(args, name, None) for name in HEAVY_FLAGS) or any(
            str(o).startswith("indentation.model") for o in getattr(args, "option", None) or ()):
        return False
    inputs = list(getattr(args, "files", []) or [])
    if len(inputs) + len(getattr(args, "example", []) or []) > MAX_INTERPRETED_INPUTS:
        return False
    total = 0
    for name in inputs:
        path = Path(name)
        if not path.is_file():
            return False                # a folder (or a missing file: the command says so)
        total += path.stat().st_size
    return total <= MAX_INTERPRETED_BYTES


def prepare(command: str, args, notice) -> str:
    """Before a command runs: what its first run does ("warm", "interpreted", "compile").

    ``notice(text)`` prints one line on stderr. Sets ``NUMBA_DISABLE_JIT`` for this process
    when it runs interpreted."""
    group = COMMAND_GROUP.get(command)
    if group is None or os.environ.get(ENV, "") == "compile" or os.environ.get("NUMBA_DISABLE_JIT"):
        return "compile"
    k = key()
    if is_warm(group, k):
        return "warm"
    later = [g for g in COMMAND_LATER.get(command, ()) if not is_warm(g, k)]
    if later and "numba" not in sys.modules and _cores() >= 2:
        for g in later:
            start_background(g, k)
    if not interpretable(command, args):
        return "compile"
    started = start_background(group, k)
    if started == "failed":             # nothing would ever compile them: compile here, as before
        return "compile"
    os.environ["NUMBA_DISABLE_JIT"] = "1"
    simulating = command == "simulate"
    notice(f"afmforce: first run: {KERNELS[group]} " + ("being compiled in the background"
           if started == "started" else "still being compiled in the background")
           + (" (~20 s of one core, once); this run uses it uncompiled (the same results)" if simulating
              else " (~1 min of one core, once); this run uses them uncompiled (same results to rounding)"))
    if simulating:
        guard(args, notice)
    return "interpreted"


class _TooLong(BaseException):
    """The integrator as Python ran past its budget (a BaseException: no ``except Exception``
    of the command swallows it)."""


def guard(args, notice, budget: float | None = None) -> None:
    """Bound the integrator's run as Python (NUMBA_DISABLE_JIT already set): after ``budget``
    seconds of this process' CPU time (:data:`INTERPRETED_BUDGET_S`) a timer stops the command
    while it integrates (or at its next drive segment: before it writes anything) and this
    process becomes the same command line run compiled (``os.execv``; the warmup started in
    the background meanwhile may have compiled it already). ``args.func`` is wrapped; the
    integrator's entry point (``dynamics.radau.integrate_segment``, a Python function here)
    too."""
    import signal

    from ..dynamics import radau

    state = {"inside": 0, "over": False}
    entry = radau.integrate_segment

    def integrate_segment(*a):
        if state["over"]:
            raise _TooLong
        state["inside"] += 1
        try:
            return entry(*a)
        finally:
            state["inside"] -= 1

    def alarm(signum, frame):
        state["over"] = True
        if state["inside"]:
            raise _TooLong

    func = args.func

    def run(a):
        previous = signal.signal(signal.SIGVTALRM, alarm)
        signal.setitimer(signal.ITIMER_VIRTUAL, INTERPRETED_BUDGET_S if budget is None else budget)
        try:
            return func(a)
        except _TooLong:
            pass
        finally:
            signal.setitimer(signal.ITIMER_VIRTUAL, 0.0)
            signal.signal(signal.SIGVTALRM, previous)
            radau.integrate_segment = entry
        notice("afmforce: first run: this run is long for the uncompiled integrator; "
               "compiling it now instead (~20 s, once)")
        _run_compiled()

    radau.integrate_segment = integrate_segment
    args.func = run


def _run_compiled() -> None:
    """Replace this process by its command line run compiled (never returns)."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    env = {name: value for name, value in os.environ.items() if name != "NUMBA_DISABLE_JIT"}
    env[ENV] = "compile"
    os.execve(sys.executable, [sys.executable, "-m", "afmforce.cli.main", *sys.argv[1:]], env)
