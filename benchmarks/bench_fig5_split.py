"""Where the Fig-5 cycle's CPU time goes (issue 35.5): ``python benchmarks/bench_fig5_split.py [--runs 60]``.

Runs the default Fig-5 cycle ``--runs`` times (a new configuration each: no cached setup;
``check="off"``) with thread-CPU-time wrappers around the compiled calls of
:mod:`afmforce.dynamics.simulate` — the integrator (``integrate_segment``, which samples the
instrument grid as it steps), the sampled-column pass (``sample_columns``) and the compliance
fits (``fit_compliance``) — and prints the best of each, the rest of the call as "python",
the load average and the accepted steps. Compare trees by alternating processes with
``PYTHONPATH=<tree>/src``.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
import time


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=60)
    args = ap.parse_args(argv)
    from afmforce.dynamics import SimulationConfig, simulate

    sm = importlib.import_module("afmforce.dynamics.simulate")
    spent: dict[str, float] = {}

    def wrap(obj, name, key):
        inner = getattr(obj, name)

        def timed(*a, **k):
            t0 = time.thread_time()
            out = inner(*a, **k)
            spent[key] = spent.get(key, 0.0) + time.thread_time() - t0
            return out
        setattr(obj, name, timed)

    wrap(sm, "sample_columns", "sampled columns")
    wrap(sm, "fit_compliance", "compliance fits")
    wrap(sm.R, "integrate_segment", "integrator")
    simulate(SimulationConfig())
    simulate(SimulationConfig())
    best: dict[str, float] = {}
    tr = None
    for i in range(args.runs):
        spent.clear()
        cfg = SimulationConfig(xi=0.1 + 1e-12 * i)
        t0 = time.thread_time()
        tr = simulate(cfg, check="off")
        spent["total"] = time.thread_time() - t0
        spent["python"] = spent["total"] - sum(v for k, v in spent.items() if k != "total")
        for k, v in spent.items():
            best[k] = min(best.get(k, v), v)
    print(f"load {os.getloadavg()[0]:.2f}; best of {args.runs}, thread CPU [ms]: "
          + ", ".join(f"{k} {v * 1e3:.3f}" for k, v in best.items())
          + f"; {tr.solver.accepted} accepted steps")
    return 0


if __name__ == "__main__":
    sys.exit(main())
