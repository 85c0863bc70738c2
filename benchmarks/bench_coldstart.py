"""Benchmark: the first afmforce command after an install, cold and warm (issue 35, item 4).

Run::

    python benchmarks/bench_coldstart.py [--commands help,version,analyze,simulate,demo]
                                         [--mode both|first-run|compile] [--json FILE]

Each command runs as ``python -m afmforce.cli.main ...`` (the console script's path: the
first-run behaviour of cli/_firstrun.py applies) in a fresh process with an empty numba cache
(``NUMBA_CACHE_DIR``: a new temporary folder per command) and an empty afmforce state folder
(``AFMFORCE_STATE_DIR``), then again with the cache it left ("warm"). Printed per run: wall
time, the CPU time of the command and the children it waited for (``resource``), the load
average before and after (the machine is shared: wall time grows with the load, CPU time
much less). ``--mode compile`` runs with ``AFMFORCE_FIRST_RUN=compile`` (the behaviour before
issue 35: the first analyze compiles its kernels in the process); ``first-run`` with the
default (the first analyze and the first simulate run their kernels uncompiled while
``afmforce warmup`` compiles them in a detached process; the warm run follows once that warmup
has finished, and the benchmark waits for it, up to 10 min; demo compiles in both modes, with
its analysis' warmup in the background in the first-run mode).

``analyze`` is ``analyze --example jpk-cell`` (a 22 kB JPK CellHesion curve shipped with
afmforce), ``simulate`` the default run (``--out``: a temporary file), ``demo`` the whole
demo. Also printed: the wall time to the first result on stdout (the demo: the first row of its
check table; other commands: their first line). The
verdict "< 3 s" is printed, never asserted (benchmarks, not tests).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

COMMANDS = {
    "help": ["--help"],
    "version": ["--version"],
    "analyze": ["analyze", "--example", "jpk-cell"],
    "simulate": ["simulate", "--out", "{tmp}/{run}.csv"],
    "demo": ["demo", "--out", "{tmp}/demo-{run}"],
}
#: A line of stdout that is a first result (the demo's title comes at once: its first result is
#: the first row of the paper's check table); other commands: their first line.
FIRST_RESULT = {"demo": re.compile(r"\s(yes|NO|-)$")}


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_once(argv: list[str], env: dict, cwd: Path, result: re.Pattern | None = None) -> dict:
    """One run; ``first_output_s`` is the wall time to its first result on stdout (``result``
    matches it; else the first line: the demo prints the paper's check table first, then each
    part as it is done)."""
    load = os.getloadavg()[0]
    cpu0, t0 = _children_cpu(), time.perf_counter()
    first = None
    with tempfile.TemporaryFile("w+") as err:
        proc = subprocess.Popen([sys.executable, "-m", "afmforce.cli.main", *argv], env=env, cwd=cwd,
                                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=err, text=True)
        for line in proc.stdout:
            if first is None and line.strip() and (result is None or result.search(line.rstrip())):
                first = time.perf_counter() - t0
        proc.wait()
        err.seek(0)
        stderr = err.read()
    wall, cpu = time.perf_counter() - t0, _children_cpu() - cpu0
    notes = [line for line in stderr.splitlines() if line.startswith("afmforce:")]
    return {"status": proc.returncode, "wall_s": round(wall, 3), "cpu_s": round(cpu, 3),
            "first_output_s": None if first is None else round(first, 3),
            "load_before": round(load, 2), "load_after": round(os.getloadavg()[0], 2), "notes": notes}


def _wait_for_warmup(state: Path, timeout: float = 600.0) -> float:
    """Seconds waited for the background warmup's lock to go (0 when none ran)."""
    t0 = time.perf_counter()
    while list(state.glob("warming-*.lock")) and time.perf_counter() - t0 < timeout:
        time.sleep(1.0)
    return time.perf_counter() - t0


def bench(name: str, mode: str) -> dict:
    with tempfile.TemporaryDirectory(prefix="afmforce-coldstart-") as tmp:
        tmp = Path(tmp)
        env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_DISABLE_JIT", "AFMFORCE_FIRST_RUN")}
        env.update(NUMBA_CACHE_DIR=str(tmp / "numba"), AFMFORCE_STATE_DIR=str(tmp / "state"))
        env.setdefault("PYTHONPATH", str(ROOT / "src"))
        if mode == "compile":
            env["AFMFORCE_FIRST_RUN"] = "compile"
        cold = run_once([a.format(tmp=tmp, run="cold") for a in COMMANDS[name]], env, tmp, FIRST_RESULT.get(name))
        waited = _wait_for_warmup(tmp / "state")
        warm = run_once([a.format(tmp=tmp, run="warm") for a in COMMANDS[name]], env, tmp, FIRST_RESULT.get(name))
        return {"command": " ".join(COMMANDS[name]), "mode": mode, "cold": cold, "warm": warm,
                "background_warmup_s": round(waited, 1)}


def _s(value) -> str:
    return "-" if value is None else f"{value:.2f} s"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--commands", default="help,version,analyze,simulate,demo")
    ap.add_argument("--mode", choices=("both", "first-run", "compile"), default="both")
    ap.add_argument("--json", type=Path, default=None, help="write the results as JSON")
    args = ap.parse_args()
    modes = ("compile", "first-run") if args.mode == "both" else (args.mode,)
    print(f"python {sys.version.split()[0]}, {os.cpu_count()} CPUs, load average {os.getloadavg()}")
    print(f"{'command':<36} {'mode':<10} {'cold wall':>9} {'cold cpu':>8} {'warm wall':>9} {'warm cpu':>8} "
          f"{'load':>10}  < 3 s cold  first result cold / warm")
    results = []
    for name in args.commands.split(","):
        for mode in modes:
            if mode == "first-run" and name not in ("analyze", "simulate", "demo") and "compile" in modes:
                continue                      # the same behaviour in both modes
            r = bench(name, mode)
            results.append(r)
            c, w = r["cold"], r["warm"]
            print(f"{r['command'][:36]:<36} {mode:<10} {c['wall_s']:9.2f} {c['cpu_s']:8.2f} {w['wall_s']:9.2f} "
                  f"{w['cpu_s']:8.2f} {c['load_before']:4.1f}-{w['load_after']:<4.1f}  "
                  f"{'yes' if c['wall_s'] < 3 else 'no'}{'' if c['status'] == 0 else ' (exit ' + str(c['status']) + ')'}"
                  f"  {_s(c['first_output_s'])} / {_s(w['first_output_s'])}",
                  flush=True)
            for note in c["notes"]:
                print(f"    {note}")
            if r["background_warmup_s"] > 1:
                print(f"    (waited {r['background_warmup_s']} s for the background warmup before the warm run)")
    if args.json:
        args.json.write_text(json.dumps(results, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
