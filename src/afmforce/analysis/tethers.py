"""Tethers of a hard contact: ruptures after the tip has left the surface.

On a rigid contact the retract first leaves the surface (the tip--surface adhesion lets go at or near the
contact line) and may then pull polymer tethers: worm-like-chain rises, each ending in a rupture, tens to
hundreds of nm away. The tip--surface adhesion is the dip *before* the retract comes back to its free
baseline (:func:`baseline_return`); a later dip is a tether, reported on its own (:func:`ruptures`), with
every rupture counted (not only those after the deepest point). A monotone relaxation back to the
baseline (the detector's or the lever's response after a large snap-off) is no attachment: the last
rupture there is the pull-off.

:func:`fit_tethers` fits each rupture's rise with a worm-like chain (:mod:`.wlc`: contour and persistence
lengths with standard errors, undetermined with a reason when the rise cannot fix them) and reads the loading
rate at the rupture. :func:`wlc_force` (from :mod:`.wlc`) is the closed-form chain (Marko & Siggia,
Macromolecules 28, 8759 (1995)) that :func:`afmforce.analysis.synthetic.tether_curve` builds its tethers with.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ._units import unit as _u
from .wlc import MAX_RELATIVE_ERROR, WlcFit, fit_rise, loading_rate, wlc_force

__all__ = ["TetherRupture", "wlc_force", "baseline_return", "renewed_pull", "running_median", "ruptures", "fit_tethers",
           "BACK_FRACTION", "LOADING_WINDOW"]

#: The retract is back at its free baseline where its running median lies above this fraction of the
#: significance threshold (``nsigma`` noise) below it ... [-]
BACK_FRACTION = 0.5
#: ... for this many running-median windows in a row [-].
BACK_HOLD = 2
#: The loading rate is read on the last ``max(running-median window, LOADING_WINDOW)`` attached samples [-].
LOADING_WINDOW = 10


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
    wlc : WlcFit or None  the worm-like-chain fit of the rise before the rupture (:func:`fit_tethers`; None:
        not fitted, ``loading_rate_reason`` says why)
    loading_rate, loading_rate_se : float  slope of the pull against time at the rupture and its standard
        error [N/s] (NaN: undetermined)
    loading_rate_reason : str  why the loading rate is undetermined ('' when it is not)
    loading_rate_method : str  ``"chain"``: the piezo speed times the lever and the fitted chain in series, v k s / (k + s)
        (``s`` the chain's stiffness at the rupture); ``"force"``: the pull's own slope in time (a parabola), when the chain's stiffness is
        undetermined ('' : none)
    fit_start : int  first sample of the curve in the rise fitted [-] (-1: none)
    """

    index: int = _u("")
    separation: float = _u("m")
    distance: float = _u("m")
    force: float = _u("N")
    drop: float = _u("N")
    tether: bool = _u("")
    wlc: WlcFit | None = None
    loading_rate: float = _u("N/s", math.nan)
    loading_rate_se: float = _u("N/s", math.nan)
    loading_rate_reason: str = ""
    loading_rate_method: str = ""
    fit_start: int = _u("", -1)


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


