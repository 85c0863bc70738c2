"""``afmforce analyze``: analyse force-curve files, folders of them and force maps.

For each curve: calibrated force against separation, jump-in, pull-off, the
van der Waals fit, the instrument's artefacts and the dynamic diagnosis.
Curves are analysed in chunks (afmforce.sweep.files): a few curves (fewer
than 64) in this process, more on a local Dask cluster (or --workers N,
--scheduler, --serial). With --out DIR: one summary table for the batch
(DIR/batch-<hash>/summary.parquet and summary.csv, with units), a heat map of
--map-quantity per force map, and, for small runs, each curve's JSON, CSV
table and figure (<name>.afmforce.json/.csv/.png); larger runs store their
chunks as they finish, so that rerunning the same command resumes. Outputs
are written atomically, input files are only read. Bad files and curves are
listed while the others are analysed; the exit status is 1 if any failed,
2 for usage errors.
"""

from __future__ import annotations

import argparse
import json
import math
import re
from pathlib import Path

from ..errors import OutputExistsError, ParameterError
from ..limits import BATCH_MAX_CURVES
from ._validate import add_choice, add_field, check_output, lazy_help
from ._analyze_liquid import liquid_flags, print_liquid
from ._analyze_tethers import print_tethers
from ._analyze_options import default as _default, option_names as _option_names, step_options as _options
from ._outcome import render, reported
from ._verdicts import MAX_LINE, clip as _clip, dynamic_label as _dynamic_label, plain as _plain, short_verdict
from .common import add_quantity, chunk_progress_bar, eprint, progress_bar, refuse_missing

SUFFIX = ".afmforce"
#: Runs with at least this many curves are batches: Dask, resumable store, summary statistics.
BATCH_CURVES = 64
#: Map image written when maps are analysed, no --map-quantity is given and no quantity of
#: :data:`afmforce.analysis.maps.DEFAULT_MAPS` has a value (drawn all "no value", with its note).
DEFAULT_MAP_QUANTITY = "adhesion"
_MAX_LISTED = 20
_BATCH_FOLDER = re.compile(r"batch-[0-9a-f]{12}")  # our summary tables are not inputs


