"""Single-sample glitches of the deflection signal: a sample far off a line its four neighbours agree on.

A photodiode or ADC glitch puts one sample hundreds of noise sigmas away while the samples around it go
on as before; the analysis would take it for a jump into contact, a pull-off or a contact point (a
virtual static curve's jump-in was put at 150 nm instead of 5 nm by one sample 150 nm high in its
contact). Such a sample is replaced by the mean of its two neighbours, with a warning naming it.

A jump into contact, a pull-off, a turning point or ringing is no glitch: their neighbours do not lie on
one line (checked by :data:`GLITCH_QUIET_SIGMAS`).
"""

from __future__ import annotations

import math

import numpy as np

from ._glue_kernel import COMPILED, glitch_scan
from ._median import median

__all__ = ["GLITCH_SIGMAS", "GLITCH_QUIET_SIGMAS", "GLITCH_WINDOW", "find_glitches", "remove_glitches"]

#: A sample is a glitch when it lies this many noise sigmas off the line through its four neighbours [-]
#: (a Gaussian noise reaches 6 in a hundred million samples; the 380 curves of tests/data and the shared
#: real files read in the scan have none this far off their neighbours' line and local noise).
GLITCH_SIGMAS = 50.0
#: ... and those four neighbours (two on each side) lie within this many noise sigmas of their own line [-].
GLITCH_QUIET_SIGMAS = 6.0
#: Samples on each side whose second differences give the local noise [-] (a contact line rougher than
#: the baseline: the Nanosurf Tap150Al map's steep contacts vary by 50-100 baseline sigmas a sample).
GLITCH_WINDOW = 10


def _noise(s: np.ndarray, d2: np.ndarray | None = None) -> float:
    """Robust white-noise sigma of ``s`` from its second differences ``d2`` (blind to slopes and steps; computed
    here unless given) [its unit]; a quantised signal quieter than its step: the step / sqrt 12."""
    if d2 is None:
        d2 = s[1:-1] - 0.5 * (s[:-2] + s[2:])         # variance 1.5 sigma^2 for white noise
    sigma = 1.4826 * median(np.abs(d2 - median(d2))) / math.sqrt(1.5)
    if sigma > 0.0:
        return sigma
    steps = np.abs(np.diff(s))
    steps = steps[steps > 0.0]
    return float(steps.min()) / math.sqrt(12.0) if steps.size else 0.0


def find_glitches(s: np.ndarray) -> np.ndarray:
    """Indices of the single-sample glitches of the signal ``s`` (see the module docstring)."""
    s = np.asarray(s, float)
    if s.size < 5:
        return np.zeros(0, np.intp)
    if COMPILED and s.ndim == 1:  # the second differences, the noise and the threshold test in one call
        d2, sigma, hit, ok = glitch_scan(np.ascontiguousarray(s), GLITCH_SIGMAS)
        if ok and not hit:
            return np.zeros(0, np.intp)  # (the usual case: no sample near the threshold)
    if not (COMPILED and s.ndim == 1 and ok):
        d2 = s[1:-1] - 0.5 * (s[:-2] + s[2:])
        sigma = _noise(s, d2)
    if not sigma > 0.0:
        return np.zeros(0, np.intp)
    cand = np.flatnonzero(np.abs(d2) > GLITCH_SIGMAS * sigma) + 1
    cand = cand[(cand >= 2) & (cand <= s.size - 3)]
    if not cand.size:
        return np.zeros(0, np.intp)
    # the cheap test first, for every candidate at once (sigma_i >= sigma below): the four neighbours' mean,
    # each row's own np.mean (the same sum in the same order)
    ys = s[cand[:, None] + _NEIGHBOURS]
    means = ys.mean(axis=1)
    far = np.abs(s[cand] - means) > GLITCH_SIGMAS * sigma
    keep = np.flatnonzero(far)
    if not keep.size:
        return np.zeros(0, np.intp)
    local = _local_noise(d2, cand[keep])
    out = []
    x = np.array([-2.0, -1.0, 1.0, 2.0])
    for k, loc in zip(keep.tolist(), local.tolist()):
        i, y, a = int(cand[k]), ys[k], float(means[k])
        sigma_i = max(sigma, loc)
        if not abs(s[i] - a) > GLITCH_SIGMAS * sigma_i:
            continue                                    # off by the local noise too: the line's test after it
        b = float(np.dot(x, y - y.mean())) / 10.0       # least-squares line through the four neighbours
        if np.max(np.abs(y - (a + b * x))) < GLITCH_QUIET_SIGMAS * sigma_i:
            out.append(i)
    return np.asarray(out, np.intp)


