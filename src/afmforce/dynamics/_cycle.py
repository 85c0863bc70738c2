"""One whole approach-retract cycle in one compiled call (issue 16: no Python in the hot path).

:func:`run_cycle` integrates every drive segment of a cycle (approach, turning
at a load or at ``turn``; dwell; retract) with
:func:`afmforce.dynamics.radau.integrate_segment`, then computes the sampled
columns and the constant-compliance lines (:func:`sample_cycle`), all without
the GIL. :func:`afmforce.dynamics.simulate` calls it once per run instead of
once per segment plus the sampling and event fits from Python, and
:func:`afmforce.dynamics.simulate_many`'s worker threads run a whole cycle per
call. The arithmetic is the one of the Python driver it replaces
(:meth:`afmforce.dynamics.simulate._Run.integrate` with a progress callback,
which still drives the segments one by one), operation for operation, so both
give bit-identical results.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._locate import (APPROACH, DWELL, E_CONTACT_T, E_CONTACT_Z, E_H_CONTACT, E_TERM_T, RETRACT,
                      TERM_NONE, sample_columns)
from ._radau_tableau import W_ERR_OLD, W_H, W_H_OLD, W_HAS_SOL, W_HAVE_JAC, W_T, W_VFAC
from .events import _line_fit
from .models import O_DEFL, O_H, O_THETA
from .radau import TERMINAL, integrate_segment

__all__ = ["run_cycle", "sample_cycle", "MAX_SEGMENTS"]

#: Rows of the segment table (approach, dwell, retract).
MAX_SEGMENTS = 3
# columns of the float segment table ``seg`` and the int one ``lab``
G_T0, G_Z0, G_V, G_T1 = 0, 1, 2, 3
L_FIRST, L_LAST, L_KIND = 0, 1, 2


@njit(cache=True, error_model="numpy", nogil=True)
def run_cycle(model, p, y, tolerances, control, grid, state, protocol, seg, lab):
    """Integrate a whole cycle, then sample it (:func:`sample_cycle`).

    Parameters
    ----------
    model, p, tolerances, control, state
        As for :func:`~afmforce.dynamics.radau.integrate_segment` (``state``: ``(y, ev,
        work, Q, y_old, J, stats)``; ``y`` is ``state[0]``).
    grid : tuple
        ``(t0, dt, average, next, rows)``: the sample grid of
        :data:`~afmforce.dynamics.radau.Sampling` with the number of buffer rows
        instead of the buffer (allocated here, without the GIL: NaN for point
        samples, zeros for window sums).
    protocol : tuple
        ``(start, velocity, t_turn_max, dwell, retract_speed, end, term_kind,
        term_level, initial_step, vfac, sample_rate, beta, beam)`` [SI]: the drive of
        :func:`afmforce.dynamics.drive.segments`, the terminal event of the
        approach, the first trial step and velocity-tolerance factor of every
        segment, the sample rate, the calibration factor and whether the model
        tilts (apparent deflection ``beta theta``).
    seg, lab : float64[MAX_SEGMENTS, 4], int64[MAX_SEGMENTS, 3]
        Filled with the segments run: ``(t_start, z_start, velocity, t_end)`` and
        ``(first sample, end sample, kind)``.

    Returns
    -------
    status, n_seg, t_turn, z_turn, columns
        ``status`` DONE or TERMINAL (turned at the load), or the negative code of
        the failed segment ``n_seg - 1``; ``columns`` is :func:`sample_cycle`'s
        tuple (empty arrays after a failure).
    """
    (start, v, t_max, dwell, vr, end, term_kind, term_level, h0, vfac, rate, beta,
     beam) = protocol
    work = state[2]
    s_next = grid[3]
    n = y.shape[0]
    if grid[2]:
        ybuf = np.zeros((grid[4], n + 1))
    else:
        ybuf = np.full((grid[4], n), np.nan)
    sampling = (grid[0], grid[1], grid[2], s_next, ybuf)
    ev = state[1]
    n_seg = 0
    turned = False
    t_turn = t_max
    z_turn = start + v * (t_max - 0.0)
    status = 0
    for j in range(MAX_SEGMENTS):
        if j == 0:
            kind, t0, z0, vel, t1 = APPROACH, 0.0, start, v, t_max
            tk, tl = term_kind, term_level
        else:
            if j == 1:
                turned = status == TERMINAL
                if turned:
                    t_turn = ev[E_TERM_T]
                    z_turn = start + v * (t_turn - 0.0)
                seg[0, G_T1] = t_turn
            if j == 1 and dwell > 0.0:
                kind, t0, z0, vel, t1 = DWELL, t_turn, z_turn, 0.0, t_turn + dwell
            elif j == 2 and dwell <= 0.0:
                break
            else:
                t0 = t_turn + dwell if dwell > 0.0 else t_turn
                kind, z0, vel, t1 = RETRACT, z_turn, -vr, t0 + (z_turn - end) / vr
            tk, tl = TERM_NONE, 0.0
        seg[j, G_T0] = t0
        seg[j, G_Z0] = z0
        seg[j, G_V] = vel
        seg[j, G_T1] = t1
        work[W_T] = t0
        work[W_H] = h0
        work[W_H_OLD] = 0.0
        work[W_ERR_OLD] = 0.0
        work[W_HAS_SOL] = 0.0
        work[W_HAVE_JAC] = 0.0
        work[W_VFAC] = vfac
        lab[j, L_FIRST] = s_next[0]
        lab[j, L_KIND] = kind
        n_seg = j + 1
        status = integrate_segment(model, p, (kind, t0, z0, vel, t1, tk, tl), tolerances,
                                   control, sampling, state)
        lab[j, L_LAST] = s_next[0]
        if status < 0:
            return status, n_seg, t_turn, z_turn, _empty_columns(p)
    cols = sample_cycle(model, p, sampling[1], rate, sampling[2], s_next, ybuf, n,
                        ev, seg[:n_seg], lab[:n_seg], beta, beam)
    return (TERMINAL if turned else 0), n_seg, t_turn, z_turn, cols


@njit(cache=True, error_model="numpy")
def _empty_columns(p):
    e = np.empty(0)
    return (e, e, np.empty(0, dtype=np.int8), np.empty((0, 1)), e, e, False, math.nan, math.nan)


@njit(cache=True, error_model="numpy", nogil=True)
def sample_cycle(model, p, dt, rate, average, s_next, ybuf, n, ev, seg, lab, beta, beam):
    """The sampled columns and compliance lines of an integrated cycle.

    ``seg``/``lab``: the rows of the segments run (see :func:`run_cycle`); with
    ``average`` the sample labels are recomputed from the segment ends (every
    grid time up to the end of the run, windows at the ends clipped).

    Returns
    -------
    tuple
        ``(time, piezo_position, segment code (int8), observables (rows x N_OBS),
        apparent deflection, apparent separation, all finite, hysteresis offset,
        compliance slope)``;
        offset and slope as :func:`afmforce.dynamics.events.compliance_lines`
        (NaN without contact).
    """
    n_seg = seg.shape[0]
    first = np.empty(n_seg, dtype=np.int64)
    last = np.empty(n_seg, dtype=np.int64)
    kinds = np.empty(n_seg, dtype=np.int8)
    for j in range(n_seg):
        kinds[j] = lab[j, L_KIND]
    if average:
        n_samp = min(ybuf.shape[0], int(math.floor(seg[n_seg - 1, G_T1] * rate
                                                   * (1.0 + 1e-12))) + 1)
        Y = np.empty((n_samp, n))
        for k in range(n_samp):
            for i in range(n):
                Y[k, i] = ybuf[k, i] / ybuf[k, n]
        # sample k belongs to the first segment whose end is >= k dt (searchsorted 'left'
        # over the inner segment ends), so segment j holds a contiguous run of samples
        sample_seg = np.empty(n_samp, dtype=np.int64)
        for k in range(n_samp):
            tk = k * dt
            j = 0
            while j < n_seg - 1 and seg[j, G_T1] < tk:
                j += 1
            sample_seg[k] = j
        for j in range(n_seg):
            first[j] = np.searchsorted(sample_seg, j)
            last[j] = np.searchsorted(sample_seg, j, side="right")
    else:
        Y = ybuf[:s_next[0]]
        for j in range(n_seg):
            first[j] = lab[j, L_FIRST]
            last[j] = lab[j, L_LAST]
    tt, zd, code, obs, finite = sample_columns(model, p, Y, dt, first, last, kinds,
                                               seg[:, G_T0].copy(), seg[:, G_Z0].copy(),
                                               seg[:, G_V].copy())
    m = tt.shape[0]
    apparent = np.empty(m)
    apparent_sep = np.empty(m)
    for k in range(m):
        apparent[k] = beta * obs[k, O_THETA] if beam else obs[k, O_DEFL]
        apparent_sep[k] = apparent[k] - zd[k]
    offset, slope = math.nan, math.nan
    if math.isfinite(ev[E_CONTACT_T]):
        z_turn = seg[0, G_Z0] + seg[0, G_V] * (seg[0, G_T1] - seg[0, G_T0])
        offset, slope = _compliance(zd, apparent, obs[:, O_H], code, ev[E_H_CONTACT],
                                    ev[E_CONTACT_Z], z_turn, beta if beam else math.nan)
    return tt, zd, code, obs, apparent, apparent_sep, finite, offset, slope


@njit(cache=True, error_model="numpy")
def _compliance(z, d, h, code, contact_separation, contact_position, turn_position, beta):
    """:func:`afmforce.dynamics.events.compliance_lines`, compiled (the same operations)."""
    seg = code.astype(np.int64)
    if not (math.isfinite(contact_position) and turn_position > contact_position):
        return math.nan, math.nan
    span = turn_position - contact_position
    lo, hi = contact_position + 0.25 * span, turn_position - 0.25 * span
    count, a0, a1, alo, ahi = _line_fit(z, d, h, seg, APPROACH, contact_separation, lo, hi)
    if count < 5 or not math.isfinite(a1):
        return math.nan, math.nan
    count, b0, b1, blo, bhi = _line_fit(z, d, h, seg, RETRACT, contact_separation, lo, hi)
    if count < 5 or not math.isfinite(b1):
        return math.nan, math.nan
    dmid = 0.5 * (max(alo, blo) + min(ahi, bhi))
    offset = (a0 + a1 * dmid) - (b0 + b1 * dmid)
    slope = beta * 0.5 * (a1 + b1) if math.isfinite(beta) else math.nan
    return offset, slope
