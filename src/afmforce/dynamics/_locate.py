"""Compiled event location on the dense output of accepted steps.

Called by :func:`afmforce.dynamics.radau.integrate_segment` after every accepted
step: evaluates the observables (:func:`afmforce.dynamics.models.observe`) at
``NSUB`` points of the step's collocation polynomial, locates crossings by
bisection on that polynomial, and keeps the running extrema. The meaning of
every event is documented in :mod:`afmforce.dynamics.events`.
"""

from __future__ import annotations

import math

from numba import njit

from .models import N_OBS, O_DEFL, O_FZ, O_H, O_HDOT, O_THETA, O_Z, observe

# --- events array layout (float, NaN = not found) ---------------------------
E_JUMP_T, E_JUMP_Z, E_JUMP_H = 0, 1, 2
E_CONTACT_T, E_CONTACT_Z = 3, 4
E_PULL_T, E_PULL_Z = 5, 6
E_MIN_DEFL, E_MIN_DEFL_Z = 7, 8            # min deflection before contact (approach)
E_MIN_THETA, E_MIN_THETA_Z = 9, 10         # min angle before contact (approach)
E_SPIKE_THETA, E_SPIKE_T, E_SPIKE_Z = 11, 12, 13   # max angle, jump-in -> contact + window
E_MIN_FZ, E_MIN_FZ_Z = 14, 15              # most negative Fz in contact on the retract
E_IN_CONTACT = 16                          # 1 while in contact
E_TERM_T = 17                              # time of the terminal event
E_H_CONTACT = 18                           # contact threshold separation [m] (input)
E_SPIKE_WINDOW = 19                        # spike search window after contact [s] (input)
E_JUMP_FACTOR = 20                         # jump-in criterion: h' < -factor * z' (input)
E_LAST_OUT = 21                            # last time h > contact separation (bounce) in contact
E_SIZE = 22

# segment kinds (= Trajectory.segment codes)
APPROACH, RETRACT, DWELL = 0, 1, 2
# terminal events
TERM_NONE, TERM_FORCE, TERM_DEFLECTION = 0, 1, 2

NSUB = 4            # dense-output points per step for extrema and crossings


@njit(cache=True, error_model="numpy")
def _dense(y_old, Q, s, out):
    """Collocation polynomial at step fraction s: y_old + Q [s, s^2, s^3]."""
    s2 = s * s
    s3 = s2 * s
    for i in range(y_old.shape[0]):
        out[i] = y_old[i] + Q[i, 0] * s + Q[i, 1] * s2 + Q[i, 2] * s3


@njit(cache=True, error_model="numpy")
def _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, s, ytmp, o):
    _dense(y_old, Q, s, ytmp)
    t = t0 + s * h
    observe(model, p, z_a + v * (t - t_a), v, ytmp, o)
    return t


@njit(cache=True, error_model="numpy")
def _bisect(model, p, t_a, z_a, v, t0, h, y_old, Q, s_lo, s_hi, idx, level, sign, ytmp, o):
    """Step fraction where obs[idx] crosses level (sign*(obs-level) turns > 0)."""
    for _ in range(50):
        s_mid = 0.5 * (s_lo + s_hi)
        _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, s_mid, ytmp, o)
        if sign * (o[idx] - level) > 0.0:
            s_hi = s_mid
        else:
            s_lo = s_mid
        if s_hi - s_lo < 1e-13:
            break
    return s_hi


