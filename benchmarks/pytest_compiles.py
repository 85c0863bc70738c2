"""A pytest plugin: which tests make numba compile, and which kernels they compile more than once.

Run from the repository root (``benchmarks`` on the path), with an empty cache to see every compile::

    NUMBA_CACHE_DIR=$(mktemp -d) PYTHONPATH=src:benchmarks \\
        pytest -p pytest_compiles -p no:cacheprovider -q tests/analysis

At the end it prints the CPU seconds numba spent compiling in each test (the slowest first) and
every kernel compiled for more than one signature in the run, with the test that compiled each
(numba's ``numba:compile`` events; CPU seconds of the pytest process: a subprocess's compiles are
not seen). ``AFMFORCE_COMPILES_JSON=PATH`` also writes the records.
"""

from __future__ import annotations

import json
import os
import time

_records: list[dict] = []
_stack: list[list] = []
_current = {"test": "(collection)"}


def pytest_configure(config):
    from numba.core import event

    class Listener(event.Listener):
        def on_start(self, ev):
            _stack.append([time.process_time(), 0.0])

        def on_end(self, ev):
            start, inner = _stack.pop()
            total = time.process_time() - start
            if _stack:
                _stack[-1][1] += total
            d = ev.data["dispatcher"]
            _records.append({"test": _current["test"],
                             "kernel": f"{d.py_func.__module__}.{d.py_func.__qualname__}",
                             "args": str(tuple(ev.data["args"])), "self_s": total - inner})

    event.register("numba:compile", Listener())


def pytest_runtest_setup(item):
    _current["test"] = item.nodeid


def pytest_terminal_summary(terminalreporter):
    tr = terminalreporter
    per_test: dict[str, float] = {}
    per_kernel: dict[str, list[dict]] = {}
    for r in _records:
        per_test[r["test"]] = per_test.get(r["test"], 0.0) + r["self_s"]
        if r["kernel"].startswith("afmforce"):
            per_kernel.setdefault(r["kernel"], []).append(r)
    tr.write_sep("=", f"numba compiles: {len(_records)}, {sum(per_test.values()):.1f} s of CPU")
    for test, s in sorted(per_test.items(), key=lambda kv: -kv[1])[:25]:
        tr.write_line(f"{s:7.1f} s  {test}")
    multi = {k: v for k, v in per_kernel.items() if len(v) > 1}
    tr.write_sep("-", f"afmforce kernels compiled for more than one signature: {len(multi)}")
    for k, v in sorted(multi.items(), key=lambda kv: -sum(r["self_s"] for r in kv[1])):
        tr.write_line(f"{k}: {len(v)}x")
        for r in v:
            tr.write_line(f"    {r['self_s']:5.2f} s {r['args']}  <- {r['test']}")
    path = os.environ.get("AFMFORCE_COMPILES_JSON")
    if path:
        with open(path, "w") as f:
            json.dump(_records, f, indent=1)