def fit_tethers(rs: list[TetherRupture], u: np.ndarray, x: np.ndarray, h: np.ndarray, t: np.ndarray | None,
                idx: np.ndarray,
                start: int, w: int, k: float, noise: float, temperature: float,
                model: str = "marko-siggia") -> list[TetherRupture]:
    """Each rupture with the worm-like-chain fit of its rise and its loading rate (:mod:`.wlc`).

    The rise of a rupture is the retract from ``w`` samples after the previous rupture (the first: after
    ``start``, the pull-off or the contact's end; the lever's response to a snap-off left out) to the sample
    before its last attached one (that one may be caught mid-drop, as :func:`ruptures` reads the pull),
    where the separation is positive; its extension is the tip--sample separation, its force the pull
    ``-u k``. The loading rate, the slope of the pull against time at the rupture, is read on the last
    ``max(w, LOADING_WINDOW)`` samples of the rise: the piezo's speed there times the lever and the fitted
    chain in series (``v k s / (k + s)``, ``s`` = ``WlcFit.slope``), else the pull's own slope
    (:func:`~.wlc.loading_rate`: a parabola, much noisier: on the SMFS curve its error is as large as the
    rate). Tethers pulled in parallel add their forces, one molecule unfolding (a sawtooth) does not: the
    rises are fitted from the last (which holds its chain alone) to the first, each alone and with the later
    determined chains' forces taken out; the better fit (smaller residual) is kept (``WlcFit.parallel``: how
    many were taken out), and the loading rate then counts their stiffness too. When the residuals cannot
    tell the two apart (:data:`AMBIGUOUS_CHI2`), the difference of their L_c and l_p joins the errors.

    Parameters
    ----------
    rs : list of TetherRupture  the ruptures (:func:`ruptures`)
    u : ndarray  the retract's deflection from the curve's zero of force [m]
    x : ndarray  the retract's position [m]
    h : ndarray  the retract's separation [m]
    t : ndarray or None  the retract's times [s] (None: no time base, no loading rate)
    idx : ndarray  the retract's samples in the curve [-]
    start : int  run sample where the tip left the surface [-]
    w : int  running-median window [samples]
    k : float  spring constant [N/m] (NaN: no fit, forces unknown)
    noise : float  baseline noise [N]
    temperature : float  [K]
    model : str  :data:`~.wlc.WLC_MODELS`
    """
    if not math.isfinite(k):
        return [dataclasses.replace(rup, loading_rate_reason="no force: the spring_constant is unknown") for rup in rs]
    rises = []
    prev = max(int(start), 0)
    for rup in rs:
        r = int(np.searchsorted(idx, rup.index))
        seg = np.arange(min(prev + w + 1, r), r)
        prev = r
        rises.append(seg[h[seg] > 0.0])
    fits: list[WlcFit | None] = [None] * len(rs)
    for m in range(len(rs) - 1, -1, -1):   # the last first: its rise holds its chain alone
        seg = rises[m]
        f = -u[seg] * k
        fit = fit_rise(h[seg], f, temperature, model, noise)
        later = [q for q in fits[m + 1:] if q is not None and q.determined]
        if later and seg.size:   # the later chains still attached, in parallel: taken out when that fits better
            bg = np.sum([q.chain(h[seg]) for q in later], axis=0)
            if np.all(np.isfinite(bg)):
                alt = dataclasses.replace(fit_rise(h[seg], f - bg, temperature, model, noise), parallel=len(later))
                best, other = (alt, fit) if alt.rms < fit.rms else (fit, alt)
                fit = _ambiguous(best, other, noise)
        fits[m] = fit
    out = []
    for m, rup in enumerate(rs):
        seg, fit = rises[m], fits[m]
        f = -u[seg] * k
        tail = seg[-max(w, LOADING_WINDOW):]
        extra = 0.0   # the stiffness of the later chains pulled with it
        if fit.parallel and seg.size:
            extra = float(sum(q.stiffness(float(h[seg[-1]])) for q in fits[m + 1:] if q is not None and q.determined))
        if t is None:
            rate, se, why, how = math.nan, math.nan, "no time base in the file", ""
        else:
            rate, se, why, how = _loading_rate(fit, t[tail], x[tail], f[f.size - tail.size:], k, noise, extra)
        out.append(dataclasses.replace(rup, wlc=fit, loading_rate=rate, loading_rate_se=se, loading_rate_reason=why,
                                       loading_rate_method=how, fit_start=int(idx[seg[0]]) if seg.size else -1))
    return out


#: Two fits of a rise (alone, or with the later chains taken out) whose residual sums differ by less than this
#: many residual variances are told apart by nothing but the model: their difference joins the errors [-].
AMBIGUOUS_CHI2 = 4.0


def _ambiguous(best: WlcFit, other: WlcFit, noise: float) -> WlcFit:
    """``best``, its L_c and l_p errors widened by their difference from ``other`` when the data cannot tell the
    two fits apart (a later chain's small, smooth force is mimicked by a shorter l_p and an offset: two
    parallel virtual tethers' first came out l_p 0.354 +- 0.011 nm alone, 0.399 with the second taken out,
    with residuals equal to 0.06 %); an error over a third of its value leaves it undetermined."""
    if not (best.determined and other.determined and best.points == other.points and best.points > 3):
        return best
    s2 = max(best.rms, noise) ** 2
    if best.points * (other.rms ** 2 - best.rms ** 2) >= AMBIGUOUS_CHI2 * s2:
        return best
    L_se = math.hypot(best.contour_length_se, best.contour_length - other.contour_length)
    p_se = math.hypot(best.persistence_length_se, best.persistence_length - other.persistence_length)
    loose = [n for n, v, e in (("L_c", best.contour_length, L_se), ("l_p", best.persistence_length, p_se))
             if e > MAX_RELATIVE_ERROR * v]
    why = (f"the rise fits as well alone as with the later chains pulled in parallel taken out: "
           f"{' and '.join(loose)} undetermined" if loose else "")
    return dataclasses.replace(best, contour_length=math.nan if "L_c" in loose else best.contour_length,
                               contour_length_se=math.nan if "L_c" in loose else L_se,
                               persistence_length=math.nan if "l_p" in loose else best.persistence_length,
                               persistence_length_se=math.nan if "l_p" in loose else p_se,
                               reason="; ".join(w for w in (best.reason, why) if w))


def _loading_rate(fit: WlcFit, t: np.ndarray, z: np.ndarray, f: np.ndarray, k: float,
                  noise: float, extra: float = 0.0) -> tuple[float, float, str, str]:
    """The loading rate at a rupture [N/s], its standard error, why undetermined, and how it was read: the
    piezo's speed ``v`` (a line of the position ``z`` in time) times the lever and the chain in series,
    ``k s / (k + s)`` with ``s`` the fitted chain's stiffness there (Evans's ``k_eff v``), else the pull's
    own slope in time. ``extra``: the stiffness of the later chains pulled in parallel [N/m]."""
    if math.isfinite(fit.slope) and t.size >= 3 and np.ptp(t) > 0:
        tc = t - t.mean()
        v = abs(float(tc @ (z - z.mean()) / (tc @ tc)))
        s_, se_s = fit.slope + extra, fit.slope_se
        if v > 0 and s_ > 0:
            keff = k * s_ / (k + s_)
            return v * keff, v * se_s * k ** 2 / (k + s_) ** 2, "", "chain"
    rate, se, why = loading_rate(t, f, noise)
    return rate, se, why, "force" if not why else ""
