"""Peak memory of the liquid fit against the sample count (issue 34 item 2).

``python benchmarks/bench_fit_memory.py [--sizes 750,1500,3000] [--json FILE]``

Per size (the approach's start, nm before the surface; turn 150 nm in, retract back to the
start) a fresh subprocess makes the issue's colloid-probe set with the independent scipy solver
(``tests/fit/liquid_reference.py``: 4 cycles at 2-20 um/s, 20 kHz, R 10 um sphere-flat,
b 5 nm, lever drag 5e-5 kg/s, 0.05 Pa s, k 0.25 N/m in the files) and fits it as the user
types it (``fit_dynamic(free=("slip_length", "lever_drag"))``: every default, the 1/f noise
model included). Printed: samples, the peak of the fit's own allocations (tracemalloc, numpy
included), the process's peak resident memory (``ru_maxrss``: interpreter, numba, the
compiled models), the fit's estimate (``afmforce.fit.memory.fit_bytes``), wall time and the
fitted values. The 3000 nm set is the issue's (~107,000 samples).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, resource, sys, time, tracemalloc
sys.path.insert(0, {tests!r})
import liquid_reference as L
from afmforce.fit import fit_dynamic
from afmforce.fit.memory import fit_bytes
start = {start}
curves = L.cycles(L.SLIP, "full", drive=dict(start=-start * 1e-9, end=-start * 1e-9))
n = sum(c.time.size for c in curves)
cfg = dict(model="spring", geometry="sphere-flat", radius=10e-6, viscosity=0.05)
rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
tracemalloc.start()
t = time.perf_counter()
res = fit_dynamic(curves, cfg, free=("slip_length", "lever_drag"))
wall = time.perf_counter() - t
peak = tracemalloc.get_traced_memory()[1]
tracemalloc.stop()
p = res.parameters
print(json.dumps(dict(start_nm=start, samples=n, fit_peak_bytes=peak, rss_before_fit=rss0,
                      maxrss_bytes=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024,
                      estimate_bytes=fit_bytes(n, 2, 4), wall_s=wall, redchi=res.redchi,
                      b=p["slip_length"].value, b_interval=p["slip_length"].interval,
                      drag=p["lever_drag"].value, drag_interval=p["lever_drag"].interval,
                      pink=res.curves[0].pink, evaluations=res.model_evaluations)))
"""


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="750,1500,3000",
                    help="approach starts [nm before the surface], one subprocess each")
    ap.add_argument("--json", default=None, help="write the rows as JSON")
    args = ap.parse_args(argv)
    rows = []
    print(f"{'start':>6} {'samples':>8} {'fit peak':>9} {'maxrss':>8} {'estimate':>9} {'wall':>7} "
          f"{'b [nm]':>22} {'drag [1e-5 kg/s]':>24}")
    for start in (float(s) for s in args.sizes.split(",")):
        code = CHILD.format(tests=str(ROOT / "tests" / "fit"), start=start)
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
        if out.returncode:
            print(out.stderr[-3000:], file=sys.stderr)
            return 1
        r = json.loads(out.stdout.strip().splitlines()[-1])
        rows.append(r)
        f = (lambda v, s: "open" if v is None else f"{v * s:.4g}")
        print(f"{start:6.0f} {r['samples']:8d} {r['fit_peak_bytes'] / 1e6:7.0f}MB "
              f"{r['maxrss_bytes'] / 1e6:6.0f}MB {r['estimate_bytes'] / 1e6:7.0f}MB {r['wall_s']:6.1f}s "
              f"{r['b'] * 1e9:.4g} [{f(r['b_interval'][0], 1e9)}, {f(r['b_interval'][1], 1e9)}] "
              f"{r['drag'] * 1e5:.4g} [{f(r['drag_interval'][0], 1e5)}, {f(r['drag_interval'][1], 1e5)}]",
              flush=True)
    if len(rows) > 1:   # linear in the samples: the fit's own peak per sample, size to size
        per = [(b["fit_peak_bytes"] - a["fit_peak_bytes"]) / (b["samples"] - a["samples"])
               for a, b in zip(rows, rows[1:])]
        print("fit peak per added sample: " + ", ".join(f"{p:.0f} B" for p in per))
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
