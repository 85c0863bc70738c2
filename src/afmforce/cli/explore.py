"""``afmforce explore``: write the interactive page (one self-contained HTML file)."""

from __future__ import annotations

import argparse

from ._outcome import reported
from ..limits import CONFIRM_GRID_POINTS, MAX_GRID_POINTS, check_count
from ._validate import check_outputs, confirm_size


def _list(dimension: str, flag: str):
    """Values checked against the same ranges as ``afmforce simulate`` (xi <= 100 kg/s, ...)."""
    from ._validate import quantity_list

    return quantity_list({"velocity": "velocity", "damping": "xi"}[dimension], flag)


def register(sub) -> None:
    p = sub.add_parser("explore", help="write an interactive HTML page: speed x friction on the Fig 5-6 run",
                       description="Simulate a grid of the paper's Fig 5-6 runs (speeds x friction "
                                   "coefficients) and write one self-contained HTML page with sliders.")
    p.add_argument("--out", default="afmforce-explore.html", help="output HTML file")
    p.add_argument("--velocities", type=_list("velocity", "--velocities"), default=None,
                   help="comma-separated speeds (default 0.1,0.3,1,3,10 um/s), e.g. 0.1um/s,1um/s")
    p.add_argument("--xis", type=_list("damping", "--xis"), default=None,
                   help="comma-separated friction coefficients (default 0.001,0.01,0.1 kg/s)")
    p.add_argument("--force", action="store_true", help="overwrite an existing output file")
    p.add_argument("--yes", action="store_true",
                   help=f"simulate a grid of more than {CONFIRM_GRID_POINTS} points (refused without it)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..explore import build_page, compute_grid
    from ..explore.page import DEFAULT_VELOCITIES, DEFAULT_XIS

    check_outputs([("--out", args.out)], force=args.force)
    n = len(args.velocities or DEFAULT_VELOCITIES) * len(args.xis or DEFAULT_XIS)
    check_count("--velocities x --xis", n, MAX_GRID_POINTS, "grid points (one simulation each)")
    confirm_size(n, CONFIRM_GRID_POINTS, yes=args.yes, what="this explore grid", unit="simulations")
    from .common import progress_bar

    bar, _ = progress_bar("explore", unit="run", leave=False)

    def advance(fraction: float) -> None:
        bar.n = int(1000 * fraction)
        bar.refresh()

    try:
        grid = compute_grid(args.velocities or DEFAULT_VELOCITIES, args.xis or DEFAULT_XIS, progress=advance)
    finally:
        bar.close()
    path = build_page(args.out, grid, force=args.force)
    reported(path)
    print(f"wrote {path} ({len(grid.runs)} simulated runs: {len(grid.velocities)} speeds x "
          f"{len(grid.xis)} friction coefficients); open it in a browser")
    return 0
