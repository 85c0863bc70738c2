"""Small dense linear algebra for the compiled integrator (LU with partial pivoting)."""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True, error_model="numpy")
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


@njit(cache=True, error_model="numpy")
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


@njit(cache=True, error_model="numpy")
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
# The same functions compile for a float or a complex ``mu``. Rounding: xq as
# accurate as the dense LU; xv carries an absolute error ~eps |bq| (bq a
# velocity residual, << the velocity tolerance atol * 10 w ~ 1e-5 m/s).

@njit(cache=True, error_model="numpy")
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


@njit(cache=True, error_model="numpy")
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


@njit(cache=True, error_model="numpy")
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


@njit(cache=True, error_model="numpy")
def _solve_complex(J, mu, S, det, c):
    """In place: ``c <- (mu I - J)^-1 c`` for complex ``mu``; ``c`` holds the real
    parts in ``c[:n]`` and the imaginary parts in ``c[n:]``."""
    n = J.shape[0]
    m = n // 2
    if m == 1:
        x0, _, x2, _ = _schur_solve(J, mu, S, det, complex(c[0], c[n]), 0j,
                                    complex(c[1], c[n + 1]), 0j)
        c[0] = x0.real
        c[1] = x2.real
        c[n] = x0.imag
        c[n + 1] = x2.imag
    else:
        x0, x1, x2, x3 = _schur_solve(J, mu, S, det, complex(c[0], c[n]), complex(c[1], c[n + 1]),
                                      complex(c[2], c[n + 2]), complex(c[3], c[n + 3]))
        c[0] = x0.real
        c[1] = x1.real
        c[2] = x2.real
        c[3] = x3.real
        c[n] = x0.imag
        c[n + 1] = x1.imag
        c[n + 2] = x2.imag
        c[n + 3] = x3.imag
