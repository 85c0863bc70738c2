"""``afmforce statics``: spring constant, calibration factor and friction hysteresis."""

from __future__ import annotations

import argparse

from ..cantilever import InclinedCantilever
from ..constants import FIG3
from ..statics import FRICTION_MODELS, static_analysis
from .common import add_quantity, print_json, print_table


def add_geometry_arguments(parser: argparse.ArgumentParser, defaults: dict = FIG3) -> None:
    """Add the inclined-cantilever flags (--k0/--B, --L0, --L1, --L2, --theta0)."""
    g = parser.add_argument_group("cantilever geometry (Fig 2)")
    stiff = g.add_mutually_exclusive_group()
    add_quantity(stiff, "--k0", "stiffness", defaults.get("k0"), "intrinsic spring constant", "N/m")
    add_quantity(stiff, "--B", "rigidity", defaults.get("B"), "flexural rigidity B = k0 L0^3/3 [N m^2]")
    add_quantity(g, "--L0", "length", defaults["L0"], "length of the flexible beam", "m")
    add_quantity(g, "--L1", "length", defaults["L1"], "length of the rigid base", "m")
    add_quantity(g, "--L2", "length", defaults["L2"], "length of the rigid probe", "m")
    add_quantity(g, "--theta0", "angle", defaults["theta0"], "inclination of the beam (e.g. -15deg)", "rad")


def cantilever_from_args(args: argparse.Namespace) -> InclinedCantilever:
    """Build the :class:`InclinedCantilever` from parsed geometry flags."""
    B = getattr(args, "B", None)
    k0 = None if B is not None else args.k0
    return InclinedCantilever(L0=args.L0, L1=args.L1, L2=args.L2, theta0=args.theta0, k0=k0, B=B)


def register(sub) -> None:
    p = sub.add_parser("statics", help="static spring constant, calibration factor, friction hysteresis",
                       description="Static analysis of the inclined cantilever (paper section 2.2, eqs 13-21).")
    add_geometry_arguments(p)
    f = p.add_argument_group("friction (section 2.2)")
    f.add_argument("--friction", choices=list(FRICTION_MODELS), default="none",
                   help="; ".join(f"{m.identifier}: {m.name}" for m in FRICTION_MODELS.values()))
    add_quantity(f, "--mu", "force", None, "constant friction force (--friction constant)", "N")
    f.add_argument("--lambda", dest="lam", type=float, default=None,
                   help="friction/load ratio lambda (--friction load)")
    add_quantity(f, "--xi", "damping", None, "viscous friction coefficient (--friction viscous)")
    add_quantity(f, "--velocity", "velocity", None, "driving speed (--friction viscous)")
    add_quantity(f, "--gap-deflection", "length", None,
                 "deflection of the inward line where the load-friction gap is evaluated (default 10 nm)", "m")
    p.add_argument("--json", action="store_true", help="print one JSON object with SI values")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    cantilever = cantilever_from_args(args)
    params = {"constant": {"mu": args.mu},
              "load": {"lam": args.lam, "deflection": args.gap_deflection},
              "viscous": {"xi": args.xi, "velocity": args.velocity}}.get(args.friction, {})
    result = static_analysis(cantilever, args.friction, **params)
    if args.json:
        print_json(result.to_dict())
        return 0
    d = result.to_dict()
    rows = [("friction model", FRICTION_MODELS[args.friction].name, "")]
    for key, unit in result.units.items():
        if isinstance(d.get(key), dict):
            for sub_key, sub_val in d[key].items():
                rows.append((f"{key} {sub_key}", sub_val, result.units.get(sub_key, "")))
        elif key in d:
            rows.append((key, d[key], unit))
    print_table([(label.replace("_", " "), _scale(v, u), _unit(u)) for label, v, u in rows],
                title="afmforce statics (SI inputs; lengths and forces scaled)")
    return 0


def _scale(value, unit):
    if unit == "m/rad" and not isinstance(value, str):
        return value * 1e9
    return value


def _unit(unit):
    return "nm/rad" if unit == "m/rad" else unit
