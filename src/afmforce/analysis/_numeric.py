"""Compiled numerical kernels shared by the analysis steps and the batch core.

numba-compiled (``cache=True``) loops over one curve; :mod:`.batch` calls the
same kernels for many curves. Every kernel is O(n).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .._linalg_small import solve_small  # re-exported: drift and the fringe fit import it from here

__all__ = ["running_mean", "two_line_split", "line_fit", "robust_line", "robust_line_thin", "largest_step",
           "mad_sigma", "lstsq_qr", "polyfit", "ptp"]


@njit(cache=True)
def running_mean(x: np.ndarray, window: int) -> np.ndarray:
    """Centered running average of ``window`` points (odd), shrinking symmetrically at the ends.

    The shrinking window keeps a straight line exactly straight, so a linear
    ramp is unchanged and a digitization staircase becomes a line (the paper's
    11-point smoothing of the position detector, section 3.1).
    """
    n = x.size
    half = window // 2
    c = np.empty(n + 1)
    c[0] = 0.0
    for i in range(n):
        c[i + 1] = c[i] + x[i]
    out = np.empty(n)
    for i in range(n):
        h = min(half, i, n - 1 - i)
        out[i] = (c[i + h + 1] - c[i - h]) / (2 * h + 1)
    return out


@njit(cache=True)
def two_line_split(x: np.ndarray, y: np.ndarray, min_points: int) -> int:
    """Index k minimising the summed squared residuals of two independent lines.

    Lines are fitted to ``[0, k)`` and ``[k, n)``; both parts hold at least
    ``min_points`` samples. Returns -1 if the curve is too short. Data are
    centred and scaled first, so metres and volts do not lose precision.
    """
    n = x.size
    if n < 2 * min_points:
        return -1
    mx = x.mean()
    my = y.mean()
    sx = 0.0
    sy = 0.0
    for i in range(n):
        sx = max(sx, abs(x[i] - mx))
        sy = max(sy, abs(y[i] - my))
    sx = sx if sx > 0 else 1.0
    sy = sy if sy > 0 else 1.0
    # cumulative sums of x, y, xx, xy, yy (one array each: the split's loop below reads them unit-stride)
    c0 = np.empty(n + 1)
    c1 = np.empty(n + 1)
    c2 = np.empty(n + 1)
    c3 = np.empty(n + 1)
    c4 = np.empty(n + 1)
    c0[0] = c1[0] = c2[0] = c3[0] = c4[0] = 0.0
    for i in range(n):
        u = (x[i] - mx) / sx
        v = (y[i] - my) / sy
        c0[i + 1] = c0[i] + u
        c1[i + 1] = c1[i] + v
        c2[i + 1] = c2[i] + u * u
        c3[i + 1] = c3[i] + u * v
        c4[i + 1] = c4[i] + v * v
    # every split's summed squared residuals first (no dependence between splits: its divisions vectorise),
    # then the first smallest; the same operations on each split as one loop doing both
    lo = min_points
    hi = n - min_points + 1
    sse = np.empty(max(hi - lo, 0))
    t0, t1, t2, t3, t4 = c0[n], c1[n], c2[n], c3[n], c4[n]
    for k in range(lo, hi):
        m = k
        s0, s1, s2, s3, s4 = c0[k], c1[k], c2[k], c3[k], c4[k]
        sxx = s2 - s0 * s0 / m
        sxy = s3 - s0 * s1 / m
        syy = s4 - s1 * s1 / m
        r = syy - (sxy * sxy / sxx if sxx > 1e-300 else 0.0)
        e = max(r, 0.0)
        m = n - k
        s0 = t0 - s0
        s1 = t1 - s1
        s2 = t2 - s2
        s3 = t3 - s3
        s4 = t4 - s4
        sxx = s2 - s0 * s0 / m
        sxy = s3 - s0 * s1 / m
        syy = s4 - s1 * s1 / m
        r = syy - (sxy * sxy / sxx if sxx > 1e-300 else 0.0)
        sse[k - lo] = e + max(r, 0.0)
    best = np.inf
    kbest = -1
    for k in range(lo, hi):
        if sse[k - lo] < best:
            best = sse[k - lo]
            kbest = k
    return kbest


@njit(cache=True)
def line_fit(x: np.ndarray, y: np.ndarray, w: np.ndarray):
    """Weighted least-squares line ``y = a + b x``; returns ``(a, b)`` (NaN if degenerate)."""
    sw = 0.0
    sx = 0.0
    sy = 0.0
    for i in range(x.size):
        sw += w[i]
        sx += w[i] * x[i]
        sy += w[i] * y[i]
    return _line_fit_rest(x, y, w, sw, sx, sy)


@njit(cache=True)
def mad_sigma(r: np.ndarray) -> float:
    """Robust standard deviation ``1.4826 * median(|r - median(r)|)``."""
    if r.size == 0:
        return np.nan
    med = np.median(r)
    return 1.4826 * np.median(np.abs(r - med))


@njit(cache=True)
def _middle_pair(r):
    """The two middle order statistics of ``r`` (the same one for an odd size; NaN if empty):
    ``np.median(r)`` is their mean, ``(lo + hi) / 2``, as numba computes it."""
    n = r.size
    if n == 0:
        return np.nan, np.nan
    half = n // 2
    s = np.partition(r, half)
    hi = s[half]
    if n % 2:
        return hi, hi
    lo = s[0]
    for i in range(1, half):
        lo = max(lo, s[i])
    return lo, hi


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


#: Half-width of the brackets of :func:`robust_line`'s medians, in the previous iteration's MAD [-]
BRACKET = 0.25


@njit(cache=True, nogil=True)
def _median_pair(a, half, even, lo_v, hi_v, buf, fast):
    """The two middle order statistics of ``a`` (left unchanged): selected in place among the samples
    in ``[lo_v, hi_v]`` when ``fast`` (finite samples, a bracket given: ``lo_v < hi_v``), among all of
    them when that misses; otherwise by ``np.partition`` (NaN ordered as numpy orders it; and numpy's
    own speed when the kernels run as Python)."""
    if not fast:
        return _middle_pair(a)
    if lo_v < hi_v:
        c, h = 0.5 * (lo_v + hi_v), 0.5 * (hi_v - lo_v) * NARROW
        lo, hi, ok = middle_bracket(a, half, even, c - h, c + h, buf)  # an IRLS that has settled: few values
        if ok:
            return lo, hi
        lo, hi, ok = middle_bracket(a, half, even, lo_v, hi_v, buf)
        if ok:
            return lo, hi
    if a.size >= SAMPLE_BRACKET_MIN:  # no bracket (a first iteration), or it missed: one from a sample
        lo_v, hi_v = _sample_bracket(a, half)
        lo, hi, ok = middle_bracket(a, half, even, lo_v, hi_v, buf)
        if ok:
            return lo, hi
    buf[:] = a
    return _middle(buf, half, even)


#: :func:`_median_pair` looks first within this fraction of the bracket it is given, about its middle [-].
NARROW = 0.2

#: :func:`_median_pair` without a bracket of its own takes one from an evenly spaced sample of ~128 of at least
#: this many values (a branchy selection over all of them mispredicts about every other comparison).
SAMPLE_BRACKET_MIN = 256


@njit(cache=True, nogil=True)
def _sample_bracket(a, half):
    """A bracket of the ``half``-th smallest of finite ``a`` (``a.size >= 256``): the order statistics 2 sqrt(m) + 1
    ranks either side of its expected rank in an evenly spaced sample of ``m`` ~ 128-255 values (the middle
    falls outside with a probability of ~1e-4; :func:`middle_bracket` then says so and the caller selects
    among all)."""
    n = a.size
    step = n // 128
    m = n // step
    s = np.empty(m)
    for i in range(m):
        s[i] = a[i * step]
    s.sort()
    j = (m * half) // n
    d = int(2.0 * math.sqrt(m)) + 1
    return s[max(j - d, 0)], s[min(j + d, m - 1)]


@njit(cache=True, nogil=True)
def _robust_line(x, y, n_iter, tuning, errors):
    """:func:`robust_line`: ``(a, b, se_a, se_b, sigma, n_used, mad, finite)`` (the standard errors
    NaN, ``n_used`` 0 unless ``errors``); ``mad`` the residuals' last median absolute deviation,
    ``finite`` whether there are three samples or more, all finite.

    One pass a step on every sample: the residuals, their median (selected in place among the
    samples within :data:`BRACKET` MADs of the previous iteration's, all of them when that misses:
    the exact order statistics), the absolute deviations, their median, the weights fused with the
    weighted line's first sums (the same sums in the same order as :func:`line_fit`)."""
    n = x.size
    finite = n >= 3
    if _COMPILED:
        for i in range(n):
            if not (np.isfinite(x[i]) and np.isfinite(y[i])):
                finite = False
                break
    else:
        finite = finite and bool(np.isfinite(x).all() and np.isfinite(y).all())
    fast = finite and _COMPILED  # as Python, np.partition selects faster than a loop
    w = np.ones(n)
    w_new = np.empty(n)
    a, b = line_fit(x, y, w)
    r = np.empty(n)
    t = np.empty(n)
    buf = np.empty(n)
    half = n // 2
    even = n % 2 == 0
    mad = np.nan
    sigma = np.nan
    for _ in range(n_iter):
        if _COMPILED:
            for i in range(n):
                r[i] = y[i] - (a + b * x[i])
        else:  # as Python: numpy's loops (the same operations on each sample)
            r[:] = y - (a + b * x)
        # np.median(r): outliers pull least squares off: recentre first
        lo, hi = _median_pair(r, half, even, -BRACKET * mad, BRACKET * mad, buf, fast)
        med = (lo + hi) / 2 if even else lo
        a += med
        # mad_sigma(r) without its first selection: subtracting one number keeps the order (rounding is
        # monotonic), so the shifted middle pair is the old one shifted, and np.median(r) is this exactly
        m2 = ((lo - med) + (hi - med)) / 2 if even else lo - med
        if _COMPILED:
            for i in range(n):
                r[i] -= med
                t[i] = np.abs(r[i] - m2)
        else:
            r -= med
            t[:] = np.abs(r - m2)
        if n == 0:
            mad = np.nan
        elif fast:
            lo, hi = _median_pair(t, half, even, (1.0 - BRACKET) * mad, (1.0 + BRACKET) * mad, buf, fast)
            mad = (lo + hi) / 2 if even else hi  # np.median as numba computes it
        else:
            mad = np.median(t)
        sigma = 1.4826 * mad
        if not sigma > 0:
            break
        sw = 0.0  # w_new.sum() and line_fit's first pass, fused with the weights
        sx = 0.0
        sy = 0.0
        if _COMPILED:
            for i in range(n):
                u = r[i] / (tuning * sigma)
                w_new[i] = (1.0 - u * u) ** 2 if abs(u) < 1.0 else 0.0
                sw += w_new[i]
                sx += w_new[i] * x[i]
                sy += w_new[i] * y[i]
        elif n:  # the same numbers, the sums in the same order (cumsum)
            u = r / (tuning * sigma)
            w_new[:] = np.where(np.abs(u) < 1.0, (1.0 - u * u) ** 2, 0.0)
            sw = np.cumsum(w_new)[-1]
            sx = np.cumsum(w_new * x)[-1]
            sy = np.cumsum(w_new * y)[-1]
        if sw <= 2.0:
            break
        w, w_new = w_new, w
        a2, b2 = _line_fit_rest(x, y, w, sw, sx, sy)
        if not (np.isfinite(a2) and np.isfinite(b2)):
            break
        a, b = a2, b2
    if not errors:
        return a, b, np.nan, np.nan, sigma, 0, mad, finite
    # standard errors of the weighted fit
    sw = 0.0
    sx = 0.0
    n_used = 0
    for i in range(n):
        sw += w[i]
        sx += w[i] * x[i]
        if w[i] > 0:
            n_used += 1
    mx = sx / sw if sw > 0 else np.nan
    sxx = 0.0
    ssr = 0.0
    for i in range(n):
        sxx += w[i] * (x[i] - mx) ** 2
        ssr += w[i] * (y[i] - a - b * x[i]) ** 2
    dof = max(n_used - 2, 1)
    s2 = ssr / max(sw, 1e-300) * n_used / dof
    se_b = np.sqrt(s2 / sxx) if sxx > 0 else np.nan
    se_a = np.sqrt(s2 * (1.0 / max(n_used, 1) + mx * mx / sxx)) if sxx > 0 else np.nan
    if not sigma > 0:
        sigma = np.sqrt(s2)
    return a, b, se_a, se_b, sigma, n_used, mad, finite


