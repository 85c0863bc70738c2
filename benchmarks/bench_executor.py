"""Benchmark of ``afmforce analyze``'s automatic executor (issue 24). One command::

    python benchmarks/bench_executor.py              # 72 files: three files of tests/data x 24
    python benchmarks/bench_executor.py --copies 40  # 120 files

Copies files of ``tests/data`` (a Bruker ASCII export, an Asylum wave, the synthetic NanoScope
export) into a temporary folder, then times, start to end in fresh processes and in this order,
``afmforce analyze DIR --serial`` (the baseline, run first and last: the best of the two),
``afmforce analyze DIR`` (the automatic choice, whose printed reason is shown) and
``afmforce analyze DIR --workers 2`` (a local Dask cluster, what the automatic choice used to pick
for 64 files or more). Prints the wall times, the ratios to
the serial run, and the load average before and after (the machine is shared). The automatic
choice should never be slower than serial by more than the noise of the machine.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FILES = ("bruker-ascii_nm_retract-reversed.txt", "asylum-mfp3d_SiN-tip_air.ibw", "bruker-nanoscope_synthetic.txt")


def _run(argv: list[str]) -> tuple[float, str]:
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"), MPLBACKEND="Agg")
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "afmforce.cli.main", *argv], capture_output=True, text=True,
                          env=env)
    wall = time.perf_counter() - t0
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} failed: {done.stderr.strip()[-300:]}")
    return wall, done.stdout


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--copies", type=int, default=24, help="copies of each file (default 24: 72 files)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "curves"
        folder.mkdir()
        for i in range(args.copies):
            for name in FILES:
                shutil.copy(ROOT / "tests" / "data" / name, folder / f"{i:03d}_{name}")
        n = args.copies * len(FILES)
        load0 = os.getloadavg()[0]
        serial1, _ = _run(["analyze", str(folder), "--serial"])
        auto, text = _run(["analyze", str(folder)])
        dask, _ = _run(["analyze", str(folder), "--workers", "2"])
        serial2, _ = _run(["analyze", str(folder), "--serial"])  # again: the load drifts during the runs
        load1 = os.getloadavg()[0]
    serial = min(serial1, serial2)
    reason = next((ln.strip() for ln in text.splitlines() if ln.startswith("  in this process")
                   or ln.startswith("  on a local Dask")), "?")
    print(f"afmforce analyze, {n} files, load average {load0:.1f} before, {load1:.1f} after:")
    print(f"  serial (baseline)     {serial:7.1f} s   1.00x   (best of {serial1:.1f} s first, {serial2:.1f} s last)")
    print(f"  automatic             {auto:7.1f} s   {auto / serial:.2f}x   ({reason})")
    print(f"  Dask, 2 workers       {dask:7.1f} s   {dask / serial:.2f}x")


if __name__ == "__main__":
    main()