def register(sub) -> None:
    p = sub.add_parser("analyze", help="analyse force-curve files and force maps: force vs separation, jumps, "
                       "fits, diagnosis", description=__doc__.split("\n\n")[1].replace("\n", " "))
    p.add_argument("files", nargs="*", metavar="FILE", help="force-curve files, force maps or folders "
                   "(searched recursively)")
    p.add_argument("--example", action="append", default=[], metavar="NAME",
                   help="analyse a sample file shipped with afmforce (repeatable; 'list' lists them): "
                        + ", ".join(_example_names()))
    p.add_argument("--out", metavar="DIR", type=Path, default=None,
                   help="write the summary table, map images and (small runs) each curve's outputs into DIR")
    p.add_argument("--json", action="store_true", help="print the results as JSON (SI) instead of a table")
    p.add_argument("--verbose", "-v", action="store_true",
                   help="print each curve's full verdict and warnings (default: one short line each)")
    p.add_argument("--force", action="store_true", help="with --out: recompute every curve and overwrite its "
                   "outputs (default: a rerun skips curves whose outputs exist and keeps the tables)")
    lazy_help(p.add_argument("--steps", default=None, metavar="A,B,...",
                             help="analysis steps to run (their requirements are added): "), _steps)
    p.add_argument("--format", default=None, metavar="ID", help="reader to use instead of detection "
                   "(see docs/analysis.md), e.g. jpk-zip for raw volts")
    add_choice(p, "channel")
    p.add_argument("--no-plot", action="store_true", help="with --out: skip the per-curve figures")
    lazy_help(p.add_argument("--map-quantity", action="append", default=[], metavar="Q",
                             help="quantity drawn as a heat map per force map (repeatable; "), _map_quantities)
    p.add_argument("--fast-map", action="store_true",
                   help="force maps at instrument speed: per pixel only the indentation fit (modulus, topography), "
                        "the adhesion and the DMT work of adhesion, about 1 ms a curve (docs/contact.md)")
    p.add_argument("--per-curve", action="store_true",
                   help=f"with --out: write each curve's JSON, CSV and figure also in runs of {BATCH_CURVES} "
                        "curves or more")
    r = p.add_argument_group("where it runs (batches of many curves)")
    r.add_argument("--workers", type=int, default=None, metavar="N", help="worker processes of the local Dask cluster "
                   "(default: one per core)")
    r.add_argument("--scheduler", metavar="tcp://HOST:PORT", help="use a running Dask cluster")
    r.add_argument("--serial", action="store_true", help="run in this process, one curve after the other")
    add_quantity(r, "--file-timeout", "time", 300.0, "time budget for reading one file; a file past it "
                 "is reported and skipped", "s")
    r.add_argument("--max-curves", type=int, default=BATCH_MAX_CURVES, metavar="N",
                   help=f"the most curves taken from all the files together, counted from the maps' headers before "
                        f"any is read (default {BATCH_MAX_CURVES:,}: sixteen 256 x 256 maps)")
    r.add_argument("--chunk-size", type=int, default=None, metavar="N",
                   help="curves per chunk (default: about 64 chunks, at most 256 curves each); "
                        "makes the run a resumable batch")
    g = p.add_argument_group("instrument and probe (values with units, e.g. 0.21N/m, 45nm/V, -15deg, 220nm)")
    add_field(g, "spring_constant", help="spring constant k (with --theta0: the intrinsic k0, corrected by eq 13/14)")
    add_field(g, "sensitivity", help="deflection sensitivity (InvOLS)")
    g.add_argument("--meta", action="append", default=[], metavar="KEY=VALUE",
                   help="any other file metadata to give or replace, with units (repeatable), e.g. "
                        "sample_rate=6kHz, velocity=1um/s (afmforce formats lists the keys)")
    add_field(g, "theta0", help="cantilever inclination for the tilt correction")
    add_field(g, "L0", help="beam length (with --L1, --L2: eq 13 instead of eq 14)")
    add_field(g, "L1", help="rigid base length")
    add_field(g, "L2", help="rigid probe length")
    add_field(g, "radius", help="probe radius R (gives gamma from the pull-off, A from A R)")
    add_field(g, "resonance_frequency", help="resonance frequency (inertia diagnosis)")
    from .calibrate import add_probe_calibration_flag; add_probe_calibration_flag(g)  # noqa: E702 (issue 34)
    add_field(g, "compliance_separation", flag="--contact-separation", dest="contact_separation",
              default_from=lambda: _default("zero", "contact_separation"),
              help="separation given to the compliance line (paper: z0; 0 also common); the same as "
                   "--option zero.contact_separation=VALUE")
    lazy_help(g.add_argument("--calibration", choices=("auto", "fit", "metadata"), default=None,
                             help="deflection calibration: auto: the file's or --sensitivity (the compliance "
                                  "slope only without one); fit: the compliance slope, a file's thermal k "
                                  "rescaled; metadata: the file's always (the same as --option "
                                  "calibration.source=VALUE; default "),
              lambda: f"{_default('calibration', 'source')})")
    _indentation_flags(p)
    liquid_flags(p)
    lazy_help(p.add_argument("--option", action="append", default=[], metavar="STEP.NAME=VALUE",
                             help="any other option of an analysis step, with units (repeatable), e.g. "
                                  "vdw.max_separation=20nm, jumps.nsigma=4, fringes.apply=never "
                                  "(docs/analysis.md lists them with their ranges); steps with options: "),
              _option_names)
    p.set_defaults(func=run)


def _indentation_flags(p) -> None:
    """Short forms of the indentation step's options (docs/contact.md)."""
    g = p.add_argument_group("indentation: Young's modulus of soft samples (docs/contact.md)")
    g.add_argument("--indentation-model", default=None, metavar="KEY",
                   help="hertz_paraboloid (default), sneddon_sphere, hertz_cone, bilodeau_pyramid3, "
                        "bilodeau_pyramid4, hertz_thin_layer, jkr, dmt, maugis (the same as --option "
                        "indentation.model=KEY)")
    add_field(g, "tip_radius", help="tip radius of a sphere model (default: --radius)")
    add_field(g, "half_angle", help="half-angle of a cone, face angle of a pyramid")
    add_field(g, "poisson", help="Poisson ratio of the sample (default: the file's own, e.g. NanoScope's "
                                 "Sample Poisson's Ratio; else 0.5)")


def _example_names() -> list[str]:
    from ..datasets import DATASETS

    return list(DATASETS)


