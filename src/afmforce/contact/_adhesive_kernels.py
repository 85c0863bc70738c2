"""Compiled kernels of the adhesive laws and their fit (numba).

* the laws' stable branches, exact, point by point: :func:`jkr_point` (JKR's quartic), :func:`maugis_point`
  and :func:`maugis_branch_point` (Maugis-Dugdale's parametric equations), :func:`branch_point` /
  :func:`branch_values` (by law code: DMT, JKR, MAUGIS), :func:`adhesive_model`;
* the fit: :func:`adhesive_normal` (sum of squares, J^T J and J^T r of the analytic Jacobian),
  :func:`adhesive_lm` (bounded Levenberg-Marquardt), :func:`gap_fit` and :func:`adhesive_walk` (the
  contact confined to the gaps between samples; :mod:`afmforce.contact.adhesive_fit`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .._linalg_small import solve_small_in_place
from ._kernels import ramp_weight

__all__ = ["DMT", "JKR", "MAUGIS", "jkr_point", "maugis_point", "maugis_params", "maugis_branch_point",
           "branch_point", "branch_values", "adhesive_normal", "adhesive_lm", "gap_fit", "adhesive_walk",
           "adhesive_model"]

_C_JKR = 2.0 / 3.0 * math.sqrt(6.0)  # JKR: D = s^4 - C s, P = s^6 - sqrt(6) s^3 with s = sqrt(A)
_SQ6 = math.sqrt(6.0)
DMT, JKR, MAUGIS = 0, 1, 2  # law codes of the kernels


@njit(cache=True)
def jkr_point(D):  # pragma: no cover - compiled
    """JKR at dimensionless indentation D: (A, P, dP/dD). s = sqrt(A) is the root of s^4 - C s = D with
    dD/ds > 0 (s >= s_m, s_m^3 = C/4), by Newton's method from above on y(s) = sqrt(D(s) - D(s_m)) =
    (s - s_m) sqrt(s^2 + 2 s s_m + 3 s_m^2) (exact: no cancellation; linear at the branch's end, where D(s)
    has a double root, so the convergence stays quadratic there). D below the branch's end gives its end."""
    sm = (_C_JKR / 4.0) ** (1.0 / 3.0)
    d_end = sm ** 4 - _C_JKR * sm
    yt = math.sqrt(max(D - d_end, 0.0))
    s = max(max(D, 0.0) ** 0.25 + _C_JKR ** (1.0 / 3.0), sm)  # above the root
    for _ in range(100):
        e = s - sm
        q = s * s + 2.0 * s * sm + 3.0 * sm * sm
        rq = math.sqrt(q)
        slope = rq + e * (s + sm) / rq
        step = (e * rq - yt) / slope
        s = max(s - step, sm)
        if abs(step) <= 1e-15 * s:
            break
    s2 = s * s
    s3 = s2 * s
    dD = max(4.0 * s3 - _C_JKR, 1e-300)
    return s2, s3 * s3 - _SQ6 * s3, (6.0 * s3 * s2 - 3.0 * _SQ6 * s2) / dD


@njit(cache=True)
def maugis_point(t, lam):  # pragma: no cover - compiled
    """Maugis-Dugdale at t = sqrt(m^2 - 1) (m = c/a): (A, P, D, dP/dt, dD/dt).

    The first equation ``lam A^2/2 a1(t) + 4 lam^2 A/3 a2(t) = 1`` is quadratic in A (positive root);
    ``P = A^3 - lam A^2 (t + m^2 atan t)``, ``D = A^2 - 4/3 lam A t``; series for small t (cancellation).
    """
    t2 = t * t
    at = math.atan(t)
    if t < 1e-3:
        a1 = t2 * t * (4.0 / 3.0 - 8.0 / 15.0 * t2)
        a2 = t2 * (0.5 - 5.0 / 24.0 * t2)
    else:
        a1 = t + (t2 - 1.0) * at
        a2 = t * at - math.sqrt(1.0 + t2) + 1.0
    d1 = 2.0 * t2 / (1.0 + t2) + 2.0 * t * at
    d2 = at + t / (1.0 + t2) - t / math.sqrt(1.0 + t2)
    qa = lam * a1 / 2.0
    qb = 4.0 * lam * lam * a2 / 3.0
    A = 2.0 / (qb + math.sqrt(qb * qb + 4.0 * qa))
    dA = -(lam * d1 / 2.0 * A * A + 4.0 * lam * lam * d2 / 3.0 * A) / (2.0 * qa * A + qb)
    g = t + (1.0 + t2) * at
    P = A * A * A - lam * A * A * g
    dP = 3.0 * A * A * dA - lam * (2.0 * A * dA * g + A * A * (2.0 + 2.0 * t * at))
    D = A * A - 4.0 / 3.0 * lam * A * t
    dD = 2.0 * A * dA - 4.0 / 3.0 * lam * (dA * t + A)
    return A, P, D, dP, dD


