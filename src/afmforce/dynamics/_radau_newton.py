"""The stage equations of one Radau IIA step: predictor, factors, simplified Newton iteration.

Simplified Newton iterations on the transformed stage equations (one real and
one complex linear system of size n per iteration, reduced to size n/2 by the
second-order structure ``J = [[0, I], [Jq, Jv]]`` of the models: Schur
complement on the position block, :mod:`._linalg`); the Jacobian is reused
until Newton converges slowly, the factors while the step size is unchanged
(Hairer & Wanner IV.8, in the formulation of ``scipy.integrate.Radau``).

The pieces of the step (here, in :mod:`._radau_control` and :mod:`._sampling`)
are compiled with ``forceinline=True`` (LLVM inlines them into the step loop of
:func:`afmforce.dynamics.radau.integrate_segment`, as if written there) and
``_nrt=False`` (they allocate nothing, so they need no reference counting of
their array arguments); their arrays are passed one by one, never in tuples.
Measured (``benchmarks/bench_ab.py``, against the former single function): as
plain calls 1.14x the time, as plain calls with the scratch arrays in a named
tuple 1.5x, with ``forceinline`` alone 1.01x, with both 0.92x.
"""

from __future__ import annotations

import math

from ._jit import piece

from ._linalg import _schur_factor, _schur_factor_complex, _solve_complex, _solve_real
from ._locate import _dense
from ._radau_tableau import (C1, C2, LU_DET_CI, LU_DET_CR, LU_DET_R, LU_H, LU_OK, MU_CI,
                             MU_CR, MU_REAL, P_, S_NFEV, S_NLU, T_, TI_, W_H_LAST, W_HAS_SOL, W_T_OLD)
from .models import rhs


@piece(inline=True)
def predict(t, h, y, y_old, Q, work, Z0, ytmp):
    """Starting stages ``Z0``: the last step's collocation polynomial extrapolated
    (zero when there is none or the new step is over 10x longer)."""
    n = y.shape[0]
    if work[W_HAS_SOL] == 1.0 and h <= 10.0 * work[W_H_LAST]:
        hl = work[W_H_LAST]
        for st in range(3):
            cst = C1 if st == 0 else (C2 if st == 1 else 1.0)
            s = (t + cst * h - work[W_T_OLD]) / hl
            _dense(y_old, Q, s, ytmp)
            for i in range(n):
                Z0[st, i] = ytmp[i] - y[i]
    else:
        for st in range(3):
            for i in range(n):
                Z0[st, i] = 0.0


@piece(inline=True)
def factorize(J, h, Sr, Sc, lu, stats):
    """Factor ``(mu I - J)`` for the real and the complex eigenvalue of the method at step
    ``h`` (Schur complements ``Sr``, ``Sc``; determinants, validity and ``h`` into ``lu``,
    layout ``LU_*``). False if either system is singular."""
    det_r = _schur_factor(J, MU_REAL / h, Sr)
    det_cr, det_ci = _schur_factor_complex(J, MU_CR / h, MU_CI / h, Sc)
    lu[LU_DET_R] = det_r
    lu[LU_DET_CR] = det_cr
    lu[LU_DET_CI] = det_ci
    stats[S_NLU] += 1
    if not (det_r != 0.0 and (det_cr != 0.0 or det_ci != 0.0)):
        lu[LU_OK] = 0.0
        return False
    lu[LU_OK] = 1.0
    lu[LU_H] = h
    return True


@piece(inline=True)
def _ipow(x, m):
    """``x ** m`` for an integer ``m >= 0`` by repeated squaring, as numba compiles ``**`` with
    an integer exponent (Python's ``pow`` rounds otherwise: the kernels run as Python give the
    compiled results bitwise, cli/_firstrun.py)."""
    r = 1.0
    while m != 0:
        if m & 1:
            r *= x
        m >>= 1
        x *= x
    return r