def _steps() -> str:  # help text, computed when printed (the pipeline imports numba)
    from ..analysis.pipeline import STEPS

    return ", ".join(STEPS)


def _map_quantities() -> str:
    from ..analysis.maps import DEFAULT_MAPS, MAP_QUANTITIES

    return f"default: those of {', '.join(DEFAULT_MAPS)} that some curve gave): " + ", ".join(MAP_QUANTITIES)


def _inputs(names: list[str]) -> list[Path]:
    from ..io import in_folder

    out: list[Path] = []
    for name in names:
        path = Path(name)
        if path.is_dir():
            found = sorted(p for p in path.rglob("*") if p.is_file() and in_folder(p)
                           and SUFFIX not in p.name and not _BATCH_FOLDER.fullmatch(p.parent.name))
            out.extend(found)
        else:
            out.append(path)
    return out


def _check(args: argparse.Namespace) -> list[str] | None:
    """Usage errors (exit 2) before any work; returns the steps."""
    from ..io import FORMATS
    from ..analysis.pipeline import resolve_steps

    from ..datasets import DATASETS, path as example_path

    if "list" in args.example:
        return None
    for name in args.example:
        if name not in DATASETS:
            raise ParameterError(f"--example {name}: unknown; choose one of {', '.join(DATASETS)} (or 'list')")
    args.files = list(args.files) + [str(example_path(n)) for n in args.example]
    if not args.files:
        raise ParameterError("give force-curve files or folders, or --example NAME (--example list shows them)")
    refuse_missing(args.files)  # before any work: no output folder for a typo
    steps = None if args.steps is None else [s.strip() for s in args.steps.split(",") if s.strip()]
    if steps == []:
        raise ParameterError(f"--steps {args.steps!r}: no step named; give comma-separated steps (e.g. "
                             "drift,compliance,calibration) or drop --steps for all")
    resolve_steps(steps)  # unknown step: ParameterError -> exit 2
    from ..calibration.record import ANALYSIS_KEYS
    from .calibrate import fill_from_calibration

    from_file = fill_from_calibration(args, ANALYSIS_KEYS)
    args.records, args.probe = _options(args)  # unknown or out-of-range option: exit 2
    if from_file:   # the warnings name a calibration file's value as its, not as one typed (ProbeCalibration.origin)
        from ..calibration.record import read_calibration_basis

        method, invols = read_calibration_basis(args.probe_calibration)   # a thermal k rescales with a fit InvOLS
        args.probe = args.probe.from_calibration_file(from_file, method=method, invols=invols)
    if args.format is not None and args.format not in FORMATS:
        raise ParameterError(f"--format {args.format}: unknown; choose one of {', '.join(FORMATS)}")
    if args.out is not None:
        check_output(args.out, folder=True)
    from ..analysis.maps import MAP_QUANTITIES

    for q in args.map_quantity:
        if q not in MAP_QUANTITIES:
            raise ParameterError(f"--map-quantity {q}: unknown; choose one of {', '.join(MAP_QUANTITIES)}")
    if args.serial and (args.workers is not None or args.scheduler):
        raise ParameterError("--serial runs in this process; drop --workers/--scheduler")
    if args.workers is not None and args.scheduler:
        raise ParameterError("--workers sizes the local cluster; a --scheduler cluster has its own workers")
    if args.workers is not None and args.workers < 1:
        raise ParameterError(f"--workers must be at least 1, got {args.workers}")
    if args.chunk_size is not None and args.chunk_size < 1:
        raise ParameterError(f"--chunk-size must be a positive integer, got {args.chunk_size}")
    return steps


