"""An interactive page: explore how friction and speed distort a force measurement.

``build_page()`` simulates a small grid of the paper's Fig 5-6 runs (speed x
friction coefficient) and writes one self-contained HTML file (no network,
no external scripts) whose sliders switch between them: actual and apparent
deflection vs separation with the static curve, and the angle vs drive
position over the whole cycle.
"""

from .page import ExploreGrid, build_page, compute_grid

__all__ = ["ExploreGrid", "build_page", "compute_grid"]
