"""``afmforce statics``: spring constant, calibration factor and friction hysteresis."""

from __future__ import annotations

import argparse

from ..cantilever import InclinedCantilever
from ..constants import FIG3
from ..statics import FRICTION_MODELS, static_analysis
from ._validate import add_field, check_beam, refuse_ignored
from .common import print_json, print_table, readable


def add_geometry_arguments(parser: argparse.ArgumentParser, defaults: dict = FIG3) -> None:
    """Add the inclined-cantilever flags (--k0/--B, --L0, --L1, --L2, --theta0)."""
    g = parser.add_argument_group("cantilever geometry (Fig 2)")
    stiff = g.add_mutually_exclusive_group()
    add_field(stiff, "k0", default=defaults.get("k0"))
    add_field(stiff, "B", default=defaults.get("B"))
    for name in ("L0", "L1", "L2", "theta0"):
        add_field(g, name, default=defaults[name])


def cantilever_from_args(args: argparse.Namespace) -> InclinedCantilever:
    """Build the :class:`InclinedCantilever` from parsed geometry flags (checked by :func:`check_beam`)."""
    B = getattr(args, "B", None)
    k0 = None if B is not None else args.k0
    check_beam(args.L0, args.L1, args.L2, k0=k0, B=B)
    return InclinedCantilever(L0=args.L0, L1=args.L1, L2=args.L2, theta0=args.theta0, k0=k0, B=B)


#: Flags of each friction model's parameters: (dest, flag, model parameter).
_FRICTION_FLAGS = (("mu", "--mu", "mu"), ("lam", "--lambda", "lam"), ("xi", "--xi", "xi"),
                   ("velocity", "--velocity", "velocity"), ("gap_deflection", "--gap-deflection", "deflection"))


def register(sub) -> None:
    p = sub.add_parser("statics", help="static spring constant, calibration factor, friction hysteresis",
                       description="Static analysis of the inclined cantilever (paper section 2.2, eqs 13-21).")
    add_geometry_arguments(p)
    f = p.add_argument_group("friction (section 2.2)")
    f.add_argument("--friction", choices=list(FRICTION_MODELS), default="none",
                   help="; ".join(f"{m.identifier}: {m.name}" for m in FRICTION_MODELS.values()))
    add_field(f, "mu", help="constant friction force (--friction constant)")
    add_field(f, "lam", flag="--lambda", help="friction/load ratio lambda (--friction load)")
    add_field(f, "xi", help="viscous friction coefficient (--friction viscous)")
    add_field(f, "velocity", help="driving speed (--friction viscous)")
    add_field(f, "gap_deflection", help="deflection of the inward line where the load-friction gap is "
              "evaluated (--friction load; default 10 nm)")
    p.add_argument("--json", action="store_true", help="print one JSON object with SI values")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    used = {p for p, _ in FRICTION_MODELS[args.friction].parameters} | (
        {"deflection"} if args.friction == "load" else set())
    refuse_ignored(args, [(dest, flag, param in used, f"by --friction {args.friction}")
                          for dest, flag, param in _FRICTION_FLAGS])
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
    print_table([(readable(label), _scale(v, u), _unit(u)) for label, v, u in rows],
                title="afmforce statics (SI inputs; lengths and forces scaled)")
    return 0


def _scale(value, unit):
    if unit == "m/rad" and not isinstance(value, str):
        return value * 1e9
    return value


def _unit(unit):
    return "nm/rad" if unit == "m/rad" else unit
