"""Compiled event location on the dense output of accepted steps.

Called by :func:`afmforce.dynamics.radau.integrate_segment` after every accepted
step (:func:`_events`; :func:`_terminal_event` for a turn at a load). The
observables (:func:`afmforce.dynamics.models.observe`) are scanned at ``NSUB``
points of the step's collocation polynomial; every crossing found is then
located by bisection on that polynomial (to 1e-13 of the step), and every new
running extremum by a golden-section search on the polynomial around the best
scan point (to 1e-9 of the step), so neither depends on ``NSUB`` beyond the
rule that a crossing pair or an extremum narrower than a quarter step could be
missed (steps are far shorter than any event feature, see the step bound).
The meaning of every event is documented in :mod:`afmforce.dynamics.events`.
"""

from __future__ import annotations

import math

from ._jit import fmax, fmin, piece
from .models import (HQA, HQB, MODEL_SPRING, N_OBS, O_DEFL, O_FZ, O_H, O_HDOT, O_THETA, O_Z,
                     TH_A, TH_B, drainage, observe, static_force)

# --- events array layout (float, NaN = not found) ---------------------------
E_JUMP_T, E_JUMP_Z, E_JUMP_H = 0, 1, 2     # leaves the static branch (h < h_s)
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
E_JUMP_FACTOR = 20                         # fast-approach criterion h' < -factor z' (input)
E_LAST_OUT = 21                            # last time h > contact separation (bounce) in contact
E_H_STATIC = 22                            # static instability separation h_s [m] (input)
E_FAST_T, E_FAST_Z = 23, 24                # first h' < -factor z' before contact
E_RING_AMP = 25                            # ringing amplitude below which damping is allowed (input)
E_SPIKE_CYCLES = 26                        # ringing resolved this many contact cycles past the spike (input)
E_SIZE = 27

# segment kinds (= Trajectory.segment codes)
APPROACH, RETRACT, DWELL = 0, 1, 2
# terminal events
TERM_NONE, TERM_FORCE, TERM_DEFLECTION = 0, 1, 2

NSUB = 4            # scan points per step (then bisection / golden section)
EXTREMUM_TOL = 1e-9     # an extremum is located to this fraction of the step
_GOLD = 0.3819660112501051


@piece()
def _dense(y_old, Q, s, out):
    """Collocation polynomial at step fraction s: y_old + Q [s, s^2, s^3]."""
    s2 = s * s
    s3 = s2 * s
    for i in range(y_old.shape[0]):
        out[i] = y_old[i] + Q[i, 0] * s + Q[i, 1] * s2 + Q[i, 2] * s3


@piece()
def _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, s, ytmp, o):
    _dense(y_old, Q, s, ytmp)
    t = t0 + s * h
    observe(model, p, z_a + v * (t - t_a), v, ytmp, o)
    return t


@piece()
def _value(model, p, zd, vd, y, idx, o):
    """``observe(model, p, zd, vd, y, o)[idx]`` by the same arithmetic, computing only what that
    observable needs (issue 35): no force for h, h', the deflection and the angle, no friction
    for Fz; any other ``idx``: :func:`~afmforce.dynamics.models.observe` into ``o``. The scans,
    bisections and golden sections read one observable at many points of a step."""
    if model == MODEL_SPRING:
        defl = y[0]
        hd = y[1] - vd
        theta = 0.0
    else:
        defl = p[HQA] * y[0] + p[HQB] * y[1]
        hd = p[HQA] * y[2] + p[HQB] * y[3] - vd
        theta = p[TH_A] * y[0] + p[TH_B] * y[1]
    if idx == O_DEFL:
        return defl
    if idx == O_THETA:
        return theta
    h = defl - zd
    if idx == O_H:
        return h
    if idx == O_HDOT:
        return hd
    if idx == O_FZ:
        fs, _ = static_force(model, h, p)
        fd, _, _ = drainage(model, h, hd, p)
        return fs + fd
    observe(model, p, zd, vd, y, o)
    return o[idx]


@piece()
def _eval_value(model, p, t_a, z_a, v, t0, h, y_old, Q, s, ytmp, idx, o):
    """Observable ``idx`` at step fraction ``s`` (:func:`_eval_obs`'s ``o[idx]``)."""
    _dense(y_old, Q, s, ytmp)
    t = t0 + s * h
    return _value(model, p, z_a + v * (t - t_a), v, ytmp, idx, o)


