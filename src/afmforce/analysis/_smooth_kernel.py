"""Compiled kernels of the ``smooth`` and ``compliance`` steps (issue 35): one call per curve instead of
dozens of numpy calls, with the same operations in the same order (numpy's pairwise means)."""

from __future__ import annotations

import numpy as np
from numba import njit

from ._contact_kernel import pairwise_sum
from ._numeric import robust_line, running_mean

__all__ = ["staircase_window", "smooth_runs", "compliance_line"]


@njit(cache=True)
def staircase_window(z, minimum):
    """``steps.smooth._staircase_window``: an odd window covering two digitization steps of a stepped
    position (at least ``minimum``); ``minimum`` when fewer than 30 % of the steps are zero."""
    n = z.size - 1
    same = 0
    for i in range(n):
        if z[i + 1] - z[i] == 0:
            same += 1
    if same / n < 0.3:  # no staircase (the caller: at least two samples)
        return minimum
    runs = np.empty(n)
    nr = 0
    i = 0
    while i < n:
        if z[i + 1] - z[i] == 0:
            j = i
            while j < n and z[j + 1] - z[j] == 0:
                j += 1
            runs[nr] = j - i + 1  # samples per plateau
            nr += 1
            i = j
        else:
            i += 1
    step = int(np.median(runs[:nr])) if nr else 1
    return max(minimum, 2 * step + 1)


@njit(cache=True)
def smooth_runs(z, segment, window):
    """Running mean (:func:`~._numeric.running_mean`) of ``z`` over each run (segment 0, 1, 2) separately,
    the runs' samples in time order: the smoothed copy and its largest change."""
    out = z.copy()
    idx = np.empty(z.size, np.int64)
    for which in range(3):
        m = 0
        for i in range(z.size):
            if segment[i] == which:
                idx[m] = i
                m += 1
        if m == 0:
            continue
        zr = np.empty(m)
        for i in range(m):
            zr[i] = z[idx[i]]
        sm = running_mean(zr, window)
        for i in range(m):
            out[idx[i]] = sm[i]
    change = 0.0  # np.max(np.abs(out - z)) (NaN first)
    for i in range(z.size):
        d = abs(out[i] - z[i])
        if d > change or d != d:
            change = d
            if d != d:
                break
    return out, change


@njit(cache=True)
def compliance_line(z, s, index, region, saturated):
    """``compliance._fit_line``'s numbers for the samples ``index[region & ~saturated]``: ``[n, intercept,
    slope, se of the centred intercept, slope_se, sigma, n_used, z_min, z_max, s_min, s_max, mean z]``
    (robust line of ``s`` on ``z - mean(z)``; ``n`` < 3: the rest NaN)."""
    out = np.full(12, np.nan)
    n = 0
    for i in range(index.size):
        if region[i] and not saturated[i]:
            n += 1
    out[0] = n
    if n < 3:
        return out
    x = np.empty(n)
    y = np.empty(n)
    m = 0
    for i in range(index.size):
        if region[i] and not saturated[i]:
            x[m] = z[index[i]]
            y[m] = s[index[i]]
            m += 1
    xm = pairwise_sum(x, np.int64(0), x.size) / n  # x.size: n counted from a literal 0 compiled another copy
    a, b, se_a, se_b, sigma, n_used = robust_line(x - xm, y)
    out[1] = a - b * xm
    out[2] = b
    out[3] = se_a
    out[4] = se_b
    out[5] = sigma
    out[6] = n_used
    out[7] = x.min()
    out[8] = x.max()
    out[9] = y.min()
    out[10] = y.max()
    out[11] = xm
    return out
