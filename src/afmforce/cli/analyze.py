"""``afmforce analyze``: analyse force-curve files (or folders of them).

For each curve: calibrated force against separation, jump-in, pull-off, the
van der Waals fit, the instrument's artefacts and the dynamic diagnosis. With
``--out DIR`` each curve gets ``<name>.afmforce.json`` (result, SI units),
``<name>.afmforce.csv`` (force-vs-separation table with units) and
``<name>.afmforce.png`` (figure), written atomically; input files are only read.
Bad files are reported and skipped; the exit status is 1 if any failed,
2 for usage errors.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from ..errors import AfmforceError, OutputExistsError, ParameterError
from .common import add_quantity, atomic_path, atomic_write_text, eprint

SUFFIX = ".afmforce"


def register(sub) -> None:
    from ..pipeline import STEPS

    p = sub.add_parser("analyze", help="analyse force-curve files: force vs separation, jumps, fits, diagnosis",
                       description=__doc__.split("\n\n")[1].replace("\n", " "))
    p.add_argument("files", nargs="+", metavar="FILE", help="force-curve files or folders (searched recursively)")
    p.add_argument("--out", metavar="DIR", type=Path, default=None,
                   help="write JSON, CSV table and figure of each curve into DIR")
    p.add_argument("--json", action="store_true", help="print the results as JSON (SI) instead of a table")
    p.add_argument("--force", action="store_true", help="overwrite existing output files")
    p.add_argument("--steps", default=None, metavar="A,B,...",
                   help="analysis steps to run (their requirements are added): " + ", ".join(STEPS))
    p.add_argument("--format", default=None, metavar="ID", help="reader to use instead of detection "
                   "(see docs/analysis.md), e.g. jpk-zip for raw volts")
    p.add_argument("--channel", choices=("auto", "measured", "nominal"), default="auto",
                   help="position channel (default: measured if recorded)")
    p.add_argument("--no-plot", action="store_true", help="with --out: skip the figures")
    g = p.add_argument_group("instrument and probe (values with units, e.g. 0.21N/m, 45nm/V, -15deg, 220nm)")
    add_quantity(g, "--spring-constant", "stiffness", None,
                 "spring constant k (with --theta0: the intrinsic k0, corrected by eq 13/14)", "N/m")
    add_quantity(g, "--sensitivity", "sensitivity", None, "deflection sensitivity (InvOLS)", "m/V")
    add_quantity(g, "--theta0", "angle", None, "cantilever inclination for the tilt correction", "rad")
    add_quantity(g, "--L0", "length", None, "beam length (with --L1, --L2: eq 13 instead of eq 14)", "m")
    add_quantity(g, "--L1", "length", None, "rigid base length", "m")
    add_quantity(g, "--L2", "length", None, "rigid probe length", "m")
    add_quantity(g, "--radius", "length", None, "probe radius R (gives gamma from the pull-off, A from A R)", "m")
    add_quantity(g, "--resonance-frequency", "frequency", None, "resonance frequency (inertia diagnosis)", "Hz")
    add_quantity(g, "--contact-separation", "length", 0.35e-9,
                 "separation given to the compliance line (paper: z0; 0 also common)", "m")
    g.add_argument("--calibration", choices=("auto", "fit", "metadata"), default="auto",
                   help="deflection calibration: from the file/--sensitivity, or the compliance slope")
    p.set_defaults(func=run)


def _inputs(names: list[str]) -> list[Path]:
    from ..io import supported_suffixes

    suffixes = tuple(supported_suffixes())
    out: list[Path] = []
    for name in names:
        path = Path(name)
        if path.is_dir():
            found = sorted(p for p in path.rglob("*") if p.is_file() and p.name.lower().endswith(suffixes)
                           and SUFFIX not in p.name)
            out.extend(found)
        else:
            out.append(path)
    return out


def _options(args: argparse.Namespace) -> dict:
    opts: dict = {"zero": {"contact_separation": args.contact_separation},
                  "calibration": {"source": args.calibration},
                  "force": {"spring_constant": args.spring_constant, "theta0": args.theta0,
                            "L0": args.L0, "L1": args.L1, "L2": args.L2},
                  "adhesion": {"radius": args.radius}, "vdw": {"radius": args.radius},
                  "diagnosis": {"resonance_frequency": args.resonance_frequency}}
    return opts


def _outputs(out: Path, stem: str) -> dict[str, Path]:
    return {ext: out / f"{stem}{SUFFIX}.{ext}" for ext in ("json", "csv", "png")}


def _write(result, curve, paths: dict[str, Path], force: bool, plot: bool) -> None:
    for key, path in paths.items():
        if key == "png" and not plot:
            continue
        if path.exists() and not force:
            raise OutputExistsError(f"{path} exists; pass --force to overwrite")
    atomic_write_text(paths["json"], result.to_json(), force=force)
    result.write_table(paths["csv"], force=force)
    if plot:
        from ..plotting import plot_summary

        fig = plot_summary(result, curve)
        with atomic_path(paths["png"], force=force) as tmp:
            fig.savefig(tmp, dpi=100, format="png")


def run(args: argparse.Namespace) -> int:
    from ..analysis.oscillation import oscillation_origin
    from ..io import load
    from ..pipeline import analyze, resolve_steps

    steps = None if args.steps is None else [s.strip() for s in args.steps.split(",") if s.strip()]
    resolve_steps(steps)  # unknown step: ParameterError -> exit 2
    if args.out is not None and args.out.exists() and not args.out.is_dir():
        raise ParameterError(f"--out {args.out} exists and is not a folder")
    files = _inputs(args.files)
    if not files:
        raise ParameterError("no force-curve files found in the given folders")
    inputs = {p.resolve() for p in files if p.exists()}
    meta = {k: v for k, v in (("spring_constant", args.spring_constant), ("sensitivity", args.sensitivity))
            if v is not None}
    opts = _options(args)
    results, failed = [], []
    bar = _progress(len(files))
    for path in files:
        try:
            curves = load(path, meta_override=meta, format=args.format)
            for i, curve in enumerate(curves):
                res = analyze(curve, steps=steps, options=opts, channel=args.channel)
                name = path.name if len(curves) == 1 else f"{path.name}#{i}"
                results.append((name, res))
                if args.out is not None:
                    stem = path.name if len(curves) == 1 else f"{path.name}_{i:04d}"
                    paths = _outputs(args.out, stem)
                    if any(p.resolve() in inputs for p in paths.values()):
                        raise OutputExistsError(f"an output would replace an input file ({stem}); choose --out")
                    _write(res, curve, paths, args.force, not args.no_plot)
        except AfmforceError as exc:
            failed.append((str(path), str(exc)))
        except (OSError, ValueError, RuntimeError, FloatingPointError, IndexError) as exc:
            failed.append((str(path), f"unexpected {type(exc).__name__}: {exc}"))
        bar(path)
    bar(None)
    peaks = [(r.details["oscillation"], r) for _, r in results if "oscillation" in r.details]
    freqs = [p.frequency for o, _ in peaks for p in (o.approach, o.retract) if p.found]
    vels = [p.velocity for o, _ in peaks for p in (o.approach, o.retract) if p.found]
    origin = oscillation_origin(freqs, vels) if len(results) > 1 else None
    if args.json:
        payload = {"results": {name: r.to_dict() for name, r in results},
                   "failed": [{"file": f, "error": e} for f, e in failed]}
        if origin is not None:
            payload["oscillation_origin"] = {"origin": origin[0], "verdict": origin[1]}
        print(json.dumps(payload, indent=2, allow_nan=False))
    else:
        _print_summary(results)
        if origin is not None and origin[0] != "none":
            print(f"oscillations across files: {origin[1]}")
    for f, e in failed:
        eprint(f"failed: {e}" if e.startswith(f) else f"failed: {f}: {e}")
    if failed:
        eprint(f"{len(failed)} of {len(files)} file(s) failed")
    return 1 if failed else 0


def _progress(n: int):
    """A tqdm bar over files on a terminal (stderr), silent otherwise."""
    if n < 2 or not sys.stderr.isatty():
        return lambda path: None
    from tqdm import tqdm

    bar = tqdm(total=n, unit="file", file=sys.stderr, leave=False)

    def step(path):
        if path is None:
            bar.close()
        else:
            bar.set_postfix_str(Path(path).name[-30:])
            bar.update(1)

    return step


_COLUMNS = (  # attribute, header, scale
    ("spring_constant", "k [N/m]", 1.0),
    ("calibration_factor", "InvOLS [nm/V]", 1e9),
    ("shift", "shift [nm]", 1e9),
    ("jump_in_separation", "jump-in h [nm]", 1e9),
    ("jump_in_force", "jump-in F [nN]", 1e9),
    ("pull_off_force", "pull-off F [nN]", 1e9),
    ("hamaker_radius", "A R [1e-27 J m]", 1e27),
    ("oscillation_frequency", "osc. [Hz]", 1.0),
)


def _fmt(v: float) -> str:
    return "-" if v is None or not math.isfinite(v) else f"{v:.4g}"


def _print_summary(results) -> None:
    if not results:
        return
    heads = ["file"] + [h for _, h, _ in _COLUMNS] + ["friction", "dynamic"]
    rows = []
    for name, r in results:
        vals = [getattr(r, a) * s for a, _, s in _COLUMNS]
        if r.deflection_unit != "V":
            vals[1] = math.nan  # vendor-calibrated signal: no InvOLS
        rows.append([name] + [_fmt(v) for v in vals]
                    + [r.friction or "-", "yes" if r.dynamic else "no"])
    widths = [max(len(h), *(len(row[i]) for row in rows)) for i, h in enumerate(heads)]
    print("  ".join(h.ljust(w) for h, w in zip(heads, widths)))
    for row in rows:
        print("  ".join(c.ljust(w) for c, w in zip(row, widths)))
    for name, r in results:
        if r.warnings or r.verdict:
            print(f"{name}: {r.verdict}" + ("".join(f"\n  warning: {w}" for w in r.warnings)))
