"""Compiled kernels of the ``kind`` step: the soft contact point and the contact's curvature (issue 35).

One call per fit instead of ~60 numpy calls (each 1-5 us of overhead). They compute the numbers of
:func:`~afmforce.analysis.contact_point.soft_contact_point` and
:func:`~afmforce.analysis.contact_point.curvature_ratio` with the same operations in the same order:
means by numpy's pairwise summation (:func:`pairwise_sum`), grids as ``np.linspace`` builds them,
the normal equations of each candidate summed over the samples in the same order.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._numeric import _polyfit_qr

__all__ = ["pairwise_sum", "block_mean", "linspace", "fit_grid", "soft_contact_kernel", "curvature_kernel"]


@njit(cache=True)
def _leaf_sum(a, lo, n):
    """numpy's pairwise summation of at most 128 values: 8 running partial sums (sequential below 8)."""
    if n < 8:
        res = -0.0  # numpy starts a short run at -0.0 (a sum of -0.0 values stays -0.0)
        for i in range(lo, lo + n):
            res += a[i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = 8
    end = n - n % 8
    while i < end:
        j = lo + i
        r0 += a[j]
        r1 += a[j + 1]
        r2 += a[j + 2]
        r3 += a[j + 3]
        r4 += a[j + 4]
        r5 += a[j + 5]
        r6 += a[j + 6]
        r7 += a[j + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


@njit(cache=True)
def pairwise_sum(a, lo, n):
    """``np.sum(a[lo:lo + n])`` of a float64 array, bit for bit: numpy's pairwise summation (blocks of
    at most 128 summed by 8 running partial sums, longer runs halved at a multiple of 8, the halves
    added left + right). Without recursion (numba's cache cannot load a recursive kernel called from
    another module): the halving tree walked with an explicit stack."""
    if n <= 128:
        return _leaf_sum(a, lo, n)
    s_lo = np.empty(64, np.int64)
    s_n = np.empty(64, np.int64)
    s_state = np.empty(64, np.int64)
    vals = np.empty(64)
    sp = 0
    nv = 0
    s_lo[0], s_n[0], s_state[0] = lo, n, 0
    sp = 1
    while sp > 0:
        t = sp - 1
        l, m = s_lo[t], s_n[t]
        if m <= 128:
            vals[nv] = _leaf_sum(a, l, m)
            nv += 1
            sp -= 1
            continue
        n2 = m // 2
        n2 -= n2 % 8
        if s_state[t] == 0:
            s_state[t] = 1
            s_lo[sp], s_n[sp], s_state[sp] = l, n2, 0
            sp += 1
        elif s_state[t] == 1:
            s_state[t] = 2
            s_lo[sp], s_n[sp], s_state[sp] = l + n2, m - n2, 0
            sp += 1
        else:
            vals[nv - 2] = vals[nv - 2] + vals[nv - 1]
            nv -= 1
            sp -= 1
    return vals[0]


@njit(cache=True)
def block_mean(x, n):
    """``contact_point._block``: ``x`` averaged in blocks of ``x.size // n`` samples (``x`` itself when
    that is at most 1), as ``x[:k * m].reshape(k, m).mean(1)`` computes it."""
    m = x.size // n
    if m <= 1:
        return x
    k = x.size // m
    out = np.empty(k)
    for r in range(k):
        out[r] = pairwise_sum(x, r * m, m) / m
    return out


@njit(cache=True)
def linspace(start, stop, num):
    """``np.linspace(start, stop, num)`` (``num >= 2``), bit for bit: ``i * step + start``, the last ``stop``."""
    out = np.empty(num)
    step = (stop - start) / (num - 1)
    for i in range(num):
        out[i] = i * step + start
    out[num - 1] = stop
    return out


@njit(cache=True)
def _argmin(a):
    """``np.argmin``: the first smallest (the first NaN if any)."""
    j = 0
    for i in range(a.size):
        if math.isnan(a[i]):
            return i
        if a[i] < a[j]:
            j = i
    return j


@njit(cache=True)
def _argmax(a):
    """``np.argmax``: the first largest (the first NaN if any)."""
    j = 0
    for i in range(a.size):
        if math.isnan(a[i]):
            return i
        if a[i] > a[j]:
            j = i
    return j


@njit(cache=True)
def _accumulate_175(xi, yi, cands, top, sg, sgg, sxg, syg):
    """The terms of sample ``(xi, yi)`` for the candidates ``cands[:top]`` (all below ``xi``), ``p = 1.75``:
    ``u ** 1.75`` by square roots (a few times faster than pow; equal to ~1 ulp), no branch (SIMD)."""
    for k in range(top):
        u = xi - cands[k]
        r = math.sqrt(u)
        g = u * r * math.sqrt(r)
        sg[k] += g
        sgg[k] += g * g
        sxg[k] += g * xi
        syg[k] += g * yi


@njit(cache=True)
def fit_grid(x, y, cands, exponent):
    """``contact_point._fit_grid``: least squares of ``y = a + b x + c (x - x_c)_+^p`` for each candidate
    ``x_c``; coefficients and residual sums (infinite where c <= 0).

    The sums of each candidate run over the samples in time order, as there, but the candidates are the
    inner loop (all those below ``x[i]``: a prefix of the ascending grid), so the power terms of
    neighbouring candidates are computed together."""
    n = x.size
    nc = cands.size
    sx = sxx = sy = sxy = syy = 0.0
    for i in range(n):
        sx += x[i]
        sxx += x[i] * x[i]
        sy += y[i]
        sxy += x[i] * y[i]
        syy += y[i] * y[i]
    kind = 1 if exponent == 1.75 else 2 if exponent == 1.5 else 0
    ascending = True
    for k in range(1, nc):
        if not cands[k] >= cands[k - 1]:
            ascending = False
    sg = np.zeros(nc)
    sgg = np.zeros(nc)
    sxg = np.zeros(nc)
    syg = np.zeros(nc)
    for i in range(n):
        xi, yi = x[i], y[i]
        if ascending and kind == 1:  # the candidates below x[i] (u > 0 exactly there), vectorised
            if xi == xi:  # NaN: u > 0 nowhere
                _accumulate_175(xi, yi, cands, np.searchsorted(cands, xi), sg, sgg, sxg, syg)
            continue
        top = np.searchsorted(cands, xi) if ascending else nc
        for k in range(top):
            u = xi - cands[k]
            if u > 0.0:
                if kind == 1:
                    r = math.sqrt(u)
                    g = u * r * math.sqrt(r)
                elif kind == 2:
                    g = u * math.sqrt(u)
                else:
                    g = u ** exponent
                sg[k] += g
                sgg[k] += g * g
                sxg[k] += g * xi
                syg[k] += g * yi
    coef = np.empty((nc, 3))
    rss = np.empty(nc)
    m = np.empty((3, 3))
    v = np.empty(3)
    c = np.empty(3)
    for k in range(nc):
        m[0, 0], m[0, 1], m[0, 2] = n + 1e-12, sx, sg[k]
        m[1, 0], m[1, 1], m[1, 2] = sx, sxx + 1e-12, sxg[k]
        m[2, 0], m[2, 1], m[2, 2] = sg[k], sxg[k], sgg[k] + 1e-12
        v[0], v[1], v[2] = sy, sxy, syg[k]
        _solve3(m, v, c)
        coef[k, 0], coef[k, 1], coef[k, 2] = c[0], c[1], c[2]
        r = syy - (c[0] * sy + c[1] * sxy + c[2] * syg[k])
        rss[k] = r if c[2] > 0 else np.inf
    return coef, rss


@njit(cache=True)
def _solve3(m, v, out):
    """``out = solve(m, v)`` for 3 x 3 (``m``, ``v`` overwritten) as LAPACK's ``dgesv`` does it: LU with
    partial pivoting, the column scaled by the pivot's reciprocal, then the two triangular solves; NaN
    for a zero pivot (singular). Without the allocations and the ~1.5 us a call of ``np.linalg.solve``
    (the last bits can differ from an optimised LAPACK's fused multiply-adds: ~1e-12 relative on these
    systems, the fits' candidates differ by 1e-7 and more)."""
    for col in range(3):
        p = col
        for r in range(col + 1, 3):
            if abs(m[r, col]) > abs(m[p, col]):
                p = r
        if m[p, col] == 0.0:
            out[0] = out[1] = out[2] = np.nan
            return
        if p != col:
            for k in range(3):
                m[col, k], m[p, k] = m[p, k], m[col, k]
            v[col], v[p] = v[p], v[col]
        inv = 1.0 / m[col, col]
        for r in range(col + 1, 3):
            m[r, col] *= inv
        for r in range(col + 1, 3):
            for k in range(col + 1, 3):
                m[r, k] -= m[r, col] * m[col, k]
    for col in range(3):
        for r in range(col + 1, 3):
            v[r] -= v[col] * m[r, col]
    for col in range(2, -1, -1):
        v[col] /= m[col, col]
        for r in range(col):
            v[r] -= v[col] * m[r, col]
    out[0], out[1], out[2] = v[0], v[1], v[2]


@njit(cache=True)
def soft_contact_kernel(zi, di, exponent, force_fraction, window, grid, max_points):
    """The numbers of :func:`~afmforce.analysis.contact_point.soft_contact_point` for the approach's
    samples ``zi``, ``di`` (time order): ``[k, position, deflection, initial_position, indentation,
    position_low, position_high]`` with ``k`` the run's sample at the contact (-1: no contact point)."""
    out = np.full(7, np.nan)
    out[0] = -1.0
    n = zi.size
    m = max(n // max_points, 1)
    if m > 1:
        jb = _argmax(block_mean(di, max_points))
        imax = min((jb + 1) * m - 1, n - 1)
    else:
        imax = _argmax(di)
    if imax < 8:
        return out
    zb = block_mean(zi[: imax + 1], max_points)
    db = block_mean(di[: imax + 1], max_points)
    dmin, dmax = db.min(), db.max()
    rng = dmax - dmin
    cut = db.size
    thr = force_fraction * rng
    for i in range(db.size):
        if db[i] - dmin > thr:
            if i > 8:
                cut = i + 1
            break
    nb = cut
    span = zb[nb - 1] - zb[0] if nb > 1 else 0.0
    if not span > 0 or nb < 8:
        return out
    dmin = db[:nb].min()
    rng = db[:nb].max() - dmin
    scale = max(rng, 1e-300)
    x = np.empty(nb)
    y = np.empty(nb)
    for i in range(nb):
        x[i] = (zb[i] - zb[0]) / span
        y[i] = (db[i] - dmin) / scale
    straight = linspace(0.0, 1.0, nb)
    x_init = x[_argmin(y - straight)]
    coarse = linspace(max(x_init - window, 0.0), min(x_init + window, 1.0), grid)
    _, coarse_rss = fit_grid(x, y, coarse, exponent)
    j = _argmin(coarse_rss)
    step = coarse[1] - coarse[0]  # refine: a finer grid over the neighbouring cells
    cands = linspace(max(coarse[j] - step, 0.0), min(coarse[j] + step, 1.0), np.int64(41))
    coef, rss = fit_grid(x, y, cands, exponent)
    j = _argmin(rss)
    zc = zb[0] + cands[j] * span
    s2 = rss[j] / max(nb - 4, 1)  # 4 parameters: a, b, c, z_c
    lim = rss[j] + 4.0 * s2
    lo, hi, found = np.inf, -np.inf, False
    for i in range(grid):
        if coarse_rss[i] <= lim:
            found = True
            lo = min(lo, coarse[i])
            hi = max(hi, coarse[i])
    low = zb[0] + min(lo, cands[j]) * span if found else zc
    high = zb[0] + max(hi, cands[j]) * span if found else zc
    nr = imax + 1
    rising = True
    for i in range(nr - 1):
        if not zi[i + 1] - zi[i] >= 0:
            rising = False
            break
    if rising:  # np.searchsorted(zr, zc): the first sample at or beyond zc
        k = nr
        for i in range(nr):
            if zi[i] >= zc:
                k = i
                break
    else:
        k = _argmin(np.abs(zi[:nr] - zc))
    k = min(max(k - 1, 0), nr - 1)
    d_c = dmin + (coef[j, 0] + coef[j, 1] * cands[j]) * rng
    out[0] = k
    out[1] = zc
    out[2] = d_c
    out[3] = zb[0] + x_init * span
    out[4] = (zi[imax] - zc) - (di[imax] - d_c)
    out[5] = min(low, high)
    out[6] = max(low, high)
    return out


@njit(cache=True)
def _slope_fit(z, d, order, lo, hi):
    """``contact_point._slope`` of the samples ``order[lo:hi]``: NaN (fewer than 3, no spread); -inf when
    the compiled polyfit refused (the caller then computes it with ``np.polyfit``)."""
    n = hi - lo
    xs = np.empty(n)
    ys = np.empty(n)
    for i in range(n):
        xs[i] = z[order[lo + i]]
        ys[i] = d[order[lo + i]]
    if n < 3 or xs.max() - xs.min() == 0:
        return np.nan
    xm = pairwise_sum(xs, np.int64(0), n) / n
    for i in range(n):
        xs[i] = xs[i] - xm
    c, ok = _polyfit_qr(xs, ys, np.int64(1))
    if not (ok and math.isfinite(c[0]) and math.isfinite(c[1])):
        return -np.inf
    return c[0]


@njit(cache=True)
def curvature_kernel(z, d, contact):
    """Early and late slopes of :func:`~afmforce.analysis.contact_point.curvature_ratio` (its thirds
    of the contact samples in the order of position, ties in time order); -inf: the caller's polyfit."""
    order = contact[np.argsort(z[contact], kind="mergesort")]
    n3 = order.size // 3
    return _slope_fit(z, d, order, np.int64(0), n3), _slope_fit(z, d, order, order.size - n3, order.size)
