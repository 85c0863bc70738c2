"""Compiled variable-projection Levenberg-Marquardt for the fringe map (:mod:`.fringes`).

Model on the samples, ``x = (z - z_mid) / L``: ``u = z_mid + c1 L (x + a2 x^2 + a3 x^3)``,
``r ~ p cos(2 pi u / P) + q sin(2 pi u / P) + line``. The line (columns of ``Q0``, an
orthonormal basis) is projected out once; the cos/sin amplitudes are a 2x2 solve per
evaluation; the nonlinear parameters ``q`` are ``(log(P / P0) or c1, a2, a3)`` (first 1-3).
The Jacobian is Kaufman's variable-projection approximation ``(I - P_X) dX/dq coef``.
Written as loops for numba: one evaluation of 2,000 samples costs a few microseconds, where
the same in numpy calls costs ~100 (the fit is dominated by call overhead, not arithmetic).
:func:`_prepare` computes, once per run, what the fits of every map order share.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import config as _numba_config, njit

from ._contact_kernel import pairwise_sum
from ._numeric import solve_small as _solve_small

__all__ = ["vp_eval", "lm_fit", "fit_orders", "finish_stats", "variance", "sincos"]

#: The kernels run as Python (``NUMBA_DISABLE_JIT``, the first run: ``cli/_firstrun.py``): the sums that
#: numpy does in one call are then left to numpy (the same numbers).
_INTERPRETED = bool(_numba_config.DISABLE_JIT)


@dataclass(frozen=True)
class _Prep:
    """What every map order's fit of one run shares (computed once per run, the same numbers)."""

    zm: float
    L: float
    var0: float
    x: np.ndarray
    x2: np.ndarray
    x3: np.ndarray
    Q0: np.ndarray
    r_perp: np.ndarray


def _prepare(z: np.ndarray, r: np.ndarray, t: np.ndarray | None, var0: float | None = None) -> _Prep:
    """Normalised position and its powers, and the residual with the line projected out (``var0``:
    ``np.var(r)`` when the caller has it)."""
    z_hi, z_lo = z.max(), z.min()
    zm = 0.5 * (z_hi + z_lo)
    L = 0.5 * float(z_hi - z_lo) or 1.0  # ptp(z)
    x = np.ascontiguousarray((z - zm) / L)
    X = np.empty((x.size, 2))  # the line's columns (1, x or t)
    X[:, 0] = 1.0
    if t is not None:
        t = np.asarray(t, float)
        t_hi, t_lo = t.max(), t.min()
        tm, tL = 0.5 * (t_hi + t_lo), 0.5 * float(t_hi - t_lo) or 1.0
        X[:, 1] = (t - tm) / tL
    else:
        X[:, 1] = x
    var0 = variance(r) if var0 is None else var0
    x2, x3 = x * x, x * x * x
    # variable projection: the line (1, x or t) is projected out once (thin QR), the cos/sin
    # amplitudes are a 2x2 solve per evaluation (compiled: analysis._fringe_kernel)
    Q0, _ = np.linalg.qr(X)
    Q0 = np.ascontiguousarray(Q0)
    r_perp = np.ascontiguousarray(r - Q0 @ (Q0.T @ r))
    return _Prep(zm, L, var0, x, x2, x3, Q0, r_perp)


@njit(cache=True)
def _thin_indices(n, m):
    """``np.unique(np.linspace(0, n - 1, m).round().astype(np.int64))`` for ``2 <= m < n``: numpy's
    grid (``i * ((n - 1) / (m - 1))``, the last point ``n - 1`` exactly), rounded half to even,
    repeated indices dropped (the grid increases)."""
    step = (n - 1.0) / (m - 1)
    out = np.empty(m, dtype=np.int64)
    k = 0
    for i in range(m):
        v = i * step + 0.0 if i < m - 1 else n - 1.0
        f = math.floor(v)
        d = v - f
        j = int(f)
        if d > 0.5 or (d == 0.5 and j % 2 == 1):
            j += 1
        if k == 0 or j != out[k - 1]:
            out[k] = j
            k += 1
    return out[:k].copy()