def run(args: argparse.Namespace) -> int:
    if "list" in args.example:  # before the analysis is imported: instant
        from ..datasets import DATASETS

        if args.json:
            print(json.dumps({"examples": {name: {"file": d.filename, "description": d.description,
                                                  "source": d.source} for name, d in DATASETS.items()}}, indent=2))
            return 0
        for name, d in DATASETS.items():
            print(f"{name:<14} {d.description}")
        return 0
    from ..sweep.files import CurveAnalysis, TooManyCurves, analysis_key, analyze_files, plan_curves
    from ..sweep.chunks import default_chunk_size

    steps = _check(args)
    from ..io import parse_meta_args

    meta = parse_meta_args(args.meta)
    args.probe = args.probe.given_as_metadata(k for k in meta if getattr(args.probe, k, None) is None)
    for key, value in (("spring_constant", args.spring_constant), ("sensitivity", args.sensitivity)):
        if value is None:
            continue
        if key in meta and not math.isclose(meta[key], value, rel_tol=1e-9):      # which one was meant: never one of them silently
            raise ParameterError(f"--{key.replace('_', '-')} and --meta {key} give different values "
                                 f"({value:g} and {meta[key]:g} [SI]); give one")
        meta.pop(key, None)     # the probe's (the user's): put over the file's by afmforce.io.given, never read as the file's
    _check_liquid_radius(args, meta)
    files = _inputs(args.files)
    if not files:
        raise ParameterError("no force-curve files found in the given folders")
    if not args.max_curves > 0:
        raise ParameterError(f"--max-curves must be positive, got {args.max_curves}")
    if not args.file_timeout > 0:
        raise ParameterError(f"--file-timeout must be positive, got {args.file_timeout} s")
    bar, _ = progress_bar("detect", len(files), unit="file", min_total=8, leave=False, counted=True)
    try:
        refs = plan_curves(files, args.format, timeout=args.file_timeout, on_file=lambda: bar.update(),
                           max_curves=args.max_curves)
    except TooManyCurves as exc:
        raise ParameterError(f"{exc}; analyse the files in parts, or raise --max-curves") from None
    finally:
        bar.close()
    if args.fast_map:
        from ._analyze_fast import run_fast_map

        return run_fast_map(args, refs, _write_maps, meta)
    n = len(refs)
    batch = n >= BATCH_CURVES or args.workers is not None or bool(args.scheduler) or args.chunk_size is not None
    local = args.serial or (args.workers is None and not args.scheduler and n < BATCH_CURVES)
    per_curve = args.out is not None and (not batch or args.per_curve)
    analysis = CurveAnalysis(
        steps=None if steps is None else tuple(steps), options=args.records, probe=args.probe, meta_override=meta,
        format=args.format, channel=args.channel, keep_json=args.json,
        out=str(args.out) if per_curve else None, force=args.force, plot=not args.no_plot,
        protect=tuple(str(p.resolve()) for p in files if p.exists()) if per_curve else (),
        file_timeout=args.file_timeout)
    clashes = analysis.clashes(refs)
    if clashes:  # never replace another run's per-curve files silently (the summaries would disagree)
        raise OutputExistsError(
            f"{args.out} holds {len(clashes)} per-curve output(s) of an analysis with other options (e.g. "
            f"{clashes[0].name}); choose another --out, or pass --force to replace them")
    chunk_size = args.chunk_size if batch else 1
    n_chunks = math.ceil(n / (chunk_size or default_chunk_size(n)))
    if batch and not args.json:
        maps = len({r.path for r in refs if r.index is not None})
        print(f"afmforce analyze: {n} items ({len(files)} file(s), {maps} of them force maps) in {n_chunks} chunks",
              flush=True)
    executor, workers = ("serial" if local else None), args.workers
    if not local and args.workers is None and not args.scheduler:  # automatic: never slower than serial
        from ..sweep.files import choose_executor

        plan, usable = choose_executor(refs, analysis)
        executor, workers = plan.executor, (usable if plan.executor == "dask" else None)
        if not args.json:
            print(f"  {'in this process' if plan.executor == 'serial' else 'on a local Dask cluster'}: "
                  f"{plan.reason}", flush=True)
    bar, update = chunk_progress_bar("analyze", n_chunks, min_total=2, leave=False)
    try:
        result = analyze_files(refs, analysis, chunk_size=chunk_size, executor=executor,
                               workers=workers, scheduler=args.scheduler,
                               store=args.out if batch and args.out is not None else None, progress=update)
    finally:
        bar.close()
    folder = None
    if result.store is not None:
        folder = result.store.root
    elif args.out is not None:  # a small run stores nothing: its summary goes where a batch's would
        folder = args.out / f"batch-{analysis_key(refs, analysis)[:12]}"
    return _report(args, result, refs, folder, batch)


def _check_liquid_radius(args, meta: dict) -> None:
    """A liquid medium runs the liquid step, which needs the probe radius; no reader gives one, so
    without --radius (or --meta radius=...) the step would be skipped silently: refused instead."""
    medium = next((getattr(r, "medium", None) for r in args.records if r.step == "liquid"), None)
    if medium in (None, "none", "air") or args.probe.radius is not None or "radius" in meta:
        return
    raise ParameterError(f"--medium {medium}: the liquid analysis (drag, drainage, DLVO fit) needs the probe "
                         "radius; give --radius (e.g. --radius 2.5um for a colloid probe), or drop --medium")


