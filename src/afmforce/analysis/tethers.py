"""Tethers of a hard contact: ruptures after the tip has left the surface.

On a rigid contact the retract first leaves the surface (the tip--surface adhesion lets go at or near the
contact line) and may then pull polymer tethers: worm-like-chain rises, each ending in a rupture, tens to
hundreds of nm away. The tip--surface adhesion is the dip *before* the retract comes back to its free
baseline (:func:`baseline_return`); a later dip is a tether, reported on its own (:func:`ruptures`), with
every rupture counted (not only those after the deepest point). A monotone relaxation back to the
baseline (the detector's or the lever's response after a large snap-off) is no attachment: the last
rupture there is the pull-off.

:func:`wlc_force` is the closed-form worm-like chain (Marko & Siggia, Macromolecules 28, 8759 (1995))
that :func:`afmforce.analysis.synthetic.tether_curve` builds its tethers with.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..forces import KB
from ._units import unit as _u

__all__ = ["TetherRupture", "wlc_force", "baseline_return", "renewed_pull", "running_median", "ruptures", "BACK_FRACTION"]

#: The retract is back at its free baseline where its running median lies above this fraction of the
#: significance threshold (``nsigma`` noise) below it ... [-]
BACK_FRACTION = 0.5
#: ... for this many running-median windows in a row [-].
BACK_HOLD = 2


@dataclass(frozen=True)
class TetherRupture:
    """One rupture of the retract: a tether (or bond) letting go.

    Attributes
    ----------
    index : int  last attached sample of the curve [-]
    separation : float  tip--sample separation at the rupture (the tether's length there) [m]
    distance : float  position from the contact point [m]
    force : float  pull at the rupture, below the baseline [N] (< 0; deflection [m] when k is unknown)
    drop : float  height of the rupture step [N] (> 0; deflection [m] when k is unknown)
    tether : bool  after the retract came back to its free baseline (a tether, not the surface's adhesion)
    """

    index: int = _u("")
    separation: float = _u("m")
    distance: float = _u("m")
    force: float = _u("N")
    drop: float = _u("N")
    tether: bool = _u("")


def wlc_force(extension: np.ndarray | float, contour_length: float, persistence_length: float,
              temperature: float = 298.15) -> np.ndarray:
    """Worm-like-chain force, Marko--Siggia interpolation [N].

    ``F = kT / p (1 / (4 (1 - x/L)^2) - 1/4 + x/L)`` for ``0 <= x < L``.

    Parameters
    ----------
    extension : float or ndarray  end-to-end distance x [m]
    contour_length : float  L [m]
    persistence_length : float  p [m]
    temperature : float  T [K]
    """
    r = np.clip(np.asarray(extension, float) / contour_length, 0.0, None)
    if np.any(r >= 1.0):
        raise ParameterError("extension reaches the contour_length: the worm-like chain's force diverges there; "
                             "give extensions below the contour length")
    return KB * temperature / persistence_length * (0.25 / (1.0 - r) ** 2 - 0.25 + r)


def running_median(u: np.ndarray, w: int) -> np.ndarray:
    """Running median of ``w`` samples (scipy's ``median_filter``, ends repeated) [same unit as u]."""
    from scipy.ndimage import median_filter  # here: its import costs 0.25 s of every command

    return median_filter(u, size=w, mode="nearest")


def baseline_return(us: np.ndarray, start: int, level: float, hold: int) -> int:
    """First sample at or after ``start`` from which the running median ``us`` stays above ``-level`` for
    ``hold`` samples: where the retract is back at its free baseline (``us.size``: never) [-]."""
    ok = us[start:] > -level
    if ok.size < hold:
        return us.size
    run = np.convolve(ok.astype(np.int64), np.ones(hold, np.int64), mode="valid")
    at = np.flatnonzero(run == hold)
    return int(start + at[0]) if at.size else us.size


def renewed_pull(us: np.ndarray, start: int, thr: float, hold: int) -> int:
    """Top of the retract before its first renewed pull from ``start`` on (``us.size``: none) [-].

    A renewed pull: the running median ``us`` lies more than ``thr`` below the highest it had come back to
    since ``start`` and more than ``thr`` below the baseline, for ``hold`` samples in a row (a tether
    already pulling when the tip snaps off, before the retract could come back to its baseline; a lever
    ringing about the baseline crosses back within a period). The top is where it had come back highest.
    """
    seg = us[start:]
    if seg.size < hold:
        return us.size
    top = np.maximum.accumulate(seg)
    deeper = (seg < top - thr) & (seg < -thr)
    run = np.convolve(deeper.astype(np.int64), np.ones(hold, np.int64), mode="valid")
    at = np.flatnonzero(run == hold)
    if not at.size:
        return us.size
    return int(start + np.argmax(seg[: at[0] + 1]))


def ruptures(u: np.ndarray, us: np.ndarray, x: np.ndarray, h: np.ndarray, idx: np.ndarray, start: int,
             release: int, thr: float, w: int, k: float, skip: int = -1) -> list[TetherRupture]:
    """Every rupture of the retract from ``start`` on.

    A rupture is a rise of the running median ``us`` by more than ``thr`` within ``w`` samples (runs of such
    rises within ``w`` of each other are one rupture, as the unbinding steps) after a renewed pull: the running
    median went deeper, by ``thr``, than where the previous rise (a rupture, or the pull-off) ended; a rise
    that goes on without one is the relaxation of the last (the detector's or the lever's response after a
    large snap-off), no new attachment. Its last attached sample is
    where the mean of the next two samples of ``u`` rises most above the mean of the two before; the pull
    there is a parabola through the ``w`` samples before it, read at it (at least 5; the last attached sample
    itself may have been caught mid-drop by the detector's averaging; the noise averaged, the worm-like
    chain's steepening followed: a line through them read the pull 10-17 % low on a virtual tether), the drop
    the running median's rise.

    Parameters
    ----------
    u, us : ndarray  the retract's residual about its baseline and its running median [m]
    x, h : ndarray  position from contact and separation of the retract's samples [m]
    idx : ndarray  the retract's samples in the curve [-]
    start : int  first run sample looked at [-]
    release : int  run sample where the retract came back to its baseline: ruptures from there on are tethers
    thr : float  significance [m]
    w : int  running-median window [samples]
    k : float  spring constant [N/m] (NaN: forces as deflections)
    skip : int  run sample of a hard contact's pull-off jump (-1: none): the rise that contains it is the
        end of the surface's adhesion, no rupture
    """
    kk = k if math.isfinite(k) else 1.0
    n = u.size
    start = max(int(start), 0)
    if n - start <= w:
        return []
    rise = us[start + w:] - us[start:n - w]
    cand = np.flatnonzero(rise > thr)
    out: list[TetherRupture] = []
    i = 0
    last_end = -1   # where the previous rise (a rupture or the pull-off) ended
    while i < cand.size:
        first = prev = int(cand[i])
        g = first
        i += 1
        while i < cand.size and cand[i] - prev <= w:
            prev = int(cand[i])
            if rise[prev] > rise[g]:
                g = prev
            i += 1
        lo, hi = start + first, start + prev + w
        renewed = last_end < 0 or float(us[last_end:lo + 1].min()) < float(us[last_end]) - thr
        last_end = min(hi, n - 1)
        if skip >= 0 and lo - w <= skip <= hi:
            continue
        if not renewed:   # still rising from the last rupture or the pull-off: a relaxation, no new attachment
            continue
        a, b = start + g, min(start + g + w, n - 3)
        if b <= a:
            continue
        j = np.arange(max(a, 1), b)
        jump = 0.5 * (u[j + 1] + u[j + 2]) - 0.5 * (u[j - 1] + u[j])
        r = int(j[np.argmax(jump)])
        seg = slice(max(r - w, 0), r)   # r itself left out: a sample caught mid-drop (the SMFS curve's last)
        xs, ys = x[seg], u[seg]
        if xs.size >= 5 and np.ptp(xs) > 0:
            pull = float(np.polyval(np.polyfit(xs - xs.mean(), ys, 2), x[r] - xs.mean()))
        else:
            pull = float(u[r])
        out.append(TetherRupture(int(idx[r]), float(h[r]), float(-x[r]), min(pull, 0.0) * kk,
                                 float(rise[g]) * kk, r >= release))
    return out
