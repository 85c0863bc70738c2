"""Compiled kernels of the ``contact`` step (issue 35): a run's regions, the saturated samples, a region's
robust slope, one call each instead of dozens of numpy calls.

They compute the numbers of :mod:`afmforce.analysis.regions` with the same operations in the same order
(numpy's pairwise means, the thinning of :func:`~._numeric.robust_line_thin`, the compiled line fits of
:mod:`._numeric`). One exception: the surface-force test takes logarithms with the C library's ``log``,
which differs from numpy's vectorised one by one ulp on about 1e-4 of the values; the test compares
fitted slopes with thresholds, so it cannot flip on a rounding but at an exact tie.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._contact_kernel import pairwise_sum
from ._numeric import _polyfit_qr, mad_sigma, robust_line, two_line_split

__all__ = ["run_index", "saturated_kernel", "thin_robust_line", "region_slope", "run_regions_kernel"]

#: status of :func:`run_regions_kernel`: the regions found (0); anything else: the caller's numpy path
#: (an error to raise with its message, or a fit the compiled solver refused)
OK, FALLBACK = 0, 1


@njit(cache=True)
def run_index(segment, which):
    """``np.flatnonzero(segment == which)``."""
    n = 0
    for i in range(segment.size):
        if segment[i] == which:
            n += 1
    out = np.empty(n, np.int64)
    n = 0
    for i in range(segment.size):
        if segment[i] == which:
            out[n] = i
            n += 1
    return out


@njit(cache=True)
def saturated_kernel(signal, min_run):
    """``regions.saturated_mask``: samples equal to the maximum (or the minimum) when at least ``min_run``
    share that value."""
    out = np.zeros(signal.size, np.bool_)
    if signal.size == 0:
        return out
    for which in range(2):
        ext = signal.max() if which == 0 else signal.min()
        hits = 0
        for i in range(signal.size):
            if signal[i] == ext:
                hits += 1
        if hits >= min_run:
            for i in range(signal.size):
                if signal[i] == ext:
                    out[i] = True
    return out


@njit(cache=True)
def thin_robust_line(x, y, max_points):
    """:func:`~._numeric.robust_line_thin`: :func:`~._numeric.robust_line` on at most ``max_points`` samples
    picked as ``np.linspace(0, n - 1, max_points).astype(np.int64)`` picks them."""
    n = x.size
    if n > max_points:
        step = (n - 1.0) / (max_points - 1)
        xs = np.empty(max_points)
        ys = np.empty(max_points)
        for i in range(max_points):
            k = n - 1 if i == max_points - 1 else int(i * step)
            xs[i] = x[k]
            ys[i] = y[k]
        return robust_line(xs, ys)
    return robust_line(x, y)


@njit(cache=True)
def _gather(a, idx):
    out = np.empty(idx.size)
    for i in range(idx.size):
        out[i] = a[idx[i]]
    return out


@njit(cache=True)
def _slope(x, y):
    """``regions._slope``: robust slope of ``y`` on ``x - mean(x)`` (NaN: fewer than 3, no spread)."""
    n = x.size
    if n < 3 or x.max() - x.min() == 0:
        return np.nan
    xm = pairwise_sum(x, np.int64(0), n) / n
    return thin_robust_line(x - xm, y, np.int64(4001))[1]


@njit(cache=True)
def region_slope(z, s, index, region, saturated):
    """``regions._region_slope``: the robust slope of the samples ``index[region & ~saturated]``."""
    m = 0
    for i in range(index.size):
        if region[i] and not saturated[i]:
            m += 1
    idx = np.empty(m, np.int64)
    m = 0
    for i in range(index.size):
        if region[i] and not saturated[i]:
            idx[m] = index[i]
            m += 1
    return _slope(_gather(z, idx), _gather(s, idx))


@njit(cache=True)
def _polyslope(x, y):
    """``polyfit(x, y, 1)[0]`` by the compiled solver; NaN and False when it refused."""
    c, ok = _polyfit_qr(x, y, np.int64(1))
    if not (ok and math.isfinite(c[0]) and math.isfinite(c[1])):
        return np.nan, False
    return c[0], True


@njit(cache=True)
def _surface_force_like(z, rise, z_split, sigma, min_nsigma, decay_lo, decay_hi, min_ratio):
    """``regions._surface_force_like`` (logarithms by the C library): ``(like, ok)``; ``ok`` False when a
    compiled line fit refused (the caller's numpy path decides)."""
    if not sigma > 0:
        return False, True
    d = z_split - pairwise_sum(z, np.int64(0), z.size) / z.size
    toward = 1.0 if d > 0 else -1.0 if d < 0 else 1.0 if d == 0 else np.nan
    m = 0
    for i in range(z.size):
        if rise[i] > min_nsigma * sigma:
            m += 1
    x = np.empty(m)
    y = np.empty(m)
    m = 0
    for i in range(z.size):
        if rise[i] > min_nsigma * sigma:
            x[m] = (z[i] - z_split) * toward
            y[m] = math.log(rise[i])
            m += 1
    if m < 6 or x.max() - x.min() == 0:
        return False, True
    mid = 0.5 * (x.min() + x.max())
    nf = 0
    for i in range(m):
        if x[i] <= mid:
            nf += 1
    nn = m - nf
    if nf < 3 or nn < 3:
        return False, True
    xf, yf, xn, yn = np.empty(nf), np.empty(nf), np.empty(nn), np.empty(nn)
    a = b = 0
    for i in range(m):
        if x[i] <= mid:
            xf[a], yf[a] = x[i], y[i]
            a += 1
        elif x[i] > mid:
            xn[b], yn[b] = x[i], y[i]
            b += 1
    if xf.max() - xf.min() == 0 or xn.max() - xn.min() == 0:
        return False, True
    s_far, ok1 = _polyslope(xf, yf)
    s_near, ok2 = _polyslope(xn, yn)
    if not (ok1 and ok2):
        return False, False
    return (1.0 / decay_hi <= s_far <= 1.0 / decay_lo and s_near >= min_ratio * s_far), True


@njit(cache=True)
def _repulsive_onset(zr, sr, far, zero_force, split, sigma, consts):
    """``regions._repulsive_onset``: ``(onset, ok)``; ``ok`` False: the caller's numpy path decides."""
    onset_nsigma, max_onset_ratio, jump_nsigma, min_nsigma, decay_lo, decay_hi, min_ratio = consts
    nb = 0
    for i in range(far.size):
        if zero_force[far[i]]:
            nb += 1
    if nb < 3 or split < 1 or far.size < 3:
        return split, True
    zb = np.empty(nb)
    sb = np.empty(nb)
    nb = 0
    for i in range(far.size):
        if zero_force[far[i]]:
            zb[nb] = zr[far[i]]
            sb[nb] = sr[far[i]]
            nb += 1
    x0 = pairwise_sum(zb, np.int64(0), zb.size) / nb  # zb.size: nb counted from a literal 0 compiled another copy
    a, b, _, _, _, _ = thin_robust_line(zb - x0, sb, np.int64(4001))
    if not (np.isfinite(a) and np.isfinite(b)):
        return split, True
    nf = 0
    for i in range(far.size):
        if far[i] < split:
            nf += 1
    free = np.empty(nf, np.int64)
    nf = 0
    for i in range(far.size):
        if far[i] < split:
            free[nf] = far[i]
            nf += 1
    free = np.sort(free)
    res = np.empty(nf)
    for i in range(nf):
        res[i] = sr[free[i]] - (a + b * (zr[free[i]] - x0))
    if nf == 0 or free[nf - 1] != split - 1 or not res[nf - 1] > onset_nsigma * sigma:
        return split, True
    last = -1
    for i in range(nf):
        if res[i] <= 0:
            last = i
    if last < 0:
        return split, True
    onset = free[last + 1]
    steep = 0.0
    if split < zr.size:
        steep = zr[split:].max() - zr[split:].min()
    if abs(zr[split] - zr[onset]) > max_onset_ratio * steep:  # a slow rise, not a curved onset
        return split, True
    at_split = sr[split] - (a + b * (zr[split] - x0))
    top = res[max(nf - 4, 0):].max()
    if top - at_split > jump_nsigma * sigma:  # a jump into contact ends it
        return split, True
    width = abs(zr[split] - zr[onset])
    nw = 0
    for i in range(nf):
        if abs(zr[free[i]] - zr[split]) <= 2.0 * width:
            nw += 1
    zw = np.empty(nw)
    rw = np.empty(nw)
    nw = 0
    for i in range(nf):
        if abs(zr[free[i]] - zr[split]) <= 2.0 * width:
            zw[nw] = zr[free[i]]
            rw[nw] = res[i]
            nw += 1
    like, ok = _surface_force_like(zw, rw, zr[split], sigma, min_nsigma, decay_lo, decay_hi, min_ratio)
    if not ok:
        return split, False
    return (split if like else onset), True


@njit(cache=True)
def run_regions_kernel(z, s, index, saturated, approach, min_points, baseline_fraction, compliance_fraction,
                       min_contrast, noise, consts):
    """``regions.find_run_regions`` where it finds the regions: ``(status, split, contact, zero_force,
    compliance, saturated, noise)`` over the run's samples; ``status`` :data:`FALLBACK` where it raises
    or a compiled fit refused (the caller then runs the numpy path)."""
    n = index.size
    empty = np.zeros(0, np.bool_)
    if n < 2 * min_points + 2:
        return FALLBACK, 0, empty, empty, empty, empty, 0.0
    zr = _gather(z, index)
    sr = _gather(s, index)
    sat = np.empty(n, np.bool_)
    nok = 0
    for i in range(n):
        sat[i] = saturated[index[i]]
        if not sat[i]:
            nok += 1
    if sr.max() - sr.min() == 0 or nok < 2 * min_points:
        return FALLBACK, 0, empty, empty, empty, empty, 0.0
    order = np.empty(nok, np.int64)
    j = 0
    for i in range(n):
        if not sat[i]:
            order[j] = i
            j += 1
    if not approach:
        order = order[::-1].copy()
    so = _gather(sr, order)
    if so.max() - so.min() == 0:
        return FALLBACK, 0, empty, empty, empty, empty, 0.0
    k = two_line_split(_gather(zr, order), so, min_points)
    if k < 0:
        return FALLBACK, 0, empty, empty, empty, empty, 0.0
    far, near = order[:k], order[k:]
    own = 0.0
    if far.size > 2:
        df = np.empty(far.size - 1)
        for i in range(far.size - 1):
            df[i] = sr[far[i + 1]] - sr[far[i]]
        own = mad_sigma(df) / np.sqrt(2.0)
    sigma = own if not np.isfinite(noise) else min(own, noise)
    span = 0.0
    if near.size:
        sn = _gather(sr, near)
        span = sn.max() - sn.min()
    if not (span > min_contrast * max(sigma, 1e-300)) or near.size < min_points:
        return FALLBACK, 0, empty, empty, empty, empty, 0.0
    split = near.min() if approach else far.min()
    contact = np.zeros(n, np.bool_)
    for i in near:
        contact[i] = True
    zero_force = np.zeros(n, np.bool_)
    zfar = _gather(zr, far)
    z_lo, z_hi = zfar.min(), zfar.max()
    lim = z_lo + baseline_fraction * (z_hi - z_lo)
    cnt = 0
    for i in range(far.size):
        if zfar[i] <= lim:
            zero_force[far[i]] = True
    for i in range(n):
        if zero_force[i]:
            cnt += 1
    if cnt < min_points:
        for i in far:
            zero_force[i] = True
    compliance = np.zeros(n, np.bool_)
    znear = _gather(zr, near)
    z_top = znear.max()
    lim = z_top - compliance_fraction * (z_top - znear.min())
    for i in range(near.size):
        if znear[i] >= lim:
            compliance[near[i]] = True
    cnt = 0
    for i in range(n):
        if compliance[i]:
            cnt += 1
    if cnt < min_points:
        for i in near:
            compliance[i] = True
    if approach:  # a curved (repulsive) contact onset the two lines left on the free side
        sigma = own
        if not sigma > 0:  # a quiet signal on a coarse ADC: the quantisation's noise (step / sqrt 12)
            smallest = np.inf
            for i in range(far.size - 1):
                st = abs(sr[far[i + 1]] - sr[far[i]])
                if st > 0:
                    smallest = min(smallest, st)
            sigma = smallest / np.sqrt(12.0) if smallest < np.inf else 1e-300
        onset, ok = _repulsive_onset(zr, sr, far, zero_force, split, sigma, consts)
        if not ok:
            return FALLBACK, 0, empty, empty, empty, empty, 0.0
        if onset < split:
            for i in far:
                if i >= onset:
                    contact[i] = True
                    zero_force[i] = False
            split = onset
    return OK, split, contact, zero_force, compliance, sat, own
