"""The core steps for many curves at once (compiled, one pass per curve, parallel over curves).

Drift, contact regions, constant compliance, calibration, shift, zero of
separation and jumps, with the pipeline's default options, on a stack of
equally long curves that share their turning sample; no smoothing, fringes,
fits or diagnosis. The methods are the pipeline's (the same two-line contact
split, baselines and compliance lines in the same regions, the same jump
criteria) with one difference for speed: lines are least squares with one
4-sigma trimming pass instead of the pipeline's bisquare IRLS, so results
agree within the noise. Each curve is a few passes over its samples in one
compiled function, curves run in parallel. Used for large data sets and by
``benchmarks/bench_analysis.py``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit, prange

from ..constants import Z0
from ..errors import ParameterError

__all__ = ["BatchResult", "analyze_batch"]


@dataclass(frozen=True)
class BatchResult:
    """Per-curve results of :func:`analyze_batch` (NaN / -1 where a curve failed).

    Attributes
    ----------
    sensitivity : ndarray  deflection per signal unit from the compliance slope [m/V for volts]
    shift : ndarray  inward shift [m]
    contact_index : ndarray of int  first approach sample in contact [-]
    jump_in_index : ndarray of int  last sample before the jump (-1: none) [-]
    jump_in_separation : ndarray  [m]
    jump_in_deflection : ndarray  deflection after the jump [m]
    pull_off_index : ndarray of int  last sample in contact on the retract (-1: none) [-]
    pull_off_deflection : ndarray  most negative deflection before pull-off [m]
    noise : ndarray  baseline noise [signal unit]
    ok : ndarray of bool  the curve had a contact region
    """

    sensitivity: np.ndarray
    shift: np.ndarray
    contact_index: np.ndarray
    jump_in_index: np.ndarray
    jump_in_separation: np.ndarray
    jump_in_deflection: np.ndarray
    pull_off_index: np.ndarray
    pull_off_deflection: np.ndarray
    noise: np.ndarray
    ok: np.ndarray


@njit(cache=True, fastmath=True)
def _sse(c0, c1, c2, c3, c4, t0, t1, t2, t3, t4, k, m):
    """Summed squared residuals of two lines from prefix sums (left k samples, right m - k)."""
    sse = 0.0
    for part in range(2):
        if part == 0:
            inv = 1.0 / k
            a0, a1, a2, a3, a4 = c0, c1, c2, c3, c4
        else:
            inv = 1.0 / (m - k)
            a0, a1, a2, a3, a4 = t0 - c0, t1 - c1, t2 - c2, t3 - c3, t4 - c4
        sxx = a2 - a0 * a0 * inv
        sxy = a3 - a0 * a1 * inv
        r = a4 - a1 * a1 * inv - (sxy * sxy / sxx if sxx > 1e-300 else 0.0)
        sse += r if r > 0 else 0.0
    return sse


@njit(cache=True, fastmath=True)
def _split(z, s, lo, m, min_points):
    """two_line_split over the contiguous samples [lo, lo + m) (returns k or -1).

    Coarse-to-fine: every ``stride``-th split first, then every split within one
    stride of the best coarse one (the two-line residual has one sharp minimum at
    a contact or a jump). The residual is symmetric in the two parts, so a run
    may be scanned in either direction (the retract is scanned forward in time).
    Sums are taken about the first sample (centring is what keeps precision).
    """
    if m < 2 * min_points:
        return -1
    stride = 32
    mx = z[lo]
    my = s[lo]
    nb = m // stride
    pref = np.empty((nb + 1, 5))  # prefix sums at k = 0, stride, 2 stride, ...
    pref[0, :] = 0.0
    c0 = c1 = c2 = c3 = c4 = 0.0
    for j in range(nb):
        b0 = b1 = b2 = b3 = b4 = 0.0
        base = lo + j * stride
        for kk in range(stride):
            u = z[base + kk] - mx
            v = s[base + kk] - my
            b0 += u
            b1 += v
            b2 += u * u
            b3 += u * v
            b4 += v * v
        c0 += b0
        c1 += b1
        c2 += b2
        c3 += b3
        c4 += b4
        pref[j + 1, 0] = c0
        pref[j + 1, 1] = c1
        pref[j + 1, 2] = c2
        pref[j + 1, 3] = c3
        pref[j + 1, 4] = c4
    t0, t1, t2, t3, t4 = c0, c1, c2, c3, c4
    for k in range(nb * stride, m):
        u = z[lo + k] - mx
        v = s[lo + k] - my
        t0 += u
        t1 += v
        t2 += u * u
        t3 += u * v
        t4 += v * v
    best = np.inf
    kc = -1
    for j in range(nb + 1):
        k = j * stride
        if k < min_points or k > m - min_points:
            continue
        sse = _sse(pref[j, 0], pref[j, 1], pref[j, 2], pref[j, 3], pref[j, 4], t0, t1, t2, t3, t4, k, m)
        if sse < best:
            best = sse
            kc = k
    if kc < 0:  # too short for the coarse grid: scan everything
        kc = min_points
    k_lo = max(min_points, kc - stride)
    k_hi = min(m - min_points, kc + stride)
    j = min(k_lo // stride, nb)
    c0, c1, c2, c3, c4 = pref[j, 0], pref[j, 1], pref[j, 2], pref[j, 3], pref[j, 4]
    best = np.inf
    kbest = -1
    for k in range(j * stride, k_hi + 1):
        if k >= k_lo:
            sse = _sse(c0, c1, c2, c3, c4, t0, t1, t2, t3, t4, k, m)
            if sse < best:
                best = sse
                kbest = k
        if k < m:
            u = z[lo + k] - mx
            v = s[lo + k] - my
            c0 += u
            c1 += v
            c2 += u * u
            c3 += u * v
            c4 += v * v
    return kbest


@njit(cache=True, fastmath=True)
def _trimmed(x, s, lo, hi, x0, t, off, slope, t0):
    """Least-squares line of ``y = s - off - slope (t - t0)`` on ``x - x0`` over [lo, hi), then
    once more without samples beyond 4 sigma (spikes, transients); sums in one pass each.

    Returns (a, b, sigma, mean of x - x0, mean of y) over the samples of the final fit.
    """
    n = hi - lo
    if n < 3:
        return np.nan, np.nan, np.nan, np.nan, np.nan
    y0 = s[lo] - off - slope * (t[lo] - t0)
    s0 = s1 = s2 = s3 = s4 = 0.0
    for i in range(lo, hi):
        u = x[i] - x0
        v = s[i] - off - slope * (t[i] - t0) - y0
        s0 += u
        s1 += v
        s2 += u * u
        s3 += u * v
        s4 += v * v
    m = n
    for it in range(2):
        sxx = s2 - s0 * s0 / m
        b = (s3 - s0 * s1 / m) / sxx if sxx > 0 else 0.0
        a = (s1 - b * s0) / m
        ssr = s4 - s1 * s1 / m - b * (s3 - s0 * s1 / m)
        sig = math.sqrt(max(ssr, 0.0) / max(m - 2, 1))
        if it == 1 or not sig > 0:
            break
        cut = 4.0 * sig
        k = 0
        q0 = q1 = q2 = q3 = q4 = 0.0
        for i in range(lo, hi):
            u = x[i] - x0
            v = s[i] - off - slope * (t[i] - t0) - y0
            if abs(v - a - b * u) < cut:
                k += 1
                q0 += u
                q1 += v
                q2 += u * u
                q3 += u * v
                q4 += v * v
        if k < 3 or k == m:
            break
        m = k
        s0, s1, s2, s3, s4 = q0, q1, q2, q3, q4
    return a + y0, b, sig, s0 / m, s1 / m + y0


@njit(cache=True, fastmath=True)
def _one(t, z, s, n_app, min_points, bf, cf, h_contact, nsigma, window, out_f, out_i):
    n = z.size
    n_ret = n - n_app
    ka = _split(z, s, 0, n_app, min_points)  # first contact sample of the approach
    kr = _split(z, s, n_app, n_ret, min_points)
    if ka < 0 or kr < 0:
        return False
    split_r = n_app + kr  # first free retract sample (time order)
    # zero-force regions: the far baseline fraction of each run's free part
    z_lim = z[0] + bf * (z[ka - 1] - z[0])
    hi_a = 0
    while hi_a < ka and z[hi_a] <= z_lim:
        hi_a += 1
    if hi_a < min_points:
        hi_a = ka
    z_lim = z[n - 1] + bf * (z[split_r] - z[n - 1])
    lo_r = n - 1
    while lo_r > split_r and z[lo_r] <= z_lim:
        lo_r -= 1
    lo_r += 1
    # drift: least-squares line in time per run (the signal's baseline)
    oa, ba, noise, _, _ = _trimmed(t, s, 0, hi_a, t[0], t, 0.0, 0.0, 0.0)
    t0a = t[0]
    if n - lo_r >= min_points:
        orr, br, _, _, _ = _trimmed(t, s, lo_r, n, t[lo_r], t, 0.0, 0.0, 0.0)
        t0r = t[lo_r]
    else:
        orr, br, t0r = oa, ba, t0a
    # constant compliance: the part of each contact region nearest the turning point
    z_lim = z[n_app - 1] - cf * (z[n_app - 1] - z[ka])
    lo_a = ka
    while lo_a < n_app - 1 and z[lo_a] < z_lim:
        lo_a += 1
    z_lim = z[n_app] - cf * (z[n_app] - z[split_r - 1])
    hi_r = n_app
    while hi_r < split_r and z[hi_r] >= z_lim:
        hi_r += 1
    if n_app - lo_a < 3 or hi_r - n_app < 3:
        return False
    xa = z[n_app - 1]
    aa, sa, _, _, _ = _trimmed(z, s, lo_a, n_app, xa, t, oa, ba, t0a)
    xr = z[n_app]
    ar, sr_, _, mz_r, md_r = _trimmed(z, s, n_app, hi_r, xr, t, orr, br, t0r)
    if not (sa != 0 and sr_ != 0 and np.isfinite(sa) and np.isfinite(sr_)):
        return False
    factor = 1.0 / sa
    # shift: retract minus approach line positions at mid signal of the two regions
    s_ref = 0.5 * (aa + ar) + 0.25 * (sa * (z[lo_a] - xa) + sr_ * (z[hi_r - 1] - xr))
    shift = ((s_ref - ar) / sr_ + xr) - ((s_ref - aa) / sa + xa)
    # zero of separation: mean of d - z on the retract compliance line
    c0 = md_r * factor - (mz_r + xr)
    # jumps: largest steps in a window before each split
    thr = nsigma * abs(noise * factor) * math.sqrt(2.0)
    best = -np.inf
    ib = -1
    prev = (s[max(ka - window, 0)] - oa - ba * (t[max(ka - window, 0)] - t0a)) * factor
    for i in range(max(ka - window, 0), min(ka + window, n_app) - 1):
        nxt = (s[i + 1] - oa - ba * (t[i + 1] - t0a)) * factor
        if prev - nxt > best:
            best = prev - nxt
            ib = i
        prev = nxt
    if ib >= 0 and best > thr:
        d_i = (s[ib] - oa - ba * (t[ib] - t0a)) * factor
        out_i[1] = ib
        out_f[2] = d_i - (z[ib] + shift) - c0 + h_contact
        out_f[3] = (s[ib + 1] - oa - ba * (t[ib + 1] - t0a)) * factor
    best = -np.inf
    jb = -1
    lo_w = max(split_r - window, n_app)
    prev = (s[lo_w] - orr - br * (t[lo_w] - t0r)) * factor
    dmin = prev
    for i in range(lo_w, min(split_r + window, n) - 1):
        nxt = (s[i + 1] - orr - br * (t[i + 1] - t0r)) * factor
        if nxt - prev > best:
            best = nxt - prev
            jb = i
            out_f[4] = dmin if dmin < prev else prev
        dmin = min(dmin, prev)
        prev = nxt
    if jb >= 0 and best > thr:
        out_i[2] = jb
    else:
        out_f[4] = np.nan
    out_f[0] = factor
    out_f[1] = shift
    out_f[5] = noise
    out_i[0] = ka
    return True


@njit(cache=True, parallel=True)
def _batch_parallel(t, z, s, n_app, min_points, bf, cf, h_contact, nsigma, window, out_f, out_i, ok):
    shared = t.shape[0] == 1
    for c in prange(z.shape[0]):
        tc = t[0] if shared else t[c]
        ok[c] = _one(tc, z[c], s[c], n_app, min_points, bf, cf, h_contact, nsigma, window, out_f[c], out_i[c])


@njit(cache=True)
def _batch_serial(t, z, s, n_app, min_points, bf, cf, h_contact, nsigma, window, out_f, out_i, ok):
    shared = t.shape[0] == 1
    for c in range(z.shape[0]):
        tc = t[0] if shared else t[c]
        ok[c] = _one(tc, z[c], s[c], n_app, min_points, bf, cf, h_contact, nsigma, window, out_f[c], out_i[c])


def analyze_batch(time: np.ndarray, position: np.ndarray, signal: np.ndarray, n_approach: int, *,
                  min_points: int = 5, baseline_fraction: float = 0.7, compliance_fraction: float = 0.5,
                  contact_separation: float = Z0, nsigma: float = 5.0, window: int = 3,
                  parallel: bool = True) -> BatchResult:
    """Core analysis of a stack of curves.

    Parameters
    ----------
    time, position, signal : ndarray, shape (n_curves, n_points) or (n_points,)
        Time [s] (may be shared, shape (n_points,)), position z [m] (increasing on
        the approach), deflection signal [V, m or N].
    n_approach : int
        Samples of the approach run; the retract run follows directly.
    window : int
        Jumps are searched within ``window`` samples of each run's split, as in
        the pipeline.
    parallel : bool
        Spread the curves over the CPU cores (numba threads); on a machine whose
        cores are busy with other work a serial run can be as fast.

    Returns
    -------
    BatchResult
    """
    z = np.ascontiguousarray(np.atleast_2d(np.asarray(position, float)))
    s = np.ascontiguousarray(np.atleast_2d(np.asarray(signal, float)))
    t = np.ascontiguousarray(np.atleast_2d(np.asarray(time, float)))
    if z.shape != s.shape:
        raise ParameterError(f"position {z.shape} and signal {s.shape} differ in shape")
    if t.shape[1] != z.shape[1] or t.shape[0] not in (1, z.shape[0]):
        raise ParameterError(f"time {t.shape} does not match the curves {z.shape}")
    n_app = int(n_approach)
    if not 2 * min_points + 2 <= n_app <= z.shape[1] - 2 * min_points - 2:
        raise ParameterError(f"n_approach={n_app} leaves too few samples for one of the runs")
    nc = z.shape[0]
    out_f = np.full((nc, 6), np.nan)
    out_i = np.full((nc, 3), -1, dtype=np.int64)
    ok = np.zeros(nc, dtype=np.bool_)
    run = _batch_parallel if parallel and nc > 1 else _batch_serial
    run(t, z, s, n_app, int(min_points), float(baseline_fraction), float(compliance_fraction),
           float(contact_separation), float(nsigma), int(window), out_f, out_i, ok)
    return BatchResult(sensitivity=out_f[:, 0], shift=out_f[:, 1], contact_index=out_i[:, 0],
                       jump_in_index=out_i[:, 1], jump_in_separation=out_f[:, 2], jump_in_deflection=out_f[:, 3],
                       pull_off_index=out_i[:, 2], pull_off_deflection=out_f[:, 4], noise=out_f[:, 5], ok=ok)
