"""The drift step's per-curve work in compiled kernels (issue 35, item 2).

:func:`decide` runs :func:`~.drift.remove_drift`'s fits and choices in one call: both runs'
robust baselines (with the approach's tail regressor), the noisy retract's borrowed line, the
settling test and the retract line's model with its best settling candidate. It gives the
numbers that reach every sample bit for bit as the numpy code of :mod:`.drift` does (the same
operations in the same order; the robust fits by :func:`~._numeric.irls_bisquare`). What only
decides between models (capped residual sums, the settling test, the settling candidates'
exponentials) is computed here to rounding; the retract line's own
coefficients, which numpy's BLAS and LAPACK compute in an order of their own, are left to
:func:`~.drift.family_coef` (a handful of numpy calls). :func:`apply` subtracts the lines.

Status codes of :func:`decide`: 0 done; 1 run the numpy code instead (a singular system, a
first-order polyfit numpy would answer, a position tilt, too few samples: the rare cases).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._numeric import _polyfit_qr, solve_small
from ._numeric import irls_bisquare

__all__ = ["decide", "apply", "LINES"]

#: Line codes of :func:`decide`, as :class:`~.drift.DriftResult.retract_line` names them.
LINES = ("approach", "continuous", "separate", "offset", "approach slope", "position tilt")

_MAX_POINTS = 4001      # drift.MAX_POINTS
_SELECT_POINTS = 1000   # drift.SELECT_POINTS
_TUNING = 4.685
_N_ITER = np.int64(6)   # int64 as drift.py's calls from Python pass it: irls_bisquare compiled once


@njit(cache=True)
def _ptp(a):
    lo = a[0]
    hi = a[0]
    for v in a:
        lo = min(lo, v)
        hi = max(hi, v)
    return hi - lo


@njit(cache=True)
def _thin(n):
    """``np.linspace(0, n - 1, MAX_POINTS).astype(np.int64)`` (the same numbers)."""
    step = (n - 1) / (_MAX_POINTS - 1)
    keep = np.empty(_MAX_POINTS, np.int64)
    for i in range(_MAX_POINTS):
        keep[i] = np.int64(i * step + 0.0)
    keep[-1] = n - 1
    return keep


@njit(cache=True)
def fit_baseline(t, s, order, tail, has_tail):
    """:func:`~.drift.fit_baseline` without ``transient`` (orders 0 and 1 never use it):
    ``(offset, slope, noise, ok)``."""
    if s.size > _MAX_POINTS:
        keep = _thin(s.size)
        t = t[keep]
        s = s[keep]
        if has_tail:
            tail = tail[keep]
    n = s.size
    tt = t - t[0]
    pt = _ptp(tt)
    if order == 0 or pt == 0:
        X = np.ones((n, 1))
    else:
        X = np.empty((n, 2))
        sc = max(pt, 1e-300)
        for i in range(n):
            X[i, 0] = 1.0
            X[i, 1] = tt[i] / sc
    p = X.shape[1]
    coef, sigma, ssr, ok = irls_bisquare(X, s, _N_ITER, _TUNING)
    if not ok:
        return 0.0, 0.0, 0.0, False
    if has_tail and n > p + 5 and _ptp(tail) > 0:
        mx = 0.0
        for v in tail:
            mx = max(mx, abs(v))
        Xt = np.empty((n, p + 1))
        for i in range(n):
            for j in range(p):
                Xt[i, j] = X[i, j]
            Xt[i, p] = tail[i] / mx
        coef_t, sigma_t, ssr_t, ok = irls_bisquare(Xt, s, _N_ITER, _TUNING)
        if not ok:
            return 0.0, 0.0, 0.0, False
        if sigma > 0 and ssr - ssr_t > 25.0 * sigma ** 2:
            coef = coef_t
            sigma = sigma_t
    slope = coef[1] / max(pt, 1e-300) if p > 1 else 0.0
    return coef[0], slope, sigma, True


@njit(cache=True)
def is_settling(t, s, nsigma=5.0):
    """:func:`~.drift.is_settling` to rounding: ``(settling, ok)``."""
    if t.size < 12 or _ptp(t) == 0:
        return False, True
    if t.size > _MAX_POINTS:
        keep = _thin(t.size)
        t = t[keep]
        s = s[keep]
    n = t.size
    pt = _ptp(t)
    mean_t = np.mean(t)
    X = np.empty((n, 3))
    x2 = 0.0
    for i in range(n):
        x = (t[i] - mean_t) / pt
        X[i, 0] = 1.0
        X[i, 1] = x
        X[i, 2] = x * x
        x2 += x * x
    x2 /= n
    for i in range(n):
        X[i, 2] -= x2
    coef, sigma, _, ok = irls_bisquare(X, s, _N_ITER, _TUNING)
    if not ok:
        return False, False
    if not sigma > 0:
        return False, True
    r = np.empty(n)
    for i in range(n):
        r[i] = s[i] - (X[i, 0] * coef[0] + X[i, 1] * coef[1] + X[i, 2] * coef[2])
    sigma = max(sigma, np.std(r))
    A = np.zeros((3, 3))
    for i in range(n):
        for j in range(3):
            for k in range(3):
                A[j, k] += X[i, j] * X[i, k]
    e = np.zeros(3)
    e[2] = 1.0
    inv2 = solve_small(A, e)
    if math.isnan(inv2[0]):
        return False, False
    cov = inv2[2] * sigma ** 2
    c = coef[2]
    se = math.sqrt(max(cov, 0.0))
    bow = abs(c) * _ptp(np.ascontiguousarray(X[:, 2]))
    if not (abs(c) > nsigma * se and bow > nsigma * sigma):
        return False, True
    half = n // 2
    c1, ok1 = _polyfit_qr(t[:half], s[:half], np.int64(1))
    c2, ok2 = _polyfit_qr(t[half:], s[half:], np.int64(1))
    if not (ok1 and ok2 and np.isfinite(c1).all() and np.isfinite(c2).all()):
        return False, False
    s1 = c1[0]
    s2 = c2[0]
    return s1 * s2 > 0 and abs(s1) > 2 * abs(s2), True


_NT = 16  # settling candidates (drift._transient's n_tau)


@njit(cache=True)
def transient(t):
    """:func:`~.drift._transient`'s columns ``exp(-(t - t[0]) / tau)`` to rounding (for the
    choice of a model only): on a uniform time axis (the samples within 1e-7 of the smallest tau
    of it) by running products corrected to first order for each sample's deviation,
    ``math.exp`` otherwise; values under 1e-150 are 0 (they change no sum they enter: the
    columns start at 1)."""
    n = t.size
    span = t[-1] - t[0] if n else 0.0
    if n < 12 or not span > 0:
        return np.empty((n, 0))
    dt = span / (n - 1)
    taus = np.empty(_NT)
    a = math.log(dt)
    b = math.log(span / 5.0)
    for k in range(_NT):
        taus[k] = math.exp(a + (b - a) * k / (_NT - 1))
    taus[0] = dt
    taus[-1] = span / 5.0
    q = np.empty(_NT)
    inv = np.empty(_NT)
    for k in range(_NT):
        q[k] = math.exp(-dt / taus[k])
        inv[k] = 1.0 / taus[k]
    t0 = t[0]
    uniform = True
    for i in range(n):
        if not abs((t[i] - t0) - i * dt) * inv[0] < 1e-7:
            uniform = False
            break
    E = np.empty((n, _NT))
    if uniform:
        P = np.ones(_NT)
        for i in range(n):
            dev = (t[i] - t0) - i * dt
            for k in range(_NT):
                pk = P[k]
                E[i, k] = pk - pk * (dev * inv[k])
                pk *= q[k]
                P[k] = pk if pk > 1e-150 else 0.0
    else:
        for i in range(n):
            d = t[i] - t0
            for k in range(_NT):
                v = math.exp(-(d * inv[k])) if d * inv[k] < 345.0 else 0.0
                E[i, k] = v if v > 1e-150 else 0.0
    return E


@njit(cache=True)
def _block_means(t, s):
    n = t.size
    m = n // _SELECT_POINTS
    if m <= 1:
        return t, s, 1
    k = n // m
    tb = np.empty(k)
    sb = np.empty(k)
    for i in range(k):
        a = 0.0
        b = 0.0
        for j in range(m):
            a += t[i * m + j]
            b += s[i * m + j]
        tb[i] = a / m
        sb[i] = b / m
    return tb, sb, m


@njit(cache=True)
def _pick(c_e, win, costs, best):
    """The winning candidate of a family (-1: none) and its capped residual sum."""
    used = -1
    for k in range(_NT):
        if win[k] and costs[k] < best:
            best = costs[k]
            used = k
    return best, used


@njit(cache=True)
def retract_choice(t, s, off_a, slope_a, t0a, t_turn, noise, gap, threshold=25.0):
    """:func:`~.drift.retract_line`'s model: ``(line, p, k)``: line code (0 approach, 1 continuous,
    2 separate, -1: no line, ``retract_line``'s NaN), the family whose coefficients give the line
    and its settling column (-1: none); ``line`` -2 when a system is singular.

    The three families of :func:`~.drift._family` (no regressor, the slope from the approach
    line's end, a line of its own; each with every settling column) are least squares on normal
    equations: their sums in one pass over the samples, their capped residual sums in another.
    """
    if not noise > 0 or t.size < 12:
        return -1, 0, -1
    t, s, m = _block_means(t, s)
    if m > 1:
        noise = noise / math.sqrt(m)
    n = t.size
    at_turn = off_a + slope_a * (t_turn - t0a)
    cap = (4.685 * noise) ** 2
    scale = max(t[-1] - t_turn, 1e-300)
    y0 = np.empty(n)
    y1 = np.empty(n)
    u = np.empty(n)
    g01 = g11 = h0 = h1 = 0.0
    for i in range(n):
        y0[i] = s[i] - (off_a + slope_a * (t[i] - t0a))
        y1[i] = s[i] - at_turn
        ui = (t[i] - t_turn) / scale
        u[i] = ui
        g01 += ui
        g11 += ui * ui
        h0 += y1[i]
        h1 += ui * y1[i]
    # the plain fits (no settling column): family 1 ``y1 ~ u``, family 2 ``y1 ~ 1 + u``
    if not g11 != 0.0:
        return -2, 0, -1
    b1 = h1 / g11
    G = np.empty((2, 2))
    G[0, 0] = n
    G[0, 1] = g01
    G[1, 0] = g01
    G[1, 1] = g11
    rh = np.empty(2)
    rh[0] = h0
    rh[1] = h1
    c2 = solve_small(G, rh)
    if math.isnan(c2[0]):
        return -2, 0, -1
    best0 = best1 = best2 = 0.0
    for i in range(n):
        r0 = y0[i]
        r1 = y1[i] - u[i] * b1
        r2 = y1[i] - c2[0] - u[i] * c2[1]
        best0 += min(r0 * r0, cap)
        best1 += min(r1 * r1, cap)
        best2 += min(r2 * r2, cap)
    E = transient(t)
    if E.shape[1] == _NT:
        ey0 = np.zeros(_NT)
        ey1 = np.zeros(_NT)
        ee = np.zeros(_NT)
        xe0 = np.zeros(_NT)
        xe1 = np.zeros(_NT)
        for i in range(n):
            a0 = y0[i]
            a1 = y1[i]
            ui = u[i]
            for k in range(_NT):
                e = E[i, k]
                ey0[k] += e * a0
                ey1[k] += e * a1
                ee[k] += e * e
                xe0[k] += e
                xe1[k] += ui * e
        # each family's least squares with each settling column; a candidate wins only with a
        # negative coefficient (rising from below)
        ce0 = np.zeros(_NT)
        ce1 = np.zeros(_NT)
        cu1 = np.zeros(_NT)
        ce2 = np.zeros(_NT)
        c12 = np.zeros(_NT)
        cu2 = np.zeros(_NT)
        w0 = np.zeros(_NT, np.bool_)
        w1 = np.zeros(_NT, np.bool_)
        w2 = np.zeros(_NT, np.bool_)
        M2 = np.empty((2, 2))
        v2 = np.empty(2)
        M3 = np.empty((3, 3))
        v3 = np.empty(3)
        for k in range(_NT):
            if not ee[k] != 0.0:
                return -2, 0, -1
            ce0[k] = ey0[k] / ee[k]
            w0[k] = ce0[k] < 0
            M2[0, 0] = g11
            M2[0, 1] = xe1[k]
            M2[1, 0] = xe1[k]
            M2[1, 1] = ee[k]
            v2[0] = h1
            v2[1] = ey1[k]
            c = solve_small(M2, v2)
            if math.isnan(c[0]):
                return -2, 0, -1
            cu1[k] = c[0]
            ce1[k] = c[1]
            w1[k] = c[1] < 0
            M3[0, 0] = n
            M3[0, 1] = g01
            M3[1, 0] = g01
            M3[1, 1] = g11
            M3[0, 2] = xe0[k]
            M3[2, 0] = xe0[k]
            M3[1, 2] = xe1[k]
            M3[2, 1] = xe1[k]
            M3[2, 2] = ee[k]
            v3[0] = h0
            v3[1] = h1
            v3[2] = ey1[k]
            c = solve_small(M3, v3)
            if math.isnan(c[0]):
                return -2, 0, -1
            c12[k] = c[0]
            cu2[k] = c[1]
            ce2[k] = c[2]
            w2[k] = c[2] < 0
        s0 = np.zeros(_NT)
        s1 = np.zeros(_NT)
        s2 = np.zeros(_NT)
        for i in range(n):
            a0 = y0[i]
            a1 = y1[i]
            ui = u[i]
            for k in range(_NT):
                e = E[i, k]
                r = a0 - e * ce0[k]
                r *= r
                s0[k] += r if r < cap else cap
                r = a1 - e * ce1[k] - ui * cu1[k]
                r *= r
                s1[k] += r if r < cap else cap
                r = a1 - e * ce2[k] - c12[k] - ui * cu2[k]
                r *= r
                s2[k] += r if r < cap else cap
        ssr0, _ = _pick(ce0, w0, s0, best0)
        ssr1, k1 = _pick(ce1, w1, s1, best1)
        ssr2, k2 = _pick(ce2, w2, s2, best2)
    else:
        ssr0, ssr1, ssr2, k1, k2 = best0, best1, best2, -1, -1
    lim = threshold * noise ** 2
    if ssr0 - min(ssr1, ssr2) <= lim:
        return 0, 0, -1
    if ssr1 - ssr2 <= lim and not gap:
        return 1, 1, k1
    return 2, 2, k2


@njit(cache=True)
def borrowed(t, s, z, has_z, off_a, slope_a, t0a, tilt, noise, threshold=25.0):
    """:func:`~.drift.borrowed_line`: ``(line code, offset, slope, tilt, ok)`` (codes 0, 3, 4, 5)."""
    n = s.size
    cap = (4.685 * noise) ** 2 if noise > 0 else np.inf
    best_line = 0
    best_off = off_a + slope_a * (t[0] - t0a)
    best_slope = slope_a
    best_tilt = 0.0
    ssr0 = 0.0
    for i in range(n):
        c = s[i] - (off_a + slope_a * (t[i] - t0a))
        ssr0 += min(c * c, cap)
    ssr_best = ssr0
    X = np.ones((n, 1))
    y = np.empty(n)
    n_cand = 3 if (has_z and math.isfinite(tilt)) else 2
    for cand in range(n_cand):
        slope = 0.0
        tl = 0.0
        for i in range(n):
            if cand == 0:
                y[i] = s[i] - 0.0
            elif cand == 1:
                y[i] = s[i] - slope_a * (t[i] - t[0])
            else:
                y[i] = s[i] - tilt * (z[i] - z[0])
        if cand == 1:
            slope = slope_a
        elif cand == 2:
            tl = tilt
        coef, _, _, ok = irls_bisquare(X, y, _N_ITER, _TUNING)
        if not ok:
            return 0, 0.0, 0.0, 0.0, False
        ssr = 0.0
        for i in range(n):
            r = y[i] - coef[0]
            ssr += min(r * r, cap)
        if ssr0 - ssr > threshold * noise ** 2 and ssr < ssr_best:
            ssr_best = ssr
            best_line = 3 + cand
            best_off = coef[0]
            best_slope = slope
            best_tilt = tl
    return best_line, best_off, best_slope, best_tilt, True


@njit(cache=True)
def decide(t, s, a_index, a_zf, a_split, r_index, r_zf, z, has_z, order, min_points, max_noise_ratio, h_tail):
    """:func:`~.drift.remove_drift`'s fits and choices: ``(status, off_a, slope_a, noise, t0a, line,
    settling, off_r, slope_r, t0r, tilt_r, z0r, p, k)``; for lines 1 and 2 (continuous, separate),
    ``off_r`` and ``slope_r`` are left to :func:`~.drift.family_coef` on the family ``p`` with the
    settling column ``k``."""
    nan = math.nan
    finite = True  # np.isfinite(t).all() and np.isfinite(s).all() and (not has_z or np.isfinite(z).all())
    for a in (t, s, z if has_z else t):
        for v in a:
            if not math.isfinite(v):
                finite = False
                break
        if not finite:
            break
    n = s.size
    for idx in (a_index, r_index):
        for i in idx:
            finite = finite and 0 <= i < n  # and in the record (no bounds checks here)
    finite = finite and t.size == n and (not has_z or z.size == n)
    finite = finite and a_zf.size == a_index.size and r_zf.size == r_index.size
    if not finite:
        return 1, nan, nan, nan, nan, 0, False, nan, nan, nan, 0.0, 0.0, 0, -1
    ia = a_index[a_zf]
    ir = r_index[r_zf]
    if (not finite or ia.size < 1 or a_index.size < 1 or r_index.size < 1 or not (order == 0 or order == 1)
            or min_points < 1 or (has_z and not 0 <= a_split < a_index.size)):  # the numpy code says what is wrong
        return 1, nan, nan, nan, nan, 0, False, nan, nan, nan, 0.0, 0.0, 0, -1
    ta = t[ia]
    sa = s[ia]
    tail = np.empty(0)
    if has_z:
        z_c = z[a_index[a_split]]
        tail = np.empty(ia.size)
        for i in range(ia.size):
            v = z_c - z[ia[i]]
            v = v if (v > 0.0 or v != v) else 0.0  # np.maximum(v, 0.0)
            v = v + h_tail
            tail[i] = 1.0 / (v * v)
    off_a, slope_a, noise, ok = fit_baseline(ta, sa, order, tail, has_z)
    if not ok:
        return 1, nan, nan, nan, nan, 0, False, nan, nan, nan, 0.0, 0.0, 0, -1
    t0a = t[ia[0]]
    settling = False
    line = 0
    off_r, slope_r, t0r, tilt_r, z0r = off_a, slope_a, t0a, 0.0, 0.0
    fam_p = 0
    fam_k = -1
    gap = r_index[0] - a_index[-1] > 1
    if ir.size >= min_points:
        tr = t[ir]
        sr = s[ir]
        off, slope, noise_r, ok = fit_baseline(tr, sr, order, tail, np.bool_(False))
        if not ok:
            return 1, nan, nan, nan, nan, 0, False, nan, nan, nan, 0.0, 0.0, 0, -1
        if noise > 0 and noise_r > max_noise_ratio * noise:
            tilt = nan
            if has_z and ia.size > 2 and _ptp(ta) > 0:
                za = z[ia]
                c, okp = _polyfit_qr(ta - t0a, za, np.int64(1))
                if not (okp and np.isfinite(c).all()):
                    return 1, nan, nan, nan, nan, 0, False, nan, nan, nan, 0.0, 0.0, 0, -1
                v = c[0]
                tilt = slope_a / v if v != 0 else nan
            zr = z[ir] if has_z else np.empty(0)
            line, off, slope, tl, ok = borrowed(tr, sr, zr, has_z, off_a, slope_a, t0a, tilt, noise_r)
            if not ok or line == 5:  # a position tilt: numpy's polyfit gives its number
                return 1, nan, nan, nan, nan, 0, False, nan, nan, nan, 0.0, 0.0, 0, -1
            if line != 0:
                off_r, slope_r, t0r, tilt_r = off, slope, t[ir[0]], tl
                z0r = z[ir[0]] if has_z else 0.0
        elif order != 1:
            line, off_r, slope_r, t0r = 2, off, slope, t[ir[0]]
        else:
            settling, ok = is_settling(tr, sr)
            if not ok:
                return 1, nan, nan, nan, nan, 0, False, nan, nan, nan, 0.0, 0.0, 0, -1
            if not settling:
                t_turn = t[r_index[0]]
                code, fam_p, fam_k = retract_choice(tr, sr, off_a, slope_a, t0a, t_turn, noise, gap)
                if code == -2:
                    return 1, nan, nan, nan, nan, 0, False, nan, nan, nan, 0.0, 0.0, 0, -1
                if code == 0:
                    line, off_r, slope_r, t0r = 0, off_a + slope_a * (t_turn - t0a), slope_a, t_turn
                elif code > 0:
                    line, off_r, slope_r, t0r = code, nan, nan, t_turn
    return 0, off_a, slope_a, noise, t0a, line, settling, off_r, slope_r, t0r, tilt_r, z0r, fam_p, fam_k


@njit(cache=True)
def apply(t, s, z, a_index, r_index, off_a, slope_a, t0a, off_r, slope_r, t0r, tilt_r, z0r):
    """``s`` less the runs' baselines (:func:`~.drift.remove_drift`'s arithmetic): ``(out, base,
    ok)``. Samples outside the runs get ``np.interp``'s value between the runs' baselines in time
    (held outside them), when the runs' samples are in time order; ``ok`` False otherwise (the
    caller then uses numpy's stable sort)."""
    n = s.size
    base = np.full(n, np.nan)
    for i in a_index:
        base[i] = off_a + slope_a * (t[i] - t0a)
    for i in r_index:
        v = off_r + slope_r * (t[i] - t0r)
        base[i] = v + (tilt_r * (z[i] - z0r) if tilt_r else 0.0)
    n_known = 0
    for i in range(n):
        n_known += not math.isnan(base[i])
    if 0 < n_known < n:
        known = np.empty(n_known, np.int64)
        m = 0
        for i in range(n):
            if not math.isnan(base[i]):
                known[m] = i
                m += 1
        for j in range(1, m):
            if t[known[j]] < t[known[j - 1]]:
                return s - base, base, False
        xp = t[known]
        fp = base[known]
        j = 0
        for i in range(n):
            if not math.isnan(base[i]):
                continue
            x = t[i]
            # np.interp: j with xp[j] <= x < xp[j + 1]
            if x < xp[0]:
                v = fp[0]
            elif x > xp[m - 1]:
                v = fp[m - 1]
            else:
                if not (xp[j] <= x and (j + 1 == m or x < xp[j + 1])):  # the previous sample's j, else bisect
                    lo = 0
                    hi = m
                    while lo < hi:  # bisect_right
                        mid = (lo + hi) >> 1
                        if x < xp[mid]:
                            hi = mid
                        else:
                            lo = mid + 1
                    j = lo - 1
                if j == m - 1:
                    v = fp[j]
                elif xp[j] == x:
                    v = fp[j]
                else:
                    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
                    v = slope * (x - xp[j]) + fp[j]
                    if math.isnan(v):
                        v = slope * (x - xp[j + 1]) + fp[j + 1]
                        if math.isnan(v) and fp[j] == fp[j + 1]:
                            v = fp[j]
            base[i] = v
    out = np.empty(n)
    for i in range(n):
        out[i] = s[i] - base[i]
    return out, base, True
