"""Compiled kernel of the adhesion step (:func:`~afmforce.analysis.unbinding.retract_adhesion`).

One call does what the numpy version did in some forty calls after the baseline line: the
residual about the line, its robust noise, the deepest dip, the running median of the retract
from the dip on (scipy's ``median_filter``, ``mode="nearest"``, odd window) and the unbinding steps
(runs of rises over the threshold). Every operation is the numpy version's, element by element:
medians and running medians are order statistics (exact whatever the selection algorithm), the
residual is computed with the same operations in the same order, so the numbers are identical
(tested against the numpy version, ``tests/analysis/test_adhesion_kernel.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._contact_kernel import pairwise_sum
from ._glue_kernel import BRACKET, middle_bracket
from ._numeric import _middle, mad_sigma, solve_small
from ._oscillation_kernel import _running_median_nearest

__all__ = ["adhesion_core", "running_median_nearest", "baseline_spread_core"]


@njit(cache=True, nogil=True)
def running_median_nearest(u: np.ndarray, w: int, start: int) -> np.ndarray:
    """``scipy.ndimage.median_filter(u, size=w, mode="nearest")[start:]`` for an odd ``w``: the
    median of the ``w`` samples centred on each (the ends repeated), from ``start`` on; it is
    :func:`~._oscillation_kernel._running_median_nearest` (O(log n) per sample: the window grows
    with the run, a window re-sorted per sample made long curves cubic)."""
    return _running_median_nearest(u, w, start)


@njit(cache=True, nogil=True)
def adhesion_core(x: np.ndarray, y: np.ndarray, free: np.ndarray, saturated: np.ndarray, a: float, b: float,
                  xm: float, nsigma: float, w: int, pull_off: int, hint: float = -1.0):
    """The retract's dip below the line ``a + b (x - xm)`` and its unbinding steps.

    Parameters
    ----------
    x, y : ndarray
        The retract's position from contact [m] and deflection [m].
    free, saturated : ndarray of bool
        Its baseline (free, unsaturated) samples and its clipped ones.
    a, b, xm : float
        The baseline line [m], [-] and the centre of its positions [m].
    nsigma : float
        Multiple of the noise a dip and a step must exceed [-].
    w : int
        Running-median window (odd) [samples].
    pull_off : int
        Run sample of a hard contact's pull-off jump (-1: none).
    hint : float
        The baseline residuals' median absolute deviation, about [m] (<= 0: none): where the noise's
        medians are looked for first (:func:`~._glue_kernel.middle_bracket`; the same numbers).

    Returns
    -------
    ok, sigma, j, depth, found, last, step_at, step_rise
        False when a residual is not finite (nothing else is then valid); the baseline noise [m], the deepest sample, its depth [m] (<= 0), whether it exceeds
        ``nsigma`` noise, the last sample below the threshold (-1 when not found), and the run
        samples just after each unbinding step with the step's height [m].
    """
    n = x.size
    u = np.empty(n)
    nf = 0
    step_at = np.empty(0, np.int64)
    step_rise = np.empty(0)
    for i in range(n):
        u[i] = y[i] - (a + b * (x[i] - xm))
        if not np.isfinite(u[i]):  # numpy's medians and argmin treat NaN otherwise: the caller's numpy path
            return False, np.nan, -1, np.nan, False, -1, step_at, step_rise
        if free[i]:
            nf += 1
    uf = np.empty(nf)
    q = 0
    for i in range(n):
        if free[i]:
            uf[q] = u[i]
            q += 1
    med = np.nan
    sigma = np.nan
    if hint > 0:  # the baseline fit's last MAD: the medians selected among the samples near it (exact)
        buf = np.empty(nf)
        half = nf // 2
        even = nf % 2 == 0
        lo, hi, ok = middle_bracket(uf, half, even, -BRACKET * hint, BRACKET * hint, buf)
        if ok:
            med = (lo + hi) / 2 if even else hi  # np.median
            dev = np.abs(uf - med)
            lo, hi, ok = middle_bracket(dev, half, even, (1.0 - BRACKET) * hint, (1.0 + BRACKET) * hint, buf)
            sigma = 1.4826 * ((lo + hi) / 2 if even else hi) if ok else 1.4826 * np.median(dev)
    if not med == med:  # (NaN: no hint, or the bracket missed)
        med = np.median(uf)
        sigma = 1.4826 * np.median(np.abs(uf - med))
    if not sigma > 0:
        sigma = mad_sigma(np.diff(uf)) / math.sqrt(2.0)
    j = 0
    best = np.inf
    for i in range(n):  # np.argmin(np.where(ok, u, inf)): the first deepest sample not clipped above zero
        if (not saturated[i] or u[i] < 0) and u[i] < best:
            best = u[i]
            j = i
    depth = min(u[j], 0.0)
    thr = nsigma * sigma
    found = -depth > thr
    last = -1
    if not found:
        return True, sigma, j, depth, found, last, step_at, step_rise
    us = running_median_nearest(u, w, np.int64(j))  # us[i - j] is the running median at sample i
    last = j
    for i in range(n - 1, j - 1, -1):
        if us[i - j] < -thr:
            last = i
            break
    stop = min(last + w + 1, n)
    m = stop - j  # the segment us[j:stop]
    if m <= w:
        return True, sigma, j, depth, found, last, step_at, step_rise
    nr = m - w
    rise = np.empty(nr)
    for i in range(nr):
        rise[i] = us[i + w] - us[i]
    at = np.empty(nr, np.int64)
    height = np.empty(nr)
    ns = 0
    i = 0
    while i < nr:
        if not rise[i] > thr:
            i += 1
            continue
        first = i  # a run of candidates, each within w of the previous one; g its (first) largest rise
        g = i
        prev = i
        i += 1
        while i < nr and i - prev <= w:
            if rise[i] > thr:
                if rise[i] > rise[g]:
                    g = i
                prev = i
            i += 1
        if pull_off >= 0 and j + first - w <= pull_off <= j + prev + w:
            continue  # the hard contact's pull-off jump (its tail included) ends the dip: not a step of it
        at[ns] = j + g + w
        height[ns] = rise[g]
        ns += 1
    return True, sigma, j, depth, found, last, at[:ns].copy(), height[:ns].copy()


@njit(cache=True, nogil=True)
def _poly_at(s, y, deg, at):
    """:func:`~.unbinding._lstsq_at`: the least-squares polynomial of degree ``deg`` (1 or 2) through
    ``(s, y)``, its normal equations in ``s`` less its mean (numpy's pairwise mean), read at ``at`` (NaN
    when singular). The inner products are summed in order (numpy's BLAS sums them in an order of its
    own) and the 3 x 3 system solved by :func:`~._numeric.solve_small` (LAPACK's LU in numpy): the same
    numbers to rounding."""
    n = s.size
    sm = pairwise_sum(s, np.int64(0), n) / n
    p = deg + 1
    A = np.zeros((p, p))
    r = np.zeros(p)
    a01 = a11 = a12 = a22 = r0 = r1 = r2 = 0.0
    for i in range(n):
        t = s[i] - sm
        t2 = t * t
        yi = y[i]
        a01 += t
        a11 += t2
        r0 += yi
        r1 += t * yi
        if deg == 2:
            a12 += t * t2
            a22 += t2 * t2
            r2 += t2 * yi
    A[0, 0] = float(n)
    A[0, 1] = A[1, 0] = a01
    A[1, 1] = a11
    r[0] = r0
    r[1] = r1
    if deg == 2:
        A[0, 2] = A[2, 0] = a11
        A[1, 2] = A[2, 1] = a12
        A[2, 2] = a22
        r[2] = r2
    coef = solve_small(A, r)
    d = at - sm
    out = coef[0] + coef[1] * d
    if deg == 2:
        out += coef[2] * (d * d)
    return out


@njit(cache=True, nogil=True)
def baseline_spread_core(x, y, free, a, b, xm, j, thr):
    """:func:`~.unbinding.baseline_spread` in one call: ``(spread, ok)``; ``ok`` False where a sample is
    not finite (the caller's numpy code then decides). The selections (the free samples within ``thr`` of
    the line, the far half by the median) are numpy's exactly; the two fits equal numpy's to rounding
    (:func:`_poly_at`)."""
    n = x.size
    xf = np.empty(n)
    yf = np.empty(n)
    m = 0
    for i in range(n):
        if free[i]:
            xi = x[i]
            yi = y[i]
            if not (np.isfinite(xi) and np.isfinite(yi)):
                return np.nan, False
            if abs(yi - (a + b * (xi - xm))) <= thr:
                xf[m] = xi
                yf[m] = yi
                m += 1
    xj = x[j]
    if not (np.isfinite(xj) and np.isfinite(a) and np.isfinite(b) and np.isfinite(xm)):
        return np.nan, False
    if m < 10:
        return np.nan, True
    xf = xf[:m]
    yf = yf[:m]
    c = pairwise_sum(xf, np.int64(0), m) / m
    lo = xf[0]
    hi = xf[0]
    for i in range(m):
        lo = min(lo, xf[i])
        hi = max(hi, xf[i])
    span = hi - lo
    if span == 0.0:
        span = 1.0
    s = np.empty(m)
    for i in range(m):
        s[i] = (xf[i] - c) / span
    sj = (xj - c) / span
    line = a + b * (xj - xm)
    out = np.nan
    quad = _poly_at(s, yf, np.int64(2), sj)
    if np.isfinite(quad):
        out = abs(quad - line)
    buf = xf.copy()
    half = m // 2
    even = m % 2 == 0
    lo_m, hi_m = _middle(buf, half, even)
    med = (lo_m + hi_m) / 2 if even else hi_m
    sf = np.empty(m)
    yh = np.empty(m)
    k = 0
    near = xj > c
    for i in range(m):
        if (xf[i] <= med) if near else (xf[i] >= med):
            sf[k] = s[i]
            yh[k] = yf[i]
            k += 1
    if k >= 5:
        lin = _poly_at(sf[:k], yh[:k], np.int64(1), sj)
        if np.isfinite(lin):
            d = abs(lin - line)
            out = d if not out >= d else out
    return out, True