@piece()
def _bisect(model, p, t_a, z_a, v, t0, h, y_old, Q, s_lo, s_hi, idx, level, sign, ytmp, o):
    """Step fraction where obs[idx] crosses level (sign*(obs-level) turns > 0)."""
    for _ in range(50):
        s_mid = 0.5 * (s_lo + s_hi)
        val = _eval_value(model, p, t_a, z_a, v, t0, h, y_old, Q, s_mid, ytmp, idx, o)
        if sign * (val - level) > 0.0:
            s_hi = s_mid
        else:
            s_lo = s_mid
        if s_hi - s_lo < 1e-13:
            break
    return s_hi


@piece()
def _extremum(model, p, t_a, z_a, v, t0, h, y_old, Q, s_lo, s_hi, idx, sign, ytmp, o):
    """Golden-section search for the minimum of sign*obs[idx] on [s_lo, s_hi].

    Returns (s, value of obs[idx]); ``o`` holds the observables there.
    """
    a = s_lo
    b = s_hi
    c = b - (1.0 - _GOLD) * (b - a)
    d = a + (1.0 - _GOLD) * (b - a)
    fc = sign * _eval_value(model, p, t_a, z_a, v, t0, h, y_old, Q, c, ytmp, idx, o)
    fd = sign * _eval_value(model, p, t_a, z_a, v, t0, h, y_old, Q, d, ytmp, idx, o)
    for _ in range(60):
        if b - a < EXTREMUM_TOL:
            break
        if fc < fd:
            b = d
            d = c
            fd = fc
            c = b - (1.0 - _GOLD) * (b - a)
            fc = sign * _eval_value(model, p, t_a, z_a, v, t0, h, y_old, Q, c, ytmp, idx, o)
        else:
            a = c
            c = d
            fc = fd
            d = a + (1.0 - _GOLD) * (b - a)
            fd = sign * _eval_value(model, p, t_a, z_a, v, t0, h, y_old, Q, d, ytmp, idx, o)
    s = c if fc < fd else d
    _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, s, ytmp, o)
    return s, o[idx]


@piece(cached=True)
def _terminal_event(model, p, t_a, z_a, v, t0, h, y_old, Q, z_new, y_new, term_kind, level,
                    ytmp, o, oprev):
    """Where in the accepted step ``[t0, t0 + h]`` the terminal level is first reached.

    ``term_kind`` TERM_FORCE watches Fz, TERM_DEFLECTION the deflection; returns
    NaN if the step ends below ``level`` (``y_new`` at drive position ``z_new``),
    ``t0`` if it starts at or above it, otherwise the crossing time (bisection on
    the dense output).
    """
    idx = O_FZ if term_kind == TERM_FORCE else O_DEFL
    observe(model, p, z_new, v, y_new, o)
    if o[idx] < level:
        return math.nan
    _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, 0.0, ytmp, oprev)
    if oprev[idx] >= level:
        return t0
    s_hit = _bisect(model, p, t_a, z_a, v, t0, h, y_old, Q, 0.0, 1.0, idx, level, 1.0, ytmp, o)
    return t0 + s_hit * h