def _report(args, result, refs, folder: Path | None, batch: bool) -> int:
    from ..sweep.files import summary_table, write_summary
    from ..sweep.summary import failure_records
    from ._outcome import RunState

    table = summary_table(result, with_json=args.json)
    ok = table[table["error"].isna()]
    records = failure_records(result)
    failed = [(r["source"], r["error"]) for r in records]
    written = {}
    if folder is not None:
        written = write_summary(result, folder)
        reported(folder)  # "summary in FOLDER/: ..." below
        written.update(_write_maps(table, folder, args.map_quantity))
    if args.json:
        _print_json(result, len(refs))
    else:
        if len(ok) <= BATCH_CURVES:
            _print_rows(ok, verbose=args.verbose, given=args.probe.origin("sensitivity"))
            print_liquid(ok)
            print_tethers(ok, verbose=args.verbose)
        else:
            _print_stats(ok)
        origin = _oscillation_origin(ok)
        if origin is not None and origin[0] != "none":
            print(f"oscillations across files: {origin[1]}")
        if batch:
            if result.chunks_run:
                print(f"  {result.chunks_run} of {result.chunks_total} chunks run on {result.executor} in "
                      f"{result.wall_time:.1f} s; {result.chunks_skipped} were already stored")
            else:
                print(f"  all {result.chunks_total} chunks were already stored in {folder} "
                      "(delete that folder to recompute)")
        if written:
            print(f"summary in {folder}/: " + ", ".join(p.name for p in written.values()))
    for record in records[:_MAX_LISTED if batch else None]:  # one line per failed file or curve
        name, error = record["source"], " ".join(render(_clean(record["error"])).split())
        # the message starts with the path (or names it first: "<path> is truncated: ..."): not twice
        named = Path(name.split("#")[0]).name in error.split(": ", 1)[0]
        eprint(f"failed: {error}" if named else f"failed: {name}: {error}")
        if RunState.debug and record["traceback"]:  # --debug: where it failed, in a batch too
            eprint(record["traceback"].rstrip())
    if len(failed) > 1:
        if batch and len(failed) > _MAX_LISTED:
            eprint(f"  ... and {len(failed) - _MAX_LISTED} more" + (f" (all in {written['errors']})"
                                                                      if "errors" in written else ""))
        kind = "file(s)" if all(r.index is None for r in refs) else "curve(s) or file(s)"
        eprint(f"{len(failed)} of {len(refs)} {kind} failed")
    return 1 if failed else 0


def _clean(error: str) -> str:
    from ..sweep.report import clean_error

    return clean_error(error)


def _write_maps(table, folder: Path, quantities: list[str]) -> dict[str, Path]:
    from ..analysis.maps import map_images
    from ..plotting import write_map_png

    from ..analysis.maps import DEFAULT_MAPS

    out, per_map = {}, {}
    chosen: dict[str, list] = {}     # quantity -> its images
    for q in dict.fromkeys(quantities or DEFAULT_MAPS):
        images = map_images(table, q)
        chosen[q] = images if quantities else [im for im in images if not im.note]
    if not quantities:      # a map none of the defaults has a value for: its adhesion map, with its note
        shown = {im.source for ims in chosen.values() for im in ims}
        chosen[DEFAULT_MAP_QUANTITY] += [im for im in map_images(table, DEFAULT_MAP_QUANTITY)
                                         if im.source not in shown]
    for q, images in chosen.items():
        for image in images:
            out[f"map {image.source} {q}"] = write_map_png(image, folder / f"{image.name}.{q}.png")
            if image.note and quantities:      # an all-grey map asked for: one line saying why
                eprint(f"note: {image.name}: map of {q} empty: {image.note}")
            per_map.setdefault(image.source, []).append(image)
    from ..analysis.maps import write_map_hdf5

    from ..plotting.maps import write_map_histograms

    for source, images in per_map.items():  # the numbers, with the grid positions; the histograms
        out[f"map {source} numbers"] = write_map_hdf5(images, folder / f"{images[0].name}.maps.h5")
        for path in write_map_histograms(images, folder / images[0].name):
            out[f"map {source} {path.name}"] = path
    out.update(_write_map_points(table, folder, quantities))
    return out


