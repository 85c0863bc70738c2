"""Benchmark of sweeps and batches (issue 7). One command::

    python benchmarks/bench_sweep.py            # ~1 minute: timed sub-grid, extrapolated
    python benchmarks/bench_sweep.py --full     # the full 100 x 100 grid (10,000 runs)

Prints three figures:

1. **10,000 Fig-5-type runs** (velocity 0.1-10 um/s x xi 0.001-0.1 kg/s, a
   log-spaced 100 x 100 grid, every other parameter the paper's Fig 5) on a local
   Dask cluster of 2 worker processes, chunks stored as they finish.
   Target < 2 min on 2 cores. Without ``--full`` a sub-grid with the same bounds
   (``--n-side`` per axis, default 20 -> 400 runs) is timed and scaled by
   10,000 / runs (its runs cover the same range of costs).
2. **Speed-up of 2 workers over 1** on that grid (both clusters warm: numba
   caches loaded in every worker before timing). Target >= 1.8x. The machine is
   shared, so the load average is printed beside it.
3. **Memory of a 128 x 128 map** streamed through ``run_batch``: 16,384 synthetic
   2,000-point curves drawn from a generator, analysed chunk by chunk, results
   written to the store as they arrive (in a fresh process, so that its peak RSS
   is its own). Target peak RSS < 1 GB; the curves alone would take 0.8 GB.
   Each curve goes through ``afmforce.pipeline.analyze`` with the core steps
   (drift, compliance, calibration, zero, jumps), or, where the pipeline is
   missing, a numpy stand-in (baseline, noise, minimum, contact, slope).
"""

from __future__ import annotations

import argparse
import math
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

V_RANGE = "velocity=0.1um/s:10um/s:{n}:log"
XI_RANGE = "xi=0.001:0.1:{n}:log"
FULL_RUNS = 10_000
MAP_SIDE = 128
CURVE_POINTS = 2000


# --- 1 and 2: simulation sweeps --------------------------------------------------------
def _grid(n_side: int):
    from afmforce.sweep import build_spec
    from afmforce.sweep.simulation import simulation_dimensions

    return build_spec([V_RANGE.format(n=n_side), XI_RANGE.format(n=n_side)], dimensions=simulation_dimensions())


def _timed_sweep(spec, workers: int, repeat: int = 1) -> tuple[float, float, object]:
    """(best seconds for the sweep on a warm cluster, seconds to start and warm it, result).

    Each repeat runs the whole sweep into a fresh store; the best time is kept
    (the machine is shared: the best run is the least disturbed one).
    """
    from afmforce.sweep import DaskExecutor, run_sweep
    from afmforce.sweep.simulation import simulate_run

    t0 = time.perf_counter()
    with DaskExecutor(workers=workers) as executor:  # the cluster `afmforce sweep --workers N` starts
        client = executor.client
        client.run(simulate_run, velocity=10e-6)  # load numba caches in every worker
        warm = time.perf_counter() - t0
        best = math.inf
        for _ in range(repeat):
            with tempfile.TemporaryDirectory() as store:
                t1 = time.perf_counter()
                result = run_sweep(simulate_run, spec, executor=executor, store=store)
                best = min(best, time.perf_counter() - t1)
    return best, warm, result


def bench_sweeps(n_side: int, full: bool, speedup: bool, repeat: int) -> None:
    from afmforce.sweep import default_chunk_size

    spec = _grid(100 if full else n_side)
    n = spec.n_runs
    print(f"1. Fig-5-type sweep: {n} runs ({' x '.join(map(str, spec.shape))} grid, velocity 0.1-10 um/s, "
          f"xi 0.001-0.1 kg/s), chunks of {default_chunk_size(n)} runs")
    load0 = os.getloadavg()[0]
    t2, warm2, result = _timed_sweep(spec, 2, 1 if full else repeat)
    failed = result.n_failed
    solver = result.table["solver.wall_time"].sum()
    print(f"   2 workers: {t2:.1f} s for {n} runs ({n / t2:.0f} runs/s; cluster start + warm-up {warm2:.1f} s "
          f"not included); solver time summed over runs {solver:.1f} s; failed runs {failed}")
    if full:
        print(f"   10,000 runs: {t2:.0f} s measured  (target < 120 s: {'met' if t2 < 120 else 'NOT met'})")
    else:
        est = t2 * FULL_RUNS / n
        print(f"   10,000 runs: {est:.0f} s extrapolated from {n} runs x {FULL_RUNS / n:g}  "
              f"(target < 120 s: {'met' if est < 120 else 'NOT met'}; --full measures it)")
    if speedup:
        from afmforce.sweep import run_sweep
        from afmforce.sweep.simulation import simulate_run

        ts = math.inf
        for _ in range(1 if full else repeat):
            t = time.perf_counter()
            run_sweep(simulate_run, spec, executor="serial")
            ts = min(ts, time.perf_counter() - t)
        t1, _, r1 = _timed_sweep(spec, 1, 1 if full else repeat)
        cols = [c for c in result.table.columns if c != "solver.wall_time"]
        same = result.table[cols].equals(r1.table[cols])
        load = os.getloadavg()
        print(f"2. speed-up 1 -> 2 workers: {t1:.1f} s / {t2:.1f} s = {t1 / t2:.2f}x  (target >= 1.8x; "
              f"tables identical: {same}; load average {load0:.2f} before, {load[0]:.2f} after, "
              f"on {os.cpu_count()} cores; best of {1 if full else repeat})")
        print(f"   serial, in this process: {ts:.1f} s (Dask overhead with 1 worker: {100 * (t1 / ts - 1):+.0f}%)")


