"""``afmforce warmup``: compile the kernels the commands use, once, ahead of their first run.

afmforce's kernels are compiled on their first call and cached on disk. This runs each
group's commands once on the shipped sample files and default settings (outputs in a
temporary folder), so that the cache holds what those commands call; later runs load them
in seconds. The first afmforce analyze (simulate) starts it in the background for the
analysis (the integrator). Safe to run again.

Each group's workload is :data:`afmforce.cli._firstrun.GROUPS`; a stamp per group says it ran
(docs/architecture.md, "First run").
"""

from __future__ import annotations

import argparse
import contextlib
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from ..errors import AfmforceError
from . import _firstrun


def register(sub) -> None:
    p = sub.add_parser("warmup", help="compile the kernels the commands use, once, ahead of their first run",
                       description=__doc__.split("\n\n")[1].replace("\n", " "))
    p.add_argument("--only", action="append", default=[], choices=tuple(_firstrun.GROUPS), metavar="GROUP",
                   help="compile only this group (repeatable): " + "; ".join(
                       f"{name}: {what}" for name, what in _firstrun.GROUPS.items()))
    p.add_argument("--lock", default=None, help=argparse.SUPPRESS)   # the background start's lock file
    p.add_argument("--json", action="store_true", help="print the groups compiled and their times as JSON")
    p.set_defaults(func=run)


def _workload(group: str, folder: Path) -> list[list[str]]:
    """The commands whose first run compiles ``group``'s kernels."""
    from .. import datasets

    if group == "analysis":
        names = [n for n, d in datasets.DATASETS.items() if Path(datasets.path(n)).suffix != ".tnd"]
        return [["analyze", *(a for n in names for a in ("--example", n))]]
    if group == "simulate":
        return [["simulate", "--out", str(folder / "run.csv")]]
    return [["demo", "--out", str(folder / "demo")]]


def warm(group: str) -> float:
    """Run ``group``'s workload in a child process (its output discarded unless it fails) and
    leave its stamp; returns the seconds it took."""
    start = time.perf_counter()
    k = _firstrun.key()                 # before compiling: sources edited meanwhile leave no stamp
    env = {name: value for name, value in os.environ.items() if name != "NUMBA_DISABLE_JIT"}
    env[_firstrun.ENV] = "compile"                  # the workload compiles, here and now
    with tempfile.TemporaryDirectory(prefix="afmforce-warmup-") as tmp:
        for argv in _workload(group, Path(tmp)):
            proc = subprocess.run([sys.executable, "-m", "afmforce.cli.main", *argv], cwd=tmp, env=env,
                                  stdin=subprocess.DEVNULL, capture_output=True, text=True)
            if proc.returncode != 0:
                tail = (proc.stderr or proc.stdout).strip().splitlines()[-1:] or ["no output"]
                raise AfmforceError(f"the warmup of {group} failed: afmforce {argv[0]} exited with "
                                    f"{proc.returncode}: {tail[0]}")
    _firstrun.write_stamp(group, k)
    return time.perf_counter() - start


def run(args: argparse.Namespace) -> int:
    from .common import print_json

    groups = args.only or list(_firstrun.GROUPS)
    if args.lock and hasattr(os, "nice"):       # started in the background: the command that started
        with contextlib.suppress(OSError):      # it (and the user's next ones) come first
            os.nice(10)
    times: dict[str, float] = {}
    try:
        for group in groups:
            if not args.json:
                print(f"compiling {group}: {_firstrun.GROUPS[group]} ...", flush=True)
            times[group] = warm(group)
            if not args.json:
                print(f"  {group}: {times[group]:.1f} s", flush=True)
    finally:
        if args.lock:
            with contextlib.suppress(OSError):
                os.unlink(args.lock)
    if args.json:
        print_json({"command": "warmup", "exit_status": 0, "groups": times})
    else:
        print(f"the kernels of {', '.join(groups)} are in numba's cache; later runs load them")
    return 0
