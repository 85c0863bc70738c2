"""Small dense linear algebra for the compiled integrator (LU with partial pivoting)."""

from __future__ import annotations

import math

from ._jit import piece


@piece()
def _lu_factor(A, piv):
    """In-place LU with partial pivoting. False if singular."""
    n = A.shape[0]
    for k in range(n):
        p = k
        amax = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > amax:
                amax = abs(A[i, k])
                p = i
        piv[k] = p
        if amax == 0.0 or not math.isfinite(amax):
            return False
        if p != k:
            for j in range(n):
                tmp = A[k, j]
                A[k, j] = A[p, j]
                A[p, j] = tmp
        for i in range(k + 1, n):
            A[i, k] /= A[k, k]
            f = A[i, k]
            for j in range(k + 1, n):
                A[i, j] -= f * A[k, j]
    return True


@piece()
def _lu_solve(LU, piv, b):
    """Solve in place with the factors of :func:`_lu_factor`."""
    n = LU.shape[0]
    for k in range(n):
        p = piv[k]
        if p != k:
            tmp = b[k]
            b[k] = b[p]
            b[p] = tmp
    for i in range(n):
        s = b[i]
        for j in range(i):
            s -= LU[i, j] * b[j]
        b[i] = s
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, n):
            s -= LU[i, j] * b[j]
        b[i] = s / LU[i, i]


@piece()
def _rms(v, scale):
    s = 0.0
    for i in range(v.shape[0]):
        r = v[i] / scale[i]
        s += r * r
    return math.sqrt(s / v.shape[0])


# --- second-order structure (Schur complement on the position block) ---------
# The models are mechanical systems y = (q, q'), so their Jacobian is
# J = [[0, I], [Jq, Jv]] (m = n/2 <= 2 degrees of freedom). The Newton systems
# of the Radau stages, (mu I - J) x = b with mu real or complex, then reduce to
#   S xq = bv + (mu I - Jv) bq,   xv = mu xq - bq,   S = mu^2 I - mu Jv - Jq,
# an m x m system (Cramer's rule for m = 2): one 2x2 real and one 2x2 complex
# solve replace the 4x4 real and 8x8 real LU of the general form (0.77x the
# time of a default Fig-5 run, 0.49x at tight tolerance; events unchanged).
# The complex one is written in real arithmetic. Rounding: xq as
# accurate as the dense LU; xv carries an absolute error ~eps |bq| (bq a
# velocity residual, << the velocity tolerance atol * 10 w ~ 1e-5 m/s).

@piece(python=True)
def _schur_factor(J, mu, S):
    """Fill ``S = mu^2 I - mu Jv - Jq`` (m x m) and return its determinant (0: singular)."""
    m = J.shape[0] // 2
    for i in range(m):
        for j in range(m):
            S[i, j] = -mu * J[m + i, m + j] - J[m + i, j]
        S[i, i] += mu * mu
    if m == 1:
        det = S[0, 0]
    elif m == 2:
        det = S[0, 0] * S[1, 1] - S[0, 1] * S[1, 0]
    else:   # not a model of this package (state_size <= 4)
        det = 0.0 * mu
    if not math.isfinite(abs(det)):
        det = 0.0 * mu      # zero of mu's type: singular / non-finite
    return det


@piece()
def _schur_solve(J, mu, S, det, bq0, bq1, bv0, bv1):
    """Solve ``(mu I - J) x = b`` with the factor of :func:`_schur_factor`.

    ``b = (bq0, bq1, bv0, bv1)`` (for m = 1: ``(bq0, bv0)``, the others ignored);
    returns ``(xq0, xq1, xv0, xv1)`` in the same layout.
    """
    m = J.shape[0] // 2
    if m == 1:
        r0 = bv0 + (mu - J[1, 1]) * bq0
        xq0 = r0 / det
        return xq0, 0.0 * xq0, mu * xq0 - bq0, 0.0 * xq0
    r0 = bv0 + (mu - J[2, 2]) * bq0 - J[2, 3] * bq1
    r1 = bv1 - J[3, 2] * bq0 + (mu - J[3, 3]) * bq1
    xq0 = (S[1, 1] * r0 - S[0, 1] * r1) / det
    xq1 = (S[0, 0] * r1 - S[1, 0] * r0) / det
    return xq0, xq1, mu * xq0 - bq0, mu * xq1 - bq1


@piece(python=True)
def _solve_real(J, mu, S, det, b):
    """In place: ``b <- (mu I - J)^-1 b`` (real ``mu``, n = 2 or 4)."""
    m = J.shape[0] // 2
    if m == 1:
        x0, _, x2, _ = _schur_solve(J, mu, S, det, b[0], 0.0, b[1], 0.0)
        b[0] = x0
        b[1] = x2
    else:
        x0, x1, x2, x3 = _schur_solve(J, mu, S, det, b[0], b[1], b[2], b[3])
        b[0] = x0
        b[1] = x1
        b[2] = x2
        b[3] = x3


