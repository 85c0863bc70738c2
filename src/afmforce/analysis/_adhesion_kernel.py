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

from ._glue_kernel import BRACKET, middle_bracket
from ._numeric import mad_sigma
from ._oscillation_kernel import _running_median_nearest

__all__ = ["adhesion_core", "running_median_nearest"]


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
