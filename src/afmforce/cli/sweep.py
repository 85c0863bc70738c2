"""``afmforce sweep``: parameter sweeps of the dynamics, chunked, resumable, on Dask."""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from ..errors import ParameterError
from ..units import format_quantity
from ._validate import CONFIRM_RUNS, check_output, check_simulation_sweep
from ._outcome import reported
from .common import chunk_progress_bar

#: Output columns summarised on the terminal, in this order.
SUMMARY_METRICS = (
    "min_apparent_deflection", "static_jump_in_deflection", "attraction_error", "attraction_ratio",
    "jump_in.separation", "jump_in.piezo_position", "spike_height", "hysteresis_offset",
    "pull_off.piezo_position", "pull_off.force", "solver.wall_time",
)


def register(sub) -> None:
    p = sub.add_parser(
        "sweep", help="parameter sweeps of the simulation (grids, random/LHS samples) on Dask",
        description="Run the dynamics simulation over a grid or a sample of parameters, in chunks on a "
                    "local Dask cluster (or --scheduler, or --serial). Finished chunks are stored as they "
                    "complete; rerunning the same command resumes. Parameters are the flat names of SimulationConfig "
                    "(see --list-parameters); values take units (0.1um/s, 200nm, -15deg).",
    )
    s = p.add_argument_group("what to sweep")
    s.add_argument("--grid", action="append", default=[], metavar="NAME=LO:HI:N[:log]",
                   help="grid axis: N values from LO to HI (log-spaced with :log), or NAME=V1,V2,...; repeat")
    s.add_argument("--range", dest="ranges", action="append", default=[], metavar="NAME=LO:HI[:log]",
                   help="range sampled by --sample; repeat")
    s.add_argument("--sample", choices=["random", "lhs"], default=None,
                   help="sampler of the ranges (default lhs: Latin hypercube)")
    s.add_argument("--n", type=int, default=None, help="number of samples")
    s.add_argument("--seed", type=int, default=None, help="sampler seed (default 0)")
    s.add_argument("--set", dest="sets", action="append", default=[], metavar="NAME=VALUE",
                   help="fixed setting for every run (default: the paper's Fig 5 values); repeat")
    s.add_argument("--config", metavar="FILE.toml", help="sweep file with [sweep], [grid], [range], [set] tables")
    s.add_argument("--example", action="store_true",
                   help="use the sweep file shipped with afmforce (Fig 5 run, 4 speeds x 3 friction coefficients; "
                        "python -c 'import afmforce.datasets as d; print(d.SWEEP_EXAMPLE)' shows where it is)")
    s.add_argument("--list-parameters", action="store_true", help="list the parameters and their units, then exit")
    r = p.add_argument_group("where it runs")
    r.add_argument("--workers", type=int, default=None, help="worker processes of the local cluster (default: one per core)")
    r.add_argument("--scheduler", metavar="tcp://HOST:PORT", help="use a running Dask cluster")
    r.add_argument("--serial", action="store_true", help="run in this process, one run after the other")
    r.add_argument("--chunk-size", type=int, default=None, help="runs per chunk (default: about 64 chunks)")
    r.add_argument("--yes", action="store_true",
                   help=f"run a sweep of more than {CONFIRM_RUNS:,} runs (refused without it)")
    o = p.add_argument_group("output")
    o.add_argument("--out", default="sweeps", metavar="DIR",
                   help="parent folder of the results (default ./sweeps); each sweep gets a sub-folder")
    o.add_argument("--plot", action="append", default=[], metavar="METRIC",
                   help="write a heat map of this output column (e.g. min_apparent_deflection); repeat")
    p.set_defaults(func=run)


def _list_parameters() -> int:
    from ..dynamics.config import FLAT

    print("parameters (flat names of SimulationConfig; part.field): SI unit, Fig 5 default, valid range")
    for name, where in FLAT.items():
        spec, part = where.spec, f"{where.part}.{where.attr}"
        only = "" if len(where.models) > 1 else f"  ({where.models[0]} model)"
        if spec is None:
            print(f"  {name:<20} {part:<26} {'text':<12} {where.default!r}{only}")
        else:
            print(f"  {name:<20} {part:<26} {spec.unit or '-':<12} {spec.show(where.default):<12} "
                  f"{spec.range_text()}{only}")
    return 0


def _describe(spec) -> str:
    parts = []
    if spec.grid:
        parts.append(" x ".join(str(len(a.values)) for a in spec.grid) + " grid ("
                     + ", ".join(a.name for a in spec.grid) + ")")
    if spec.ranges:
        parts.append(f"{spec.n} {spec.sample} samples of " + ", ".join(r.name for r in spec.ranges))
    return " x ".join(parts)


