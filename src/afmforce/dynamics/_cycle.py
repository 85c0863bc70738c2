"""The sampled columns and compliance lines of a cycle in one compiled call (issue 16).

After :meth:`afmforce.dynamics.simulate._Run.integrate` has run the drive
segments (:func:`afmforce.dynamics.radau.integrate_segment`, one call each),
:func:`sample_cycle` turns the integrator's sample buffer into the
trajectory's columns -- time, drive position, segment code, the observables,
the apparent deflection and separation -- and fits the constant-compliance
lines, without the GIL: in :func:`afmforce.dynamics.simulate_many` it runs on
the worker threads. It replaces the Python of the same steps (``np.searchsorted``
relabelling of averaged samples, ``beta * angle``, ``apparent - z``,
:func:`afmforce.dynamics.events.compliance_lines`) operation for operation, so
the results are bit-identical.

(A compiled driver of the segments themselves was tried: it links the
integrator into a second compiled function, which numba optimises again,
+4.5 s CPU on the first call with an empty cache, for 10-15 us per run.)
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._locate import APPROACH, E_CONTACT_T, E_CONTACT_Z, E_H_CONTACT, RETRACT, sample_columns
from .events import _line_fit
from .models import O_DEFL, O_H, O_THETA

__all__ = ["sample_cycle"]

# columns of the float segment table ``seg`` and the int one ``lab``
G_T0, G_Z0, G_V, G_T1 = 0, 1, 2, 3
L_FIRST, L_LAST, L_KIND = 0, 1, 2


@njit(cache=True, error_model="numpy", nogil=True)
def sample_cycle(model, p, dt, rate, average, s_next, ybuf, n, ev, seg, lab, beta, beam):
    """The sampled columns and compliance lines of an integrated cycle.

    ``seg``: float64[segments, 4], ``(t_start, z_start, velocity, t_end)`` of each
    segment run; ``lab``: int64[segments, 3], ``(first sample, end sample, kind)``;
    ``ybuf``/``s_next``: the sample buffer of :data:`~afmforce.dynamics.radau.Sampling`
    (``average``: window sums; the sample labels are then recomputed from the segment
    ends, every grid time up to the end of the run, windows at the ends clipped).

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
        for j in range(n_seg):       # np.searchsorted(sample_seg, j, side="left"/"right")
            first[j] = n_samp
            last[j] = n_samp
        for k in range(n_samp - 1, -1, -1):
            j = sample_seg[k]
            first[j] = k
            for i in range(j):
                first[i] = k
                last[i] = k
    else:
        Y = ybuf[:s_next[0]]
        for j in range(n_seg):
            first[j] = lab[j, L_FIRST]
            last[j] = lab[j, L_LAST]
    t0 = np.empty(n_seg)
    z0 = np.empty(n_seg)
    v = np.empty(n_seg)
    for j in range(n_seg):
        t0[j] = seg[j, G_T0]
        z0[j] = seg[j, G_Z0]
        v[j] = seg[j, G_V]
    tt, zd, code, obs, finite = sample_columns(model, p, Y, dt, first, last, kinds, t0, z0, v)
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
    seg = code
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
