"""Benchmark: the core analysis steps on many 2,000-point curves, and nanite for the ratio.

Run::

    python benchmarks/bench_analysis.py [--curves 4000] [--points 2000] [--repeat 3]

Core steps (:func:`afmforce.analysis.batch.analyze_batch`): drift, contact
regions, constant compliance, calibration, shift, zero of separation, jumps;
no fits. The same curves then go through nanite's preprocessing
(``compute_tip_position``, ``correct_force_offset``, ``correct_tip_offset``),
the comparable part of the most used open AFM force-curve package. nanite is a
benchmark-only dependency: ``pip install afmforce[bench]``.

Targets (issue 5): >= 2,000 curves/s on a 2-core machine; >= 20x nanite.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time

import numpy as np

from afmforce.analysis.batch import analyze_batch
from afmforce.analysis.synthetic import static_curve

SENSITIVITY = 50e-9  # m/V
SPRING_CONSTANT = 0.21  # N/m


def make_curves(n_curves: int, n_points: int, seed: int = 0):
    """``n_curves`` noisy, drifting variants of one quasi-static curve with ``n_points`` samples."""
    start, turn = -60e-9, 30e-9
    end = -1.3 * 5.6e-8 / SPRING_CONSTANT - 40e-9
    path = (turn - start) + (turn - end)
    velocity = 0.5e-6
    rate = velocity * n_points / path
    base = static_curve(velocity=velocity, sample_rate=rate, start=start, turn=turn, end=end,
                        sensitivity=SENSITIVITY, seed=None)
    n = len(base)
    rng = np.random.default_rng(seed)
    t = base.time
    noise = rng.standard_normal((n_curves, n)) * (0.05e-9 / SENSITIVITY)
    drift = rng.normal(0, 0.02, (n_curves, 1)) * t[None, :]
    offset = rng.normal(0, 0.1, (n_curves, 1))
    signal = base.deflection_signal[None, :] - 0.3 + offset + drift + noise
    z = np.broadcast_to(base.piezo_nominal, (n_curves, n)).copy()
    n_app = int(np.sum(base.segment == 0))
    return t, z, signal, n_app, base


def _timed(fn, repeat):
    """Best wall-clock and CPU (all threads) seconds of ``repeat`` calls, and the last result."""
    best_w = best_c = math.inf
    res = None
    for _ in range(repeat):
        w0, c0 = time.perf_counter(), time.process_time()
        res = fn()
        best_w = min(best_w, time.perf_counter() - w0)
        best_c = min(best_c, time.process_time() - c0)
    return best_w, best_c, res


def bench_afmforce(t, z, s, n_app, repeat, parallel):
    analyze_batch(t, z[:8], s[:8], n_app, parallel=parallel)  # compile / load the cache
    return _timed(lambda: analyze_batch(t, z, s, n_app, parallel=parallel), repeat)


def bench_nanite(t, z, s, n_app, n_curves, repeat):
    try:
        import nanite
    except ImportError:
        return None
    steps = ["compute_tip_position", "correct_force_offset", "correct_tip_offset"]
    seg = np.concatenate([np.zeros(n_app, bool), np.ones(z.shape[1] - n_app, bool)])
    meta = {"spring constant": SPRING_CONSTANT, "sensitivity": SENSITIVITY, "imaging mode": "force-distance",
            "duration": float(t[-1]), "point count": int(t.size), "rate approach": float(1 / (t[1] - t[0])),
            "path": "synthetic", "enum": 0}

    def run():
        for i in range(n_curves):
            data = {"force": s[i] * SENSITIVITY * SPRING_CONSTANT, "height (measured)": -z[i],
                    "segment": seg, "time": t}
            nanite.Indentation(data=data, metadata=dict(meta)).apply_preprocessing(steps)

    return _timed(run, repeat)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--curves", type=int, default=4000)
    ap.add_argument("--points", type=int, default=2000)
    ap.add_argument("--nanite-curves", type=int, default=200, help="curves timed through nanite")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    t, z, s, n_app, base = make_curves(args.curves, args.points)
    n = z.shape[1]
    nc = args.curves
    print(f"afmforce core analysis benchmark: {nc} curves x {n} points, {os.cpu_count()} CPUs "
          "(wall clock, and CPU time summed over threads: the machine may be shared)")
    rates = {}
    for parallel in (False, True):
        w, c, res = bench_afmforce(t, z, s, n_app, args.repeat, parallel)
        rates[parallel] = (nc / w, nc / c)
        label = "parallel" if parallel else "serial  "
        print(f"  afmforce batch core, {label} (drift, compliance, calibration, zero, jumps): "
              f"{nc / w:,.0f} curves/s wall, {nc / c:,.0f} curves per CPU-second")
    truth = base.truth
    ok_ji = np.mean(np.abs(res.jump_in_index - truth["jump_in_index"]) <= 1)
    ok_po = np.mean(np.abs(res.pull_off_index - truth["pull_off_index"]) <= 1)
    cal = np.median(np.abs(res.sensitivity / SENSITIVITY - 1))
    print(f"  accuracy: jump-in within one sample {ok_ji:.1%}, pull-off {ok_po:.1%}, "
          f"median calibration error {cal:.2%}")
    best_wall = max(r[0] for r in rates.values())
    best_cpu = max(r[1] for r in rates.values())
    print(f"  target >= 2,000 curves/s (wall): {'met' if best_wall >= 2000 else 'NOT met'} ({best_wall:,.0f})")
    m = min(args.nanite_curves, nc)
    out = bench_nanite(t, z, s, n_app, m, args.repeat)
    if out is None:
        print("  nanite not installed: no ratio. Install the benchmark extra: pip install 'afmforce[bench]'")
        return 0
    wn, cn, _ = out
    print(f"  nanite preprocessing (compute_tip_position, correct_force_offset, correct_tip_offset): "
          f"{m / wn:,.0f} curves/s wall, {m / cn:,.0f} curves per CPU-second")
    ratio_w, ratio_c = best_wall / (m / wn), best_cpu / (m / cn)
    print(f"  ratio afmforce / nanite: {ratio_w:,.1f}x wall clock, {ratio_c:,.1f}x per CPU-second "
          f"-- target >= 20x: {'met' if max(ratio_w, ratio_c) >= 20 else 'NOT met'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
