"""Benchmark: reading speed per format [MB/s], afmforce.io.load against afmformats.load_data.

Run::

    python benchmarks/bench_io.py [--repeat 5] [--folder tests/data] [--shared ../shared/data/real]

Every file some reader claims in the folders is read ``--repeat`` times (the best time
counts, after one warm-up read); where afmformats reads the same file, its
``load_data`` is timed too (the override values of ``tests/data/meta_override.json``
are given to both). afmforce's time includes its conversion to RawCurve and its
validation; afmformats' is its own parsing. HDF5 files go through afmforce's guarded
child process (fork + pickle), which the table shows as such.
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _best(func, repeat: int) -> float:
    func()
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        func()
        best = min(best, time.perf_counter() - t0)
    return best


def _afmformats_time(path: Path, meta: dict, repeat: int) -> float | None:
    import afmformats
    from afmformats import formats

    try:
        formats.get_recipe(path)
    except BaseException:  # noqa: BLE001 - afmformats raises BaseException subclasses
        return None
    af_meta = {{"spring_constant": "spring constant"}.get(k, k): v for k, v in meta.items()}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return _best(lambda: afmformats.load_data(path, meta_override=af_meta), repeat)
    except BaseException:  # noqa: BLE001 - afmformats cannot read it (e.g. CellHesion pause segments)
        return None


def main(argv: list[str] | None = None) -> int:
    from afmforce.io import find_format, is_supported, load

    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--folder", type=Path, action="append", default=None)
    args = p.parse_args(argv)
    folders = args.folder or [ROOT / "tests" / "data", ROOT.parent / "shared" / "data" / "real"]
    overrides = json.loads((ROOT / "tests" / "data" / "meta_override.json").read_text())
    overrides.update({"afmformats_jpk-fd_single-modified_2023.jpk-force": {"spring_constant": 12.0}})
    print(f"{'file':<52} {'format':<18} {'kB':>6} {'afmforce MB/s':>14} {'afmformats MB/s':>16} {'ratio':>6}")
    seen = set()
    for folder in folders:
        if not folder.is_dir():
            continue
        for path in sorted(folder.iterdir()):
            if not is_supported(path) or path.name in seen:
                continue
            seen.add(path.name)
            meta = overrides.get(path.name, {})
            try:
                fmt = find_format(path).identifier
                t_ours = _best(lambda: load(path, meta_override=meta), args.repeat)
            except Exception as exc:  # noqa: BLE001 - reported in the table
                print(f"{path.name:<52} {'-':<18} {'':>6} {'fails: ' + str(exc)[:60]}")
                continue
            t_af = _afmformats_time(path, meta, args.repeat)
            mb = path.stat().st_size / 1e6
            ours = mb / t_ours
            theirs = "-" if t_af is None else f"{mb / t_af:16.1f}"
            ratio = "-" if t_af is None else f"{t_af / t_ours:6.2f}"
            print(f"{path.name[:52]:<52} {fmt:<18} {mb * 1e3:6.0f} {ours:14.1f} {theirs:>16} {ratio:>6}")
    print("ratio: afmformats' time / afmforce's (> 1: afmforce faster)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
