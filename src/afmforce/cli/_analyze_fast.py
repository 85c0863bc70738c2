"""``afmforce analyze MAP --fast-map``: force maps at instrument speed (issue 35).

Every pixel through :class:`afmforce.sweep.map_fast.PixelAnalysis` (the indentation fit,
the adhesion, the work of adhesion in closed form) on the batch engine; with ``--out`` the rows
are stored chunk by chunk (a rerun resumes) and the maps are written as by ``analyze``: a PNG in
um with a colour bar and a histogram per quantity, ``<map>.maps.h5``, ``summary.parquet`` and
``summary.csv``.
"""

from __future__ import annotations

import argparse
import math

from ..errors import ParameterError

#: Quantities mapped when no --map-quantity is given.
FAST_MAP_QUANTITIES = ("modulus", "topography", "adhesion", "work_of_adhesion")
#: Distinct warnings printed (each with its number of curves); the summary table holds every curve's.
MAX_WARNINGS = 5


def summary_lines(table, quantities) -> list[str]:
    """One printed line per mapped quantity: its registered label, sign and display unit
    (:data:`afmforce.analysis.maps.MAP_QUANTITIES`, the same as the map images': adhesion is the
    depth of the retract dip, positive), the median and the range over the analysed pixels."""
    import numpy as np

    from ..analysis.maps import MAP_DISPLAY_UNITS, map_quantity

    lines = []
    for name in quantities:
        q = map_quantity(name)
        if q.column not in table:
            continue
        factor, unit = MAP_DISPLAY_UNITS.get(q.unit, (1.0, q.unit))
        v = table[q.column].to_numpy(float) * (q.sign * factor) + 0.0     # + 0.0: no "-0" printed
        v = v[[math.isfinite(x) for x in v]]
        if v.size:
            lines.append(f"  {name} ({q.label}): median {float(np.median(v)):.4g} {unit}, "
                         f"from {v.min():.4g} to {v.max():.4g} {unit}")
    return lines


def warning_lines(table) -> list[str]:
    """Each distinct warning of the analysed pixels (the ``warnings`` column, the full analysis's: joined by
    `` | ``), with the number of pixels it was given for, clipped to one terminal line each."""
    from ._outcome import render
    from ._verdicts import MAX_LINE, clip, plain

    import re

    # one line per warning, not per number in it: "indentation 10.32 nm exceeds ..." on 36 pixels with 36
    # depths was 36 lines (the Nanosurf 10 x 10 map); each pixel's own numbers stay in the table's column
    number = re.compile(r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?")
    counts: dict[str, int] = {}
    first: dict[str, str] = {}
    texts: dict[str, set] = {}
    for cell in table.get("warnings", ()):
        for w in (cell if isinstance(cell, str) else "").split(" | "):
            if w:
                key = number.sub("#", w)
                counts[key] = counts.get(key, 0) + 1
                first.setdefault(key, w)
                texts.setdefault(key, set()).add(w)
    lines = []
    for key, n in list(counts.items())[:MAX_WARNINGS]:
        head = (f"  warning ({n} of {len(table)} curves, e.g.): " if len(texts[key]) > 1 else
                f"  warning ({n} of {len(table)} curves): ")
        lines.append(head + clip(plain(render(first[key])), MAX_LINE - len(head)))
    if len(counts) > MAX_WARNINGS:
        lines.append(f"  ... and {len(counts) - MAX_WARNINGS} other warning(s): the column `warnings` of the summary "
                     "table (--out) holds each curve's")
    return lines


def failure_lines(failed, limit: int = 20) -> list[str]:
    """One line per distinct error of the failed pixels, naming the map and how many of its curves
    (a map whose 16,384 pixels all lack the tip radius: one line, not 16,384), in the flags' words."""
    from ._outcome import render

    groups: dict[tuple[str, str], list[str]] = {}
    for _, row in failed.iterrows():
        source = str(row["source"])
        file, _, curve = source.rpartition("#") if "#" in source else (source, "", "")
        groups.setdefault((file, " ".join(render(str(row["error"])).split())), []).append(curve)
    lines = []
    for (file, error), curves in list(groups.items())[:limit]:
        which = f"#{curves[0]}" if len(curves) == 1 else f"{len(curves)} curves"
        lines.append(f"failed: {file} ({which}): {error}")
    if len(groups) > limit:
        lines.append(f"  ... and {len(groups) - limit} other error(s)")
    return lines


def run_fast_map(args: argparse.Namespace, refs: list, write_maps, meta: dict | None = None) -> int:
    """``write_maps(table, folder, quantities)``: analyze's map writer (images, HDF5, histograms); ``meta``:
    the metadata typed as the files' (``--meta``, SI; the probe's values are ``args.probe``'s)."""
    from ..sweep.map_fast import PixelAnalysis, analyze_refs
    from ..sweep.summary import write_table
    from ..analysis.options import IndentationOptions
    from .common import eprint

    maps = [r for r in refs if r.index is not None]
    if not maps:
        raise ParameterError("--fast-map analyses force maps (one curve per pixel); the inputs hold none")
    others = sorted({r.step for r in args.records if r.step != "indentation"})
    if others:     # never dropped silently (was: --calibration fit gave the file's calibration)
        raise ParameterError(f"--fast-map runs the indentation fit only (the file's or your calibration); options "
                             f"of {', '.join(others)} apply to the full analysis: drop --fast-map, or drop them")
    indentation = next((r for r in args.records if r.step == "indentation"), IndentationOptions())
    analysis = PixelAnalysis(indentation, probe=args.probe, meta_override=dict(meta or {}), channel=args.channel)
    executor = "serial" if args.serial else None
    result = analyze_refs(maps, analysis, executor=executor, workers=args.workers, scheduler=args.scheduler,
                          store=args.out, chunk_size=args.chunk_size)
    table = result.table()
    ok = table[table["error"].isna()]
    print(f"afmforce analyze --fast-map: {len(ok)} of {len(table)} curves analysed "
          f"({result.chunks_run} chunks run on {result.executor} in {result.wall_time:.1f} s, "
          f"{result.chunks_skipped} already stored)")
    for line in summary_lines(ok, FAST_MAP_QUANTITIES):
        print(line)
    for line in warning_lines(ok):
        print(line)
    if result.store is not None:
        folder = result.store.root
        write_table(table, folder)   # column names with their units, as analyze's (sweep.summary.column_label)
        written = write_maps(table, folder, args.map_quantity or list(FAST_MAP_QUANTITIES))
        print(f"summary in {folder}/: summary.parquet, summary.csv, " + ", ".join(p.name for p in written.values()))
    failed = table[table["error"].notna()]
    for line in failure_lines(failed):
        eprint(line)
    if len(failed):
        eprint(f"{len(failed)} of {len(table)} curves failed")
    return 1 if len(failed) else 0
