"""``afmforce reproduce``: the paper's figures and numbers into a folder."""

from __future__ import annotations

import argparse

from ..errors import ParameterError


def register(sub) -> None:
    p = sub.add_parser("reproduce", help="reproduce the paper's figures and numbers (report.md, PNG)",
                       description="Write every figure of the paper that afmforce reproduces, with "
                                   "report.md and report.json (paper value, ours, difference, tolerance).")
    p.add_argument("--out", default="afmforce-paper", help="output folder (default ./afmforce-paper)")
    p.add_argument("--only", default=None,
                   help="comma-separated figures: fig1,fig3,fig4,fig5,fig6,fig7,fig9")
    p.add_argument("--fast", action="store_true", help="quicker, lower-resolution run")
    p.add_argument("--svg", action="store_true", help="also write SVG figures")
    p.add_argument("--force", action="store_true",
                   help="replace the figures and reports of an earlier run in --out")
    p.set_defaults(func=run)


def run_reproduce(out: str, only, fast: bool, svg: bool):
    """Run :func:`afmforce.paper.reproduce.reproduce` with a progress bar on a terminal."""
    from ..paper.reproduce import reproduce

    from .common import progress_bar

    bar, progress = progress_bar("reproduce", unit="figure", leave=False)

    try:
        return reproduce(out, only=only, fast=fast, svg=svg, progress=progress)
    finally:
        bar.close()


def summarize(res) -> str:
    """Short text summary of a reproduce run."""
    gated = [c for c in res.checks if c.gated]
    n_ok = sum(bool(c.passed) for c in gated)
    lines = [f"wrote {sum(len(v) for v in res.figures.values())} figure files, report.md and report.json "
             f"to {res.out_dir}/ in {res.wall_time:.1f} s",
             f"numbers: {n_ok} of {len(gated)} gated checks pass (paper within its stated "
             f"tolerance, bound or reference); {len(res.checks) - len(gated)} shown without "
             "pass/fail (estimates, known differences)"]
    for c in gated:
        if not c.passed:
            lines.append(f"  FAILED: {c.quantity}: ours {c.ours:.4g} {c.unit}, paper {c.paper}, ref {c.reference}")
    for k, msg in res.failed_figures.items():
        lines.append(f"  figure {k} not written: {msg}")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    from ._outcome import reported
    from ._validate import check_folder_outputs

    only = None if args.only is None else [s.strip() for s in args.only.split(",") if s.strip()]
    if only == []:
        raise ParameterError("--only: no figure named; give some of fig1,fig3,fig4,fig5,fig6,fig7,fig9 "
                             "(or drop --only for all)")
    from ..paper.reproduce import planned_files

    check_folder_outputs(args.out, planned_files(only, args.svg), flag="--out", force=args.force)
    res = run_reproduce(args.out, only, args.fast, args.svg)
    reported(res.out_dir)  # summarize() names the folder
    print(summarize(res))
    return 0 if res.passed else 1