def _write_map_points(table, folder: Path, quantities: list[str]) -> dict[str, Path]:
    """The maps whose recorded positions make no grid (``analysis.maps.map_points``): a PNG of points
    in um per quantity, ``<map>.maps.h5`` with the positions, the histograms; never forced into a grid."""
    from ..analysis.maps import DEFAULT_MAPS, map_points, write_points_hdf5
    from ..plotting.maps import write_map_histograms, write_map_points_png

    out, per_map = {}, {}
    for q in dict.fromkeys(quantities or DEFAULT_MAPS):
        for points in map_points(table, q):
            if points.note and not quantities:
                continue
            out[f"map {points.source} {q}"] = write_map_points_png(points, folder / f"{points.name}.{q}.png")
            per_map.setdefault(points.source, []).append(points)
    for source, sets in per_map.items():
        eprint(f"note: {sets[0].name}: mapped as points at the recorded positions: {sets[0].why}")
        out[f"map {source} numbers"] = write_points_hdf5(sets, folder / f"{sets[0].name}.maps.h5")
        for path in write_map_histograms(sets, folder / sets[0].name):
            out[f"map {source} {path.name}"] = path
    return out


def _print_json(result, n_items: int | None = None) -> None:
    """The analysis JSON; when a file or curve failed, also the contract's ``error`` object
    (type, message, exit status 1) beside the results of the others."""
    import re

    from ..sweep.report import analysis_json

    payload = analysis_json(result)
    failed = payload["failed"]
    if failed:
        first = failed[0]
        kind = re.match(r"^(?:chunk failed: )?(?:unexpected )?([A-Z]\w*(?:Error|Exception|Interrupt))\b",
                        first["error"])
        where = first["file"] + (f"#{first['curve']}" if "curve" in first else "")
        total = f" of {n_items}" if n_items else ""
        payload["error"] = {"type": kind.group(1) if kind else "AnalysisError",
                            "message": f"{len(failed)}{total} file(s) or curve(s) failed; first {where}: "
                                       f"{first['error']}", "exit_status": 1}
    print(json.dumps(payload, indent=2, allow_nan=False))


def _oscillation_origin(ok):
    from ..sweep.report import oscillation_origin_of

    return oscillation_origin_of(ok)


#: The table's columns: (summary column, label, the prefix its declared SI unit is shown with); the
#: unit itself is the column's declared one (afmforce.sweep.summary.SUMMARY_UNITS), see :func:`_columns`.
_SHOWN = (
    ("spring_constant", "k", ""),
    ("sensitivity_used", "sens. used", "n"),  # the forces' (file/user or fit: the cell says which)
    ("sensitivity_fit", "sens. fit", "n"),
    ("adhesion_force", "adhesion F", "n"),  # a force: negative (a pull); maps show its depth, positive
    ("rupture_distance", "rupture", "n"),
    ("indentation", "indent.", "n"),
    ("youngs_modulus", "E", "k"),
    ("shift", "shift", "n"),
    ("jump_in_separation", "jump-in h", "n"),
    ("jump_in_force", "jump-in F", "n"),
    ("pull_off_force", "pull-off F", "n"),
    ("hamaker_radius", "A R", "1e-27 "),
    ("oscillation_frequency", "osc.", ""),
    ("work_of_adhesion", "w", "m"),   # --indentation-model jkr|dmt|maugis: shown when some curve has it
)
#: A prefix's factor from SI to the shown unit.
_PREFIX = {"": 1.0, "n": 1e9, "m": 1e3, "k": 1e-3, "1e-27 ": 1e27}


def _columns() -> tuple[tuple[str, str, float], ...]:
    """(column, header with its unit, factor from SI) of the table, from the declared units."""
    from ..sweep.summary import SUMMARY_UNITS

    return tuple((c, f"{label} [{prefix}{SUMMARY_UNITS[c]}]", _PREFIX[prefix]) for c, label, prefix in _SHOWN)


_ASKED_COLUMNS = frozenset({"work_of_adhesion"})


def _fmt(v: float) -> str:
    return "-" if v is None or not math.isfinite(v) else f"{v:.4g}"


