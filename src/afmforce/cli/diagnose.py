"""``afmforce diagnose``: is inertia measurable for this probe and speed? (eqs 3, 4)."""

from __future__ import annotations

import argparse

from ..constants import FIG1, HAMAKER, Z0
from ..diagnostics import Diagnosis, diagnose
from .common import add_quantity, print_json, print_table


def register(sub) -> None:
    p = sub.add_parser("diagnose", help="inertia parameter, inertial lag, jump-in and pull-off estimates",
                       description="Dynamic diagnosis of section 2.1 (eqs 3-4). Defaults: Fig 1 probe at 10 um/s.")
    add_quantity(p, "--spring-constant", "stiffness", FIG1["spring_constant"], "spring constant k", "N/m")
    add_quantity(p, "--mass", "mass", FIG1["mass"], "effective mass", "kg")
    add_quantity(p, "--radius", "length", FIG1["radius"], "effective radius R", "m")
    add_quantity(p, "--hamaker", "energy", HAMAKER, "Hamaker constant A", "J")
    add_quantity(p, "--z0", "length", Z0, "soft-wall length", "m")
    add_quantity(p, "--velocity", "velocity", FIG1["velocities"][0], "driving speed", "m/s")
    add_quantity(p, "--resolution", "length", 0.5e-9, "deflection resolution", "m")
    add_quantity(p, "--separation", "length", 5e-9, "separation where the force gradient is taken", "m")
    p.add_argument("--json", action="store_true", help="print one JSON object with SI values")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    d = diagnose(spring_constant=args.spring_constant, mass=args.mass, radius=args.radius,
                 velocity=args.velocity, resolution=args.resolution, separation=args.separation,
                 hamaker=args.hamaker, z0=args.z0)
    if args.json:
        print_json(d.to_dict())
        return 0
    values = d.to_dict()
    rows = [(k.replace("_", " "), values[k], u) for k, u in Diagnosis.UNITS.items()]
    print_table(rows, title="afmforce diagnose")
    print(f"  verdict: {d.verdict}")
    return 0
