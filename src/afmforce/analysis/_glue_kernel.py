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

__all__ = ["span_stats", "median_abs_step", "first_below", "glitch_scan", "orient_scan", "robust_line_ab", "middle_bracket", "COMPILED", "BRACKET"]


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


@njit(cache=True, nogil=True)
def orient_scan(seg, t, z, s, check_time: bool, min_block: int, min_run: int, end_samples: int, jump_steps: float):
    """Whether :func:`~afmforce.analysis.orientation.orient` leaves a curve as it is, without a note, at its
    conventions' test (the readers' curves), and what :func:`~afmforce.analysis.state.prepare` reads off it,
    in one pass over the samples instead of some thirty numpy calls (issue 35 item 2).

    ``seg`` the segment labels, ``t`` the times (read only with ``check_time``), ``z`` the position of the
    channel the analysis reads, ``s`` the deflection signal. Returns ``(plain, a0, a1, r0, r1, span_a,
    span_r, sign_ok)``. ``plain`` True says, for every curve it is True on, what ``orient`` finds by its own
    steps: one block of each run label among the blocks of ``min_block`` samples or more (one cycle), the
    approach (label 0, samples ``a0 .. a1 - 1``) and the retract (label 1, ``r0 .. r1 - 1``) each one
    contiguous block of ``min_run`` samples or more, no run whose time falls at its start (a backwards run
    needs that), every position and signal sample finite, both runs' position spans (``span_a``, ``span_r``:
    ``ptp``, exact) above zero, no position step among a run's first or last ``end_samples`` steps above
    ``jump_steps`` times the run's median step (shown without the median: at least the median's share of the
    steps are ``jump_steps`` times as large as the largest end step, so the median is too; rounding is
    monotone), and the position rising over the approach and falling over the retract by the medians of each
    run's first and last tenth (shown without the medians: every sample of the later tenth beyond every
    sample of the earlier one). False says only that the scan could not show it (the caller runs ``orient``).
    ``sign_ok`` True says :func:`~afmforce.analysis.state._check_sign` finds nothing on ``s``: its tail (the
    median of the approach's last ``max(3, n // 50)`` samples) or the retract's start (the median of its first
    ``max(3, m // 50)``) is not below the baseline (the median of the approach's first ``max(5, n // 3)``),
    every sample of it being at least as large as every baseline sample."""
    n = seg.size
    bad = (False, 0, 0, 0, 0, 0.0, 0.0, False)
    if t.size != n or z.size != n or s.size != n or n == 0:
        return bad
    blocks0 = 0
    blocks1 = 0
    count0 = 0
    count1 = 0
    a0 = -1
    a1 = -1
    r0 = -1
    r1 = -1
    start = 0
    for i in range(1, n + 1):
        if i == n or seg[i] != seg[i - 1]:
            lab = seg[start]
            if lab == 0:
                count0 += i - start
                if a0 < 0:
                    a0 = start
                a1 = i
                if i - start >= min_block:
                    blocks0 += 1
            elif lab == 1:
                count1 += i - start
                if r0 < 0:
                    r0 = start
                r1 = i
                if i - start >= min_block:
                    blocks1 += 1
            start = i
    if blocks0 > 1 or blocks1 > 1 or count0 < min_run or count1 < min_run:
        return bad
    if a1 - a0 != count0 or r1 - r0 != count1:  # a run split by other labels: orient's own path
        return bad
    if check_time and (t[a0 + 1] - t[a0] < 0.0 or t[r0 + 1] - t[r0] < 0.0):
        return bad
    for i in range(n):
        if not (np.isfinite(z[i]) and np.isfinite(s[i])):
            return bad
    spans = np.empty(2)
    for part in range(2):
        lo, hi = (a0, a1) if part == 0 else (r0, r1)
        zmin = z[lo]
        zmax = z[lo]
        for i in range(lo + 1, hi):
            v = z[i]
            if v < zmin:
                zmin = v
            if v > zmax:
                zmax = v
        spans[part] = zmax - zmin
        if not spans[part] > 0.0:
            return bad
        m = hi - lo
        if m >= 4 * end_samples + 4:  # orient's end jumps: the runs it looks at
            big = 0.0
            for j in range(end_samples):
                big = max(big, abs(z[lo + j + 1] - z[lo + j]), abs(z[hi - 1 - j] - z[hi - 2 - j]))
            if big > 0.0:
                steps = m - 1
                count = 0
                for i in range(lo, hi - 1):
                    if jump_steps * abs(z[i + 1] - z[i]) >= big:
                        count += 1
                h = steps // 2
                if count < (steps - h if steps % 2 else steps - h + 1):
                    return bad
        k = max(1, m // 10)
        first_lo = z[lo]
        first_hi = z[lo]
        for i in range(lo, lo + k):
            first_lo = min(first_lo, z[i])
            first_hi = max(first_hi, z[i])
        last_lo = z[hi - 1]
        last_hi = z[hi - 1]
        for i in range(hi - k, hi):
            last_lo = min(last_lo, z[i])
            last_hi = max(last_hi, z[i])
        if part == 0 and not last_lo > first_hi:  # the approach rises
            return bad
        if part == 1 and not last_hi < first_lo:  # the retract falls
            return bad
    na = a1 - a0
    head = max(5, na // 3)
    base_hi = s[a0]
    for i in range(a0, a0 + min(head, na)):
        base_hi = max(base_hi, s[i])
    tail = max(3, na // 50)
    low = s[a1 - 1]
    for i in range(max(a1 - tail, a0), a1):
        low = min(low, s[i])
    sign_ok = low >= base_hi
    if not sign_ok:
        k2 = min(max(3, (r1 - r0) // 50), r1 - r0)
        low = s[r0]
        for i in range(r0, r0 + k2):
            low = min(low, s[i])
        sign_ok = low >= base_hi
    return True, a0, a1, r0, r1, spans[0], spans[1], sign_ok


#: The kernels run compiled (False under ``NUMBA_DISABLE_JIT``, where they are plain Python).
COMPILED = hasattr(span_stats, "py_func")
