"""Samples of the compiled integrator on the instrument's time grid, from the dense output.

Two detectors: point sampling (the state at the grid times ``t0 + k dt``) and
averaging (each sample the exact mean of the collocation polynomial over its
window ``[t_k - dt/2, t_k + dt/2]``), selected by the ``average`` field of
:data:`afmforce.dynamics.radau.Sampling`.
"""

from __future__ import annotations

import math

from numba import njit

from ._jit import fmax, fmin, piece
from .models import (O_DEFL, O_FY, O_FZ, O_H, O_HDOT, O_THETA, O_Y2, O_Y2DOT, O_Z,
                     observables)


@piece(inline=True)
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
        a = fmax(lo, t_old)
        b = fmin(hi, t_new)
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


@piece(inline=True, cached=True)
def sample_step(t_old, t_new, h, y_old, Q, s_t0, s_dt, average, s_next, ybuf, ytmp):
    """Write the samples of the accepted step ``[t_old, t_new]`` into ``ybuf``.

    Point sampling: rows ``s_next[0]`` ... with grid time ``s_t0 + k s_dt`` <= ``t_new``
    get the dense state (NaN for a grid time before ``t_old``, which a run that starts
    on the grid never has: every row below ``s_next[0]`` is written, so the buffer
    needs no initial value); ``s_next[0]`` moves past them. Averaging: the step's
    integral is added to every window it overlaps (column ``n`` collects the
    covered time); ``s_next[0]`` counts the complete windows. Rows beyond
    ``ybuf`` are not written.
    """
    if average:
        _accumulate_windows(t_old, t_new, h, y_old, Q, s_t0, s_dt, s_next, ybuf)
        return
    # the polynomial's coefficients as scalars, loaded once a step (through the arrays, LLVM
    # reloaded them after every store into ybuf: 0.19 ms of the Fig-5 cycle's 31,001 samples;
    # issue 35.5, fifth pass); the arithmetic of ._locate._dense but for 1/h
    n = y_old.shape[0]
    four = n > 2
    y0, y1 = y_old[0], y_old[1]
    a0, b0, c0 = Q[0, 0], Q[0, 1], Q[0, 2]
    a1, b1, c1 = Q[1, 0], Q[1, 1], Q[1, 2]
    y2 = y_old[2] if four else 0.0
    y3 = y_old[3] if four else 0.0
    a2 = Q[2, 0] if four else 0.0
    b2 = Q[2, 1] if four else 0.0
    c2 = Q[2, 2] if four else 0.0
    a3 = Q[3, 0] if four else 0.0
    b3 = Q[3, 1] if four else 0.0
    c3 = Q[3, 2] if four else 0.0
    ih = 1.0 / h                # a multiplication a sample, not a division (issue 35.5:
    k = s_next[0]               # 0.161 -> 0.127 ms for Fig 5's 31,001 samples; 1 ulp of s)
    while k < ybuf.shape[0]:
        ts = s_t0 + k * s_dt
        if ts > t_new:
            break
        if ts >= t_old:
            s = (ts - t_old) * ih
            s2 = s * s
            s3 = s2 * s
            ybuf[k, 0] = y0 + a0 * s + b0 * s2 + c0 * s3
            ybuf[k, 1] = y1 + a1 * s + b1 * s2 + c1 * s3
            if four:
                ybuf[k, 2] = y2 + a2 * s + b2 * s2 + c2 * s3
                ybuf[k, 3] = y3 + a3 * s + b3 * s2 + c3 * s3
        else:                       # a grid time before the step (none expected): no value
            for i in range(n):
                ybuf[k, i] = math.nan
        k += 1
    s_next[0] = k


@njit(cache=True, error_model="numpy", nogil=True)
def sample_columns(model, p, ybuf, n, averaged, dt, seg_first, seg_last, seg_kind, seg_t0,
                   seg_z0, seg_v, beam, beta, tt, zd, code, obs, app, app_sep):
    """Time, drive, segment code, observables and apparent deflection of the first ``n``
    samples, written into the first ``n`` rows of ``tt, zd, code, obs, app, app_sep``.

    Row ``k`` of ``ybuf`` holds the state at ``t = k dt`` (``averaged``: its window sums, with
    the covered time in the last column; the state is their ratio). Samples ``seg_first[j]``
    to ``seg_last[j] - 1`` belong to drive segment ``j`` (``z = seg_z0 + seg_v (t -
    seg_t0)``). ``app`` is ``beta * theta`` for the beam (``beam``), the deflection for the
    spring; ``app_sep = app - z``. The outputs come from the caller (allocated in the thread
    that prepares the run, :class:`~afmforce.dynamics.simulate._Run`). ``nogil``: in
    :func:`afmforce.dynamics.simulate_many` it overlaps the other threads' integrations.
    Returns whether every state is finite."""
    ns = ybuf.shape[1] - 1 if averaged else ybuf.shape[1]
    four = ns > 2
    # one pass over the rows (issue 35: three passes read and wrote ~4 MB on Fig 5), a loop per
    # drive segment (sample ranges in order, not overlapping, as simulate builds them; a row in
    # none gets code 0 and NaN), the state as scalars (issue 35.5, fifth pass: 0.34 -> 0.25 ms
    # on Fig 5, bitwise the same). ``bad`` sums ``0 * state``: NaN if any state is not finite
    bad = 0.0
    k0 = 0
    for j in range(seg_first.shape[0] + 1):
        a = n if j == seg_first.shape[0] else max(k0, min(seg_first[j], n))
        for k in range(k0, a):                  # in no segment (none expected)
            tt[k] = k * dt
            code[k] = 0
            zd[k] = app[k] = app_sep[k] = math.nan
            for i in range(obs.shape[1]):
                obs[k, i] = math.nan
        if a == n:
            break
        b = max(a, min(seg_last[j], n))
        t0, z0, v = seg_t0[j], seg_z0[j], seg_v[j]
        for k in range(a, b):
            t = k * dt
            tt[k] = t
            y0, y1 = ybuf[k, 0], ybuf[k, 1]
            y2 = ybuf[k, 2] if four else 0.0
            y3 = ybuf[k, 3] if four else 0.0
            if averaged:
                w = ybuf[k, ns]
                y0, y1 = y0 / w, y1 / w
                if four:
                    y2, y3 = y2 / w, y3 / w
            bad += (y0 + y1 + y2 + y3) * 0.0
            code[k] = seg_kind[j]
            z = z0 + v * (t - t0)
            zd[k] = z
            r = observables(model, p, z, v, y0, y1, y2, y3)
            ok = obs[k]
            ok[O_H], ok[O_HDOT], ok[O_DEFL], ok[O_THETA], ok[O_FZ], ok[O_Y2], ok[O_Y2DOT], \
                ok[O_FY], ok[O_Z] = r
            ak = beta * r[O_THETA] if beam else r[O_DEFL]
            app[k] = ak
            app_sep[k] = ak - z
        k0 = b
    return bad == 0.0