@njit(cache=True, error_model="numpy")
def _events(model, p, kind, t_a, z_a, v, t0, h, y_old, Q, ev, ytmp, o, oprev):
    """Update the event record with the accepted step [t0, t0 + h]."""
    hc = ev[E_H_CONTACT]
    jf = ev[E_JUMP_FACTOR]
    _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, 0.0, ytmp, oprev)
    for k in range(1, NSUB + 1):
        s = k / NSUB
        t = _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, s, ytmp, o)
        s_prev = (k - 1) / NSUB
        if kind == APPROACH:
            if ev[E_IN_CONTACT] == 0.0:
                # jump-in criterion: first h' < -jf * z' before contact
                if math.isnan(ev[E_JUMP_T]) and o[O_HDOT] + jf * v < 0.0:
                    if oprev[O_HDOT] + jf * v >= 0.0:
                        sj = _bisect(model, p, t_a, z_a, v, t0, h, y_old, Q, s_prev, s,
                                     O_HDOT, -jf * v, -1.0, ytmp, o)
                    else:
                        sj = s_prev
                    tj = _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, sj, ytmp, o)
                    ev[E_JUMP_T] = tj
                    ev[E_JUMP_Z] = z_a + v * (tj - t_a)
                    ev[E_JUMP_H] = o[O_H]
                    ev[E_SPIKE_THETA] = o[O_THETA]
                    ev[E_SPIKE_T] = tj
                    ev[E_SPIKE_Z] = ev[E_JUMP_Z]
                    t = _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, s, ytmp, o)
                if o[O_H] < hc:
                    sc = _bisect(model, p, t_a, z_a, v, t0, h, y_old, Q, s_prev, s,
                                 O_H, hc, -1.0, ytmp, o)
                    tc = _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, sc, ytmp, o)
                    if not o[O_DEFL] >= ev[E_MIN_DEFL]:
                        ev[E_MIN_DEFL] = o[O_DEFL]
                        ev[E_MIN_DEFL_Z] = o[O_Z]
                    if not o[O_THETA] >= ev[E_MIN_THETA]:
                        ev[E_MIN_THETA] = o[O_THETA]
                        ev[E_MIN_THETA_Z] = o[O_Z]
                    ev[E_CONTACT_T] = tc
                    ev[E_CONTACT_Z] = z_a + v * (tc - t_a)
                    ev[E_IN_CONTACT] = 1.0
                    ev[E_LAST_OUT] = tc
                    if math.isnan(ev[E_SPIKE_T]):
                        ev[E_SPIKE_THETA] = o[O_THETA]
                        ev[E_SPIKE_T] = tc
                        ev[E_SPIKE_Z] = ev[E_CONTACT_Z]
                    t = _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, s, ytmp, o)
                else:
                    if not o[O_DEFL] >= ev[E_MIN_DEFL]:
                        ev[E_MIN_DEFL] = o[O_DEFL]
                        ev[E_MIN_DEFL_Z] = o[O_Z]
                    if not o[O_THETA] >= ev[E_MIN_THETA]:
                        ev[E_MIN_THETA] = o[O_THETA]
                        ev[E_MIN_THETA_Z] = o[O_Z]
            elif o[O_H] > hc:
                ev[E_LAST_OUT] = t      # bounced out of contact
            # spike: largest angle from jump-in (or contact) to contact + window
            if not math.isnan(ev[E_SPIKE_T]):
                if math.isnan(ev[E_CONTACT_T]) or t <= ev[E_CONTACT_T] + ev[E_SPIKE_WINDOW]:
                    if o[O_THETA] > ev[E_SPIKE_THETA]:
                        ev[E_SPIKE_THETA] = o[O_THETA]
                        ev[E_SPIKE_T] = t
                        ev[E_SPIKE_Z] = o[O_Z]
        elif kind == DWELL:
            if ev[E_IN_CONTACT] == 1.0 and o[O_H] > hc:
                ev[E_LAST_OUT] = t
        elif kind == RETRACT:
            if ev[E_IN_CONTACT] == 1.0:
                if o[O_H] > hc:
                    sp = _bisect(model, p, t_a, z_a, v, t0, h, y_old, Q, s_prev, s,
                                 O_H, hc, 1.0, ytmp, o)
                    tp = _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, sp, ytmp, o)
                    ev[E_PULL_T] = tp
                    ev[E_PULL_Z] = z_a + v * (tp - t_a)
                    ev[E_IN_CONTACT] = 0.0
                    t = _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, s, ytmp, o)
                elif not o[O_FZ] >= ev[E_MIN_FZ]:
                    ev[E_MIN_FZ] = o[O_FZ]
                    ev[E_MIN_FZ_Z] = o[O_Z]
        for i in range(N_OBS):
            oprev[i] = o[i]