@njit(cache=True, nogil=True)
def _line_fit_rest(x, y, w, sw, sx, sy):
    """:func:`line_fit` after its first pass (``sw, sx, sy``), line by line."""
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


@njit(cache=True, nogil=True)
def robust_line(x: np.ndarray, y: np.ndarray, n_iter: int = 6, tuning: float = 4.685):
    """Line fit with Tukey bisquare weights (IRLS), robust to spikes and transients.

    Returns
    -------
    a, b : float
        Intercept and slope of ``y = a + b x``.
    se_a, se_b : float
        Standard errors (from the weighted residual variance).
    sigma : float
        Robust scale of the residuals.
    n_used : int
        Number of samples with non-zero weight.
    """
    a, b, se_a, se_b, sigma, n_used, _, _ = _robust_line(x, y, np.int64(n_iter), np.float64(tuning), np.bool_(True))
    return a, b, se_a, se_b, sigma, n_used


@njit(cache=True)
def largest_step(d: np.ndarray, lo: int, hi: int, sign: float) -> int:
    """Index i in [lo, hi-1) maximising ``sign * (d[i+1] - d[i])`` (-1 if empty)."""
    best = -np.inf
    ib = -1
    for i in range(max(lo, 0), min(hi, d.size) - 1):
        s = sign * (d[i + 1] - d[i])
        if s > best:
            best = s
            ib = i
    return ib


