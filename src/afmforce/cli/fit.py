"""``afmforce fit``: fit the dynamic model jointly to curves measured at several speeds.

Model flags and defaults are those of ``afmforce simulate`` (the beam defaults
to the paper's Fig 5 lever); each curve's speed and sample rate come from its
file (``velocity``, ``sample_rate``) or from ``--velocities``/``--sample-rates``.
"""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

from .._files import atomic_write_text
from ..errors import AfmforceError, ParameterError
from ._outcome import RunState, render
from ._validate import add_field, check_folder_outputs, check_outputs
from ..limits import MAX_STARTS
from .common import busy, eprint, print_json, refuse_missing

__all__ = ["register", "run", "model_config", "add_model_flags"]


def add_model_flags(parser: argparse.ArgumentParser) -> None:
    """The model flags of ``afmforce simulate`` (model, beam, spring, surfaces, the surface force
    laws (eq 2, the double layer and the others, from their records), friction)."""
    from . import simulate as S

    for add in (S._model_group, S._beam_group, S._spring_group, S._surface_group, S._liquid_group,
                S._laws_groups, S._friction_group):
        add(parser)
    g = parser.add_argument_group("solver")
    S._q(g, "--rtol", "relative tolerance (velocities, Newton)")
    S._q(g, "--atol", "absolute tolerance on positions")
    S.add_sampling_flag(g, "average")


def model_config(args: argparse.Namespace):
    """The SimulationConfig of the model flags (drive fields are set per curve)."""
    from .simulate import config_from_args

    return config_from_args(args)


#: Quantity (afmforce._fields.QUANTITIES) whose range checks each value of a list flag, by dimension.
_LIST_QUANTITY = {"velocity": "velocity", "frequency": "sample_rate", "damping": "xi"}


