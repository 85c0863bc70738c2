"""``afmforce diagnose``: is inertia measurable for this probe and speed? (eqs 3, 4)."""

from __future__ import annotations

import argparse

from ..constants import FIG1, HAMAKER, Z0
from ..diagnostics import Diagnosis, diagnose
from ._validate import add_field
from .common import print_json, print_table, readable


def register(sub) -> None:
    p = sub.add_parser("diagnose", help="inertia parameter, inertial lag, jump-in and pull-off estimates",
                       description="Dynamic diagnosis of section 2.1 (eqs 3-4). Defaults: Fig 1 probe at 10 um/s.")
    for name, default in (("spring_constant", FIG1["spring_constant"]), ("mass", FIG1["mass"]),
                          ("radius", FIG1["radius"]), ("hamaker", HAMAKER), ("z0", Z0),
                          ("velocity", FIG1["velocities"][0]), ("resolution", 0.5e-9), ("separation", 5e-9)):
        add_field(p, name, default=default)
    p.add_argument("--json", action="store_true", help="print one JSON object with SI values")
    p.set_defaults(func=run)


#: Why a row is not defined (its value NaN): the static jump-in needs a spring softer than the
#: steepest attraction, max Fs' = (A R/6)(2/3) 3^(-1/2) z0^-3 (afmforce.forces.static_jump_in_separation).
_NONE = {"static jump-in separation": "none: the spring is stiffer than the steepest van der Waals "
                                      "gradient, so the tip does not jump into contact"}


def run(args: argparse.Namespace) -> int:
    d = diagnose(spring_constant=args.spring_constant, mass=args.mass, radius=args.radius,
                 velocity=args.velocity, resolution=args.resolution, separation=args.separation,
                 hamaker=args.hamaker, z0=args.z0)
    if args.json:
        print_json(d.to_dict())
        return 0
    values = d.to_dict()
    rows = [(readable(k), values[k], u) for k, u in Diagnosis.UNITS.items()]
    rows = [(label, _NONE.get(label, value) if value is None or value != value else value, u)
            for label, value, u in rows]     # NaN: not defined for this probe, said why
    print_table(rows, title="afmforce diagnose")
    first, *rest = d.verdict.split("; ")  # one clause a line: every line short, nothing left out
    print(f"  verdict: {first}" + "".join(f";\n           {c}" for c in rest))
    return 0