def _stats_rows(result, units) -> list[tuple[str, str, str, str]]:
    rows = []
    for name in SUMMARY_METRICS:
        if name not in result.table.columns:
            continue
        values = result.table[name].to_numpy(dtype=float, na_value=np.nan)
        values = values[np.isfinite(values)]
        if not len(values):
            continue
        unit = units.get(name, "")
        rows.append((name, *(format_quantity(float(v), unit, 4) for v in
                             (values.min(), np.median(values), values.max()))))
    return rows


def _save_plot(result, metric: str, units: dict):
    from ..plotting import plot_metric
    from .common import atomic_path

    path = result.store.root / f"{metric}.png"
    ax = plot_metric(result, metric, units=units)
    with atomic_path(path) as tmp:
        ax.figure.savefig(tmp, dpi=120, bbox_inches="tight", format="png")
    return path


def run(args: argparse.Namespace) -> int:
    from ..sweep import build_spec, run_sweep
    from ..sweep.chunks import default_chunk_size
    from ..sweep.simulation import OUTPUT_UNITS, parameter_units, simulate_run, simulation_dimensions
    from ..sweep.spec import chunk_size_from_config

    if args.list_parameters:
        return _list_parameters()
    if args.example:
        if args.config:
            raise ParameterError("--example is a sweep file: give it or --config, not both")
        from ..datasets import SWEEP_EXAMPLE

        args.config = str(SWEEP_EXAMPLE)
    if args.serial and (args.scheduler or args.workers):
        raise ParameterError("--serial runs in this process; drop --workers/--scheduler")
    if args.chunk_size is not None and args.chunk_size < 1:
        raise ParameterError(f"--chunk-size must be a positive integer, got {args.chunk_size}")
    numeric = [m for m in OUTPUT_UNITS if m != "solver.status"]
    unknown = [m for m in args.plot if m not in numeric]
    if unknown:
        raise ParameterError(f"--plot {unknown[0]}: no such numeric output; choose one of {', '.join(numeric)}")
    spec = build_spec(args.grid, args.ranges, args.sets, sample=args.sample, n=args.n, seed=args.seed,
                      config=args.config, dimensions=simulation_dimensions())
    check_simulation_sweep(spec, yes=args.yes)  # every value in range, sane sizes: before any work
    check_output(args.out, folder=True)
    chunk_size = args.chunk_size or chunk_size_from_config(args.config)
    n_chunks = math.ceil(spec.n_runs / (chunk_size or default_chunk_size(spec.n_runs)))
    # default: time one run, run here when that is sooner than starting a cluster (sweep.autoplan)
    executor = "serial" if args.serial or (n_chunks <= 1 and not args.scheduler) else (
        "dask" if args.scheduler or args.workers else "auto")
    print(f"afmforce sweep: {spec.n_runs} runs, {_describe(spec)}", flush=True)
    bar, update = chunk_progress_bar("sweep", n_chunks)
    try:
        result = run_sweep(simulate_run, spec, chunk_size=chunk_size, executor=executor, workers=args.workers,
                           scheduler=args.scheduler, store=args.out, progress=update)
    finally:
        bar.close()
    units = {**parameter_units(result.parameter_names), **OUTPUT_UNITS}
    paths = result.write(result.store.root, units)
    for metric in args.plot:
        paths[f"plot {metric}"] = _save_plot(result, metric, units)

    if result.chunks_run:
        print(f"  {result.chunks_run} of {result.chunks_total} chunks run on {result.executor} in "
              f"{result.wall_time:.1f} s; {result.chunks_skipped} were already in the store; "
              f"{len(result.failures)} failed")
    else:
        print(f"  all {result.chunks_total} chunks were already in the store (delete the folder to recompute)")
    print(f"results in {result.store.root}/")
    reported(result.store.root)
    print("  " + ", ".join(p.name for p in paths.values()))
    rows = _stats_rows(result, units)
    if rows:
        width = max(len(r[0]) for r in rows)
        print(f"  {'output':<{width}}  {'min':>12}  {'median':>12}  {'max':>12}")
        for name, lo, mid, hi in rows:
            print(f"  {name:<{width}}  {lo:>12}  {mid:>12}  {hi:>12}")
    if result.n_failed:
        print(f"{result.n_failed} of {len(result.table)} runs failed; their parameters and errors are in "
              f"{paths['errors']}", file=sys.stderr)
        for run_id, row in result.errors.head(3).iterrows():
            print(f"  run {run_id}: {row['error']}", file=sys.stderr)
        return 1
    return 0