#: log of the largest float: math.exp beyond it overflows (+inf compiled; OverflowError as Python).
_LOG_MAX = 709.782712893384


@njit(cache=True)
def _exp(q):
    """``exp(q)``, +inf where it overflows, compiled and as Python alike (the first run's Python
    kernels, cli/_firstrun: math.exp raises OverflowError there, and the file failed)."""
    return math.exp(q) if q < _LOG_MAX else math.inf


@njit(cache=True)
def _unpack(q, known, P0, period, n_map):
    """The map ``(P, c1, a2, a3)`` of the nonlinear parameters ``q``: ``q[0]`` is c1 when the period is
    ``known``, else ln(P / P0) (c1 = 1); a2, a3 follow as the map's order ``n_map`` has them."""
    if known:
        c1 = q[0]
        P = period
    else:
        c1 = 1.0
        P = P0 * _exp(q[0])
    a2 = q[1] if n_map >= 1 else 0.0
    a3 = q[2] if n_map >= 2 else 0.0
    return P, c1, a2, a3


#: :func:`sincos`'s constants: pi/2 in three parts (fdlibm's ``__rem_pio2``: the first holds 33 bits, so
#: ``k * _PIO2_1`` is exact for the ``|k| <= 2^20`` reduced here), 2/pi, and fdlibm's minimax polynomials of
#: sin and cos on [-pi/4, pi/4] (``__kernel_sin``, ``__kernel_cos``; their error < 1 ulp there).
_PIO2_1 = 1.57079632673412561417e+00
_PIO2_2 = 6.07710050630396597660e-11
_PIO2_2T = 2.02226624879595063154e-21
_INVPIO2 = 6.36619772367581382433e-01
_S1, _S2, _S3, _S4, _S5, _S6 = (-1.66666666666666324348e-01, 8.33333333332248946124e-03, -1.98412698298579493134e-04,
                                2.75573137070700676789e-06, -2.50507602534068634195e-08, 1.58969099521155010221e-10)
_C1, _C2, _C3, _C4, _C5, _C6 = (4.16666666666666019037e-02, -1.38888888888741095749e-03, 2.48015872894767294178e-05,
                                -2.75573143513906633035e-07, 2.08757232129817482790e-09, -1.13596475577881948265e-11)
#: :func:`sincos` reduces ``|theta| * 2 / pi`` up to this itself; larger, infinite and NaN angles go to libm.
_SINCOS_LIM = 1e6
#: ``x + _ROUND - _ROUND`` is ``x`` rounded to the nearest integer (ties to even) for ``|x| < 2^51``.
_ROUND = 6755399441055744.0


@njit(cache=True)
def sincos(th, c, s):
    """``c[i] = cos(th[i])``, ``s[i] = sin(th[i])`` within ~1 ulp of libm's (1.1e-16 in absolute terms, tested
    against ``math.cos``/``math.sin`` up to |theta| = 1e7): Cody-Waite reduction by pi/2 in three parts and
    fdlibm's polynomials, written without branches so LLVM vectorises the loop (AVX2/AVX-512: ~2 ns a
    sample where libm's scalar pair costs ~13 ns; the fringe fit's evaluations are mostly these). Angles
    beyond ``_SINCOS_LIM * pi / 2``, infinite or NaN take libm's values in a second pass."""
    n = th.size
    for i in range(n):
        t = th[i]
        y = t * _INVPIO2
        y = y if abs(y) <= _SINCOS_LIM else 0.0
        kf = (y + _ROUND) - _ROUND
        x = ((t - kf * _PIO2_1) - kf * _PIO2_2) - kf * _PIO2_2T
        z = x * x
        sx = x + (z * x) * (_S1 + z * (_S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))))
        r = z * (_C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * (_C5 + z * _C6)))))
        hz = 0.5 * z
        w = 1.0 - hz
        cx = w + (((1.0 - w) - hz) + z * r)
        q = np.int64(kf) & 3
        a = cx if q & 1 else sx
        b = sx if q & 1 else cx
        s[i] = -a if q & 2 else a
        c[i] = -b if (q + 1) & 2 else b
    for i in range(n):
        t = th[i]
        if not abs(t * _INVPIO2) <= _SINCOS_LIM:
            c[i] = math.cos(t)
            s[i] = math.sin(t)