def _cell(row, column: str, scale: float) -> str:
    """A number of the table; ``undetermined (+-B)`` where the analysis left it undetermined: NaN with its
    declared bound (:attr:`~afmforce.analysis.registry.ResultField.bound`) finite; a modulus whose interval is
    ``[0, open]`` (:func:`~afmforce.analysis.plausibility.interval_undetermined`): ``undetermined [0, open]``."""
    from ..analysis.plausibility import UNDETERMINED, interval_undetermined
    from ..analysis.registry import result_fields

    v = row[column]
    if column == "youngs_modulus" and v is not None and math.isfinite(float(v)) and "youngs_modulus_low" in row \
            and interval_undetermined(float(row["youngs_modulus_low"]), float(row["youngs_modulus_high"])):
        return f"{UNDETERMINED} [0, open]"
    f = result_fields().get(column)
    b = row.get(f.bound) if f is not None and f.bound else None
    if (v is None or not math.isfinite(float(v))) and b is not None and math.isfinite(float(b)):
        return f"{UNDETERMINED} (+-{float(b) * scale:.3g})"
    return _fmt(float(v) * scale)


def _calibration_tag(row, given: str = "file") -> str:
    """Which sensitivity the forces used, for the table's cell: `` (fit)`` (the compliance slope) or
    `` (file)`` / `` (user)`` / `` (meta)`` / `` (calibration)`` (the file's, --sensitivity, --meta sensitivity=,
    a --probe-calibration file's:
    :meth:`~afmforce.analysis.options.ProbeCalibration.origin`); nothing without a number."""
    if not math.isfinite(float(row["sensitivity_used"])):
        return ""
    return " (fit)" if row["calibration_source"] == "fit" else f" ({given})"


def _print_rows(ok, verbose: bool = False, given: str = "file") -> None:
    """One line per curve (small runs), then one short verdict line per curve (``verbose``: in full)."""
    if not len(ok):
        return
    columns = [(c, h, s) for c, h, s in _columns() if c not in _ASKED_COLUMNS
               or (c in ok and any(math.isfinite(float(v)) for v in ok[c] if v is not None))]
    heads = ["file", "contact"] + [h for _, h, _ in columns] + ["friction", "dynamic"]
    rows = []
    for _, r in ok.iterrows():
        vals = [_cell(r, c, s) + (_calibration_tag(r, given) if c == "sensitivity_used" else "")
                for c, _, s in columns]
        rows.append([r["name"], r["contact_kind"] or "-"] + vals
                    + [r["friction"] or "-", _dynamic_label(r)])
    widths = [max(len(h), *(len(row[i]) for row in rows)) for i, h in enumerate(heads)]
    print("  ".join(h.ljust(w) for h, w in zip(heads, widths)))
    for row in rows:
        print("  ".join(c.ljust(w) for c, w in zip(row, widths)))
    clipped = False
    ok = ok.assign(verdict=[render(v) if isinstance(v, str) else v for v in ok["verdict"]])
    for _, r in ok.iterrows():
        warnings = [w for w in (r["warnings"] or "").split(" | ") if w]
        if not (warnings or r["verdict"]):
            continue
        warnings = [render(w) for w in warnings]     # `spring_constant` -> --spring-constant
        if verbose:
            print(f"{r['name']}: {r['verdict']}" + "".join(f"\n  warning: {w}" for w in warnings))
            continue
        head = f"{r['name']}: "
        line = short_verdict(r, max(60, MAX_LINE - len(head)))
        print(head + line + "".join(f"\n  warning: {_clip(_plain(w), MAX_LINE - 11)}" for w in warnings))
        clipped = clipped or line != str(r["verdict"]) or any(_plain(w) != w for w in warnings)
    if clipped:
        print("(short verdicts: --verbose or --json gives them in full)")


def _print_stats(ok) -> None:
    """Minimum, median and maximum of the main columns (large runs)."""
    import numpy as np

    print(f"{len(ok)} curves analysed; {int(ok['dynamic'].fillna(False).sum())} flagged dynamic")
    print(f"  {'quantity':<16}  {'min':>10}  {'median':>10}  {'max':>10}  {'found':>7}")
    for col, head, scale in _columns():
        if col not in ok:
            continue
        v = ok[col].to_numpy(float) * scale
        v = v[np.isfinite(v)]
        if len(v):
            print(f"  {head:<16}  {_fmt(v.min()):>10}  {_fmt(float(np.median(v))):>10}  {_fmt(v.max()):>10}  "
                  f"{len(v):>7}")