#: The kernels run compiled (False under ``NUMBA_DISABLE_JIT``, where they are plain Python).
_COMPILED = hasattr(line_fit, "py_func")


def robust_line_thin(x: np.ndarray, y: np.ndarray, max_points: int = 4001):
    """:func:`robust_line` on at most ``max_points`` evenly spaced samples (long baselines and runs:
    60,000 samples cost 10 ms for a slope whose standard error, sqrt(n / max_points) larger, stays
    far below what it is used for)."""
    n = x.size
    if n > max_points:
        keep = np.linspace(0, n - 1, max_points).astype(np.int64)
        x, y = np.ascontiguousarray(x[keep]), np.ascontiguousarray(y[keep])
    return robust_line(x, y)


@njit(cache=True)
def _wls_small(X, y, w):
    """Weighted least squares by the normal equations (p <= 3 columns, Gaussian elimination with
    partial pivoting); ``ok`` False when a pivot is zero (singular: the caller uses lstsq). The
    sums of p = 1..3 columns are unrolled (each in a register; the same sums in the same order as
    the general loop)."""
    n, p = X.shape
    A = np.zeros((p, p))
    b = np.zeros(p)
    if p == 1:
        b0 = a00 = 0.0
        for i in range(n):
            wi = w[i]
            if wi != 0.0:
                x0 = X[i, 0]
                xw0 = x0 * wi
                b0 += xw0 * y[i]
                a00 += xw0 * x0
        A[0, 0] = a00
        b[0] = b0
    elif p == 2:
        b0 = b1 = a00 = a01 = a10 = a11 = 0.0
        for i in range(n):
            wi = w[i]
            if wi != 0.0:
                x0 = X[i, 0]
                x1 = X[i, 1]
                yi = y[i]
                xw0 = x0 * wi
                xw1 = x1 * wi
                b0 += xw0 * yi
                a00 += xw0 * x0
                a01 += xw0 * x1
                b1 += xw1 * yi
                a10 += xw1 * x0
                a11 += xw1 * x1
        A[0, 0] = a00
        A[0, 1] = a01
        A[1, 0] = a10
        A[1, 1] = a11
        b[0] = b0
        b[1] = b1
    elif p == 3:
        b0 = b1 = b2 = a00 = a01 = a02 = a10 = a11 = a12 = a20 = a21 = a22 = 0.0
        for i in range(n):
            wi = w[i]
            if wi != 0.0:
                x0 = X[i, 0]
                x1 = X[i, 1]
                x2 = X[i, 2]
                yi = y[i]
                xw0 = x0 * wi
                xw1 = x1 * wi
                xw2 = x2 * wi
                b0 += xw0 * yi
                a00 += xw0 * x0
                a01 += xw0 * x1
                a02 += xw0 * x2
                b1 += xw1 * yi
                a10 += xw1 * x0
                a11 += xw1 * x1
                a12 += xw1 * x2
                b2 += xw2 * yi
                a20 += xw2 * x0
                a21 += xw2 * x1
                a22 += xw2 * x2
        A[0, 0] = a00
        A[0, 1] = a01
        A[0, 2] = a02
        A[1, 0] = a10
        A[1, 1] = a11
        A[1, 2] = a12
        A[2, 0] = a20
        A[2, 1] = a21
        A[2, 2] = a22
        b[0] = b0
        b[1] = b1
        b[2] = b2
    else:
        for i in range(n):
            wi = w[i]
            if wi == 0.0:
                continue
            for j in range(p):
                xw = X[i, j] * wi
                b[j] += xw * y[i]
                for k in range(p):
                    A[j, k] += xw * X[i, k]
    out = solve_small(A, b)
    return out, not math.isnan(out[0])


