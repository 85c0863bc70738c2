"""Compiled kernels of the pipeline's own work outside the steps (issue 35, item 2).

:func:`span_stats` gives what :func:`~afmforce.analysis.plausibility._span` reads off a curve's two
runs (the finite forces' extremes and count, the signal's extremes) in one pass instead of a dozen
numpy calls; :func:`median_abs_step` and :func:`first_below` serve the diagnosis step;
:func:`robust_line_ab` is :func:`~afmforce.analysis._numeric.robust_line`'s line (the adhesion's
baseline, a run's speed) with its passes fused. Extremes and
medians are exact whatever the order of the pass, so the numbers are those of numpy.

:data:`COMPILED` is False when numba's JIT is off (``NUMBA_DISABLE_JIT``: the first run after an
install, :mod:`afmforce.cli._firstrun`): the callers then keep their numpy path, which is faster
than these loops run as Python.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._numeric import line_fit

__all__ = ["span_stats", "median_abs_step", "first_below", "robust_line_ab", "middle_bracket", "COMPILED", "BRACKET"]


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


@njit(cache=True, nogil=True)
def _select(a: np.ndarray, k: int) -> float:
    """The ``k``-th smallest of ``a`` (rearranged in place: everything before ``k`` is not larger),
    by Hoare's selection with a median-of-three pivot."""
    lo = 0
    hi = a.size - 1
    while hi > lo:
        mid = (lo + hi) >> 1
        if a[mid] < a[lo]:
            a[mid], a[lo] = a[lo], a[mid]
        if a[hi] < a[lo]:
            a[hi], a[lo] = a[lo], a[hi]
        if a[hi] < a[mid]:
            a[hi], a[mid] = a[mid], a[hi]
        pivot = a[mid]
        i = lo
        j = hi
        while i <= j:
            while a[i] < pivot:
                i += 1
            while a[j] > pivot:
                j -= 1
            if i <= j:
                a[i], a[j] = a[j], a[i]
                i += 1
                j -= 1
        if k <= j:
            hi = j
        elif k >= i:
            lo = i
        else:
            break
    return a[k]


@njit(cache=True, nogil=True)
def _middle(a: np.ndarray, half: int, even: bool):
    """The two middle order statistics of ``a`` (``half = a.size // 2``; the same one for an odd size)."""
    hi = _select(a, half)
    if not even:
        return hi, hi
    lo = a[0]
    for i in range(1, half):
        lo = max(lo, a[i])
    return lo, hi


@njit(cache=True, nogil=True)
def middle_bracket(a: np.ndarray, half: int, even: bool, lo_v: float, hi_v: float, buf: np.ndarray):
    """:func:`_middle` of ``a`` (left unchanged) when its middle order statistics lie in ``[lo_v, hi_v]``:
    one branch-free pass counts the samples below and gathers those within into ``buf``, and the
    selection runs on these few. Returns ``(lo, hi, ok)``; ``ok`` False when the bracket misses."""
    n = a.size
    below = 0
    m = 0
    for i in range(n):
        v = a[i]
        below += v < lo_v
        buf[m] = v
        m += (v >= lo_v) & (v <= hi_v)
    first = half - 1 if even else half
    if not (below <= first and half < below + m):
        return 0.0, 0.0, False
    part = buf[:m]
    hi = _select(part, half - below)
    if not even:
        return hi, hi, True
    lo = hi if half - below == 0 else part[0]  # (half - below >= 1: ``first`` is in the bracket too)
    for i in range(1, half - below):
        lo = max(lo, part[i])
    return lo, hi, True


#: Half-width of the brackets of :func:`robust_line_ab`'s medians, in the previous iteration's MAD [-]
BRACKET = 0.25


@njit(cache=True, nogil=True)
def robust_line_ab(x: np.ndarray, y: np.ndarray, n_iter: int = 6, tuning: float = 4.685):
    """``a, b`` of :func:`~afmforce.analysis._numeric.robust_line` (``y = a + b x``, Tukey bisquare IRLS),
    the same numbers: the same operations on every sample in the same order, the medians (order
    statistics) selected exactly among the samples near the previous iteration's (a bracket of
    :data:`BRACKET` MADs; all of them when it misses), the passes fused, without the standard
    errors. Returns ``(a, b, mad, ok)``: ``mad`` the residuals' last median absolute deviation (a hint
    for the caller's own medians); ``ok`` False for fewer than three samples or a sample that is not
    finite (nothing computed: the caller uses ``robust_line``)."""
    n = x.size
    if n < 3:
        return np.nan, np.nan, np.nan, False
    for i in range(n):
        if not (np.isfinite(x[i]) and np.isfinite(y[i])):
            return np.nan, np.nan, np.nan, False
    w = np.ones(n)
    a, b = line_fit(x, y, w)
    r = np.empty(n)
    t = np.empty(n)
    buf = np.empty(n)
    half = n // 2
    even = n % 2 == 0
    mad = -1.0  # the previous iteration's median absolute deviation (none yet)
    for _ in range(n_iter):
        for i in range(n):
            r[i] = y[i] - (a + b * x[i])
        ok = False
        if mad > 0:
            lo, hi, ok = middle_bracket(r, half, even, -BRACKET * mad, BRACKET * mad, buf)
        if not ok:
            buf[:] = r
            lo, hi = _middle(buf, half, even)
        med = (lo + hi) / 2 if even else lo
        a += med
        m2 = ((lo - med) + (hi - med)) / 2 if even else lo - med
        for i in range(n):
            r[i] -= med
            t[i] = np.abs(r[i] - m2)
        ok = False
        if mad > 0:
            lo, hi, ok = middle_bracket(t, half, even, (1.0 - BRACKET) * mad, (1.0 + BRACKET) * mad, buf)
        if not ok:
            buf[:] = t
            lo, hi = _middle(buf, half, even)
        mad = (lo + hi) / 2 if even else hi  # np.median as numba computes it
        sigma = 1.4826 * mad
        if not sigma > 0:
            break
        sw = 0.0  # w.sum() and line_fit's first pass, fused with the weights (the same sums in the same order)
        sx = 0.0
        sy = 0.0
        for i in range(n):
            u = r[i] / (tuning * sigma)
            w[i] = (1.0 - u * u) ** 2 if abs(u) < 1.0 else 0.0
            sw += w[i]
            sx += w[i] * x[i]
            sy += w[i] * y[i]
        if sw <= 2.0:
            break
        a2, b2 = _line_fit_rest(x, y, w, sw, sx, sy)
        if not (np.isfinite(a2) and np.isfinite(b2)):
            break
        a, b = a2, b2
    return a, b, mad, True


@njit(cache=True, nogil=True)
def _line_fit_rest(x, y, w, sw, sx, sy):
    """:func:`~afmforce.analysis._numeric.line_fit` after its first pass (``sw, sx, sy``), line by line."""
    if sw <= 0:
        return np.nan, np.nan
    mx = sx / sw
    my = sy / sw
    sxx = 0.0
    sxy = 0.0
    for i in range(x.size):
        dx = x[i] - mx
        sxx += w[i] * dx * dx
        sxy += w[i] * dx * (y[i] - my)
    if sxx <= 0:
        return my, np.nan
    b = sxy / sxx
    return my - b * mx, b


#: The kernels run compiled (False under ``NUMBA_DISABLE_JIT``, where they are plain Python).
COMPILED = hasattr(span_stats, "py_func")