@njit(cache=True)
def maugis_params(t, lam):  # pragma: no cover - compiled
    """:func:`maugis_point` on an array of t: arrays (A, P, D, dP/dt, dD/dt)."""
    n = t.size
    A, P, D, dP, dD = np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    for i in range(n):
        A[i], P[i], D[i], dP[i], dD[i] = maugis_point(t[i], lam)
    return A, P, D, dP, dD


@njit(cache=True)
def maugis_branch_point(D, lam, lt_tab, y_tab):  # pragma: no cover - compiled
    """Maugis-Dugdale's stable branch at D: (A, P, dP/dD). The table: y = sqrt(D - D_end) (increasing)
    against ln t, from the branch's end (``lt_tab[0]``, y = 0, dD/dt = 0) on. A start by interpolation in
    y, then Newton's method in ln t on y(ln t) -- linear at the end, where D has a double root -- to
    rounding."""
    n = y_tab.size
    d_end = maugis_point(math.exp(lt_tab[0]), lam)[2]
    yt = math.sqrt(max(D - d_end, 0.0))
    yc = min(yt, y_tab[n - 1])
    lo, hi = 0, n - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if y_tab[mid] <= yc:
            lo = mid
        else:
            hi = mid
    f = (yc - y_tab[lo]) / (y_tab[hi] - y_tab[lo]) if y_tab[hi] > y_tab[lo] else 0.0
    lt = lt_tab[lo] + f * (lt_tab[hi] - lt_tab[lo])
    lt_end = lt_tab[0]
    A, P, Dt, dP, dD = maugis_point(math.exp(lt), lam)
    for _ in range(40):
        y = math.sqrt(max(Dt - d_end, 0.0))
        slope = dD * math.exp(lt) / (2.0 * y) if y > 0 else -np.inf  # dy / d ln t (< 0 on the branch)
        if not (slope < 0.0 and math.isfinite(slope)):
            break
        step = (y - yt) / slope
        lt = min(lt - step, lt_end)
        A, P, Dt, dP, dD = maugis_point(math.exp(lt), lam)
        if abs(step) <= 1e-14:
            break
    return A, P, dP / min(dD, -1e-300)


@njit(cache=True)
def branch_point(law, D, lam, lt_tab, y_tab):  # pragma: no cover - compiled
    """The law's stable branch at dimensionless indentation D: (A, P, dP/dD)."""
    if law == DMT:
        Dp = max(D, 0.0)
        return math.sqrt(Dp), Dp * math.sqrt(Dp) - 2.0, 1.5 * math.sqrt(Dp)
    if law == JKR:
        return jkr_point(D)
    return maugis_branch_point(D, lam, lt_tab, y_tab)


@njit(cache=True)
def branch_values(law, D, lam, lt_tab, y_tab):  # pragma: no cover - compiled
    """:func:`branch_point` on an array: arrays (A, P, dP/dD)."""
    n = D.size
    A, P, dP = np.empty(n), np.empty(n), np.empty(n)
    for i in range(n):
        A[i], P[i], dP[i] = branch_point(law, D[i], lam, lt_tab, y_tab)
    return A, P, dP