@piece(inline=True)
def newton(model, p, drive, t, h, y, J, Sr, Sc, lu, scale, newton_tol, nmax, Z0, Z, W, F, dW,
           rr, cc, ytmp, yst, stats):
    """Simplified Newton iterations from ``Z0`` with the factors of :func:`factorize`.

    ``scale`` is the error scale of the increments, ``newton_tol`` the
    convergence tolerance, ``nmax`` the most iterations; ``W`` (transformed
    stages), ``F`` (f at the stages), ``dW`` (increment), all (3, n), ``rr`` (n),
    ``cc`` (2n), ``ytmp``, ``yst`` (n) are scratch. Returns ``(converged, iterations, rate)``;
    on success ``Z`` holds the stage increments ``Y_i - y`` at ``t + c_i h``.
    """
    n = y.shape[0]
    I3 = 3 * n
    for st in range(3):
        for i in range(n):
            Z[st, i] = Z0[st, i]
            W[st, i] = (TI_[st, 0] * Z0[0, i] + TI_[st, 1] * Z0[1, i]
                                + TI_[st, 2] * Z0[2, i])
    dw_old = -1.0
    rate = -1.0
    converged = False
    n_iter = 0
    mr = MU_REAL / h
    mcr = MU_CR / h
    mci = MU_CI / h
    for k in range(nmax):
        n_iter = k + 1
        good = True
        for st in range(3):
            cst = C1 if st == 0 else (C2 if st == 1 else 1.0)
            tt = t + cst * h
            for i in range(n):
                yst[i] = y[i] + Z[st, i]
            if not rhs(model, p, drive.z_a + drive.v * (tt - drive.t_a), drive.v, yst, ytmp):
                good = False
                break
            stats[S_NFEV] += 1
            for i in range(n):
                F[st, i] = ytmp[i]
        if not good:
            break
        for i in range(n):
            f0 = F[0, i]
            f1 = F[1, i]
            f2 = F[2, i]
            fr = TI_[0, 0] * f0 + TI_[0, 1] * f1 + TI_[0, 2] * f2
            fc1 = TI_[1, 0] * f0 + TI_[1, 1] * f1 + TI_[1, 2] * f2
            fc2 = TI_[2, 0] * f0 + TI_[2, 1] * f1 + TI_[2, 2] * f2
            rr[i] = fr - mr * W[0, i]
            cc[i] = fc1 - mcr * W[1, i] + mci * W[2, i]
            cc[n + i] = fc2 - mci * W[1, i] - mcr * W[2, i]
        _solve_real(J, mr, Sr, lu[LU_DET_R], rr)
        _solve_complex(J, mcr, mci, Sc, lu[LU_DET_CR], lu[LU_DET_CI], cc)
        dwn = 0.0
        for i in range(n):
            dW[0, i] = rr[i]
            dW[1, i] = cc[i]
            dW[2, i] = cc[n + i]
            for st in range(3):
                q = dW[st, i] / scale[i]
                dwn += q * q
        dwn = math.sqrt(dwn / I3)
        if not math.isfinite(dwn):
            break
        if dw_old >= 0.0:
            rate = dwn / dw_old
        if rate >= 0.0 and (rate >= 1.0 or
                            _ipow(rate, nmax - k) / (1.0 - rate) * dwn > newton_tol):
            break
        for st in range(3):
            for i in range(n):
                W[st, i] += dW[st, i]
        for st in range(3):
            for i in range(n):
                Z[st, i] = (T_[st, 0] * W[0, i] + T_[st, 1] * W[1, i]
                                    + T_[st, 2] * W[2, i])
        if dwn == 0.0 or (rate >= 0.0 and rate / (1.0 - rate) * dwn < newton_tol):
            converged = True
            break
        dw_old = dwn
    return converged, n_iter, rate


@piece(inline=True, cached=True)
def dense_coefficients(y, Z, y_old, Q):
    """Dense output of the accepted step: ``y_old = y``, ``Q = Z^T P`` (the collocation
    polynomial ``y_old + Q [s, s^2, s^3]`` in the step fraction ``s``)."""
    for i in range(y.shape[0]):
        y_old[i] = y[i]
        for c in range(3):
            Q[i, c] = (Z[0, i] * P_[0, c] + Z[1, i] * P_[1, c]
                       + Z[2, i] * P_[2, c])
