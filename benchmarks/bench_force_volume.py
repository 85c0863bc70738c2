"""Benchmark: a 256-curve NanoScope force volume read and analysed (issue 32, item 9).

Run::

    python benchmarks/bench_force_volume.py [--file PATH] [--repeat 3] [--workers 2] [--serial-only]

The file is ``shared/data/real/bruker-nanoscope_force-volume_v9.2_Egel.spm`` (16 x 16 curves of
1024 + 1024 points, 2.2 MB; or ``AFMFORCE_REAL_DATA``). Reported: the read
(``afmforce.io.load``, best of ``--repeat`` after one warm-up; target < 1 s), and the analysis of
every curve with the default steps through ``afmforce.sweep.files.analyze_files`` (the engine of
``afmforce analyze``), in this process and on a local Dask cluster of ``--workers`` workers
(target < 30 s on 2 cores; the cluster's start-up included), after one curve warmed the compiled
kernels. The machine's cores and load average are printed with the numbers: on a shared machine
the times are upper bounds. Not a test: nothing here fails on time.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = Path(os.environ.get("AFMFORCE_REAL_DATA") or ROOT.parent / "shared" / "data" / "real") \
    / "bruker-nanoscope_force-volume_v9.2_Egel.spm"


def _load() -> str:
    try:
        one, five, _ = os.getloadavg()
    except OSError:
        return "load average unknown"
    return f"load average {one:.1f} (1 min), {five:.1f} (5 min)"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--file", type=Path, default=DEFAULT)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--serial-only", action="store_true")
    args = ap.parse_args(argv)
    if not args.file.is_file():
        print(f"{args.file}: not found (set AFMFORCE_REAL_DATA or --file)", file=sys.stderr)
        return 1
    from afmforce._cores import available_cores
    from afmforce.analysis.pipeline import analyze
    from afmforce.io import load
    from afmforce.sweep.files import CurveAnalysis, analyze_files, plan_curves, summary_table

    print(f"machine: {os.cpu_count()} CPU(s), {available_cores()} available to this process; {_load()}")
    curves = load(args.file)
    best = float("inf")
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        curves = load(args.file)
        best = min(best, time.perf_counter() - t0)
    print(f"read {args.file.name}: {len(curves)} curves in {best:.3f} s (best of {args.repeat}; target < 1 s)")
    t0 = time.perf_counter()
    analyze(curves[0])
    print(f"warm-up (compiled kernels from the cache or compiled now): {time.perf_counter() - t0:.1f} s")
    refs = plan_curves([args.file])
    runs = [("serial", dict(executor="serial"))]
    if not args.serial_only:
        runs.append((f"dask, {args.workers} workers", dict(workers=args.workers)))
    for name, kw in runs:
        print(f"  ({_load()} before)")
        t0 = time.perf_counter()
        result = analyze_files(refs, CurveAnalysis(), chunk_size=max(1, len(refs) // (4 * args.workers)), **kw)
        wall = time.perf_counter() - t0
        table = summary_table(result)
        failed = int(table["error"].notna().sum()) + sum(len(f.items) for f in result.failures)
        print(f"analyse {len(refs)} curves, {name}: {wall:.1f} s ({wall / len(refs) * 1e3:.0f} ms per curve; "
              f"{failed} failed; target < 30 s on 2 cores)")
    print(f"machine after: {_load()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