@njit(cache=True)
def adhesive_normal(u, F, law, x, R, kc, d_end, lam, lt_tab, y_tab, width, A, g):  # pragma: no cover
    """The sum of squares [N^2] of an adhesive law at x = (E, w, cj, b); fills ``A`` (4 x 4) with J^T J
    and ``g`` (4) with J^T r of the weighted model Jacobian J = d model / d (E, w, cj, b) and the weighted
    residuals r = q (F - model); ``A.size == 0``: the sum of squares alone.

    ``model = pi w R P((u - cj)/d_s + d_end) + b`` for u > cj (contact: cj is where it begins), ``b``
    before; ``d_s = (pi^2 w^2 R / (kc E)^2)^(1/3)``; weights as in fit._weights at the indentation u - c,
    c = cj - d_end d_s."""
    E, w, cj, b = x[0], x[1], x[2], x[3]
    jac = A.size > 0
    fs = math.pi * w * R
    K = kc * E
    ds = (math.pi * math.pi * w * w * R / (K * K)) ** (1.0 / 3.0)
    c = cj - d_end * ds
    cE, cw, cc = fs * 2.0 / (3.0 * E), fs / w, -fs / ds  # d_s ~ E^(-2/3) w^(2/3); fs ~ w
    a00 = a01 = a02 = a03 = a11 = a12 = a13 = a22 = a23 = a33 = 0.0
    g0 = g1 = g2 = g3 = 0.0
    S = 0.0
    for i in range(u.size):
        q = ramp_weight(u[i] - c, width)
        if q == 0.0:
            continue
        model = b
        j0 = j1 = j2 = 0.0
        if u[i] > cj:
            rel = (u[i] - cj) / ds
            _, P, dP = branch_point(law, rel + d_end, lam, lt_tab, y_tab)
            model += fs * P
            j0 = q * cE * dP * rel
            j1 = q * cw * (P - 2.0 / 3.0 * rel * dP)
            j2 = q * cc * dP
        r = q * (F[i] - model)
        S += r * r
        if jac:
            j3 = q
            a00 += j0 * j0
            a01 += j0 * j1
            a02 += j0 * j2
            a03 += j0 * j3
            a11 += j1 * j1
            a12 += j1 * j2
            a13 += j1 * j3
            a22 += j2 * j2
            a23 += j2 * j3
            a33 += j3 * j3
            g0 += j0 * r
            g1 += j1 * r
            g2 += j2 * r
            g3 += j3 * r
    if jac:
        A[0, 0], A[0, 1], A[0, 2], A[0, 3] = a00, a01, a02, a03
        A[1, 0], A[1, 1], A[1, 2], A[1, 3] = a01, a11, a12, a13
        A[2, 0], A[2, 1], A[2, 2], A[2, 3] = a02, a12, a22, a23
        A[3, 0], A[3, 1], A[3, 2], A[3, 3] = a03, a13, a23, a33
        g[0], g[1], g[2], g[3] = g0, g1, g2, g3
    return S


@njit(cache=True)
def adhesive_lm(u, F, law, x0, lo, hi, R, kc, d_end, lam, lt_tab, y_tab, width,
                max_iter):  # pragma: no cover - compiled
    """Bounded Levenberg-Marquardt on (E, w, cj, b) of :func:`adhesive_normal` (Marquardt's diagonal
    scaling; a variable on a bound that the gradient pushes outwards is held there, one with lo = hi
    fixed). Returns
    (x, sum of squares, J^T J at x, iterations)."""
    x = np.minimum(np.maximum(x0.copy(), lo), hi)
    A = np.zeros((4, 4))
    g = np.zeros(4)
    empty = np.zeros((0, 0))
    S = adhesive_normal(u, F, law, x, R, kc, d_end, lam, lt_tab, y_tab, width, A, g)
    mu = 1e-4
    M = np.zeros((4, 4))
    y = np.zeros(4)
    xn = np.zeros(4)
    nrm = np.zeros(4)
    it = 0
    for it in range(max_iter):
        free = np.ones(4, dtype=np.bool_)
        nfree = 0
        for j in range(4):
            if lo[j] >= hi[j] or (x[j] <= lo[j] and g[j] < 0) or (x[j] >= hi[j] and g[j] > 0):
                free[j] = False
            else:
                nfree += 1
            nrm[j] = math.sqrt(A[j, j]) if A[j, j] > 0 else 1.0
        if nfree == 0:
            break
        improved = False
        Sn = S
        while mu < 1e12:
            for j in range(4):
                for k in range(4):
                    M[j, k] = A[j, k] / (nrm[j] * nrm[k]) if (free[j] and free[k]) else 0.0
                if free[j]:
                    M[j, j] += mu
                    y[j] = g[j] / nrm[j]
                else:
                    M[j, j] = 1.0
                    y[j] = 0.0
            if not solve_small_in_place(M, y):
                mu *= 10.0
                continue
            for j in range(4):
                xn[j] = min(max(x[j] + y[j] / nrm[j], lo[j]), hi[j])
            Sn = adhesive_normal(u, F, law, xn, R, kc, d_end, lam, lt_tab, y_tab, width, empty, g[:0])
            if Sn < S:
                improved = True
                break
            mu *= 8.0
        if not improved:
            break
        gain = S - Sn
        x[:] = xn
        S = Sn
        if gain <= 1e-11 * S:  # the sum of squares to 1e-11: the parameters to ~1e-5 of their errors (J^T J
            break             # kept from the step before: as good for the covariance)
        S = adhesive_normal(u, F, law, x, R, kc, d_end, lam, lt_tab, y_tab, width, A, g)
        mu = max(mu / 5.0, 1e-9)
    return x, S, A, it


