"""Compiled parts of the oscillation search (:func:`afmforce.analysis.oscillation.find_peak`, issue 35).

:func:`detrend` (median sample step, cubic trend removed, Hann window applied) and
:func:`band_peak` (search band, running median of the power, strongest normalised line) are the
numpy calls of ``find_peak`` written as loops over one run: the same operations in the same order
(``np.polyfit`` as :func:`~._numeric.polyfit`'s compiled QR, ``np.polyval``'s Horner scheme,
``np.fft.rfftfreq``'s grid, ``scipy.ndimage.median_filter``'s ``mode="nearest"`` window), so the
same numbers. The transform stays ``np.fft.rfft`` between the two.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._numeric import _polyfit_qr

__all__ = ["detrend", "band_peak", "median_step"]


@njit(cache=True)
def detrend(t, r, w):
    """``(dt, x w, ok)``: the median sample step [s], the residual less its cubic trend in normalised
    time, times the window ``w``; ``ok`` False when the cubic fit is ill-conditioned (the caller
    then uses numpy's), or ``dt`` is not positive."""
    n = r.size
    d = np.empty(n - 1)
    for i in range(n - 1):
        d[i] = t[i + 1] - t[i]
    dt = np.median(d)
    xw = np.empty(n)
    if not dt > 0:
        return dt, xw, False
    span = max(t[n - 1] - t[0], dt)
    tt = np.empty(n)
    for i in range(n):
        tt[i] = (t[i] - t[0]) / span
    c, ok = _polyfit_qr(tt, r, np.int64(3))
    if not ok:
        return dt, xw, False
    for j in range(4):
        if not np.isfinite(c[j]):
            return dt, xw, False
    for i in range(n):
        y = 0.0 * tt[i] + c[0]  # np.polyval: Horner from zeros
        y = y * tt[i] + c[1]
        y = y * tt[i] + c[2]
        y = y * tt[i] + c[3]
        xw[i] = (r[i] - y) * w[i]
    return dt, xw, True


@njit(cache=True)
def median_step(t, index):
    """``np.median(np.diff(t[index]))`` (the same number; NaN when a step is NaN, as numpy's) of at
    least two samples: a run's sample step when it is too short for a search."""
    m = index.size - 1
    d = np.empty(m)
    for i in range(m):
        v = t[index[i + 1]] - t[index[i]]
        if v != v:
            return np.nan
        d[i] = v
    return np.median(d)


#: :func:`_running_median_nearest` keeps a window of at most this many samples sorted (O(width) a sample,
#: without the Fenwick tree's sort of the whole record: 94 -> 7 us for the adhesion's 5-sample window on
#: 1,700 samples, 49 -> 30 us for the periodogram's 101 bins on 1,000).
SMALL_WINDOW = 128


@njit(cache=True)
def _running_median_small(p, width, start, out):
    """:func:`_running_median_nearest` of finite ``p`` into ``out``: the window's samples kept sorted, the
    sample that leaves found by value (any equal sample is the same number) and the one that enters
    inserted in place; the median is the middle of the window."""
    m = p.size
    h = width // 2
    win = np.empty(width)
    for j in range(width):  # the first window, sorted by insertion (its ends repeated)
        v = p[min(max(start + j - h, 0), m - 1)]
        k = j
        while k > 0 and win[k - 1] > v:
            win[k] = win[k - 1]
            k -= 1
        win[k] = v
    out[0] = win[h]
    for c in range(start + 1, m):
        old = p[min(max(c - 1 - h, 0), m - 1)]
        new = p[min(c + h, m - 1)]
        k = 0
        while win[k] != old:
            k += 1
        if new >= old:
            while k + 1 < width and win[k + 1] < new:
                win[k] = win[k + 1]
                k += 1
        else:
            while k > 0 and win[k - 1] > new:
                win[k] = win[k - 1]
                k -= 1
        win[k] = new
        out[c - start] = win[h]
    return out


@njit(cache=True)
def _running_median_nearest(p, width, start=0):
    """``scipy.ndimage.median_filter(p, size=width, mode="nearest")[start:]`` for odd ``width``: the
    window's samples counted by rank in a Fenwick tree, the median found as the middle rank (the
    median is one of the samples: the same number), O(log n) per sample whatever the width; a window of
    at most :data:`SMALL_WINDOW` finite samples is kept sorted instead (:func:`_running_median_small`)."""
    m = p.size
    h = width // 2
    out = np.empty(max(m - start, 0))
    if start >= m:
        return out
    if 1 <= width <= SMALL_WINDOW:
        finite = True
        for i in range(max(start - h, 0), m):
            if not np.isfinite(p[i]):
                finite = False
                break
        if finite:
            return _running_median_small(p, width, start, out)
    s0 = max(start - h, 0)  # every sample the windows touch lies in p[s0:]
    q = p[s0:]
    nq = q.size
    order = np.argsort(q)
    sv = q[order]
    rank = np.empty(nq, np.int64)
    for r in range(nq):
        rank[order[r]] = r
    tree = np.zeros(nq + 1, np.int64)
    top = 1
    while top * 2 <= nq:
        top *= 2
    for j in range(width):
        i = rank[min(max(start + j - h, 0), m - 1) - s0] + 1
        while i <= nq:
            tree[i] += 1
            i += i & -i
    for c in range(start, m):
        if c > start:  # slide: one sample leaves, one enters (ends repeated)
            i = rank[min(max(c - 1 - h, 0), m - 1) - s0] + 1
            while i <= nq:
                tree[i] -= 1
                i += i & -i
            i = rank[min(c + h, m - 1) - s0] + 1
            while i <= nq:
                tree[i] += 1
                i += i & -i
        pos = 0  # the (h + 1)-th smallest in the window
        k = h + 1
        step = top
        while step > 0:
            if pos + step <= nq and tree[pos + step] < k:
                pos += step
                k -= tree[pos]
            step //= 2
        out[c - start] = sv[pos]
    return out


@njit(cache=True)
def band_peak(spec, n, dt, min_cycles, max_nyquist_fraction):
    """The search band of the power ``spec`` (``np.fft.rfft`` of ``n`` samples ``dt`` apart) and its
    strongest line against the running median: ``(first bin, bins, index in the band, ratio)``
    (bins < 16: no search)."""
    val = 1.0 / (n * dt)
    lower = min_cycles / (n * dt)
    upper = max_nyquist_fraction * (0.5 / dt)
    k0 = -1
    count = 0
    for k in range(spec.size):
        f = k * val
        if f >= lower and f <= upper:
            if k0 < 0:
                k0 = k
            count += 1
    if count < 16:
        return k0, count, -1, 0.0
    p = spec[k0:k0 + count]
    width = max(9, 2 * (count // 20) + 1)
    local = _running_median_nearest(p, width)
    best = -1.0
    kb = 0
    for i in range(count):
        ratio = p[i] / local[i] if local[i] > 0 else p[i] / np.inf
        if ratio > best:
            best = ratio
            kb = i
    return k0, count, kb, best
