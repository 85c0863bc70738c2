"""Compiled kernels of the pipeline's own work outside the steps (issue 35, item 2).

:func:`span_stats` gives what :func:`~afmforce.analysis.plausibility._span` reads off a curve's two
runs (the finite forces' extremes and count, the signal's extremes) in one pass instead of a dozen
numpy calls; :func:`median_abs_step` and :func:`first_below` serve the diagnosis step. Extremes and
medians are exact whatever the order of the pass, so the numbers are those of numpy.

:data:`COMPILED` is False when numba's JIT is off (``NUMBA_DISABLE_JIT``: the first run after an
install, :mod:`afmforce.cli._firstrun`): the callers then keep their numpy path, which is faster
than these loops run as Python.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["span_stats", "median_abs_step", "first_below", "COMPILED"]


@njit(cache=True, nogil=True)
def span_stats(force: np.ndarray, signal: np.ndarray, ia: np.ndarray, ib: np.ndarray):
    """Over the samples ``ia`` then ``ib``: ``(n, fmin, fmax, smin, smax)``, the number of finite
    ``force`` values and their extremes, and the extremes of ``signal`` (NaN when there are no samples)."""
    n = 0
    fmin = np.inf
    fmax = -np.inf
    smin = np.inf
    smax = -np.inf
    for part in range(2):
        idx = ia if part == 0 else ib
        for q in range(idx.size):
            i = idx[q]
            f = force[i]
            if np.isfinite(f):
                n += 1
                if f < fmin:
                    fmin = f
                if f > fmax:
                    fmax = f
            s = signal[i]
            if s < smin:
                smin = s
            if s > smax:
                smax = s
    if ia.size + ib.size == 0:
        smin = np.nan
        smax = np.nan
    return n, fmin, fmax, smin, smax


@njit(cache=True, nogil=True)
def median_abs_step(z: np.ndarray, idx: np.ndarray) -> float:
    """``np.median(np.abs(np.diff(z[idx])))`` (``idx`` of two samples or more): the median step."""
    d = np.empty(idx.size - 1)
    for i in range(idx.size - 1):
        d[i] = abs(z[idx[i + 1]] - z[idx[i]])
    return np.median(d)


@njit(cache=True, nogil=True)
def first_below(h: np.ndarray, idx: np.ndarray, k: int, limit: float) -> int:
    """The first ``i > k`` with ``h[idx[i]] < limit`` (``idx.size`` if none)."""
    for i in range(max(k + 1, 0), idx.size):
        if h[idx[i]] < limit:
            return i
    return idx.size


#: The kernels run compiled (False under ``NUMBA_DISABLE_JIT``, where they are plain Python).
COMPILED = hasattr(span_stats, "py_func")