@njit(cache=True)
def gap_fit(u, F, law, us, k, start, w_floor, fixed, R, kc, d_end, lam, lt_tab, y_tab, width,
             max_iter):  # pragma: no cover - compiled
    """:func:`adhesive_lm` with the jump cj confined to gap k, E and w held where ``fixed`` says."""
    lo = np.empty(4)
    hi = np.empty(4)
    s = start.copy()
    gap = us[k + 1] - us[k]
    lo[0], hi[0] = 1e-12 * s[0], np.inf
    lo[1], hi[1] = w_floor, np.inf
    for j in range(2):
        if not math.isnan(fixed[j]):
            lo[j] = hi[j] = s[j] = fixed[j]
    lo[2], hi[2] = us[k] + 1e-9 * gap, us[k + 1] - 1e-9 * gap
    lo[3], hi[3] = -np.inf, np.inf
    x, S, A, _ = adhesive_lm(u, F, law, s, lo, hi, R, kc, d_end, lam, lt_tab, y_tab, width, max_iter)
    return x, S, A


@njit(cache=True)
def adhesive_walk(u, F, law, us, k0, x0, w_floor, fixed, R, kc, d_end, lam, lt_tab, y_tab, width,
                  max_iter):  # pragma: no cover - compiled
    """:func:`adhesive_lm` with the jump cj confined to the gap ``[us[k], us[k+1]]`` between two
    consecutive sample depths (where the set of points in contact is fixed): first the gap k0, then the
    gaps on each side while the sum of squares falls. One gap's look-ahead, two where the best point is
    pressed against that end of its gap (the smooth part of the fit pulls on); while the sum of squares
    falls the steps grow (1, 2, 4, ... gaps: a start far from the optimum, as on a retract's neck where
    each gap gains a little), and an overshoot (no gain after a long step) resumes gap by gap from the
    best. ``fixed``: E and w held at its first two
    entries where they are not NaN. Returns (gap, x, sum of squares, J^T J) of the best."""
    m = us.size - 1
    best_k = k0
    best_x, best_S, best_A = gap_fit(u, F, law, us, k0, x0, w_floor, fixed, R, kc, d_end, lam, lt_tab, y_tab,
                                      width, max_iter)
    tried = np.zeros(m, dtype=np.bool_)
    tried[k0] = True
    for direction in (-1, 1):
        k = best_k
        step = 1
        misses = 0
        while True:
            edge = us[best_k] if direction < 0 else us[best_k + 1]
            pressed = abs(best_x[2] - edge) <= 1e-6 * (us[best_k + 1] - us[best_k])
            if misses >= (2 if pressed else 1):
                break
            k = best_k + direction * step if misses == 0 else k + direction
            if k < 0 or k >= m:
                if step > 1:  # past the end after a long step: back to single gaps
                    step = 1
                    continue
                break
            if tried[k]:
                misses += 1
                continue
            tried[k] = True
            x, S, A = gap_fit(u, F, law, us, k, best_x, w_floor, fixed, R, kc, d_end, lam, lt_tab, y_tab, width,
                               max_iter)
            if S < best_S:
                best_k, best_S = k, S
                best_x[:] = x
                best_A[:, :] = A
                misses = 0
                step *= 2
            elif step > 1:  # an overshoot: resume gap by gap from the best
                step = 1
            else:
                misses += 1
    return best_k, best_x, best_S, best_A


@njit(cache=True)
def adhesive_model(u, law, x, R, kc, d_end, lam, lt_tab, y_tab):  # pragma: no cover - compiled
    """The law's force [N] at each tip depth u, baseline excluded, at x = (E, w, cj, b) (as in
    :func:`adhesive_normal`: contact where u > cj)."""
    E, w, cj = x[0], x[1], x[2]
    fs = math.pi * w * R
    K = kc * E
    ds = (math.pi * math.pi * w * w * R / (K * K)) ** (1.0 / 3.0)
    out = np.zeros(u.size)
    for i in range(u.size):
        if u[i] > cj:
            out[i] = fs * branch_point(law, (u[i] - cj) / ds + d_end, lam, lt_tab, y_tab)[1]
    return out