@njit(cache=True)
def _vp_core(q, known, P0, period, n_map, x, x2, x3, zm, L, Q0, rp, W, fast):
    """The model at ``q``: fills the workspace ``W`` (rows: residual, theta, map polynomial, cos, sin,
    projected cos, projected sin) and returns ``(half the SSR, p, q amplitudes, the inverse 2x2
    normal matrix i00, i01, i11, 2 pi / P, c1)``; half the SSR is +inf where no fit exists."""
    n = x.size
    P, c1, a2, a3 = _unpack(q, known, P0, period, n_map)
    if not (P > 0.0 and P < math.inf):  # exp(q) under- or overflowed: a trial step far off, rejected
        return math.inf, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, c1
    w = 2.0 * math.pi / P
    if not w < math.inf:  # a subnormal P (log(P/P0) near -700): every phase is infinite, no fit exists
        return math.inf, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, c1
    res = W[0]
    th = W[1]
    poly = W[2]
    cr = W[3]  # cos and sin before the projection (the Jacobian needs them: not computed twice)
    sr = W[4]
    cs = W[5]
    sn = W[6]
    g00 = g01 = g10 = g11 = 0.0  # Q0^T C
    for i in range(n):
        p = x[i] + a2 * x2[i] + a3 * x3[i]
        poly[i] = p
        th[i] = w * (zm + c1 * L * p)
        if not abs(th[i]) < math.inf:  # a trial step far off (c1 or the map's terms overflow): the first
            # run's Python kernels raised "math domain error" from math.cos(inf); rejected as no fit
            return math.inf, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, c1
    if fast:
        sincos(th, cr, sr)  # vectorised: the evaluation's cost was mostly libm's cos and sin
    else:
        for i in range(n):
            cr[i] = math.cos(th[i])
            sr[i] = math.sin(th[i])
    for i in range(n):
        cs[i] = cr[i]
        sn[i] = sr[i]
        g00 += Q0[i, 0] * cs[i]
        g01 += Q0[i, 0] * sn[i]
        g10 += Q0[i, 1] * cs[i]
        g11 += Q0[i, 1] * sn[i]
    A00 = A01 = A11 = b0 = b1 = 0.0
    for i in range(n):  # Cp = C - Q0 (Q0^T C), in place
        cs[i] -= Q0[i, 0] * g00 + Q0[i, 1] * g10
        sn[i] -= Q0[i, 0] * g01 + Q0[i, 1] * g11
        A00 += cs[i] * cs[i]
        A01 += cs[i] * sn[i]
        A11 += sn[i] * sn[i]
        b0 += cs[i] * rp[i]
        b1 += sn[i] * rp[i]
    reg = 1e-12 * (A00 + A11) + 1e-300  # a period far beyond the range: cos ~ the line
    A00 += reg
    A11 += reg
    det = A00 * A11 - A01 * A01
    if not det > 0.0:  # cos and sin collinear to rounding (underflow): no amplitude to solve for
        return math.inf, 0.0, 0.0, 0.0, 0.0, 0.0, w, c1
    i00, i01, i11 = A11 / det, -A01 / det, A00 / det
    c0 = i00 * b0 + i01 * b1
    c1c = i01 * b0 + i11 * b1
    cost = 0.0
    for i in range(n):
        res[i] = cs[i] * c0 + sn[i] * c1c - rp[i]
        cost += res[i] * res[i]
    return 0.5 * cost, c0, c1c, i00, i01, i11, w, c1