@piece(python=True)
def _schur_factor_complex(J, mr, mi, S):
    """:func:`_schur_factor` for ``mu = mr + i mi`` in real arithmetic.

    ``S[i, j, 0] + i S[i, j, 1]`` = ``mu^2 I - mu Jv - Jq``; returns the
    determinant as ``(re, im)`` (``(0, 0)``: singular). Written out in real
    parts (not numba's complex type) because it compiles several times faster.
    """
    m = J.shape[0] // 2
    m2r = mr * mr - mi * mi
    m2i = 2.0 * mr * mi
    for i in range(m):
        for j in range(m):
            S[i, j, 0] = -mr * J[m + i, m + j] - J[m + i, j]
            S[i, j, 1] = -mi * J[m + i, m + j]
        S[i, i, 0] += m2r
        S[i, i, 1] += m2i
    if m == 1:
        dr, di = S[0, 0, 0], S[0, 0, 1]
    elif m == 2:
        dr = (S[0, 0, 0] * S[1, 1, 0] - S[0, 0, 1] * S[1, 1, 1]
              - S[0, 1, 0] * S[1, 0, 0] + S[0, 1, 1] * S[1, 0, 1])
        di = (S[0, 0, 0] * S[1, 1, 1] + S[0, 0, 1] * S[1, 1, 0]
              - S[0, 1, 0] * S[1, 0, 1] - S[0, 1, 1] * S[1, 0, 0])
    else:   # not a model of this package (state_size <= 4)
        dr, di = 0.0, 0.0
    if not (math.isfinite(dr) and math.isfinite(di)):
        dr, di = 0.0, 0.0
    return dr, di


@piece()
def _cdiv(ar, ai, br, bi):
    """(ar + i ai) / (br + i bi) (Smith's algorithm)."""
    if abs(br) >= abs(bi):
        r = bi / br
        d = br + bi * r
        return (ar + ai * r) / d, (ai - ar * r) / d
    r = br / bi
    d = br * r + bi
    return (ar * r + ai) / d, (ai * r - ar) / d


@piece(python=True)
def _solve_complex(J, mr, mi, S, dr, di, c):
    """In place: ``c <- (mu I - J)^-1 c`` for ``mu = mr + i mi`` with the factor of
    :func:`_schur_factor_complex`; ``c`` holds the real parts in ``c[:n]`` and the
    imaginary parts in ``c[n:]``."""
    n = J.shape[0]
    m = n // 2
    if m == 1:
        bqr, bqi, bvr, bvi = c[0], c[n], c[1], c[n + 1]
        # r = bv + (mu - Jv) bq
        ar = mr - J[1, 1]
        rr = bvr + ar * bqr - mi * bqi
        ri = bvi + ar * bqi + mi * bqr
        xr, xi = _cdiv(rr, ri, dr, di)
        c[0] = xr
        c[n] = xi
        c[1] = mr * xr - mi * xi - bqr
        c[n + 1] = mr * xi + mi * xr - bqi
        return
    q0r, q1r, v0r, v1r = c[0], c[1], c[2], c[3]
    q0i, q1i, v0i, v1i = c[n], c[n + 1], c[n + 2], c[n + 3]
    a00 = mr - J[2, 2]
    a11 = mr - J[3, 3]
    # r = bv + (mu I - Jv) bq
    r0r = v0r + a00 * q0r - mi * q0i - J[2, 3] * q1r
    r0i = v0i + a00 * q0i + mi * q0r - J[2, 3] * q1i
    r1r = v1r - J[3, 2] * q0r + a11 * q1r - mi * q1i
    r1i = v1i - J[3, 2] * q0i + a11 * q1i + mi * q1r
    # Cramer: xq0 = (S11 r0 - S01 r1) / det, xq1 = (S00 r1 - S10 r0) / det
    n0r = S[1, 1, 0] * r0r - S[1, 1, 1] * r0i - S[0, 1, 0] * r1r + S[0, 1, 1] * r1i
    n0i = S[1, 1, 0] * r0i + S[1, 1, 1] * r0r - S[0, 1, 0] * r1i - S[0, 1, 1] * r1r
    n1r = S[0, 0, 0] * r1r - S[0, 0, 1] * r1i - S[1, 0, 0] * r0r + S[1, 0, 1] * r0i
    n1i = S[0, 0, 0] * r1i + S[0, 0, 1] * r1r - S[1, 0, 0] * r0i - S[1, 0, 1] * r0r
    x0r, x0i = _cdiv(n0r, n0i, dr, di)
    x1r, x1i = _cdiv(n1r, n1i, dr, di)
    c[0] = x0r
    c[1] = x1r
    c[n] = x0i
    c[n + 1] = x1i
    c[2] = mr * x0r - mi * x0i - q0r
    c[3] = mr * x1r - mi * x1i - q1r
    c[n + 2] = mr * x0i + mi * x0r - q0i
    c[n + 3] = mr * x1i + mi * x1r - q1i