@piece()
def _scan_extremum(model, p, t_a, z_a, v, t0, h, y_old, Q, s_a, s_b, idx, sign, best,
                   ytmp, o):
    """Extremum of sign*obs[idx] over [s_a, s_b] if it beats ``sign*best`` (else NaN, NaN).

    Scans NSUB + 1 points, then refines around the best interior one.
    """
    kbest = -1
    vbest = sign * best if not math.isnan(best) else math.inf
    vals_s = s_a
    for k in range(NSUB + 1):
        s = s_a + (s_b - s_a) * k / NSUB
        val = _eval_value(model, p, t_a, z_a, v, t0, h, y_old, Q, s, ytmp, idx, o)
        if sign * val < vbest:
            vbest = sign * val
            kbest = k
            vals_s = s
    if kbest < 0:
        return math.nan, math.nan
    if kbest == 0 or kbest == NSUB:
        # the best scan point is an end of [s_a, s_b] and the observable is no better just
        # inside it: the extremum is that end (the golden section would converge to within
        # EXTREMUM_TOL of it and then keep the end; a running extremum that moves on every
        # step, as the approach's attraction or the adhesion does, costs 1 evaluation
        # instead of ~45: issue 35.5)
        s_in = vals_s + EXTREMUM_TOL if kbest == 0 else vals_s - EXTREMUM_TOL
        if sign * _eval_value(model, p, t_a, z_a, v, t0, h, y_old, Q, s_in, ytmp, idx,
                              o) >= vbest:
            _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, vals_s, ytmp, o)
            return vals_s, o[idx]
    ds = (s_b - s_a) / NSUB
    lo = fmax(s_a, vals_s - ds)
    hi = fmin(s_b, vals_s + ds)
    s, val = _extremum(model, p, t_a, z_a, v, t0, h, y_old, Q, lo, hi, idx, sign, ytmp, o)
    if sign * val > vbest:        # the scan point itself is better (end of the interval)
        s = vals_s
        _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, s, ytmp, o)
        val = o[idx]
    return s, val


@piece()
def _update_min(model, p, t_a, z_a, v, t0, h, y_old, Q, s_a, s_b, idx, sign, e_val, e_pos,
                e_time, ev, ytmp, o):
    """Running extremum (min of sign*obs[idx]) over [s_a, s_b] into ev[e_val], ev[e_pos]."""
    s, val = _scan_extremum(model, p, t_a, z_a, v, t0, h, y_old, Q, s_a, s_b, idx, sign,
                            ev[e_val], ytmp, o)
    if not math.isnan(s):
        ev[e_val] = val
        ev[e_pos] = o[O_Z]
        if e_time >= 0:
            ev[e_time] = t0 + s * h