@njit(cache=True)
def median_near(x, guess, width, buf):
    """``np.median(x)`` of a finite array (the same number: the middle order statistics, their
    mean for an even size), from the samples in ``[guess - width, guess + width]`` when these
    hold the middle (one counting pass, :func:`middle_bracket`), a selection of a copy
    otherwise. ``buf``: scratch of ``x.size`` samples."""
    n = x.size
    half = n // 2
    even = n % 2 == 0
    if width > 0 and n > 64:
        lo, hi, ok = middle_bracket(x, half, even, guess - width, guess + width, buf)
        if ok:
            return (lo + hi) / 2 if even else hi
    for i in range(n):
        buf[i] = x[i]
    lo, hi = _middle(buf[:n], half, even)
    return (lo + hi) / 2 if even else hi


@njit(cache=True)
def _resid(X, y, coef, r):
    """``r = y - X coef``, each row's sum from 0.0 column by column (p = 1..3 unrolled)."""
    n, p = X.shape
    if p == 1:
        c0 = coef[0]
        for i in range(n):
            r[i] = y[i] - (0.0 + X[i, 0] * c0)
    elif p == 2:
        c0 = coef[0]
        c1 = coef[1]
        for i in range(n):
            r[i] = y[i] - ((0.0 + X[i, 0] * c0) + X[i, 1] * c1)
    elif p == 3:
        c0 = coef[0]
        c1 = coef[1]
        c2 = coef[2]
        for i in range(n):
            r[i] = y[i] - (((0.0 + X[i, 0] * c0) + X[i, 1] * c1) + X[i, 2] * c2)
    else:
        for i in range(n):
            s = 0.0
            for j in range(p):
                s += X[i, j] * coef[j]
            r[i] = y[i] - s


