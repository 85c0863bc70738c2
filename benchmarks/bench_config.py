"""Cost of building a SimulationConfig (issues 11.7 and 16): ``python benchmarks/bench_config.py``.

A sweep or a fit builds one configuration per run, mostly with one value
changed; the cost that matters is construction with a *new* value (the
caches of the cantilever and of the static solves miss). Rows, median and
minimum over ``-n`` constructions [us]:

- ``SimulationConfig()`` and ``SimulationConfig(**SHORT)`` (4 drive fields);
- a new ``xi`` / ``hamaker`` / ``k0`` every time (``k0``: a new cantilever);
- ``config.replace(velocity=...)``;
- a new ``hamaker`` plus the static start solve (``validate()``; before issue
  11.7 construction always did it), i.e. what a run needs before integrating;
- ``simulate(**SHORT)``: a whole short run (no contact, ~18 steps).

Works on the versions before and after issue 11.7 (flat keyword names), so the
same script gives the before/after table. Options: ``-n N``, ``--json FILE``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics as st
import time
import warnings

SHORT = dict(start=-40e-9, turn=-35e-9, end=-40e-9, velocity=1e-6)


def _time(fn, n):
    out = []
    for i in range(n):
        t0 = time.perf_counter()
        fn(i)
        out.append(time.perf_counter() - t0)
    return st.median(out) * 1e6, min(out) * 1e6


def main(n: int = 4000) -> dict:
    from afmforce.dynamics import SimulationConfig, simulate

    def with_start(i):
        cfg = SimulationConfig(hamaker=2e-19 * (1 + i * 1e-7))
        if hasattr(cfg, "validate"):       # after issue 11.7 the solve is lazy
            cfg.validate()

    base = SimulationConfig()
    SimulationConfig(**SHORT)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        simulate(**SHORT)
        rows = {
            "SimulationConfig()": _time(lambda i: SimulationConfig(), n),
            "SimulationConfig(**SHORT)": _time(lambda i: SimulationConfig(**SHORT), n),
            "new xi each time": _time(lambda i: SimulationConfig(xi=0.01 + i * 1e-7), n),
            "new hamaker each time": _time(lambda i: SimulationConfig(hamaker=1e-19 * (1 + i * 1e-7)), n),
            "new k0 each time (new cantilever)": _time(lambda i: SimulationConfig(k0=0.1 * (1 + i * 1e-7)), n),
            "replace(velocity=new)": _time(lambda i: base.replace(velocity=1e-7 * (1 + i * 1e-7)), n),
            "new hamaker + static start solve": _time(with_start, n),
            "simulate(**SHORT), whole short run": _time(lambda i: simulate(**SHORT), max(1, n // 4)),
        }
    print(f"load average {os.getloadavg()[0]:.2f}; {n} constructions per row; [us]")
    for k, (med, mn) in rows.items():
        print(f"  {k:40s} median {med:8.1f}   min {mn:8.1f}")
    return rows


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-n", type=int, default=4000)
    ap.add_argument("--json")
    a = ap.parse_args()
    r = main(a.n)
    if a.json:
        with open(a.json, "w") as fh:
            json.dump({k: {"median_us": v[0], "min_us": v[1]} for k, v in r.items()}, fh, indent=1)
