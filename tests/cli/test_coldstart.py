"""Issue 35 item 4: the first command after an install answers in seconds, and a stale numba
cache never runs old code. Structural checks only (no wall-clock verdicts): what is imported,
what is compiled, what the cache holds. The timings are in benchmarks/bench_coldstart.py."""

from __future__ import annotations

import json
import math
import os
import pickle
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from afmforce import datasets
from afmforce.cli import _firstrun
from afmforce.cli.main import main

SRC = Path(__file__).resolve().parents[2] / "src"
HEAVY = ("numpy", "numba", "dask", "distributed", "matplotlib", "scipy", "pandas", "xarray", "h5py")


def _python(code: str, tmp_path: Path, *, src: Path = SRC, own_cache: bool = True,
            **env) -> subprocess.CompletedProcess:
    """Run ``code`` in a fresh interpreter: an empty numba cache of its own (``own_cache``; else
    this process's cache) and an empty state folder."""
    full = {k: v for k, v in os.environ.items() if k not in ("NUMBA_DISABLE_JIT", _firstrun.ENV)}
    full.update(PYTHONPATH=str(src), AFMFORCE_STATE_DIR=str(tmp_path / "state"), **env)
    if own_cache:
        full["NUMBA_CACHE_DIR"] = str(tmp_path / "numba")
    elif full.get("NUMBA_CACHE_DIR"):
        full["NUMBA_CACHE_DIR"] = os.path.abspath(full["NUMBA_CACHE_DIR"])
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=full,
                          cwd=tmp_path, timeout=600)


def _files(folder: Path) -> list[Path]:
    return sorted(p for p in folder.rglob("*") if p.is_file()) if folder.exists() else []


