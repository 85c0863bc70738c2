"""The compiled integrator before issue 11.8 (commit 545d9a1: one 588-line module, 31
positional arguments), kept only for the in-process A/B of ``benchmarks/bench_ab.py``.
Not part of the package; imports its unchanged helpers from it.

Compiled Radau IIA (order 5) integrator with dense output and event location.

Method: the three-stage Radau IIA collocation method of order 5, L-stable and
stiffly accurate, implemented after Hairer & Wanner, *Solving Ordinary
Differential Equations II* (2nd ed., Springer 1996), section IV.8 (code
RADAU5), in the formulation of ``scipy.integrate.Radau``:

* simplified Newton iterations on the transformed stage equations (one real
  and one complex linear system of size n per iteration, reduced to size
  n/2 by the second-order structure ``J = [[0, I], [Jq, Jv]]`` of the models:
  Schur complement on the position block, :mod:`._linalg`), the Jacobian
  reused until Newton converges slowly, factors reused while the step size
  is unchanged;
* embedded error estimate filtered through ``(I - h gamma0 J)^-1`` (so stiff
  components do not spoil it), with the improved estimate after a rejection;
* step-size control with the predictive (Gustafsson) controller;
* dense output from the collocation polynomial (cubic in the step fraction).

Everything is compiled with numba (``cache=True``) around the model
functions of :mod:`afmforce.dynamics.models`. One call integrates one segment
of the piecewise-linear drive (so the kink of ``z(t)`` is never stepped over),
samples the solution on the instrument's time grid, locates events inside
each accepted step on the dense output (:mod:`._locate`), and may stop at a
terminal event (turn at a load) or pause after a number of steps (progress
reporting). All integrator state lives in small work arrays, so a paused
call resumes exactly.

A failure never passes silently: the return code says why the segment did
not reach its end (see ``STATUS``), and :func:`afmforce.dynamics.simulate`
turns it into a :class:`~afmforce.errors.SolverError`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from afmforce.dynamics._linalg import _rms, _schur_factor, _schur_factor_complex, _solve_complex, _solve_real
from afmforce.dynamics._locate import (  # noqa: F401  (re-exported: the event layout used by simulate)
    APPROACH, DWELL, E_CONTACT_T, E_CONTACT_Z, E_H_CONTACT, E_IN_CONTACT, E_JUMP_FACTOR,
    E_FAST_T, E_FAST_Z, E_H_STATIC, E_JUMP_H, E_JUMP_T, E_JUMP_Z, E_LAST_OUT, E_MIN_DEFL, E_MIN_DEFL_Z, E_MIN_FZ, E_MIN_FZ_Z,
    E_MIN_THETA, E_MIN_THETA_Z, E_PULL_T, E_PULL_Z, E_SIZE, E_SPIKE_T, E_SPIKE_THETA,
    E_RING_AMP, E_SPIKE_WINDOW, E_SPIKE_Z, E_TERM_T, RETRACT, TERM_DEFLECTION, TERM_FORCE, TERM_NONE,
    _bisect, _dense, _eval_obs, _events)
from afmforce.dynamics.models import (HQA, HQB, K_EFF, N_OBS, O_DEFL, O_FZ, contact_frequency, error_frequency,
                     jac, observe, rhs, ringing_amplitude)

# --- return codes -----------------------------------------------------------
DONE = 0            # reached the end of the segment
TERMINAL = 1        # stopped at the terminal event (turn at a load)
PAUSED = 2          # paused after `chunk_steps` steps; call again to resume
MAX_STEPS = -1
STEP_TOO_SMALL = -2
NONFINITE = -3
NEWTON_FAILED = -4
STATUS = {
    DONE: "success",
    TERMINAL: "success",
    PAUSED: "paused",
    MAX_STEPS: "max_steps_exceeded",
    STEP_TOO_SMALL: "step_size_too_small",
    NONFINITE: "nonfinite_state",
    NEWTON_FAILED: "newton_failed_at_fixed_step",
}

# --- work array layout (float) ---------------------------------------------
W_T = 0            # current time
W_H = 1            # proposed next step size
W_H_OLD = 2        # previous accepted step size (0: none)
W_ERR_OLD = 3      # previous error norm (0: none)
W_HAS_SOL = 4      # 1 if Q/y_old/t_old/h_last hold the last step's polynomial
W_T_OLD = 5
W_H_LAST = 6
W_CUR_JAC = 7      # 1 if J was evaluated at the current state
W_HAVE_JAC = 8     # 1 if J holds any Jacobian
W_VFAC = 9         # velocity tolerance = atol * W_VFAC * error_frequency (0: atol[n-1] only)
W_SIZE = 10

# --- statistics (int) -------------------------------------------------------
S_STEPS, S_ACCEPTED, S_REJECTED, S_NFEV, S_NJEV, S_NLU, S_DAMPED, S_NEWTON_FAIL = range(8)
S_SIZE = 8

NEWTON_MAXITER = 6
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0

_S6 = math.sqrt(6.0)
C1 = (4.0 - _S6) / 10.0
C2 = (4.0 + _S6) / 10.0
E1 = (-13.0 - 7.0 * _S6) / 3.0
E2 = (-13.0 + 7.0 * _S6) / 3.0
E3 = -1.0 / 3.0
MU_REAL = 3.0 + 3.0 ** (2.0 / 3.0) - 3.0 ** (1.0 / 3.0)
MU_CR = 3.0 + 0.5 * (3.0 ** (1.0 / 3.0) - 3.0 ** (2.0 / 3.0))
MU_CI = -0.5 * (3.0 ** (5.0 / 6.0) + 3.0 ** (7.0 / 6.0))
T_ = np.array([
    [0.09443876248897524, -0.14125529502095421, 0.03002919410514742],
    [0.25021312296533332, 0.20412935229379994, -0.38294211275726192],
    [1.0, 1.0, 0.0]])
TI_ = np.array([
    [4.17871859155190428, 0.32768282076106237, 0.52337644549944951],
    [-4.17871859155190428, -0.32768282076106237, 0.47662355450055044],
    [0.50287263494578682, -2.57192694985560522, 0.59603920482822492]])
P_ = np.array([
    [13.0 / 3.0 + 7.0 * _S6 / 3.0, -23.0 / 3.0 - 22.0 * _S6 / 3.0, 10.0 / 3.0 + 5.0 * _S6],
    [13.0 / 3.0 - 7.0 * _S6 / 3.0, -23.0 / 3.0 + 22.0 * _S6 / 3.0, 10.0 / 3.0 - 5.0 * _S6],
    [1.0 / 3.0, -8.0 / 3.0, 10.0 / 3.0]])
EPS = np.finfo(float).eps


@njit(cache=True, error_model="numpy")
def _accumulate_windows(t_old, t_new, h, y_old, Q, s_t0, s_dt, s_next, ybuf):
    """Add the integral of the step's dense polynomial over each sample window it overlaps.

    Window ``k`` is ``[s_t0 + (k - 1/2) s_dt, s_t0 + (k + 1/2) s_dt]``; the
    polynomial is ``y_old + Q [s, s^2, s^3]`` on ``[t_old, t_old + h]``, so its
    integral over ``[a, b]`` is exact: ``h * sum_j c_j (s_b^(j+1) - s_a^(j+1)) / (j+1)``.
    """
    n = y_old.shape[0]
    half = 0.5 * s_dt
    k = s_next[0]
    while k < ybuf.shape[0]:
        ts = s_t0 + k * s_dt
        lo = ts - half
        if lo >= t_new:
            break
        hi = ts + half
        a = max(lo, t_old)
        b = min(hi, t_new)
        if b > a:
            sa = (a - t_old) / h
            sb = (b - t_old) / h
            d1 = sb - sa
            d2 = (sb * sb - sa * sa) * 0.5
            d3 = (sb * sb * sb - sa * sa * sa) / 3.0
            d4 = (sb * sb * sb * sb - sa * sa * sa * sa) * 0.25
            for i in range(n):
                ybuf[k, i] += h * (y_old[i] * d1 + Q[i, 0] * d2 + Q[i, 1] * d3 + Q[i, 2] * d4)
            ybuf[k, n] += b - a
        if hi <= t_new:
            k += 1
        else:
            break
    s_next[0] = k


@njit(cache=True, error_model="numpy", nogil=True)
def integrate_segment(model, p, kind, t_a, z_a, v, t_end, y, rtol, rtolv, atol,
                      hmax_frac, hmax_dz, damp_cycles, damp_kappa, term_kind, term_level,
                      s_t0, s_dt, s_next, ybuf, ev, work, Q, y_old, J, stats,
                      max_steps, chunk_steps, h_fixed=0.0, s_avg=0.0):
    """Integrate one drive segment from ``work[W_T]`` to ``t_end``.

    Parameters (all arrays are updated in place)
    ----------
    model, p : int, float64[:]
        Model id and parameter vector (:mod:`.models`).
    kind : int
        Segment kind: APPROACH, RETRACT or DWELL (selects the events).
    t_a, z_a, v : float
        Drive ``z(t) = z_a + v (t - t_a)`` [s, m, m/s].
    t_end : float
        End time of the segment [s].
    y : float64[n]
        State at ``work[W_T]`` on entry, at the end (or pause) on exit.
    rtol : float; rtolv, atol : float64[n]
        Tolerances: error norm RMS of err / (atol + rtolv |y|); ``rtol`` sets
        the Newton tolerance.
    hmax_frac, hmax_dz : float
        Step bound: the drive may move at most ``max(hmax_frac * h, hmax_dz)``
        per step (h the separation), so no surface event is stepped over.
    damp_cycles, damp_kappa : float
        In-contact ringing treatment (0: resolve it). Otherwise, once the
        probe has stayed in contact (h < contact separation) for
        ``spike_window`` without bouncing out, and where the contact
        stiffness ``kappa = -Fs'(h)`` exceeds ``damp_kappa * k`` at both ends
        of the step, the step is never shorter than ``damp_cycles / omega_c``
        (omega_c the contact mode,
        :func:`~afmforce.dynamics.models.contact_frequency`) and such a step
        is accepted once its Newton iteration converges: Radau IIA's
        L-stability then damps the ringing (|R(i y)| < 0.06 for y >= 50)
        instead of resolving it. The slow motion stays accurate (stiffly
        accurate method; drive travel per step bounded by ``hmax_dz``).
    term_kind, term_level : int, float
        Terminal event: stop when Fz (TERM_FORCE) or the deflection
        (TERM_DEFLECTION) first exceeds ``term_level``.
    s_t0, s_dt : float
        Sample grid ``s_t0 + k s_dt``; ``s_next[0]`` is the next index to write
        into row ``k`` of ``ybuf``; rows beyond ``ybuf`` are not written.
    ev : float64[E_SIZE]
        Event record (see ``E_*``).
    work, Q, y_old, J, stats
        Integrator state (``W_*``), last dense polynomial, Jacobian, counters.
    max_steps, chunk_steps : int
        Total step budget; pause (return PAUSED) after ``chunk_steps`` steps.
    h_fixed : float
        If > 0, take fixed steps of this size without error control (for
        convergence-order tests); a Newton failure then returns NEWTON_FAILED.
    s_avg : float
        0: samples are the state at the grid times (point sampling). 1: each
        sample is the integral of the dense polynomial over its window
        ``[t_k - s_dt/2, t_k + s_dt/2]`` (exact, clipped to the integrated
        time), accumulated into ``ybuf[k, :n]`` with the covered time in
        ``ybuf[k, n]`` (``ybuf`` then has ``n + 1`` columns, zero-initialised);
        ``s_next[0]`` counts windows that are complete.

    Returns
    -------
    int
        DONE, TERMINAL, PAUSED or a negative failure code.
    """
    n = y.shape[0]
    I3 = 3 * n
    Z = np.zeros((3, n))
    W = np.zeros((3, n))
    Z0 = np.zeros((3, n))
    F = np.zeros((3, n))
    dW = np.zeros((3, n))
    fcur = np.empty(n)
    fnew = np.empty(n)
    ytmp = np.empty(n)
    yst = np.empty(n)
    scale = np.empty(n)
    err = np.empty(n)
    rr = np.empty(n)
    cc = np.empty(2 * n)
    # Newton matrices (mu I - J) in the second-order form of ._linalg (Schur complements)
    Sr = np.zeros((2, 2))
    Sc = np.zeros((2, 2, 2))        # complex entries as (re, im)
    det_r = 0.0
    det_cr = 0.0
    det_ci = 0.0
    o = np.empty(N_OBS)
    oprev = np.empty(N_OBS)
    have_lu = False
    lu_h = 0.0
    av = atol[n - 1]

    newton_tol = max(10.0 * EPS / rtol, min(0.03, math.sqrt(rtol)))
    t = work[W_T]
    zt = z_a + v * (t - t_a)
    if not rhs(model, p, zt, v, y, fcur):
        return NONFINITE
    stats[S_NFEV] += 1
    if work[W_HAVE_JAC] == 0.0:
        if not jac(model, p, zt, v, y, J):
            return NONFINITE
        stats[S_NJEV] += 1
        work[W_HAVE_JAC] = 1.0
        work[W_CUR_JAC] = 1.0
    current_jac = work[W_CUR_JAC] == 1.0
    h_abs = work[W_H]
    h_abs_old = work[W_H_OLD]
    err_old = work[W_ERR_OLD]
    steps_here = 0
    rate = 0.0
    n_iter = 0
    safety = 0.9

    while t < t_end:
        if stats[S_STEPS] >= max_steps:
            work[W_T] = t
            return MAX_STEPS
        if steps_here >= chunk_steps:
            work[W_T] = t
            work[W_H] = h_abs
            work[W_H_OLD] = h_abs_old
            work[W_ERR_OLD] = err_old
            work[W_CUR_JAC] = 1.0 if current_jac else 0.0
            return PAUSED
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        # step bound from the drive travel
        if v != 0.0:
            zt = z_a + v * (t - t_a)
            hsep = 0.0
            if model == 0:
                hsep = y[0] - zt
            else:
                hsep = p[HQA] * y[0] + p[HQB] * y[1] - zt
            max_step = max(hmax_frac * hsep, hmax_dz) / abs(v)
        else:
            max_step = t_end - t
        if h_fixed > 0.0:
            h_abs = h_fixed
            max_step = h_fixed
        if h_abs > max_step:
            h_abs = max_step
            h_abs_old = 0.0
            err_old = 0.0
        elif h_abs < min_step:
            h_abs = min_step
            h_abs_old = 0.0
            err_old = 0.0
        forced = False
        if damp_cycles > 0.0 and ev[E_IN_CONTACT] == 1.0 and \
                t >= ev[E_LAST_OUT] + ev[E_SPIKE_WINDOW]:
            zt = z_a + v * (t - t_a)
            wc, kappa = contact_frequency(model, p, zt, y)
            if kappa >= damp_kappa * p[K_EFF] and wc > 0.0 and \
                    ringing_amplitude(model, p, v, y, fcur, wc) <= ev[E_RING_AMP]:
                h_damp = min(damp_cycles / wc, max_step, t_end - t)
                if h_abs < h_damp:
                    h_abs = h_damp
                    forced = True
        accepted = False
        rejected = False
        t_new = t
        err_norm = 0.0
        while not accepted:
            if h_abs < min_step:
                work[W_T] = t
                return STEP_TOO_SMALL
            t_new = t + h_abs
            if t_new >= t_end or t_end - t_new < min_step:
                t_new = t_end
            h = t_new - t
            h_abs = h
            stats[S_STEPS] += 1
            steps_here += 1
            # predictor: extrapolate the last collocation polynomial
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
            zt = z_a + v * (t - t_a)
            av = atol[n - 1]
            if work[W_VFAC] > 0.0:
                av = min(av, atol[0] * work[W_VFAC] * error_frequency(model, p, zt, v, y))
            for i in range(n):
                ai = atol[i] if i < n // 2 else av
                scale[i] = ai + abs(y[i]) * rtolv[i]
            converged = False
            while not converged:
                if not have_lu or lu_h != h:
                    mr = MU_REAL / h
                    mcr = MU_CR / h
                    mci = MU_CI / h
                    det_r = _schur_factor(J, mr, Sr)
                    det_cr, det_ci = _schur_factor_complex(J, mcr, mci, Sc)
                    ok1 = det_r != 0.0
                    ok2 = det_cr != 0.0 or det_ci != 0.0
                    stats[S_NLU] += 1
                    if not (ok1 and ok2):
                        have_lu = False
                        break
                    have_lu = True
                    lu_h = h
                # --- simplified Newton on the transformed stage equations
                for st in range(3):
                    for i in range(n):
                        Z[st, i] = Z0[st, i]
                        W[st, i] = TI_[st, 0] * Z0[0, i] + TI_[st, 1] * Z0[1, i] + TI_[st, 2] * Z0[2, i]
                dw_old = -1.0
                rate = -1.0
                converged = False
                n_iter = 0
                mr = MU_REAL / h
                mcr = MU_CR / h
                mci = MU_CI / h
                nmax = 4 * NEWTON_MAXITER if forced else NEWTON_MAXITER
                for k in range(nmax):
                    n_iter = k + 1
                    good = True
                    for st in range(3):
                        cst = C1 if st == 0 else (C2 if st == 1 else 1.0)
                        tt = t + cst * h
                        for i in range(n):
                            yst[i] = y[i] + Z[st, i]
                        if not rhs(model, p, z_a + v * (tt - t_a), v, yst, ytmp):
                            good = False
                            break
                        stats[S_NFEV] += 1
                        for i in range(n):
                            F[st, i] = ytmp[i]
                    if not good:
                        break
                    for i in range(n):
                        fr = TI_[0, 0] * F[0, i] + TI_[0, 1] * F[1, i] + TI_[0, 2] * F[2, i]
                        fc1 = TI_[1, 0] * F[0, i] + TI_[1, 1] * F[1, i] + TI_[1, 2] * F[2, i]
                        fc2 = TI_[2, 0] * F[0, i] + TI_[2, 1] * F[1, i] + TI_[2, 2] * F[2, i]
                        rr[i] = fr - mr * W[0, i]
                        cc[i] = fc1 - mcr * W[1, i] + mci * W[2, i]
                        cc[n + i] = fc2 - mci * W[1, i] - mcr * W[2, i]
                    _solve_real(J, mr, Sr, det_r, rr)
                    _solve_complex(J, mcr, mci, Sc, det_cr, det_ci, cc)
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
                                        rate ** (nmax - k) / (1.0 - rate) * dwn > newton_tol):
                        break
                    for st in range(3):
                        for i in range(n):
                            W[st, i] += dW[st, i]
                    for st in range(3):
                        for i in range(n):
                            Z[st, i] = T_[st, 0] * W[0, i] + T_[st, 1] * W[1, i] + T_[st, 2] * W[2, i]
                    if dwn == 0.0 or (rate >= 0.0 and rate / (1.0 - rate) * dwn < newton_tol):
                        converged = True
                        break
                    dw_old = dwn
                if not converged:
                    if current_jac:
                        break
                    zt = z_a + v * (t - t_a)
                    if not jac(model, p, zt, v, y, J):
                        return NONFINITE
                    stats[S_NJEV] += 1
                    current_jac = True
                    have_lu = False
            if not converged:
                if h_fixed > 0.0:
                    work[W_T] = t
                    return NEWTON_FAILED
                h_abs *= 0.5
                have_lu = False
                rejected = True
                forced = False
                stats[S_REJECTED] += 1
                stats[S_NEWTON_FAIL] += 1
                continue
            # --- error estimate
            for i in range(n):
                ze = (E1 * Z[0, i] + E2 * Z[1, i] + E3 * Z[2, i]) / h
                ytmp[i] = y[i] + Z[2, i]
                err[i] = fcur[i] + ze
                ai = atol[i] if i < n // 2 else av
                scale[i] = ai + max(abs(y[i]), abs(ytmp[i])) * rtolv[i]
            _solve_real(J, MU_REAL / h, Sr, det_r, err)
            err_norm = _rms(err, scale)
            safety = 0.9 * (2 * NEWTON_MAXITER + 1) / (2 * NEWTON_MAXITER + n_iter)
            if rejected and err_norm > 1.0:
                for i in range(n):
                    yst[i] = y[i] + err[i]
                if rhs(model, p, z_a + v * (t - t_a), v, yst, fnew):
                    stats[S_NFEV] += 1
                    for i in range(n):
                        ze = (E1 * Z[0, i] + E2 * Z[1, i] + E3 * Z[2, i]) / h
                        err[i] = fnew[i] + ze
                    _solve_real(J, MU_REAL / h, Sr, det_r, err)
                    err_norm = _rms(err, scale)
            if not math.isfinite(err_norm):
                err_norm = 1e10
            if h_fixed > 0.0:
                err_norm = 1.0
            if forced and err_norm > 1.0:
                wc, kappa = contact_frequency(model, p, z_a + v * (t + h - t_a), ytmp)
                if kappa < damp_kappa * p[K_EFF]:
                    forced = False      # left the hard contact: normal error control
            if forced and err_norm > 1.0:
                # damping step (see docstring): accept, restart the controller
                stats[S_DAMPED] += 1
                accepted = True
                err_norm = 1.0
                h_abs_old = 0.0
                err_old = 0.0
            elif err_norm > 1.0:
                if h_abs_old > 0.0 and err_old > 0.0:
                    mult = h_abs / h_abs_old * (err_old / err_norm) ** 0.25
                else:
                    mult = 1.0
                factor = min(1.0, mult) * err_norm ** -0.25
                h_abs *= max(MIN_FACTOR, safety * factor)
                have_lu = False
                rejected = True
                stats[S_REJECTED] += 1
            else:
                accepted = True

        # --- accepted step [t, t_new]; ytmp holds y_new
        for i in range(n):
            if not math.isfinite(ytmp[i]):
                work[W_T] = t
                return NONFINITE
        zt_new = z_a + v * (t_new - t_a)
        if not rhs(model, p, zt_new, v, ytmp, fnew):
            work[W_T] = t
            return NONFINITE
        stats[S_NFEV] += 1
        # dense polynomial of this step (Q = Z^T P)
        for i in range(n):
            y_old[i] = y[i]
            for c in range(3):
                Q[i, c] = Z[0, i] * P_[0, c] + Z[1, i] * P_[1, c] + Z[2, i] * P_[2, c]
        t_old = t
        work[W_HAS_SOL] = 1.0
        work[W_T_OLD] = t_old
        work[W_H_LAST] = h
        # terminal event (turn at a load): retake the step to end there
        if term_kind != TERM_NONE:
            idx = O_FZ if term_kind == TERM_FORCE else O_DEFL
            observe(model, p, zt_new, v, ytmp, o)
            if o[idx] >= term_level:
                _eval_obs(model, p, t_a, z_a, v, t_old, h, y_old, Q, 0.0, yst, oprev)
                s_lo = 0.0
                if oprev[idx] >= term_level:
                    ev[E_TERM_T] = t_old
                    work[W_T] = t_old
                    return TERMINAL
                s_hit = _bisect(model, p, t_a, z_a, v, t_old, h, y_old, Q, s_lo, 1.0,
                                idx, term_level, 1.0, yst, o)
                t_hit = t_old + s_hit * h
                if t_hit - t_old < 2.0 * min_step:
                    ev[E_TERM_T] = t_old
                    work[W_T] = t_old
                    return TERMINAL
                t_end = t_hit
                h_abs = t_hit - t_old
                stats[S_REJECTED] += 1
                term_kind = TERM_NONE       # now a plain segment ending at t_hit
                ev[E_TERM_T] = t_hit
                continue
        stats[S_ACCEPTED] += 1
        # samples on the instrument grid
        if s_avg > 0.0:
            _accumulate_windows(t_old, t_new, h, y_old, Q, s_t0, s_dt, s_next, ybuf)
        k = ybuf.shape[0] if s_avg > 0.0 else s_next[0]
        while k < ybuf.shape[0]:
            ts = s_t0 + k * s_dt
            if ts > t_new:
                break
            if ts >= t_old:
                _dense(y_old, Q, (ts - t_old) / h, yst)
                for i in range(n):
                    ybuf[k, i] = yst[i]
            k += 1
        if s_avg <= 0.0:
            s_next[0] = k
        _events(model, p, kind, t_a, z_a, v, t_old, h, y_old, Q, ev, yst, o, oprev)
        # --- next step size, Jacobian reuse
        recompute_jac = n_iter > 2 and rate > 1e-3
        if h_abs_old > 0.0 and err_old > 0.0 and err_norm > 0.0:
            mult = h_abs / h_abs_old * (err_old / err_norm) ** 0.25
        else:
            mult = 1.0
        if err_norm > 0.0:
            factor = min(1.0, mult) * err_norm ** -0.25
        else:
            factor = MAX_FACTOR
        factor = min(MAX_FACTOR, safety * factor)
        if rejected:                    # RADAU5: no increase right after a rejection
            factor = min(factor, 1.0)
        if not recompute_jac and factor < 1.2:
            factor = 1.0
        t = t_new
        for i in range(n):
            y[i] = ytmp[i]
            fcur[i] = fnew[i]
        if recompute_jac:
            if not jac(model, p, zt_new, v, y, J):
                return NONFINITE
            stats[S_NJEV] += 1
            current_jac = True
            have_lu = False
        else:
            current_jac = False
        h_abs_old = h_abs
        err_old = err_norm
        h_abs = h_abs * factor

    work[W_T] = t
    work[W_H] = h_abs
    work[W_H_OLD] = h_abs_old
    work[W_ERR_OLD] = err_old
    work[W_CUR_JAC] = 1.0 if current_jac else 0.0
    if ev[E_TERM_T] == t and not math.isnan(ev[E_TERM_T]):
        return TERMINAL
    return DONE
