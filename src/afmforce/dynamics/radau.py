"""Compiled Radau IIA (order 5) integrator with dense output and event location.

Method: the three-stage Radau IIA collocation method of order 5, L-stable and
stiffly accurate, implemented after Hairer & Wanner, *Solving Ordinary
Differential Equations II* (2nd ed., Springer 1996), section IV.8 (code
RADAU5), in the formulation of ``scipy.integrate.Radau``:

* simplified Newton iterations on the transformed stage equations (one real
  and one complex linear system of size n per iteration, reduced to size
  n/2 by the second-order structure ``J = [[0, I], [Jq, Jv]]`` of the models:
  Schur complement on the position block, :mod:`._linalg`), the Jacobian
  reused until Newton converges slowly, factors reused while the step size
  is unchanged (:mod:`._radau_newton`);
* embedded error estimate filtered through ``(I - h gamma0 J)^-1`` (so stiff
  components do not spoil it), with the improved estimate after a rejection;
  step-size control with the predictive (Gustafsson) controller
  (:mod:`._radau_control`);
* dense output from the collocation polynomial (cubic in the step fraction),
  sampled on the instrument's grid (:mod:`._sampling`).

Everything is compiled with numba (``cache=True``) around the model functions of
:mod:`afmforce.dynamics.models`; this module holds the step loop and its records. One
call integrates one segment of the piecewise-linear drive (so the kink of ``z(t)`` is
never stepped over), samples the solution on the instrument's time grid, locates events
inside each accepted step on the dense output (:mod:`._locate`), and may stop at a
terminal event (turn at a load) or pause after a number of steps (progress reporting).
All integrator state lives in small work arrays, so a paused call resumes exactly.

A failure never passes silently: the return code says why the segment did
not reach its end (see ``STATUS``), and :func:`afmforce.dynamics.simulate`
turns it into a :class:`~afmforce.errors.SolverError`.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import njit

from ._jit import ENTRY, fmax, fmin
from ._locate import (  # noqa: F401  (re-exported: the event layout used by simulate)
    APPROACH, DWELL, E_CONTACT_T, E_CONTACT_Z, E_H_CONTACT, E_IN_CONTACT, E_JUMP_FACTOR,
    E_FAST_T, E_FAST_Z, E_H_STATIC, E_JUMP_H, E_JUMP_T, E_JUMP_Z, E_LAST_OUT, E_MIN_DEFL,
    E_MIN_DEFL_Z, E_MIN_FZ, E_MIN_FZ_Z, E_MIN_THETA, E_MIN_THETA_Z, E_PULL_T, E_PULL_Z, E_SIZE,
    E_SPIKE_T, E_SPIKE_THETA, E_RING_AMP, E_SPIKE_WINDOW, E_SPIKE_Z, E_TERM_T, RETRACT, E_SPIKE_CYCLES,
    TERM_DEFLECTION, TERM_FORCE, TERM_NONE, _events, _terminal_event)
from ._radau_control import (controller, damping_step, error_norm, error_scale,
                             improved_error_norm, left_hard_contact, max_step, next_step_factor,
                             safety_factor, velocity_atol)
from ._radau_newton import dense_coefficients, factorize, newton, predict
from ._radau_tableau import (  # noqa: F401  (re-exported: the state layout used by simulate)
    EPS, LU_DET_R, LU_H, LU_OK, LU_SIZE, MIN_FACTOR, NEWTON_MAXITER, S_ACCEPTED, S_DAMPED,
    S_NEWTON_FAIL, S_NFEV, S_NJEV, S_NLU, S_REJECTED, S_SIZE, S_STEPS, W_CUR_JAC,
    W_ERR_OLD, W_H, W_H_LAST, W_H_OLD, W_HAS_SOL, W_HAVE_JAC, W_SIZE, W_T, W_T_OLD, W_VFAC)
from ._sampling import sample_step
from .models import N_OBS, jac, rhs

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

# --- the records passed to integrate_segment --------------------------------
# Python passes plain tuples in these field orders (numba dispatches plain tuples in C,
# named tuples ~5x slower: what a short run would pay per segment); the compiled code
# turns them into these named tuples. Build them with the functions below, which also
# fix the types (one compiled specialisation).

#: Drive segment ``z(t) = z_a + v (t - t_a)`` up to ``t_end`` [s, m, m/s, s], its kind
#: (APPROACH, RETRACT, DWELL: selects the events) and terminal event: stop when Fz
#: (TERM_FORCE) or the deflection (TERM_DEFLECTION) first reaches ``term_level``.
Drive = namedtuple("Drive", "kind t_a z_a v t_end term_kind term_level")
#: Error norm RMS of err / (atol + rtolv |y|) (atol, rtolv: float64[n]); ``rtol`` sets the
#: Newton tolerance.
Tolerances = namedtuple("Tolerances", "rtol rtolv atol")
#: Step bounds and budget: the drive moves at most ``max(hmax_frac * h, hmax_dz)`` per step
#: (h the separation); in-contact damping (``damp_cycles`` 0: resolve the ringing, else see
#: :func:`integrate_segment`); ``h_fixed`` > 0: fixed steps without error control (order
#: tests); ``max_steps`` in all, pause (PAUSED) after ``chunk_steps`` in this call.
StepControl = namedtuple("StepControl", "hmax_frac hmax_dz damp_cycles damp_kappa h_fixed "
                                        "max_steps chunk_steps")
#: Sample grid ``t0 + k dt``; ``average`` False: the state at the grid times into row k
#: of ``buf``, ``next[0]`` the next row; True: window means (see :mod:`._sampling`).
Sampling = namedtuple("Sampling", "t0 dt average next buf")
#: The state ``y`` (float64[n]) and everything kept between calls: the event record ``ev``
#: (``E_*``), ``work`` (``W_*``), the last dense polynomial ``Q``, ``y_old``, the
#: Jacobian ``J`` and the counters ``stats`` (``S_*``); all updated in place.
SolverState = namedtuple("SolverState", "y ev work Q y_old J stats")


def drive_record(kind, t_a, z_a, v, t_end, term_kind=TERM_NONE, term_level=0.0) -> tuple:
    """:data:`Drive` as the plain tuple :func:`integrate_segment` takes."""
    return (int(kind), float(t_a), float(z_a), float(v), float(t_end), int(term_kind),
            float(term_level))


def tolerance_record(rtol, rtolv, atol) -> tuple:
    """:data:`Tolerances` as a plain tuple."""
    return (float(rtol), rtolv, atol)


def control_record(hmax_frac, hmax_dz, damp_cycles, damp_kappa, max_steps, chunk_steps,
                   h_fixed=0.0) -> tuple:
    """:data:`StepControl` as a plain tuple."""
    return (float(hmax_frac), float(hmax_dz), float(damp_cycles), float(damp_kappa),
            float(h_fixed), int(max_steps), int(chunk_steps))


def sampling_record(t0, dt, average, next_index, buf) -> tuple:
    """:data:`Sampling` as a plain tuple (``next_index``: int64[1], ``buf``: float64[:, :])."""
    return (float(t0), float(dt), bool(average), next_index, buf)


def state_record(y, ev, work, Q, y_old, J, stats) -> tuple:
    """:data:`SolverState` as a plain tuple."""
    return (y, ev, work, Q, y_old, J, stats)


def new_state(y, ev) -> tuple:
    """:data:`SolverState` (plain tuple) with fresh work arrays for the state ``y``."""
    n = y.shape[0]
    return (y, ev, np.zeros(W_SIZE), np.zeros((n, 3)), np.zeros(n), np.zeros((n, n)),
            np.zeros(S_SIZE, dtype=np.int64))


@njit(cache=True, error_model="numpy", inline="always")
def _save(work, t, h_abs, h_abs_old, err_old, current_jac):
    work[W_T] = t
    work[W_H] = h_abs
    work[W_H_OLD] = h_abs_old
    work[W_ERR_OLD] = err_old
    work[W_CUR_JAC] = 1.0 if current_jac else 0.0


@njit(cache=True, error_model="numpy", nogil=True, **ENTRY)
def integrate_segment(model, p, drive, tolerances, control, sampling, state):
    """Integrate one drive segment from ``work[W_T]`` to its end.

    Parameters (all arrays are updated in place)
    ----------
    model, p : int, float64[:]
        Model id and parameter vector (:mod:`.models`).
    drive, tolerances, control, sampling, state : tuple
        :data:`Drive`, :data:`Tolerances`, :data:`StepControl`, :data:`Sampling`,
        :data:`SolverState` as plain tuples (:func:`drive_record`, ...). ``state.y``
        holds the state at ``work[W_T]`` on entry, at the end (or pause) on exit.

    In-contact ringing (``control.damp_cycles`` > 0): once the probe has stayed in contact
    (h < contact separation) without bouncing out for ``spike_window``, or for
    ``ev[E_SPIKE_CYCLES]`` contact cycles both after contact and after the last spike
    maximum, and where the contact stiffness ``kappa = -Fs'(h)`` exceeds ``damp_kappa * k``
    at both ends of the step, the step is never shorter than ``damp_cycles / omega_c``
    (omega_c the contact mode, :func:`~afmforce.dynamics.models.contact_frequency`) and such
    a step is accepted once its Newton iteration converges: Radau IIA's L-stability then
    damps the ringing (|R(i y)| < 0.06 for y >= 50) instead of resolving it. The slow motion
    stays accurate (stiffly accurate method; drive travel per step bounded by ``hmax_dz``).

    Returns
    -------
    int
        DONE, TERMINAL, PAUSED or a negative failure code.
    """
    d = Drive(*drive)
    c = StepControl(*control)
    rtol, rtolv, atol = tolerances
    s_t0, s_dt, average, s_next, ybuf = sampling
    y, ev, work, Q, y_old, J, stats = state
    n = y.shape[0]
    # scratch (passed to the pieces one by one: see ._radau_newton). np.empty and loops, not
    # np.zeros (compiled per shape: 0.4 s of the first call); not views of one block (1.4x
    # the run time: LLVM then loses the shapes and that the arrays are distinct)
    Z0 = np.empty((3, n))               # predicted stages
    Z = np.empty((3, n))                # stage increments Y_i - y
    W = np.empty((3, n))                # transformed stages
    F = np.empty((3, n))                # f at the stages
    dW = np.empty((3, n))               # Newton increment
    fcur = np.empty(n)                  # f at the current state
    fnew = np.empty(n)                  # f at the new state
    ytmp = np.empty(n)                  # the new state (after the error estimate)
    yst = np.empty(n)                   # a stage or dense state
    scale = np.empty(n)
    err = np.empty(n)
    rr = np.empty(n)                    # real Newton system
    cc = np.empty(2 * n)                # complex Newton system (re, im)
    Sr = np.empty((2, 2))               # Schur factors (._linalg)
    Sc = np.empty((2, 2, 2))
    lu = np.empty(LU_SIZE)              # their determinants, validity, step (LU_*)
    o = np.empty(N_OBS)
    oprev = np.empty(N_OBS)
    for i in range(3):
        for j in range(n):
            Z0[i, j] = Z[i, j] = W[i, j] = F[i, j] = dW[i, j] = 0.0
    for i in range(2):
        for j in range(2):
            Sr[i, j] = Sc[i, j, 0] = Sc[i, j, 1] = 0.0
    for i in range(LU_SIZE):
        lu[i] = 0.0
    newton_tol = fmax(10.0 * EPS / rtol, fmin(0.03, math.sqrt(rtol)))
    t_end = d.t_end
    term_kind = d.term_kind
    t = work[W_T]
    if not rhs(model, p, d.z_a + d.v * (t - d.t_a), d.v, y, fcur):
        return NONFINITE
    stats[S_NFEV] += 1
    if work[W_HAVE_JAC] == 0.0:
        if not jac(model, p, d.z_a + d.v * (t - d.t_a), d.v, y, J):
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
        if stats[S_STEPS] >= c.max_steps:
            work[W_T] = t
            return MAX_STEPS
        if steps_here >= c.chunk_steps:
            _save(work, t, h_abs, h_abs_old, err_old, current_jac)
            return PAUSED
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        h_max = max_step(model, p, d, t, t_end, y, c.hmax_frac, c.hmax_dz)
        if c.h_fixed > 0.0:
            h_abs = c.h_fixed
            h_max = c.h_fixed
        if h_abs > h_max:
            h_abs = h_max
            h_abs_old = 0.0
            err_old = 0.0
        elif h_abs < min_step:
            h_abs = min_step
            h_abs_old = 0.0
            err_old = 0.0
        h_damp = damping_step(model, p, d, t, t_end, y, fcur, ev, c.damp_cycles, c.damp_kappa,
                              h_max)
        forced = h_abs < h_damp
        h_prop = h_abs                  # the controller's step, if a damping step fails
        if forced:
            h_abs = h_damp
        accepted = False
        rejected = False
        t_new = t
        err_n = 0.0
        # --- attempts at a step from t until one is accepted
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
            predict(t, h, y, y_old, Q, work, Z0, ytmp)
            av = velocity_atol(model, p, d, t, y, atol, work)
            error_scale(y, atol, av, rtolv, scale)
            nmax = 4 * NEWTON_MAXITER if forced else NEWTON_MAXITER
            # Newton; once more with a fresh Jacobian if an old one does not converge
            converged = False
            while True:
                if (lu[LU_OK] == 0.0 or lu[LU_H] != h) and \
                        not factorize(J, h, Sr, Sc, lu, stats):
                    break
                converged, n_iter, rate = newton(model, p, d, t, h, y, J, Sr, Sc, lu, scale,
                                                 newton_tol, nmax, Z0, Z, W, F, dW, rr, cc,
                                                 ytmp, yst, stats)
                if converged or current_jac:
                    break
                if not jac(model, p, d.z_a + d.v * (t - d.t_a), d.v, y, J):
                    return NONFINITE
                stats[S_NJEV] += 1
                current_jac = True
                lu[LU_OK] = 0.0
            if not converged:
                if c.h_fixed > 0.0:
                    work[W_T] = t
                    return NEWTON_FAILED
                # a failed damping step falls back to the controller's step, not to half
                # the damping step (which cascaded through ~4 more failures, issue 16)
                # (and does not count as a rejection of the controller's step)
                if forced:
                    h_abs = h_prop
                else:
                    h_abs *= 0.5
                    rejected = True
                lu[LU_OK] = 0.0
                forced = False
                stats[S_REJECTED] += 1
                stats[S_NEWTON_FAIL] += 1
                continue
            err_n = error_norm(h, y, fcur, J, Sr, lu[LU_DET_R], Z, atol, av, rtolv, ytmp,
                               err, scale)
            if rejected and err_n > 1.0:
                err_n = improved_error_norm(model, p, d, t, h, y, J, Sr, lu[LU_DET_R], Z,
                                            err, scale, yst, fnew, stats, err_n)
            if not math.isfinite(err_n):
                err_n = 1e10
            safety = safety_factor(n_iter)
            if c.h_fixed > 0.0:
                err_n = 1.0
            if forced and err_n > 1.0 and \
                    left_hard_contact(model, p, d, t + h, ytmp, c.damp_kappa):
                forced = False      # left the hard contact: normal error control
            if forced and err_n > 1.0:
                # damping step (see docstring): accept, restart the controller
                stats[S_DAMPED] += 1
                accepted = True
                err_n = 1.0
                h_abs_old = 0.0
                err_old = 0.0
            elif err_n > 1.0:
                h_abs *= fmax(MIN_FACTOR, safety * controller(h_abs, h_abs_old, err_old, err_n))
                lu[LU_OK] = 0.0
                rejected = True
                stats[S_REJECTED] += 1
            else:
                accepted = True

        # --- accepted step [t, t_new]; ytmp holds y_new
        for i in range(y.shape[0]):
            if not math.isfinite(ytmp[i]):
                work[W_T] = t
                return NONFINITE
        zt_new = d.z_a + d.v * (t_new - d.t_a)
        if not rhs(model, p, zt_new, d.v, ytmp, fnew):
            work[W_T] = t
            return NONFINITE
        stats[S_NFEV] += 1
        dense_coefficients(y, Z, y_old, Q)
        t_old = t
        work[W_HAS_SOL] = 1.0
        work[W_T_OLD] = t_old
        work[W_H_LAST] = h
        # terminal event (turn at a load): retake the step to end there
        if term_kind != TERM_NONE:
            t_hit = _terminal_event(model, p, d.t_a, d.z_a, d.v, t_old, h, y_old, Q, zt_new,
                                    ytmp, term_kind, d.term_level, yst, o, oprev)
            if not math.isnan(t_hit):
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
        sample_step(t_old, t_new, h, y_old, Q, s_t0, s_dt, average, s_next, ybuf, yst)
        _events(model, p, d.kind, d.t_a, d.z_a, d.v, t_old, h, y_old, Q, ev, yst, o,
                oprev)
        # --- next step size, Jacobian reuse
        recompute_jac = n_iter > 2 and rate > 1e-3
        factor = next_step_factor(h_abs, h_abs_old, err_old, err_n, safety, rejected,
                                  recompute_jac)
        t = t_new
        for i in range(y.shape[0]):
            y[i] = ytmp[i]
            fcur[i] = fnew[i]
        if recompute_jac:
            if not jac(model, p, zt_new, d.v, y, J):
                return NONFINITE
            stats[S_NJEV] += 1
            current_jac = True
            lu[LU_OK] = 0.0
        else:
            current_jac = False
        h_abs_old = h_abs
        err_old = err_n
        h_abs = h_abs * factor

    _save(work, t, h_abs, h_abs_old, err_old, current_jac)
    if ev[E_TERM_T] == t and not math.isnan(ev[E_TERM_T]):
        return TERMINAL
    return DONE

