"""``afmforce demo``: the paper's numbers recomputed, ours beside the paper's."""

from __future__ import annotations

import argparse

from ..paper import evaluate_checks
from .common import print_json


def register(sub) -> None:
    p = sub.add_parser("demo", help="reproduce the paper's numbers (the main job on built-in defaults)",
                       description="Recompute every number of the paper that afmforce can, and print "
                                   "ours beside the paper's value.")
    p.add_argument("--json", action="store_true", help="print the checks as JSON")
    p.set_defaults(func=run)


def format_checks(results) -> str:
    """A plain-text table of evaluated paper checks."""
    head = f"{'quantity':<64} {'source':<20} {'paper':>10} {'afmforce':>12} {'unit':<7} {'diff':>7}  ok"
    lines = [head, "-" * len(head)]
    for r in results:
        paper = "-" if r.paper is None else f"{r.paper:.4g}"
        diff = "-" if r.relative_difference is None else f"{100 * r.relative_difference:+.1f}%"
        lines.append(f"{r.quantity[:64]:<64} {r.source[:20]:<20} {paper:>10} {r.ours:>12.5g} "
                     f"{r.unit:<7} {diff:>7}  {'yes' if r.passed else 'NO'}")
    n_ok = sum(r.passed for r in results)
    lines.append(f"{n_ok} of {len(results)} numbers agree with the paper within its rounding")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    results = evaluate_checks()
    if args.json:
        print_json([r.to_dict() for r in results])
    else:
        print("afmforce demo: Attard, Carambassis & Rutland, Langmuir 15, 553 (1999), recomputed\n")
        print(format_checks(results))
    return 0 if all(r.passed for r in results) else 1