@njit(cache=True)
def irls_bisquare(X, y, n_iter, tuning):
    """Bisquare-weighted least squares of ``y`` on the columns of ``X`` (see
    :func:`afmforce.analysis.drift._irls`): ``(coef, sigma, weighted SSR, ok)``; ``ok`` False when a
    normal-equation system was singular (the caller then uses its numpy version).

    Each iteration: the residuals, their scale ``1.4826 * median(|r - median(r)|)`` (the medians
    exactly ``np.median``'s, selected among the samples near the previous iteration's:
    :func:`median_near`), the bisquare weights, the weighted normal equations
    (:func:`_wls_small`); it stops once the coefficients move by less than 1e-4 of the scale."""
    n, p = X.shape
    w = np.ones(n)
    coef, ok = _wls_small(X, y, w)
    if not ok:
        return coef, 0.0, 0.0, False
    sigma = 0.0
    r = np.empty(n)
    d = np.empty(n)
    buf = np.empty(n)
    med = 0.0
    mad = 0.0
    for it in range(n_iter):
        _resid(X, y, coef, r)
        if n == 0:
            sigma = math.nan
            break
        med = median_near(r, med, 0.05 * mad if it else 0.0, buf)
        for i in range(n):
            d[i] = abs(r[i] - med)
        mad = median_near(d, mad, 0.05 * mad if it else 0.0, buf)
        sigma = 1.4826 * mad
        if not sigma > 0:
            break
        c = tuning * sigma
        for i in range(n):
            u = r[i] / c
            w[i] = (1.0 - u * u) ** 2 if abs(u) < 1.0 else 0.0
        new, ok = _wls_small(X, y, w)
        if not ok:
            return coef, sigma, 0.0, False
        moved = 0.0
        for j in range(p):
            moved += abs(new[j] - coef[j])
        coef = new
        if moved < 1e-4 * sigma:
            break
    _resid(X, y, coef, r)
    ssr = 0.0
    for i in range(n):
        e = r[i]
        ssr += w[i] * e * e
    return coef, sigma, ssr, True


