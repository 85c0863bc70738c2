"""``afmforce plan``: which driving speeds and sample rates determine friction best.

See :mod:`afmforce.fit.plan` and docs/fit.md.
"""

from __future__ import annotations

import argparse

from .._files import atomic_write_text
from ..constants import PLAN_SPEEDS
from ..limits import MAX_DESIGN_CURVES
from ._validate import add_field, check_outputs
from .common import busy, print_json, quantity

__all__ = ["register", "run"]


def _simulation_default(name: str) -> float:
    """The simulation's default of ``name`` [SI] (the plan's curves start from it), for the help."""
    from ..dynamics import SimulationConfig

    return getattr(SimulationConfig(), name)


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``plan`` sub-command."""
    from .fit import _list, add_model_flags

    p = subparsers.add_parser(
        "plan", help="design a multi-speed measurement: speeds and sample rates that fix xi best",
        description="For a probe (model flags as in afmforce simulate, --xi the friction to "
                    "determine): predicted standard error of xi per candidate speed and sample "
                    "rate (Fisher information of the fit), the best set of --curves speeds, and "
                    "the fastest speed at which the static analysis stays within --force-error.")
    g = p.add_argument_group("design")
    g.add_argument("--speeds", type=_list("velocity", "--speeds"),
                   default=list(PLAN_SPEEDS), metavar="V1,V2,..",
                   help=f"candidate driving speeds (default {','.join(f'{v * 1e6:g}' for v in PLAN_SPEEDS)} um/s)")
    g.add_argument("--sample-rates", type=_list("frequency", "--sample-rates"), default=None,
                   metavar="F1,F2,..", help="sample rate of each candidate speed "
                                            "(default: --points-per-nm x speed)")
    g.add_argument("--points-per-nm", type=quantity("dimensionless", "--points-per-nm", positive=True), default=2.0,
                   help="samples per nm of drive travel when no rates are given (default %(default)g)")
    add_field(g, "deflection_noise", flag="--noise", default=0.05e-9)
    g.add_argument("--curves", type=int, default=4,
                   help=f"curves in a design (default %(default)s; at most {MAX_DESIGN_CURVES})")
    add_field(g, "force_error", help="allowed error of the static pull-in force (default 10 %% of it)")
    add_field(g, "start", help="start of each approach", default_from=lambda: _simulation_default("start"))
    add_field(g, "turn", help="turn of each approach", default_from=lambda: _simulation_default("turn"))
    add_field(g, "slip_target", help="plan the slip length instead: the 95 %% half-width wanted (issue 25; "
                                     "with --slip-length, --medium, --geometry ...; docs/liquid.md)")
    add_model_flags(p)
    o = p.add_argument_group("output")
    o.add_argument("--json", action="store_true", help="print the plan as JSON (SI units)")
    o.add_argument("--report", metavar="FILE.md", help="write the Markdown summary")
    o.add_argument("--force", action="store_true", help="overwrite existing outputs")
    p.set_defaults(func=run)
    return p


def _given(args) -> set:
    """Flags typed on the command line (a non-default --speeds)."""
    return {"--speeds"} if list(args.speeds) != list(PLAN_SPEEDS) else set()


def run(args: argparse.Namespace) -> int:
    """Run the command; returns the exit status."""
    from ..fit.plan import plan_experiment
    from .fit import model_config

    check_outputs([("--report", args.report)], force=args.force)
    drive = {name: _simulation_default(name) if getattr(args, name) is None else getattr(args, name)
             for name in ("start", "turn")}
    args.start = args.turn = None
    cfg = model_config(args).replace(**drive)
    with busy("afmforce plan"):
        if args.slip_target is not None:
            from ..fit.plan_slip import plan_slip
            kw = {} if "--speeds" not in _given(args) else {"speeds": args.speeds}
            plan = plan_slip(cfg, target=args.slip_target, noise=args.deflection_noise, n_curves=args.curves,
                             points_per_nm=args.points_per_nm, **kw)
        else:
            plan = plan_experiment(cfg, noise=args.deflection_noise, speeds=args.speeds,
                                   sample_rates=args.sample_rates, points_per_nm=args.points_per_nm,
                                   n_curves=args.curves, force_error=args.force_error)
    if args.report:
        atomic_write_text(args.report, plan.markdown(), force=args.force)
    if args.json:
        print_json(plan.to_dict())
    else:
        print(plan.markdown())
    return 0