def _list(dimension: str, flag: str):
    """``V1,V2,...`` with units, each value checked against its quantity's range; empty lists refused."""
    from ._validate import quantity_list

    conv = quantity_list(_LIST_QUANTITY[dimension], flag)

    def parse(text: str) -> list[float]:
        return list(conv(text))

    parse.__name__ = conv.__name__
    return parse


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``fit`` sub-command."""
    from ..fit import PARAMETERS

    p = subparsers.add_parser(
        "fit", help="fit the dynamic model to curves at several driving speeds (friction, A*R)",
        description="Fit the dynamic model (afmforce simulate) jointly to calibrated approach "
                    "curves measured at several driving speeds: global parameters (--free), and "
                    "per curve the zero of position, the baseline offset and drift. Reports "
                    "standard errors, profile-likelihood intervals and whether friction is "
                    "detected (likelihood ratio, AIC/BIC); in a liquid the slip length, the "
                    "spring constant in situ and whether slip is detected (docs/liquid.md). "
                    "See docs/fit.md.")
    p.add_argument("curves", nargs="*", metavar="CURVE",
                   help="force-curve files with a calibrated deflection [m] (or volts/newtons with the "
                        "file's calibration), at several driving speeds, or folders of them")
    p.add_argument("--example", metavar="NAME", default=None,
                   help="fit sample curves shipped with afmforce instead of files: speeds (simulated Fig 5 "
                        "beam, xi = 0.01 kg/s, at 0.5, 1, 2 and 5 um/s)")
    g = p.add_argument_group("fit")
    g.add_argument("--free", default="hamaker,xi",
                   help=f"global parameters to fit, comma-separated, among {', '.join(PARAMETERS)} "
                        "(default hamaker,xi)")
    g.add_argument("--velocities", type=_list("velocity", "--velocities"), default=None,
                   metavar="V1,V2,..", help="driving speed of each curve (default: from the files)")
    g.add_argument("--sample-rates", type=_list("frequency", "--sample-rates"), default=None,
                   metavar="F1,F2,..", help="sample rate of each curve (default: from the files)")
    g.add_argument("--meta", action="append", default=[], metavar="KEY=VALUE",
                   help="file metadata to give or replace in every curve, with units (repeatable), "
                        "e.g. sensitivity=50nm/V, spring_constant=0.14N/m, sample_rate=2kHz "
                        "(afmforce formats lists the keys)")
    g.add_argument("--no-drift", action="store_true", help="fit no drift slope per curve")
    g.add_argument("--quadratic-compliance", action="store_true",
                   help="calibrate curves in volts by a quadratic fit of their compliance region "
                        "(a curved photodiode response; both runs needed: analysis.liquid, "
                        "docs/liquid.md) instead of the file's sensitivity")
    g.add_argument("--retract", action="store_true", default=None,
                   help="fit the retract run too (outward compliance and its hysteresis; the "
                        "pull-off is left out like the jump-in); default: when a free parameter "
                        "needs it (lever_drag) and the files have it")
    g.add_argument("--no-retract", action="store_false", dest="retract",
                   help="fit the approach runs only")
    g.add_argument("--level", type=float, default=0.95,
                   help="confidence level of intervals and friction test (default %(default)g)")
    g.add_argument("--starts", type=int, default=2,
                   help=f"local fits from the best points of a scan in xi (default %(default)s; at most {MAX_STARTS})")
    g.add_argument("--no-compare", action="store_true",
                   help="skip the model comparison (static / no friction / friction)")
    g.add_argument("--no-profile", action="store_true",
                   help="Wald intervals only (skip the profile likelihood)")
    g.add_argument("--noise-model", choices=("auto", "white"), default="auto",
                   help="auto (default): add 1/f detector noise where the residuals show it "
                        "(generalised least squares); white: white noise only")
    g.add_argument("--fringes", nargs="?", const="periodic", default="periodic",
                   choices=("periodic", "parabola", "off"),
                   help="interference fringes in the baseline: periodic (default) cos and sin of "
                        "the separation shared by all curves (one spot); parabola: a line and a "
                        "parabola before contact per curve; off")
    g.add_argument("--calibration", choices=("auto", "fit", "metadata"), default="auto",
                   type=lambda w: "metadata" if w == "file" else w,  # "file": the former word for metadata
                   help="as analyze's --calibration (one rule): auto (default): the files' sensitivities "
                        "(the compliance slope only without one); fit: the compliance slope (a thermal k "
                        "rescaled); metadata: the files' always")
    add_field(g, "fringe_period", default=335e-9,
              help="fringe period in the separation: half the laser wavelength (335 nm: a 670 nm laser)")
    add_field(g, "jump_window", default=None,
              help="left out after the jump-in (default: until the deflection has landed on the "
                   "contact line, at most 2 ms)")
    add_model_flags(p)
    o = p.add_argument_group("output")
    o.add_argument("--json", action="store_true", help="print the result as JSON (SI units)")
    o.add_argument("--out", metavar="FILE.json", help="write the JSON result")
    o.add_argument("--report", metavar="FILE.md", help="write a Markdown summary")
    o.add_argument("--plots", metavar="DIR",
                   help="write a figure per curve (data, model, residuals) and the profiles")
    o.add_argument("--force", action="store_true", help="overwrite existing outputs")
    p.set_defaults(func=run)
    return p


def _load(paths, meta=None, found=frozenset()):
    """The curves of ``paths``, their names and the files skipped: every curve of a file with
    several (a force map, ``FILE#2``...); a missing calibration asked for with the fit's ``--meta``
    (its ``--spring-constant`` is the model lever's). A file ``found`` in a folder that no reader
    can read is skipped, ``(path, message)``, as ``afmforce analyze`` goes on past a bad file of a
    batch; a file named is read or the error is the command's."""
    from ..errors import FileFormatError, MissingMetadataError
    from ..fit.core import MAX_CURVES, check_curve_count
    from ..io import load
    from ..sweep.files import TooManyCurves, plan_curves

    curves, names, skipped = [], [], []
    for path in paths:
        try:   # a force map's curves counted from its header before it is read: a 64 x 64 map was
            plan_curves([path], max_curves=MAX_CURVES - len(curves))   # read whole (1 GB) to be refused
        except TooManyCurves as exc:
            check_curve_count(exc.total)
        try:
            got = load(path, meta_override=meta or None)
        except MissingMetadataError as exc:
            if not exc.keys:
                raise
            what = str(exc).split("; give ")[0]
            flags = " ".join(f"--meta {k}=VALUE" for k in exc.keys)
            raise MissingMetadataError(
                f"{what}; give them with {flags} (e.g. --meta spring_constant=0.1N/m "
                "--meta sensitivity=50nm/V; in `afmforce fit` --spring-constant is the model's lever)",
                keys=exc.keys, flags=("--meta",)) from None
        except FileFormatError as exc:
            if str(path) not in found:
                raise
            skipped.append((str(path), str(exc)))
            continue
        name = Path(path).name
        curves += list(got)
        check_curve_count(len(curves))   # files whose header gives no count: refused once read past the cap
        names += [name] if len(got) == 1 else [f"{name}#{i + 1}" for i in range(len(got))]
    if skipped and not curves:
        raise FileFormatError(f"no file could be read: {skipped[0][1]}"
                              + (f" (and {len(skipped) - 1} more)" if len(skipped) > 1 else ""))
    return curves, names, skipped


def run(args: argparse.Namespace) -> int:
    """Run the command; returns the exit status."""
    from ..fit import fit_dynamic
    from ..fit.core import LEVER_FIELDS, MASS_FIELDS, lever_sources

    # the files' calibration is given with --meta here: --spring-constant is the model's lever
    RunState.flags.update(spring_constant="--meta spring_constant=VALUE", sensitivity="--meta sensitivity=VALUE")
    from ..fit.figures import plot_curves, plot_profiles, plot_residuals

    if args.example is not None:
        from ..datasets import fit_example

        args.curves = list(args.curves) + [str(p) for p in fit_example(args.example)]
    if not args.curves:
        raise ParameterError("give force-curve files at several speeds, or --example speeds")
    refuse_missing(args.curves)  # before any work: no output folder for a typo
    from .analyze import _inputs  # folders as `analyze` reads them: every curve file in them

    named = {str(Path(c)) for c in args.curves if not Path(c).is_dir()}
    args.curves = [str(p) for p in _inputs(args.curves)]
    found = frozenset(c for c in args.curves if c not in named)      # files found in the folders
    if not args.curves:
        raise ParameterError("no force-curve files found in the given folders")
    check_outputs([("--out", args.out), ("--report", args.report)], force=args.force,
                  inputs=[*args.curves, getattr(args, "probe_calibration", None)])
    if args.plots:   # never replace an earlier run's figures silently
        check_folder_outputs(args.plots, ("fit_curve*.png", "fit_profiles.png", "fit_residuals.png"),
                             flag="--plots", force=args.force)
    if not 0.5 < args.level < 1:
        raise ParameterError(f"--level must lie between 0.5 and 1, got {args.level}")
    cfg = model_config(args)
    from ..fit.params import check_free

    check_free(args.free.split(","), cfg.model, cfg.friction.law if cfg.model == "beam" else None)  # before loading
    from ..io import parse_meta_args

    curves, names, skipped = _load(args.curves, parse_meta_args(args.meta), found)
    for path, message in skipped:
        eprint(f"warning: skipped {render(message)}")
    for flag, vals in (("--velocities", args.velocities), ("--sample-rates", args.sample_rates)):
        if vals is not None and len(vals) != len(curves):
            raise ParameterError(f"{flag} has {len(vals)} values for {len(curves)} curves"
                                 + (f" (in {len(args.curves)} files)" if len(curves) != len(args.curves)
                                    else ""))
    if args.quadratic_compliance:    # issue 25: volts -> metres by the curved compliance
        from ..analysis.liquid import calibrate_liquid_curve
        curves = [calibrate_liquid_curve(c) if c.deflection_unit == "V" else c for c in curves]
    with warnings.catch_warnings(record=True), busy("afmforce fit"):
        warnings.simplefilter("ignore")
        res = fit_dynamic(curves, cfg, free=args.free.split(","), names=names,
                          velocities=args.velocities, sample_rates=args.sample_rates,
                          drift=not args.no_drift, starts=args.starts, level=args.level,
                          profile=() if args.no_profile else None,
                          compare=not args.no_compare, jump_window=args.jump_window,
                          sampling=None,    # --sampling (default average) is in cfg
                          retract=args.retract, noise=args.noise_model,
                          fringes=args.fringes, fringe_period=args.fringe_period,
                          calibration=args.calibration,
                          # the model's lever and mass are the files' unless a flag gives one (issue 34)
                          **lever_sources(n for n in LEVER_FIELDS + MASS_FIELDS
                                          if getattr(args, n, None) is not None))
    d = res.to_dict()
    # how each curve was calibrated (the analysis's calibration: the file's, or the compliance slope)
    d["calibration"] = {c.name: c.metadata.get("calibration") for c in res._problem.ev.curves}
    d["skipped_files"] = [{"file": path, "error": message} for path, message in skipped]
    if args.plots:
        written = plot_curves(res, res._problem.ev.curves, args.plots, force=True)
        prof = plot_profiles(res, Path(args.plots) / "fit_profiles.png", force=True)
        resid = plot_residuals(res, res._problem.ev.curves, Path(args.plots) / "fit_residuals.png",
                               force=True)
        d["figures"] = [str(p) for p in written] + ([str(prof)] if prof else []) + [str(resid)]
    if args.out:
        from .common import to_jsonable
        import json

        atomic_write_text(args.out, json.dumps(to_jsonable(d), indent=2) + "\n", force=args.force)
    if args.report:
        atomic_write_text(args.report, render(res.markdown()), force=args.force)   # keys as flags
    if args.json:
        print_json(d)
    else:
        print(render(res.markdown()))
    for w in res.warnings:
        eprint(f"warning: {render(w)}")
    if skipped:      # as `afmforce analyze`: the batch went on, the status says a file failed
        eprint(f"warning: {len(skipped)} file(s) of the folders could not be read and were left out of the fit")
    return 1 if skipped else 0