# --- 3: 128 x 128 map memory ------------------------------------------------------------
def synthetic_curve(pixel: int, n: int = CURVE_POINTS):
    """A cheap approach-retract curve: baseline, attractive dip, constant compliance, noise."""
    from afmforce.raw import RawCurve

    rng = np.random.default_rng(pixel)
    half = n // 2
    z_in = np.linspace(-100e-9, 20e-9, half)
    z = np.concatenate([z_in, z_in[::-1]])
    contact = rng.normal(0.0, 2e-9)
    d = np.where(z > contact, z - contact, -1.5e-9 * np.exp((z - contact) / 2e-9))
    d = d + rng.normal(0.0, 0.05e-9, n)
    segment = np.repeat(np.array([0, 1], dtype=np.int8), [half, n - half])
    return RawCurve(time=np.arange(n) / 2000.0, piezo_nominal=z, deflection_signal=d, segment=segment,
                    metadata={"spring_constant": 0.1, "velocity": 1e-6, "sample_rate": 2000.0,
                              "pixel": pixel}, deflection_unit="m")


def standin_analysis(curve) -> dict:
    """Summary of one curve without the analysis pipeline (numpy only)."""
    z, d = curve.piezo_nominal, curve.deflection_signal
    app = curve.approach
    za, da = z[app], d[app]
    base = da[: len(da) // 3]
    offset, noise = float(base.mean()), float(base.std())
    dd = da - offset
    contact = int(np.argmax(dd > 5 * noise + (dd.max() - 5 * noise) * 0.05)) if dd.max() > 5 * noise else -1
    top = slice(int(0.9 * len(za)), None)
    slope = float(np.polyfit(za[top], dd[top], 1)[0])
    return {"baseline": offset, "noise": noise, "min_deflection": float(dd.min()),
            "contact_position": float(za[contact]) if contact >= 0 else np.nan, "compliance_slope": slope}


#: The pipeline's core steps (issue 5's throughput benchmark: no fits).
CORE_STEPS = ["drift", "compliance", "calibration", "zero", "jumps"]


def _analysis():
    try:
        from afmforce.pipeline import analyze  # noqa: F401
    except ImportError:
        return standin_analysis, "stand-in summary (afmforce.pipeline not available)"
    return pipeline_analysis, f"afmforce.pipeline.analyze, steps {'+'.join(CORE_STEPS)}"


def pipeline_analysis(curve) -> dict:
    """The summary fields of the pipeline's analysis of one curve (one map pixel)."""
    from afmforce.analysis.result import SUMMARY_FIELDS
    from afmforce.pipeline import analyze

    result = analyze(curve, steps=CORE_STEPS)
    return {name: getattr(result, name) for name, _, _ in SUMMARY_FIELDS}


def bench_map_child(side: int) -> None:
    """Run in a fresh process: stream the map through run_batch and print peak RSS."""
    from afmforce.sweep import run_batch

    func, name = _analysis()
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    curves = (synthetic_curve(p) for p in range(side * side))
    with tempfile.TemporaryDirectory() as store:
        t = time.perf_counter()
        result = run_batch(curves, func, executor="serial", store=store, key=f"map-{side}", chunk_size=256)
        out = result.write(os.path.join(store, "map.parquet"))
        elapsed = time.perf_counter() - t
        rows = sum(len(f) for f in result.iter_tables())
        errors = sum(int(f["error"].notna().sum()) for f in result.iter_tables())
        size = os.path.getsize(out)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    per_curve = synthetic_curve(0).time.nbytes * 3 + CURVE_POINTS
    print(f"3. {side} x {side} map ({side * side} curves of {CURVE_POINTS} points, {name}): "
          f"{elapsed:.1f} s, {rows} rows ({errors} errors), table {size / 1e6:.1f} MB")
    print(f"   peak RSS {peak:.0f} MB (after imports {rss0:.0f} MB; all curves at once would be "
          f"{per_curve * side * side / 1e6:.0f} MB)  (target < 1024 MB: {'met' if peak < 1024 else 'NOT met'})")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--full", action="store_true", help="run all 10,000 runs instead of extrapolating")
    p.add_argument("--n-side", type=int, default=20, help="grid points per axis of the timed sub-grid")
    p.add_argument("--repeat", type=int, default=2, help="timed repeats of the sub-grid (best kept)")
    p.add_argument("--no-speedup", action="store_true", help="skip the 1-worker run")
    p.add_argument("--no-map", action="store_true", help="skip the 128 x 128 map")
    p.add_argument("--map-side", type=int, default=MAP_SIDE, help="pixels per side of the map (default 128)")
    p.add_argument("--map-child", type=int, default=None, help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.map_child:
        bench_map_child(args.map_child)
        return 0
    bench_sweeps(args.n_side, args.full, not args.no_speedup, args.repeat)
    if not args.no_map:
        subprocess.run([sys.executable, __file__, "--map-child", str(args.map_side)], check=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