@njit(cache=True)
def _vp_jac(known, L, x2, x3, Q0, W, c0, c1c, i00, i01, i11, w, c1, J):
    """Kaufman's variable-projection Jacobian (into ``J``) at the point :func:`_vp_core` left in ``W``."""
    n = x2.size
    th = W[1]
    poly = W[2]
    cr = W[3]
    sr = W[4]
    cs = W[5]
    sn = W[6]
    m = J.shape[1]
    k = w * c1 * L
    gd = np.empty(n)  # g = d(X coef)/dtheta from the unprojected cos/sin
    for i in range(n):
        gd[i] = c1c * cr[i] - c0 * sr[i]
    for j in range(m):
        # column j of V = g * dtheta/dq_j
        h0 = h1 = 0.0
        for i in range(n):
            if j == 0:
                d = w * L * poly[i] if known else -th[i]
            elif j == 1:
                d = k * x2[i]
            else:
                d = k * x3[i]
            J[i, j] = gd[i] * d
            h0 += Q0[i, 0] * J[i, j]
            h1 += Q0[i, 1] * J[i, j]
        e0 = e1 = 0.0
        for i in range(n):
            J[i, j] -= Q0[i, 0] * h0 + Q0[i, 1] * h1
            e0 += cs[i] * J[i, j]
            e1 += sn[i] * J[i, j]
        f0 = i00 * e0 + i01 * e1
        f1 = i01 * e0 + i11 * e1
        for i in range(n):
            J[i, j] -= cs[i] * f0 + sn[i] * f1


@njit(cache=True)
def vp_eval(q, known, P0, period, n_map, x, x2, x3, zm, L, Q0, rp, res, J, want_jac, fast):
    """Residual (into ``res``), Jacobian (into ``J`` when ``want_jac``); returns half the SSR."""
    W = np.empty((7, x.size))
    cost, c0, c1c, i00, i01, i11, w, c1 = _vp_core(q, known, P0, period, n_map, x, x2, x3, zm, L, Q0, rp, W, fast)
    if not cost < math.inf:
        return cost
    res[:] = W[0]
    if want_jac:
        _vp_jac(known, L, x2, x3, Q0, W, c0, c1c, i00, i01, i11, w, c1, J)
    return cost


@njit(cache=True)
def lm_fit(q0, known, P0, period, n_map, x, x2, x3, zm, L, Q0, rp, max_nfev, ftol, xtol, fast):
    """Levenberg-Marquardt on :func:`vp_eval`; returns ``(q, cost, status)`` (status 0: budget
    spent, 1: converged: an accepted step changed the cost by < ftol of it, or q by
    < xtol (xtol + |q|), or no descent is left).

    Two workspaces: a trial point's evaluation becomes the current one when the step is accepted
    (its Jacobian is then computed from it; the model is not evaluated twice at one point)."""
    n = x.size
    m = q0.size
    q = q0.copy()
    WS = np.empty((2, 7, n))
    cur = 0
    J = np.empty((n, m))
    cost, c0, c1c, i00, i01, i11, w, c1 = _vp_core(q, known, P0, period, n_map, x, x2, x3, zm, L, Q0, rp, WS[cur], fast)
    if not cost < math.inf:  # no fit at the start (see vp_eval)
        return q, cost, 1
    _vp_jac(known, L, x2, x3, Q0, WS[cur], c0, c1c, i00, i01, i11, w, c1, J)
    nfev = 1
    lam = 1e-3
    while nfev < max_nfev:
        A = J.T @ J
        g = J.T @ WS[cur, 0]
        d = np.empty(m)
        for j in range(m):
            d[j] = A[j, j] if A[j, j] > 0 else 1.0
        accepted = False
        while nfev < max_nfev:
            B = A.copy()
            for j in range(m):
                B[j, j] += lam * d[j]
            dq = -_solve_small(B, g)
            if np.isnan(dq[0]):
                lam *= 10.0
                if lam > 1e12:
                    return q, cost, 1
                continue
            qn = q + dq
            cn, c0, c1c, i00, i01, i11, w, c1 = _vp_core(qn, known, P0, period, n_map, x, x2, x3, zm, L, Q0, rp,
                                                         WS[1 - cur], fast)
            nfev += 1
            if cn <= cost:
                small_f = cost - cn <= ftol * cost
                small_x = True
                for j in range(m):
                    if abs(dq[j]) > xtol * (xtol + abs(q[j])):
                        small_x = False
                q = qn
                cur = 1 - cur
                cost = cn
                _vp_jac(known, L, x2, x3, Q0, WS[cur], c0, c1c, i00, i01, i11, w, c1, J)
                lam = max(lam / 3.0, 1e-12)
                if small_f or small_x:
                    return q, cost, 1
                accepted = True
                break
            lam *= 4.0
            if lam > 1e12:
                return q, cost, 1
        if not accepted:
            break
    return q, cost, 0


