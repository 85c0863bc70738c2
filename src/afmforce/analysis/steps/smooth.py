"""The ``smooth`` step: digitization smoothing of the position (running average).

Declared once by its record :data:`SMOOTH` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import numpy as np

from .._numeric import running_mean
from .._smooth_kernel import smooth_runs, staircase_window
from ..options import SmoothOptions
from ..regions import run_indices
from ..registry import AnalysisStep
from ..state import SmoothResult, State

__all__ = ["smooth", "SMOOTH"]


def _staircase_window(z: np.ndarray, minimum: int = 11) -> int:
    """Odd window covering two digitization steps of a stepped position channel (at least ``minimum``)."""
    same = np.diff(z) == 0
    if same.mean() < 0.3:  # no staircase
        return minimum
    edges = np.flatnonzero(np.diff(np.concatenate([[False], same, [False]]).astype(np.int8)))
    runs = edges[1::2] - edges[::2] + 1  # samples per plateau
    step = int(np.median(runs)) if runs.size else 1
    return max(minimum, 2 * step + 1)


def _smooth_run(z: np.ndarray, window: int, staircase: bool = False) -> np.ndarray:
    """Running mean of one run; for a ``staircase`` (digitized) channel, within half a window
    of the run's ends, the line through the next ``window`` fully averaged samples.

    The symmetric window shrinks at the ends, and a shrunken window cannot average out a
    digitization staircase: the last half window (5 nm of a 5 nm-step detector) would keep
    its steps, which bends the constant-compliance line that ends at the turning point.
    A smooth channel keeps the shrinking window (a line would overshoot a decelerating turn).
    """
    out = running_mean(z, window)
    half = window // 2
    if not staircase or half < 1 or z.size < 2 * window + 2 * half:
        return out
    k = np.arange(z.size, dtype=float)
    for inner, edge in ((slice(half, half + window), slice(0, half)),
                        (slice(z.size - half - window, z.size - half), slice(z.size - half, z.size))):
        b, a = np.polyfit(k[inner], out[inner], 1)
        out[edge] = a + b * k[edge]
    return out


def smooth(st: State, o: SmoothOptions) -> State:
    """Running average of the position channel, each run separately (Fig 7C).

    ``o.window="auto"``: the paper's 11 points, or two digitization steps of a
    stepped (digitized) channel if those are longer, so that the average
    interpolates linearly between levels as in the paper. On a stepped channel,
    within half a window of a run's ends the position continues the line of the
    averaged samples next to them (a shrinking window would leave the steps there).
    """
    staircase = False
    seg = np.asarray(st.curve.segment)
    fast = st.z.dtype == np.float64 and st.z.ndim == 1 and st.z.flags.c_contiguous and seg.dtype == np.int8
    if o.window == "auto":  # the record checked a given window (a positive odd number)
        window = staircase_window(st.z, 11) if fast and st.z.size >= 2 else _staircase_window(st.z)
        staircase = window > 11
    else:
        window = int(o.window)
    if fast and not staircase:  # one compiled call: the running mean of each run, the largest change
        z, change = smooth_runs(st.z, seg, window)
    else:
        z = st.z.copy()
        for which in (0, 1, 2):
            idx = run_indices(seg, which)
            if idx.size:
                z[idx] = _smooth_run(st.z[idx], window, staircase)
        change = float(np.max(np.abs(z - st.z))) if z.size else 0.0
    return st.update("smooth", SmoothResult(window, st.channel, change), z=z)


SMOOTH = AnalysisStep("smooth", "Digitization smoothing of the position (running average)", smooth, SmoothOptions,
                      reference="section 3.1, Fig 7C", runs=())