@piece(cached=True)
def _events(model, p, kind, t_a, z_a, v, t0, h, y_old, Q, ev, ytmp, o, oprev):
    """Update the event record with the accepted step [t0, t0 + h]."""
    # ``r0`` is an int64 zero known only at run time: integer constants passed as
    # ``K + r0`` reach the callees as int64, not as literals, so that numba
    # compiles each callee once instead of once per constant (first call 2x faster)
    r0 = kind - kind
    hc = ev[E_H_CONTACT]
    jf = ev[E_JUMP_FACTOR]
    hs = ev[E_H_STATIC]
    if kind == APPROACH:
        s_end = 1.0
        if ev[E_IN_CONTACT] == 0.0:
            # contact inside this step?
            _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, 0.0, ytmp, oprev)
            s_prev = 0.0
            sc = math.nan
            for k in range(1, NSUB + 1):
                s = k / NSUB
                _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, s, ytmp, o)
                # leaves the static branch: first h < h_s
                if math.isnan(ev[E_JUMP_T]) and o[O_H] < hs:
                    if oprev[O_H] >= hs:
                        sj = _bisect(model, p, t_a, z_a, v, t0, h, y_old, Q, s_prev, s,
                                     O_H + r0, hs, -1.0, ytmp, o)
                    else:
                        sj = s_prev
                    tj = _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, sj, ytmp, o)
                    ev[E_JUMP_T] = tj
                    ev[E_JUMP_Z] = z_a + v * (tj - t_a)
                    ev[E_JUMP_H] = o[O_H]
                    if math.isnan(ev[E_SPIKE_T]):
                        ev[E_SPIKE_THETA] = o[O_THETA]
                        ev[E_SPIKE_T] = tj
                        ev[E_SPIKE_Z] = ev[E_JUMP_Z]
                    _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, s, ytmp, o)
                # fast approach: first h' < -jf z'
                if math.isnan(ev[E_FAST_T]) and o[O_HDOT] + jf * v < 0.0:
                    if oprev[O_HDOT] + jf * v >= 0.0:
                        sf = _bisect(model, p, t_a, z_a, v, t0, h, y_old, Q, s_prev, s,
                                     O_HDOT + r0, -jf * v, -1.0, ytmp, o)
                    else:
                        sf = s_prev
                    tf = t0 + sf * h
                    ev[E_FAST_T] = tf
                    ev[E_FAST_Z] = z_a + v * (tf - t_a)
                    _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, s, ytmp, o)
                if o[O_H] < hc:
                    sc = _bisect(model, p, t_a, z_a, v, t0, h, y_old, Q, s_prev, s,
                                 O_H + r0, hc, -1.0, ytmp, o)
                    break
                for i in range(N_OBS):
                    oprev[i] = o[i]
                s_prev = s
            s_end = 1.0 if math.isnan(sc) else sc
            # minima before contact
            _update_min(model, p, t_a, z_a, v, t0, h, y_old, Q, 0.0, s_end, O_DEFL + r0, 1.0,
                        E_MIN_DEFL + r0, E_MIN_DEFL_Z + r0, r0 - 1, ev, ytmp, o)
            _update_min(model, p, t_a, z_a, v, t0, h, y_old, Q, 0.0, s_end, O_THETA + r0, 1.0,
                        E_MIN_THETA + r0, E_MIN_THETA_Z + r0, r0 - 1, ev, ytmp, o)
            if not math.isnan(sc):
                tc = _eval_obs(model, p, t_a, z_a, v, t0, h, y_old, Q, sc, ytmp, o)
                ev[E_CONTACT_T] = tc
                ev[E_CONTACT_Z] = z_a + v * (tc - t_a)
                ev[E_IN_CONTACT] = 1.0
                ev[E_LAST_OUT] = tc
                if math.isnan(ev[E_SPIKE_T]):
                    ev[E_SPIKE_THETA] = o[O_THETA]
                    ev[E_SPIKE_T] = tc
                    ev[E_SPIKE_Z] = ev[E_CONTACT_Z]
        else:
            _last_out(model, p, t_a, z_a, v, t0, h, y_old, Q, ev, hc, O_H + r0, ytmp, o)
        # spike: largest angle from jump-in (or contact) to contact + window
        if not math.isnan(ev[E_SPIKE_T]):
            s_hi = 1.0
            if not math.isnan(ev[E_CONTACT_T]):
                s_hi = fmin(1.0, (ev[E_CONTACT_T] + ev[E_SPIKE_WINDOW] - t0) / h)
            s_lo = fmax(0.0, (ev[E_SPIKE_T] - t0) / h)
            if s_hi > s_lo:
                _update_min(model, p, t_a, z_a, v, t0, h, y_old, Q, s_lo, s_hi, O_THETA + r0,
                            -1.0, E_SPIKE_THETA + r0, E_SPIKE_Z + r0, E_SPIKE_T + r0, ev, ytmp, o)
    elif kind == DWELL:
        if ev[E_IN_CONTACT] == 1.0:
            _last_out(model, p, t_a, z_a, v, t0, h, y_old, Q, ev, hc, O_H + r0, ytmp, o)
    elif kind == RETRACT:
        if ev[E_IN_CONTACT] == 1.0:
            sp = math.nan
            s_prev = 0.0
            for k in range(1, NSUB + 1):
                s = k / NSUB
                if _eval_value(model, p, t_a, z_a, v, t0, h, y_old, Q, s, ytmp, O_H + r0,
                               o) > hc:
                    sp = _bisect(model, p, t_a, z_a, v, t0, h, y_old, Q, s_prev, s,
                                 O_H + r0, hc, 1.0, ytmp, o)
                    break
                s_prev = s
            s_end = 1.0 if math.isnan(sp) else sp
            _update_min(model, p, t_a, z_a, v, t0, h, y_old, Q, 0.0, s_end, O_FZ + r0, 1.0,
                        E_MIN_FZ + r0, E_MIN_FZ_Z + r0, r0 - 1, ev, ytmp, o)
            if not math.isnan(sp):
                tp = t0 + sp * h
                ev[E_PULL_T] = tp
                ev[E_PULL_Z] = z_a + v * (tp - t_a)
                ev[E_IN_CONTACT] = 0.0


@piece()
def _last_out(model, p, t_a, z_a, v, t0, h, y_old, Q, ev, hc, i_h, ytmp, o):
    """In contact: remember the last time the tip bounced out (h > hc; ``i_h`` = O_H)."""
    for k in range(NSUB, -1, -1):
        s = k / NSUB
        t = t0 + s * h
        if _eval_value(model, p, t_a, z_a, v, t0, h, y_old, Q, s, ytmp, i_h, o) > hc:
            if t > ev[E_LAST_OUT]:
                ev[E_LAST_OUT] = t
            return
