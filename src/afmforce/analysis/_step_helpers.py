"""Helpers shared by the pipeline steps (:mod:`afmforce.analysis.steps`)."""

from __future__ import annotations

import numpy as np

from ._numeric import robust_line
from .state import State


def line_slope(x: np.ndarray, y: np.ndarray) -> float:
    """Least-squares slope of ``y`` against ``x`` [unit of y / unit of x] (NaN when ``x`` does not move)."""
    xc = x - x.mean()
    den = float(np.dot(xc, xc))
    return float(np.dot(xc, y - y.mean())) / den if den > 0.0 else float("nan")


def _kind(st: State) -> str:
    """``"hard"``, ``"soft"`` (or ``"hard"`` when the kind step did not run)."""
    k = st.details.get("kind")
    return k.kind if k is not None else "hard"


def _skip(st: State, step: str, why: str, detail=None) -> State:
    """Record that ``step`` does not apply to this curve, and why."""
    if detail is not None:  # one new state (each update copies the state's dict)
        return st.update(step, detail, skipped={**st.skipped, step: why})
    return st.update(skipped={**st.skipped, step: why})


def _zero_deflection_position(st: State, run=None) -> float:
    """Where a run's (default: the approach's) contact line crosses zero signal: contact at zero load.

    Interference depends on the separation, constant in contact: its value there
    is the free-branch fringe at this position.
    """
    run = st.approach if run is None else run
    idx = run.index[run.contact & ~run.saturated]
    z_first = float(st.z[run.index[run.split]])
    if idx.size < 3:
        return z_first
    x0 = st.z[idx].mean()
    a, b, *_ = robust_line(st.z[idx] - x0, st.signal[idx])
    return float(x0 - a / b) if np.isfinite(b) and b != 0 else z_first