@njit(cache=True)
def lstsq_qr(A, b, rcond=1e-5):
    """Least squares ``min |A x - b|`` by Householder QR (``n x m``, a few columns; ``A`` and ``b``
    are not changed): ``(x, ok)``; ``ok`` False when a diagonal element of R is under ``rcond``
    times the largest (ill-conditioned or rank-deficient: the caller then uses
    ``np.linalg.lstsq``, whose truncated answer this does not give; within the bound the two
    agree to about ``n eps / rcond``).

    As accurate as LAPACK's SVD solver for a full-rank ``A`` (both backward stable), without the
    ~30 us of its Python wrapper: the analysis fits 2-4 columns to a few hundred samples dozens of
    times a curve (issue 35)."""
    n, m = A.shape
    R = A.copy()
    c = b.copy()
    x = np.full(m, np.nan)
    if n < m:
        return x, False
    diag = np.empty(m)
    for k in range(m):
        s = 0.0
        for i in range(k, n):
            s += R[i, k] * R[i, k]
        nrm = math.sqrt(s)
        if nrm == 0.0:
            return x, False
        alpha = -nrm if R[k, k] >= 0 else nrm
        v0 = R[k, k] - alpha
        vv = v0 * v0 + s - R[k, k] * R[k, k]  # |v|^2 with v = (v0, R[k+1:, k])
        if vv > 0.0:
            for j in range(k + 1, m):
                d = v0 * R[k, j]
                for i in range(k + 1, n):
                    d += R[i, k] * R[i, j]
                f = 2.0 * d / vv
                R[k, j] -= f * v0
                for i in range(k + 1, n):
                    R[i, j] -= f * R[i, k]
            d = v0 * c[k]
            for i in range(k + 1, n):
                d += R[i, k] * c[i]
            f = 2.0 * d / vv
            c[k] -= f * v0
            for i in range(k + 1, n):
                c[i] -= f * R[i, k]
        diag[k] = alpha
    big = 0.0
    for k in range(m):
        big = max(big, abs(diag[k]))
    for k in range(m):
        if not abs(diag[k]) > rcond * big:
            return x, False
    for k in range(m - 1, -1, -1):
        s = c[k]
        for j in range(k + 1, m):
            s -= R[k, j] * x[j]
        x[k] = s / diag[k]
    return x, True


@njit(cache=True)
def _polyfit_qr(x, y, deg):
    n = x.size
    V = np.empty((n, deg + 1))
    for i in range(n):
        p = 1.0
        for j in range(deg, -1, -1):  # highest power first, as np.polyfit
            V[i, j] = p
            p *= x[i]
    scale = np.empty(deg + 1)
    for j in range(deg + 1):
        s = 0.0
        for i in range(n):
            s += V[i, j] * V[i, j]
        scale[j] = math.sqrt(s)
        if scale[j] == 0.0:
            return np.full(deg + 1, np.nan), False
        for i in range(n):
            V[i, j] /= scale[j]
    c, ok = lstsq_qr(V, y, 1e-5)
    for j in range(deg + 1):
        c[j] /= scale[j]
    return c, ok


def polyfit(x: np.ndarray, y: np.ndarray, deg: int) -> np.ndarray:
    """``np.polyfit(x, y, deg)`` (coefficients, highest power first) by :func:`lstsq_qr` on the same
    column-scaled Vandermonde matrix; ``np.polyfit`` itself when that is rank-deficient, or the
    samples are not finite. Equal to it to rounding (backward-stable solvers of one problem), about
    ten times faster for the few hundred samples of a baseline or a contact region."""
    x = np.ascontiguousarray(x, dtype=float)
    y = np.ascontiguousarray(y, dtype=float)
    if x.ndim == 1 and y.ndim == 1 and x.size == y.size and x.size > deg:
        c, ok = _polyfit_qr(x, y, int(deg))
        if ok and np.isfinite(c).all():
            return c
    return np.polyfit(x, y, deg)


def ptp(a) -> np.ndarray:
    """``np.ptp(a)`` (of the whole array) as ``a.max() - a.min()``: the same number, without the ~5 us
    of its wrappers (a curve's analysis takes some eighty)."""
    a = np.asarray(a)
    return a.max() - a.min()
