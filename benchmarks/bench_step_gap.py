"""Where the whole ``analyze(curve)``'s time goes against its steps timed alone (issue 35 item 2).

    python benchmarks/bench_step_gap.py                                  # the CellHesion curve, 40 rounds
    python benchmarks/bench_step_gap.py afmforce-map_jpk-map2x2.h5 --rounds 60

One curve of ``tests/data`` (loaded as ``bench_map.py --part curve`` loads it) is analysed once with
every step's input state captured (with the contents of the state's shared cache as the step found
it). Each step's CPU time (``time.process_time``, median of ``--rounds``) is then taken five ways:

- **pipeline**: inside ``analyze(curve)`` (the registry's ``AnalysisStep.run`` wrapped by a timer);
- **replay**: the captured inputs run once each in the pipeline's order, round after round (no
  orientation, state preparation, plausibility or result between them);
- **alone**: one step ``--rounds`` times in a row on its captured input, the state's cache reset to what
  the step found before each call (``bench_map``'s earlier "alone" numbers kept the cache the first call
  had filled: the oscillation step then skips the runs' speeds);
- **evict**: as alone, an 8 MB array streamed (summed and a strided copy) before each call: the data
  and second-level caches cold, no data-dependent branches;
- **branchy**: as alone, ten quicksorts of 4,000 random numbers (32 KB) before each call: the branch
  predictor's history trained on other data, little data evicted.

Replay close to pipeline says the time between the steps is not the pipeline's own code (no dispatch,
state, warning or copy overhead); evict/branchy close to pipeline says a step run once after other work
costs that much (cold caches and predictors), and a step repeated on one input measures less.
The machine's load average is printed with the numbers.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MODES = ("pipeline", "replay", "alone", "evict", "branchy")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("name", nargs="?", default="jpk_cellhesion_spot3.jpk-force")
    ap.add_argument("--rounds", type=int, default=40)
    args = ap.parse_args()
    from afmforce.analysis import registry
    from afmforce.analysis.pipeline import analyze
    from afmforce.io import load

    overrides = json.loads((ROOT / "tests" / "data" / "meta_override.json").read_text())
    path = next((ROOT / "tests" / "data").rglob(args.name))
    curve = load(path, meta_override=overrides.get(args.name))[0]
    clock, orig, n = time.process_time, registry.AnalysisStep.run, args.rounds
    inputs: dict = {}

    def capture(self, st, o):
        inputs.setdefault(self.identifier, (self, st, o, dict(st.cache)))
        return orig(self, st, o)

    registry.AnalysisStep.run = capture
    try:
        analyze(curve)
    finally:
        registry.AnalysisStep.run = orig
    order = list(inputs)
    rng = np.random.default_rng(0)
    big, small = rng.random(1 << 20), rng.random(4000)
    before = {"evict": lambda: (big.sum(), big[::8].copy()),
              "branchy": lambda: [np.sort(small.copy(), kind="quicksort") for _ in range(10)]}

    def call(k):
        step, st, o, c0 = inputs[k]
        st.cache.clear()
        st.cache.update(c0)
        t = clock()
        orig(step, st, o)
        return clock() - t

    def run(mode: str) -> dict[str, float]:
        acc: dict[str, list[float]] = {k: [] for k in order}
        if mode == "pipeline":
            def timed(self, st, o):
                t = clock()
                try:
                    return orig(self, st, o)
                finally:
                    acc[self.identifier].append(clock() - t)
            registry.AnalysisStep.run = timed
            try:
                whole = []
                for _ in range(n):
                    t = clock()
                    analyze(curve)
                    whole.append(clock() - t)
            finally:
                registry.AnalysisStep.run = orig
            acc["(whole analyze)"] = whole
        elif mode == "replay":
            for _ in range(n):
                for k in order:
                    acc[k].append(call(k))
        else:
            for k in order:
                for _ in range(n):
                    if mode in before:
                        before[mode]()
                    acc[k].append(call(k))
        return {k: float(np.median(v)) for k, v in acc.items()}

    res = {m: run(m) for m in MODES}
    print(f"{args.name} ({curve.segment.size} points), CPU time per step [us], median of {n}; "
          f"load average {' '.join(f'{v:.1f}' for v in os.getloadavg())}")
    print("step".ljust(16) + "".join(m.rjust(10) for m in MODES))
    for k in sorted(order, key=lambda k: -res["pipeline"][k]):
        print(k.ljust(16) + "".join(f"{res[m][k] * 1e6:10.0f}" for m in MODES))
    print("sum of steps".ljust(16) + "".join(f"{sum(res[m][k] for k in order) * 1e6:10.0f}" for m in MODES))
    print(f"whole analyze {res['pipeline']['(whole analyze)'] * 1e6:.0f} us (median; the timers' own cost included); "
          f"load average {' '.join(f'{v:.1f}' for v in os.getloadavg())}")


if __name__ == "__main__":
    main()
