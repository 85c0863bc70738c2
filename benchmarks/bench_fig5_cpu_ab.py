"""A/B of the Fig-5 cycle's CPU time on a loaded machine (issue 31: the laws registry's cost).

``python benchmarks/bench_fig5_cpu_ab.py --before DIR [--rounds 8] [--runs 80]``: ``DIR`` is
another checkout (``git archive <commit> | tar -x -C DIR``). Each round runs, in a fresh process
per tree (alternating), ``--runs`` Fig-5 cycles (a new configuration each: no cached setup;
``check="off"``) and records each run's *thread CPU time*, which a shared machine's load
disturbs less than wall time. Prints the minimum, 10th percentile and median per tree.
Use ``benchmarks/bench_ab.py`` for the bitwise comparison of the answers.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics as st
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
CODE = r'''
import json, sys, time
from afmforce.dynamics import simulate, SimulationConfig
simulate(SimulationConfig()); simulate(SimulationConfig())
ts = []
for i in range(int(sys.argv[1])):
    c = SimulationConfig(xi=0.1 + 1e-12 * i)
    t = time.thread_time(); simulate(c, check="off"); ts.append(time.thread_time() - t)
print(json.dumps(ts))
'''


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", type=Path, required=True)
    ap.add_argument("--after", type=Path, default=HERE)
    ap.add_argument("--rounds", type=int, default=8)
    ap.add_argument("--runs", type=int, default=80)
    args = ap.parse_args(argv)
    trees = {"before": args.before / "src", "after": args.after / "src"}
    res: dict[str, list[float]] = {k: [] for k in trees}
    for _ in range(args.rounds):
        for name, src in trees.items():
            env = {**os.environ, "PYTHONPATH": str(src), "NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
            out = subprocess.run([sys.executable, "-c", CODE, str(args.runs)], env=env,
                                 capture_output=True, text=True, check=True)
            res[name] += json.loads(out.stdout.strip().splitlines()[-1])
    for name, ts in res.items():
        ts.sort()
        print(f"{name}: min {ts[0] * 1e3:.3f} ms, 10th pct {ts[len(ts) // 10] * 1e3:.3f} ms, "
              f"median {st.median(ts) * 1e3:.3f} ms (n={len(ts)})")
    b, a = sorted(res["before"]), sorted(res["after"])
    print(f"after/before: min {a[0] / b[0]:.3f}, median {st.median(a) / st.median(b):.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
