"""Which afmforce kernels numba compiles more than once, and what each compile costs.

Runs afmforce commands in this process (``AFMFORCE_FIRST_RUN=compile``: compiled, as
``afmforce warmup`` runs them) and records numba's ``numba:compile`` events: each
(kernel, signature) compiled, its own seconds (the time of the kernels it compiled on the way
excluded) and its seconds in all (CPU seconds of this process: numba compiles in one
thread, and a loaded machine does not inflate them). Then walks every imported afmforce module for numba
dispatchers and lists those that hold more than one signature.

Run with an empty cache to see every compile::

    NUMBA_CACHE_DIR=$(mktemp -d) python benchmarks/kernel_signatures.py
    NUMBA_CACHE_DIR=$(mktemp -d) python benchmarks/kernel_signatures.py -- analyze FILE

(with a warm cache only what is missing compiles; the signatures are those called either way).
With no command it runs the workload of ``afmforce warmup``'s group ``--group`` (default: the
analysis, every shipped sample file).
``--json PATH`` writes the records.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import sys
import tempfile
import time


def _workload(group: str) -> list[list[str]]:
    from pathlib import Path

    from afmforce.cli import warmup

    return warmup._workload(group, Path(tempfile.mkdtemp(prefix="afmforce-signatures-")))


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--group", default="analysis", help="afmforce warmup's group whose workload runs "
                   "(analysis, simulate, demo) when no command is given")
    p.add_argument("--json", default=None, help="write the records here")
    p.add_argument("--all", action="store_true", help="also list numba's own functions compiled more "
                   "than once (its overloads of numpy: compiled per caller, not ours to change)")
    p.add_argument("command", nargs="*", help="an afmforce command line (after --)")
    args = p.parse_args(argv)
    os.environ["AFMFORCE_FIRST_RUN"] = "compile"

    from numba.core import event
    from numba.core.registry import CPUDispatcher

    records: list[dict] = []
    stack: list[list] = []

    class Listener(event.Listener):
        def on_start(self, ev):
            d = ev.data["dispatcher"]
            stack.append([time.process_time(), 0.0, f"{d.py_func.__module__}.{d.py_func.__qualname__}"])

        def on_end(self, ev):
            start, inner, kernel = stack.pop()
            total = time.process_time() - start
            if stack:
                stack[-1][1] += total
            records.append({"kernel": kernel, "args": str(tuple(ev.data["args"])), "self_s": total - inner,
                            "total_s": total, "caller": stack[-1][2] if stack else None})

    commands = [args.command] if args.command else _workload(args.group)
    from afmforce.cli.main import main as cli

    wall = time.perf_counter()
    with event.install_listener("numba:compile", Listener()):
        for command in commands:
            with tempfile.TemporaryDirectory() as tmp:
                here = os.getcwd()
                os.chdir(tmp)
                try:
                    with contextlib.redirect_stdout(io.StringIO()):
                        rc = cli(command)
                finally:
                    os.chdir(here)
            if rc:
                print(f"afmforce {' '.join(command)} exited {rc}", file=sys.stderr)
    wall = time.perf_counter() - wall
    cpu = time.process_time()

    multi = []
    seen = set()
    for name, module in sorted(sys.modules.items()):
        if not name.startswith("afmforce") or module is None:
            continue
        for value in vars(module).values():
            if isinstance(value, CPUDispatcher) and id(value) not in seen:
                seen.add(id(value))
                if len(value.signatures) > 1:
                    multi.append((f"{value.py_func.__module__}.{value.py_func.__qualname__}",
                                  [str(s) for s in value.signatures]))
    compile_s = sum(r["self_s"] for r in records)
    by_kernel: dict[str, list[dict]] = {}
    for r in records:
        by_kernel.setdefault(r["kernel"], []).append(r)
    repeated = {k: v for k, v in by_kernel.items() if len(v) > 1 and (args.all or k.startswith("afmforce"))}
    extra_s = sum(sum(r["self_s"] for r in v) - max(r["self_s"] for r in v) for v in repeated.values())
    print(f"wall {wall:.1f} s, CPU {cpu:.1f} s; {len(records)} compiles of {len(by_kernel)} kernels, "
          f"{compile_s:.1f} s of compiling; {len(seen)} dispatchers imported")
    print(f"kernels compiled more than once: {len(repeated)} (their extra compiles ~{extra_s:.1f} s)")
    for k, v in sorted(repeated.items(), key=lambda kv: -sum(r["self_s"] for r in kv[1])):
        print(f"  {k}: {len(v)}x")
        for r in v:
            print(f"      {r['self_s']:5.2f} s {r['args']} <- {r['caller'] or 'Python'}")
    print(f"dispatchers holding more than one signature: {len(multi)}")
    for k, sigs in multi:
        print(f"  {k}: {sigs}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"wall_s": wall, "cpu_s": cpu, "records": records, "multi": multi}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