def test_importing_the_command_line_loads_no_heavy_library(tmp_path):
    code = ("import sys, afmforce, afmforce.cli.main, afmforce.cli._firstrun, afmforce.cli.warmup\n"
            f"print(sorted(m for m in {HEAVY!r} if m in sys.modules))")
    proc = _python(code, tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "[]"


_COMPILED = """
import gc, sys
compiled = []
if "numba" in sys.modules:
    from numba.core.dispatcher import Dispatcher
    compiled = [o.py_func.__qualname__ for o in gc.get_objects() if isinstance(o, Dispatcher) and o.signatures]
print("LOADED", sorted(m for m in {heavy!r} if m in sys.modules), "COMPILED", compiled, file=sys.stderr)
"""


@pytest.mark.parametrize("argv", [["--help"], ["--version"], ["analyze", "--help"], ["simulate", "--help"],
                                  ["demo", "--help"], ["warmup", "--help"], ["formats"]])
def test_help_and_version_compile_nothing_and_start_nothing(tmp_path, argv):
    """The afmforce process itself (argv from sys.argv) with an empty numba cache: no kernel
    compiled or loaded, no cache file written, no background warmup started; the top-level
    help and version load no numpy at all (a command's help may import its modules to list
    their choices: docs/architecture.md, "The command line")."""
    code = (f"import sys; sys.argv = ['afmforce', *{argv!r}]\n"
            "from afmforce.cli.main import main\n"
            "try:\n    main()\nexcept SystemExit:\n    pass\n" + _COMPILED.format(heavy=HEAVY))
    proc = _python(code, tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "COMPILED []" in proc.stderr
    if argv[0].startswith("--"):                  # afmforce --help, --version
        assert "LOADED [] " in proc.stderr
    assert [f for f in _files(tmp_path / "numba") if f.suffix in (".nbi", ".nbc")] == []
    assert _files(tmp_path / "state") == []


def test_importing_every_module_compiles_no_kernel(tmp_path):
    """No module-level call compiles (or loads) a kernel: a command compiles only what it calls.
    Every module of the package imported, with an empty numba cache."""
    code = ("import importlib, pkgutil, afmforce\n"
            "names = [m.name for m in pkgutil.walk_packages(afmforce.__path__, 'afmforce.')]\n"
            "for name in names:\n    importlib.import_module(name)\n"
            "print('MODULES', len(names), file=sys.stderr)\n" + _COMPILED.format(heavy=HEAVY))
    proc = _python("import sys\n" + code, tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert int(proc.stderr.split("MODULES ")[1].split()[0]) > 150      # the walk saw the package
    assert "COMPILED []" in proc.stderr and "'numba'" in proc.stderr   # the kernels were defined
    assert [f for f in _files(tmp_path / "numba") if f.suffix in (".nbi", ".nbc")] == []


_CALLEE = "from numba import njit\n\n\n@njit(cache=True)\ndef f(x):\n    return x + {c}\n"
_CALLER = ("from numba import njit\n\nfrom ._cs_callee import f\n\n\n@njit(cache=True)\n"
           "def g(x):\n    return {k} * f(x)\n")
_RUN = "import afmforce.instrument._cs_caller as m; print(m.g(1.0), dict(m.g.stats.cache_hits))"


def test_a_kernel_sees_an_edit_of_the_file_it_calls(tmp_path):
    """numba stamps a cached function with its own file only: the caller's cache held the old
    callee (the bug). afmforce's locators stamp every kernel with all the sources a kernel may
    reach (afmforce._jitcache): editing the callee's file, or the caller's, recompiles."""
    pkg = tmp_path / "src" / "afmforce"
    shutil.copytree(SRC / "afmforce", pkg, ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
    callee, caller = pkg / "instrument" / "_cs_callee.py", pkg / "instrument" / "_cs_caller.py"
    callee.write_text(_CALLEE.format(c="1.0"))
    caller.write_text(_CALLER.format(k="2.0"))

    def run() -> tuple[float, bool]:
        proc = _python(_RUN, tmp_path, src=tmp_path / "src")
        assert proc.returncode == 0, proc.stderr
        value, hits = proc.stdout.split(" ", 1)
        return float(value), hits.strip() != "{}"

    assert run() == (4.0, False)                 # compiled and cached
    assert run() == (4.0, True)                  # loaded from the cache
    callee.write_text(_CALLEE.format(c="100.0"))  # another file: numba alone returned 4.0 here
    assert run() == (202.0, False)
    assert run() == (202.0, True)
    caller.write_text(_CALLER.format(k="3.0"))   # its own file (numba's content hash)
    assert run() == (303.0, False)
    (pkg / "constants.py").write_text((pkg / "constants.py").read_text() + "\n# an edit\n")
    assert run() == (303.0, False)               # any source a kernel may reach recompiles it


def test_stamps_follow_the_kernel_sources(tmp_path, monkeypatch):
    pkg = tmp_path / "afmforce"
    shutil.copytree(SRC / "afmforce", pkg, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(_firstrun, "_package", lambda: pkg)
    monkeypatch.setenv("AFMFORCE_STATE_DIR", str(tmp_path / "state"))
    assert not _firstrun.is_warm("analysis")
    assert _firstrun.write_stamp("analysis") is not None
    assert _firstrun.is_warm("analysis") and not _firstrun.is_warm("simulate")
    before = _firstrun.key()
    assert _firstrun.key() == before
    numeric = pkg / "analysis" / "_numeric.py"
    numeric.write_text(numeric.read_text() + "\n")
    assert _firstrun.key() != before and not _firstrun.is_warm("analysis")
    (pkg / "cli" / "main.py").write_text("# the command line holds no kernel\n")
    k = _firstrun.key()
    (pkg / "cli" / "demo.py").write_text("# nor does this\n")
    assert _firstrun.key() == k


def test_one_background_warmup_at_a_time(tmp_path, monkeypatch):
    monkeypatch.setenv("AFMFORCE_STATE_DIR", str(tmp_path))
    k = _firstrun.key()
    lock = tmp_path / f"warming-analysis-{k}.lock"
    lock.write_text(f"{os.getpid()}\n")         # a live process holds it
    assert _firstrun.start_background("analysis", k) == "running"
    assert sorted(p.name for p in tmp_path.iterdir()) == [lock.name]


def test_no_state_folder_no_uncompiled_run(tmp_path, monkeypatch):
    """Where no warmup can start (the state folder is not writable), the first analyze compiles
    in its process as before: running uncompiled would never end."""
    from argparse import Namespace

    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("AFMFORCE_STATE_DIR", str(blocker / "state"))
    monkeypatch.delenv(_firstrun.ENV, raising=False)
    monkeypatch.delenv("NUMBA_DISABLE_JIT", raising=False)
    monkeypatch.delitem(sys.modules, "numba", raising=False)
    assert _firstrun.start_background("analysis") == "failed"
    args = Namespace(files=[], example=["jpk-cell"], scheduler=None, workers=None)
    assert _firstrun.prepare("analyze", args, print) == "compile"
    assert "NUMBA_DISABLE_JIT" not in os.environ


def test_interpreted_only_for_a_few_small_files(tmp_path, monkeypatch):
    from argparse import Namespace

    monkeypatch.delitem(sys.modules, "numba", raising=False)   # as in a fresh afmforce process
    small = tmp_path / "a.txt"
    small.write_bytes(b"0" * 1000)
    big = tmp_path / "b.txt"
    big.write_bytes(b"0" * (_firstrun.MAX_INTERPRETED_BYTES + 1))
    args = dict(files=[str(small)], example=[], scheduler=None, workers=None)
    assert _firstrun.interpretable("analyze", Namespace(**args))
    assert _firstrun.interpretable("simulate", Namespace(**args)) == hasattr(signal, "setitimer")
    assert not _firstrun.interpretable("demo", Namespace(**args))
    assert not _firstrun.interpretable("analyze", Namespace(**{**args, "files": [str(big)]}))
    assert not _firstrun.interpretable("analyze", Namespace(**{**args, "files": [str(tmp_path)]}))
    assert not _firstrun.interpretable("analyze", Namespace(**{**args, "workers": 2}))
    assert not _firstrun.interpretable("analyze", Namespace(**{**args, "indentation_model": "jkr"}))
    assert not _firstrun.interpretable("analyze", Namespace(**{**args, "fast_map": True}))
    assert not _firstrun.interpretable("analyze", Namespace(**{**args, "option": ["indentation.model=jkr"]}))
    assert _firstrun.interpretable("analyze", Namespace(**{**args, "option": ["vdw.max_separation=20nm"]}))
    assert not _firstrun.interpretable("analyze", Namespace(**{**args, "files": [str(small)] * (_firstrun.MAX_INTERPRETED_INPUTS + 1)}))


def test_first_analyze_runs_uncompiled_with_the_compiled_answers(tmp_path, capsys):
    """The first ``afmforce analyze`` with no warm cache: one line on stderr, a warmup started
    in the background (here recorded, not run), numba's JIT off in that process, and the
    results of every shipped sample curve equal to those of the compiled kernels."""
    names = [n for n, d in datasets.DATASETS.items() if Path(datasets.path(n)).suffix != ".tnd"]
    argv = ["analyze", *(a for n in names for a in ("--example", n)), "--json"]
    code = ("import sys, json\n"
            "from afmforce.cli import _firstrun\n"
            "started = []\n"
            "_firstrun.start_background = lambda group, k=None: started.append(group) or 'started'\n"
            f"sys.argv = ['afmforce', *{argv!r}]\n"
            "from afmforce.cli.main import main\n"
            "status = main()\n"
            "import numba\n"
            "print(json.dumps({'status': status, 'started': started, 'jit_off': numba.config.DISABLE_JIT}),"
            " file=sys.stderr)")
    proc = _python(code, tmp_path)
    assert proc.returncode == 0, proc.stderr
    report = json.loads(proc.stderr.strip().splitlines()[-1])
    assert report == {"status": 0, "started": ["analysis"], "jit_off": 1}
    assert "first run: the analysis kernels are being compiled in the background" in proc.stderr
    assert [f for f in _files(tmp_path / "numba") if f.suffix in (".nbi", ".nbc")] == []  # nothing compiled
    interpreted = json.loads(proc.stdout)

    assert main(argv) == 0                        # compiled (this process)
    compiled = json.loads(capsys.readouterr().out)
    assert sorted(interpreted["results"]) == sorted(compiled["results"]) and len(compiled["results"]) == len(names)
    differences = _differences(interpreted, compiled)
    assert differences == [], differences[:5]


#: Python and the compiled kernels round differently in the last bits (the order of a sum, a
#: fused multiply-add): measured up to 1.2e-14 relative (a fringe fit's baseline slope).
REL_TOL = 1e-12


def _differences(a, b, path: str = "") -> list[str]:
    """Where two JSON values differ: keys, lengths, strings exactly, numbers beyond REL_TOL."""
    if isinstance(a, dict) and isinstance(b, dict):
        if set(a) != set(b):
            return [f"{path}: keys {sorted(set(a) ^ set(b))}"]
        return [d for k in a for d in _differences(a[k], b[k], f"{path}/{k}")]
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path}: {len(a)} != {len(b)} items"]
        return [d for i, (u, v) in enumerate(zip(a, b)) for d in _differences(u, v, f"{path}[{i}]")]
    if isinstance(a, float) and isinstance(b, float):
        return [] if math.isclose(a, b, rel_tol=REL_TOL, abs_tol=1e-300) else [f"{path}: {a!r} != {b!r}"]
    return [] if a == b and type(a) is type(b) else [f"{path}: {a!r} != {b!r}"]


def test_demo_compiles_its_analysis_in_the_background_while_it_simulates(tmp_path, monkeypatch):
    """demo cannot run uncompiled (it simulates); on two cores its analysis kernels are
    compiled by a background warmup meanwhile, and only when that warmup has not run."""
    from argparse import Namespace

    started = []
    monkeypatch.setenv("AFMFORCE_STATE_DIR", str(tmp_path))
    monkeypatch.delenv(_firstrun.ENV, raising=False)
    monkeypatch.delenv("NUMBA_DISABLE_JIT", raising=False)
    monkeypatch.delitem(sys.modules, "numba", raising=False)
    monkeypatch.setattr(_firstrun, "start_background", lambda group, k=None: started.append(group) or "started")
    monkeypatch.setattr(_firstrun, "_cores", lambda: 2)
    args = Namespace(out=str(tmp_path / "paper"))
    assert _firstrun.prepare("demo", args, print) == "compile"
    assert started == ["analysis"] and "NUMBA_DISABLE_JIT" not in os.environ
    _firstrun.write_stamp("analysis")
    assert _firstrun.prepare("demo", args, print) == "compile" and started == ["analysis"]
    _firstrun.write_stamp("demo")
    assert _firstrun.prepare("demo", args, print) == "warm"
    monkeypatch.setattr(_firstrun, "_cores", lambda: 1)
    (tmp_path / f"warm-analysis-{_firstrun.key()}").unlink()
    (tmp_path / f"warm-demo-{_firstrun.key()}").unlink()
    assert _firstrun.prepare("demo", args, print) == "compile" and started == ["analysis"]   # one core: no



def test_warmup_leaves_a_stamp_only_when_its_workload_succeeds(tmp_path, monkeypatch, capsys):
    """The warmup's machinery (its workloads replaced by cheap commands: the real ones compile
    for minutes): each group's commands run in a child process, a stamp per group, none when a
    command fails, and the error is one line."""
    from afmforce.cli import warmup

    monkeypatch.setenv("AFMFORCE_STATE_DIR", str(tmp_path))
    monkeypatch.setattr(warmup, "_workload", lambda group, folder: [["formats"]] if group == "analysis"
                        else [["statics", "--k0", "-1N/m"]])
    assert main(["warmup", "--only", "analysis"]) == 0
    assert _firstrun.is_warm("analysis") and "analysis" in capsys.readouterr().out
    assert main(["warmup", "--only", "simulate"]) == 1
    err = capsys.readouterr().err
    assert not _firstrun.is_warm("simulate")
    assert err.startswith("error: the warmup of simulate failed: afmforce statics exited with 2")
    assert len(err.strip().splitlines()) == 1


def test_warmup_workloads_are_commands_that_parse():
    """The real workloads: commands of this CLI whose arguments parse (the sample files exist)."""
    from afmforce.cli import warmup
    from afmforce.cli.main import build_parser

    for group in _firstrun.GROUPS:
        for argv in warmup._workload(group, Path("/tmp/afmforce-warmup-test")):
            args = build_parser(argv[0]).parse_args(argv)
            assert args.command == argv[0]
            for name in getattr(args, "example", []) or []:
                assert Path(datasets.path(name)).is_file()


#: Runs of the kinds the default simulate and the demo make (the paper's figures: spring and
#: beam, viscous friction; the virtual experiment; the liquid one: slip and lever drag, the
#: model with the extras), plus load-dependent friction: (label, simulate's keywords).
_RUNS = """
from afmforce.paper.demo import DEMO_RUNS, _COMMON
from afmforce.paper.demo_liquid import LIQUID_DEMO
from afmforce.paper.runs import FIG1_RUN, FIG5_RUN, FIG9_RUN
RUNS = [("fig1 spring 5 um/s", dict(velocity=5e-6, **FIG1_RUN)),
        ("fig5 beam xi 0.1, 1 um/s", dict(xi=0.1, velocity=1e-6, **FIG5_RUN)),
        ("fig9 spring 2 um/s", dict(velocity=2e-6, sample_rate=4e3, **FIG9_RUN)),
        ("demo virtual run with friction", {**_COMMON, **DEMO_RUNS[1][1]}),
        ("demo liquid 40 um/s", dict(velocity=40e-6, sample_rate=40e3, **LIQUID_DEMO)),
        ("load-dependent friction", dict(friction="load", zeta=3e14, end=-190e-9))]
"""
_SIMULATE_RUNS = _RUNS + """
import dataclasses, pickle, sys
from afmforce.dynamics import simulate
out = []
for label, kw in RUNS:
    tr = simulate(**kw)
    record = {f.name: getattr(tr, f.name) for f in dataclasses.fields(tr)
              if f.name not in ("config", "events", "solver")}
    record["events"] = dataclasses.asdict(tr.events)
    record["solver"] = {k: v for k, v in dataclasses.asdict(tr.solver).items() if k != "wall_time"}
    out.append((label, record))
with open(sys.argv[1], "wb") as f:
    pickle.dump(out, f)
"""


def _bitwise(a, b, path: str = "") -> list[str]:
    """Where two records differ at all (arrays and floats bit for bit, NaN equal to NaN)."""
    if isinstance(a, dict):
        if set(a) != set(b):
            return [f"{path}: keys {sorted(set(a) ^ set(b))}"]
        return [d for k in a for d in _bitwise(a[k], b[k], f"{path}/{k}")]
    if isinstance(a, np.ndarray):
        same = a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
        return [] if same else [f"{path}: arrays differ"]
    if isinstance(a, float):
        return [] if np.float64(a).tobytes() == np.float64(b).tobytes() else [f"{path}: {a!r} != {b!r}"]
    return [] if a == b else [f"{path}: {a!r} != {b!r}"]


def test_the_integrator_as_python_takes_the_compiled_steps_bitwise(tmp_path):
    """The integrator run as Python (NUMBA_DISABLE_JIT, a fresh process) gives the compiled
    integrator's trajectories bit for bit: every sampled array, every event, every solver
    count (the step sizes follow from every bit of the state, so one rounding apart anywhere
    would show), on the kinds of runs the default simulate and the demo make. numba compiles
    ``x ** 3`` as ``x * x * x`` where Python calls pow: written out in the kernels."""
    script = tmp_path / "runs.py"
    script.write_text(_SIMULATE_RUNS)
    full = {k: v for k, v in os.environ.items() if k != _firstrun.ENV}
    full.update(PYTHONPATH=str(SRC), NUMBA_DISABLE_JIT="1", NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    # the interpreted runs in their process while this one runs the compiled: the same two
    # computations as one after the other, side by side (the suite runs on one core of two)
    with subprocess.Popen([sys.executable, str(script), str(tmp_path / "python.pkl")], stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True, env=full, cwd=tmp_path) as child:
        try:
            namespace: dict = {}
            compiled_runs = _SIMULATE_RUNS.replace("sys.argv[1]", repr(str(tmp_path / "compiled.pkl")))
            exec(compiled_runs, namespace)                              # compiled, in this process
            _, stderr = child.communicate(timeout=900)
        finally:
            if child.poll() is None:
                child.kill()
    assert child.returncode == 0, stderr
    assert [f for f in _files(tmp_path / "numba") if f.suffix in (".nbi", ".nbc")] == []   # nothing compiled
    interpreted = pickle.loads((tmp_path / "python.pkl").read_bytes())
    compiled = pickle.loads((tmp_path / "compiled.pkl").read_bytes())
    assert [label for label, _ in interpreted] == [label for label, _ in compiled]
    for (label, a), (_, b) in zip(interpreted, compiled):
        assert len(a["time"]) > 100 and a["solver"]["steps"] > 100, label     # a real run
        differences = _bitwise(a, b)
        assert differences == [], (label, differences[:5])


def _without_wall_time(csv: Path) -> list[str]:
    """The trajectory file's lines, its solver header without the wall time."""
    lines = csv.read_text().splitlines()
    for i, line in enumerate(lines):
        if line.startswith("# solver: "):
            solver = json.loads(line[len("# solver: "):])
            assert solver.pop("wall_time") > 0.0
            lines[i] = "# solver: " + json.dumps(solver)
    return lines


_FIRST_SIMULATE = """
import sys, json
from afmforce.cli import _firstrun
started = []
_firstrun.start_background = lambda group, k=None: started.append(group) or 'started'
_firstrun.INTERPRETED_BUDGET_S = {budget}
sys.argv = ['afmforce', 'simulate', '--out', 'first.csv', '--no-progress']
from afmforce.cli.main import main
status = main()
import numba
print(json.dumps({{'status': status, 'started': started, 'jit_off': numba.config.DISABLE_JIT}}), file=sys.stderr)
"""


@pytest.mark.skipif(not hasattr(signal, "setitimer"), reason="no interval timer: simulate compiles")
def test_first_simulate_runs_uncompiled_with_the_compiled_answers(tmp_path):
    """The first ``afmforce simulate`` with no warm cache: one line on stderr, the warmup of the
    integrator started in the background (here recorded), nothing compiled, and the trajectory
    file equal to the compiled run's, byte for byte but the wall time."""
    proc = _python(_FIRST_SIMULATE.format(budget=600.0), tmp_path)
    assert proc.returncode == 0, proc.stderr
    report = json.loads(proc.stderr.strip().splitlines()[-1])
    assert report == {"status": 0, "started": ["simulate"], "jit_off": 1}
    notes = [line for line in proc.stderr.splitlines() if line.startswith("afmforce:")]
    assert len(notes) == 1 and "the integrator is being compiled in the background" in notes[0]
    assert [f for f in _files(tmp_path / "numba") if f.suffix in (".nbi", ".nbc")] == []
    assert main(["simulate", "--out", str(tmp_path / "compiled.csv"), "--no-progress"]) == 0
    assert _without_wall_time(tmp_path / "first.csv") == _without_wall_time(tmp_path / "compiled.csv")


@pytest.mark.skipif(not hasattr(signal, "setitimer"), reason="no interval timer: simulate compiles")
def test_an_uncompiled_simulate_past_its_budget_runs_again_compiled(tmp_path):
    """Past its budget (here 1 ms of CPU time: the timer fires before or while it integrates) the first
    simulate stops before writing anything and the process becomes the same command run
    compiled (this process's numba cache): one more line, the same file."""
    proc = _python(_FIRST_SIMULATE.format(budget=0.001), tmp_path, own_cache=False)
    assert proc.returncode == 0, proc.stderr
    notes = [line for line in proc.stderr.splitlines() if line.startswith("afmforce:")]
    assert "being compiled in the background" in notes[0]
    assert "long for the uncompiled integrator; compiling it now" in notes[1]
    assert not proc.stderr.strip().splitlines()[-1].startswith("{")     # execv: the script did not go on
    assert "wrote first.csv" in proc.stdout
    assert main(["simulate", "--out", str(tmp_path / "compiled.csv"), "--no-progress"]) == 0
    assert _without_wall_time(tmp_path / "first.csv") == _without_wall_time(tmp_path / "compiled.csv")
