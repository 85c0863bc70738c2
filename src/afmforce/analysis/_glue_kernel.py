"""Compiled kernels of the pipeline's own work outside the steps (issue 35, item 2).

:func:`span_stats` gives what :func:`~afmforce.analysis.plausibility._span` reads off a curve's two
runs (the finite forces' extremes and count, the signal's extremes) in one pass instead of a dozen
numpy calls; :func:`median_abs_step` and :func:`first_below` serve the diagnosis step;
:func:`robust_line_ab` is :func:`~afmforce.analysis._numeric.robust_line`'s line (the adhesion's
baseline, a run's speed) without the standard errors. Extremes and
medians are exact whatever the order of the pass, so the numbers are those of numpy.

:data:`COMPILED` is False when numba's JIT is off (``NUMBA_DISABLE_JIT``: the first run after an
install, :mod:`afmforce.cli._firstrun`): the callers then keep their numpy path, which is faster
than these loops run as Python.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._numeric import BRACKET, _robust_line, middle_bracket  # noqa: F401 (re-exported: the adhesion kernel)

__all__ = ["span_stats", "median_abs_step", "first_below", "glitch_scan", "robust_line_ab", "middle_bracket", "COMPILED", "BRACKET"]


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
def glitch_scan(s: np.ndarray, sigmas: float):
    """:func:`~afmforce.analysis.glitches.find_glitches`' first pass in one call: the second differences
    ``d2 = s[1:-1] - 0.5 (s[:-2] + s[2:])``, the robust noise ``1.4826 median(|d2 - median(d2)|) / sqrt(1.5)``
    (the medians exact: order statistics, the middle pair's mean as numpy's) and whether any sample ``2 <= i <=
    n - 3`` has ``|d2[i - 1]| > sigmas * sigma``. Returns ``(d2, sigma, any, ok)``; ``ok`` False (the caller
    takes its numpy path) for fewer than 5 samples, a sample that is not finite, or ``sigma <= 0`` (a quantised
    signal: the caller's own step rule)."""
    n = s.size
    if n < 5:
        return np.empty(0), 0.0, False, False
    for i in range(n):
        if not np.isfinite(s[i]):
            return np.empty(0), 0.0, False, False
    m = n - 2
    d2 = np.empty(m)
    for i in range(m):
        d2[i] = s[i + 1] - 0.5 * (s[i] + s[i + 2])
    med = np.median(d2)
    dev = np.empty(m)
    for i in range(m):
        dev[i] = abs(d2[i] - med)
    sigma = 1.4826 * np.median(dev) / math.sqrt(1.5)
    if not sigma > 0.0:
        return d2, sigma, False, False
    lim = sigmas * sigma
    hit = False
    for i in range(1, m - 1):  # sample i + 1 in 2 .. n - 3
        if abs(d2[i]) > lim:
            hit = True
            break
    return d2, sigma, hit, True


@njit(cache=True, nogil=True)
def first_below(h: np.ndarray, idx: np.ndarray, k: int, limit: float) -> int:
    """The first ``i > k`` with ``h[idx[i]] < limit`` (``idx.size`` if none)."""
    for i in range(max(k + 1, 0), idx.size):
        if h[idx[i]] < limit:
            return i
    return idx.size


@njit(cache=True, nogil=True)
def robust_line_ab(x: np.ndarray, y: np.ndarray, n_iter: int = 6, tuning: float = 4.685):
    """``a, b`` of :func:`~afmforce.analysis._numeric.robust_line` (``y = a + b x``, Tukey bisquare IRLS)
    without its standard errors. Returns ``(a, b, mad, ok)``: ``mad`` the residuals' last median
    absolute deviation (a hint for the caller's own medians, :func:`middle_bracket`); ``ok`` False for
    fewer than three samples or a sample that is not finite (then all NaN: the caller uses ``robust_line``)."""
    a, b, _, _, _, _, mad, ok = _robust_line(x, y, np.int64(n_iter), np.float64(tuning), np.bool_(False))
    if not ok:
        return np.nan, np.nan, np.nan, False
    return a, b, mad, True


#: The kernels run compiled (False under ``NUMBA_DISABLE_JIT``, where they are plain Python).
COMPILED = hasattr(span_stats, "py_func")