#: :func:`fit_orders`' ``posed``: each order's fit spans at least this many periods [-].
_WELL_POSED_CYCLES = 1.0


@njit(cache=True)
def fit_orders(o_first, o_last, known, P0, period, x, x2, x3, zm, L, Q0, rp, max_nfev, ftol, xtol, fast):
    """The map orders ``o_first..o_last`` fitted in turn by :func:`lm_fit` (what :func:`.fringes._fit_order`
    did per order, in one call: the same starts, the same numbers), the best by the Bayesian
    information criterion ``n ln(SSR/n) + (order + 3) ln n`` (the first of equals).

    Each order starts from the lower order's map when that converged (a warm start); the cubic from
    a3 = 0, and from a3 = +-0.05 only while its best cost does not improve on the lower order's.
    Returns ``(P, c1, a2, a3, converged, rms residual)`` of the best order and ``posed``: every order's fit
    converged with at least :data:`_WELL_POSED_CYCLES` periods over the range.

    ``fast``: cos and sin by :func:`sincos` (within an ulp of libm's). A well-posed fit moves by rounding
    when its cos and sin do (the same numbers to ~1e-13); a fit that wanders (no convergence, or off to a
    period far beyond the range: cos and sin then nearly the baseline's line, its steps ill-conditioned)
    amplifies an ulp into percent, so its caller fits again with ``fast`` False where ``posed`` is False
    (:func:`.fringes._fit_map`): those numbers are libm's, as before."""
    n = x.size
    best_bic = math.inf
    bP, bc1, ba2, ba3, bconv, bres = math.nan, 1.0, 0.0, 0.0, False, math.nan
    have = False  # a lower order was fitted: its map, residual and convergence
    pP, pc1, pa2, pres, pconv = math.nan, 1.0, 0.0, math.nan, False
    posed = True  # every order's fit converged over at least WELL_POSED_CYCLES periods
    for o in range(o_first, o_last + 1):
        n_map = max(0, min(o, 3) - 1)
        ref = 0.5 * n * (pres * pres) if have and math.isfinite(pres) else math.nan  # NaN: none
        q0 = np.zeros(1 + n_map)
        q0[0] = 1.0 if known else 0.0
        if have and pconv and math.isfinite(pP):  # the lower order's map: nested models, a warm start
            q0[0] = pc1 if known else math.log(pP / P0)
            if n_map >= 1:
                q0[1] = pa2
        n_starts = 1 if n_map < 2 else 3
        bq = q0
        bcost = math.inf
        bstatus = 0
        first = True
        for s in range(n_starts):
            q = q0.copy()
            if n_map >= 2:
                q[2] = 0.0 if s == 0 else (0.05 if s == 1 else -0.05)
            qs, cost, status = lm_fit(q, known, P0, period, n_map, x, x2, x3, zm, L, Q0, rp, max_nfev, ftol, xtol, fast)
            if first or cost < bcost:
                bq, bcost, bstatus = qs, cost, status
                first = False
            if not math.isnan(ref) and bcost < ref:
                break  # the cubic already improves on the lower order: not stuck, no other start needed
        P, c1, a2, a3 = _unpack(bq, known, P0, period, n_map)
        res = math.sqrt(2.0 * bcost / n)
        conv = bstatus > 0
        posed = posed and conv and c1 * 2.0 * L >= _WELL_POSED_CYCLES * P
        if fast and not posed:  # the caller fits again with libm's cos and sin: no use going on
            return bP, bc1, ba2, ba3, bconv, bres, posed
        if math.isfinite(res):
            r2 = max(res, 1e-300)
            bic = n * math.log(r2 * r2) + (o + 3) * math.log(n)
        else:
            bic = math.inf
        if o == o_first or bic < best_bic:
            best_bic = bic
            bP, bc1, ba2, ba3, bconv, bres = P, c1, a2, a3, conv, res
        have = True
        pP, pc1, pa2, pres, pconv = P, c1, a2, res, conv
    return bP, bc1, ba2, ba3, bconv, bres, posed