def _local_noise(d2: np.ndarray, cand: np.ndarray) -> np.ndarray:
    """Each candidate's local noise: the robust sigma of the second differences ``d2`` of the
    :data:`GLITCH_WINDOW` samples on each side, the glitch's own three left out (a steep, rough contact line
    is noisier than the baseline the global one sees). Candidates with a whole window on both sides (an even
    count, ``2 h``) at once: each row's two middle values by one partition, averaged as :func:`~._median.median` does
    (the mean's sign of zero does not reach the absolute deviations); those near the ends one by one. (A NaN
    or infinite signal never gets here: its sigma is NaN.)"""
    out = np.empty(cand.size)
    inner = (cand - 1 - GLITCH_WINDOW >= 0) & (cand + GLITCH_WINDOW <= d2.size)
    if inner.any():
        h = _WINDOW.size // 2
        win = d2[cand[inner][:, None] + _WINDOW]
        part = np.partition(win, (h - 1, h), axis=1)
        mid = (part[:, h - 1] + part[:, h]) / 2.0
        part = np.partition(np.abs(win - mid[:, None]), (h - 1, h), axis=1)
        out[inner] = 1.4826 * ((part[:, h - 1] + part[:, h]) / 2.0) / math.sqrt(1.5)
    for k in np.flatnonzero(~inner).tolist():
        i = int(cand[k])
        near = np.concatenate((d2[max(0, i - 1 - GLITCH_WINDOW): max(0, i - 2)],
                               d2[i + 1: i + GLITCH_WINDOW])).astype(np.float64, copy=False)
        mid = median(near) if near.size else 0.0       # (once: the same for every value of the window)
        out[k] = 1.4826 * median(np.abs(near - mid)) / math.sqrt(1.5) if near.size else 0.0
    return out


#: The second differences around a candidate ``i`` that give its local noise: ``d2[i - 1 - GLITCH_WINDOW:
#: i - 2]`` and ``d2[i + 1: i + GLITCH_WINDOW]`` (``d2[j]`` is sample ``j + 1``'s).
_WINDOW = np.r_[np.arange(-1 - GLITCH_WINDOW, -2), np.arange(1, GLITCH_WINDOW)]
assert _WINDOW.size % 2 == 0  # (the rows' medians above: the two middle values)
#: The four neighbours of a candidate, relative to it.
_NEIGHBOURS = np.array([-2, -1, 1, 2])


def remove_glitches(s: np.ndarray) -> tuple[np.ndarray, str | None]:
    """The signal with its single-sample glitches replaced by their neighbours' mean, and a warning (None
    when there are none). ``s`` itself is left as it is."""
    bad = find_glitches(s)
    if not bad.size:
        return s, None
    out = np.array(s, float)
    out[bad] = 0.5 * (out[bad - 1] + out[bad + 1])
    where = ", ".join(str(i) for i in bad[:5].tolist()) + (", ..." if bad.size > 5 else "")
    return out, (f"{bad.size} single-sample glitch{'es' if bad.size > 1 else ''} in the deflection signal "
                 f"(sample{'s' if bad.size > 1 else ''} {where}: more than {GLITCH_SIGMAS:g} noise sigmas off the "
                 "line of the neighbours) replaced by the neighbours' mean")