@njit(cache=True)
def _pairwise(a):
    """``np.add.reduce(a)`` (1-D contiguous float64): numpy's pairwise summation, bit for bit
    (:func:`._contact_kernel.pairwise_sum`, the one copy)."""
    return pairwise_sum(a, np.int64(0), a.size)


def finish_stats(res: np.ndarray, u: np.ndarray, z: np.ndarray, p0: float, p1: float) -> tuple[float, float, float]:
    """:func:`.fringes._finish`'s statistics: ``np.max(np.abs(u - np.polyval((p0, p1), z)))``,
    ``np.var(res)`` and ``np.sqrt(np.mean(res**2))``, in one compiled call (the same numbers, bit for
    bit); those numpy calls themselves where the kernels run as Python (the first run's
    ``NUMBA_DISABLE_JIT``: the loops as Python cost ~10 ms on 1,300 samples)."""
    if _INTERPRETED:
        return (float(np.max(np.abs(u - np.polyval(np.array([p0, p1]), z)))), float(np.var(res)),
                float(np.sqrt(np.mean(res**2))))
    return _finish_stats(res, u, z, p0, p1)


@njit(cache=True)
def _finish_stats(res, u, z, p0, p1):
    """:func:`finish_stats` compiled (numpy's pairwise sums: :func:`_pairwise`)."""
    n = res.size
    dev = -math.inf
    for i in range(n):
        lin = (0.0 * z[i] + p0) * z[i] + p1  # np.polyval's Horner from zeros
        d = abs(u[i] - lin)
        if d > dev or d != d:
            dev = d
            if d != d:
                break
    var = _var(res)
    w = np.empty(n)
    for i in range(n):
        w[i] = res[i] * res[i]
    rms = math.sqrt(_pairwise(w) / n)
    return dev, var, rms


@njit(cache=True)
def _var(a):
    """``np.var(a)`` of a non-empty 1-D contiguous float64 array, bit for bit (its pairwise sums)."""
    n = a.size
    mean = _pairwise(a) / n
    w = np.empty(n)
    for i in range(n):
        e = a[i] - mean
        w[i] = e * e
    return _pairwise(w) / n


def variance(a: np.ndarray) -> float:
    """``float(np.var(a))`` (the same number) without numpy's ~10 us of wrappers."""
    a = np.asarray(a, dtype=float)
    if a.ndim != 1 or a.size == 0 or _INTERPRETED:
        return float(np.var(a))
    return float(_var(np.ascontiguousarray(a)))
