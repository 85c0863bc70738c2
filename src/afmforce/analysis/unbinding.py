"""Adhesion for every contact kind: the retract's dip below its own baseline.

The adhesion of a curve is the deepest retract force below the retract's own
zero-force baseline (a robust line through the retract's free part, against
position: a tilted baseline is followed), so it is always <= 0. It is reported
(``found``) only when it exceeds ``nsigma`` times the baseline noise (the robust
standard deviation of the free part about that line, which includes the slow
noise a sample-to-sample estimate misses). With it come its position, the last
rupture (where the retract comes back to the baseline for good, as a distance
from the contact point) and the unbinding steps: upward steps of the smoothed
retract between the deepest point and the last rupture, each larger than
``nsigma`` noise; on a hard contact the pull-off jump that ends the dip is not one.
The distances count from the approach's contact point, or, when the retract leaves
its repulsive contact (falls below its baseline) inside it -- a soft sample that
relaxed during the contact, a cell -- from there (``detach_position``): measured
from the approach's contact point they came out negative, a rupture "before contact".

This is the adhesion of soft and biological samples (unbinding, tethers) as well
as of rigid ones; the paper's hard-contact pull-off (:mod:`.jumps`) stays for
hard contacts, where it is the same dip ending in one jump. On a hard contact
(``hard``) the adhesion is the tip--surface detachment, the dip before the
retract comes back to its baseline; the tethers pulled after it are reported on
their own, every rupture counted, the last rupture as a separation
(:mod:`.tethers`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ._adhesion_kernel import adhesion_core, baseline_spread_core
from ._median import median
from ._glue_kernel import COMPILED, robust_line_ab
from ._numeric import mad_sigma, robust_line_thin
from .regions import RunRegions
from ._units import unit as _u
from .tethers import (BACK_FRACTION, BACK_HOLD, TetherRupture, baseline_return, fit_tethers, renewed_pull,
                      running_median, ruptures)
from .options import AdhesionOptions as _A  # the default: declared once, in the step's record
from .wlc import DEFAULT_TEMPERATURE

__all__ = ["UnbindingStep", "Adhesion", "retract_adhesion", "baseline_spread", "BASELINE_SPREAD_NOTE", "RETURN_SPAN"]


@dataclass(frozen=True)
class UnbindingStep:
    """One upward step of the retract (a bond or tether letting go).

    Attributes
    ----------
    index : int  sample of the curve just after the step [-]
    distance : float  distance from the contact point [m]
    force : float  height of the step [N] (> 0; deflection [m] when k is unknown)
    """

    index: int = _u("")
    distance: float = _u("m")
    force: float = _u("N")


@dataclass(frozen=True)
class Adhesion:
    """Adhesion of the retract run.

    Attributes
    ----------
    found : bool  the dip exceeds ``nsigma`` noise
    force : float  deepest force below the retract baseline [N] (<= 0; NaN without k)
    deflection : float  the same in deflection [m] (<= 0)
    index : int  sample of the deepest point [-]
    distance : float  its distance from the contact point [m]
    noise : float  baseline noise [N] (deflection noise x k)
    nsigma : float  multiple of the noise a dip must exceed [-]
    rupture_distance : float  distance from the contact point of the last rupture [m]; on a hard contact
        the tip--sample separation there (the pull-off's, about 0, when no tether holds the tip)
    steps : tuple of UnbindingStep
    verdict : str
    tethers : tuple of TetherRupture
        Hard contact: every rupture after the pull-off (:mod:`.tethers`); ``tether`` marks those after the
        retract came back to its free baseline (empty on soft contacts: their ruptures are ``steps``)
    detach_position : float  where the retract leaves its repulsive contact, from the approach's contact
        point towards the sample [m] (> 0 on a relaxing sample: the distances above are measured from
        there; 0: from the approach's contact point)
    dip_sigmas : float  depth of the deepest dip in baseline noise sigmas [-] (reported also when it is
        under ``nsigma``: the verdict then gives the dip and why it is not counted)
    dip_force : float  the deepest dip below the baseline [N] (<= 0; deflection [m] when k is unknown), also
        when it is not counted (``force`` is then NaN)
    baseline_spread : float  the baseline model's systematic on ``force`` [N] (deflection [m] when k is
        unknown): the largest difference of the dip's depth measured from the other reasonable baselines
        (:func:`baseline_spread`) and from the reported line (NaN when not assessed)
    return_distance : float  where the retract comes back within ``nsigma`` noise of its baseline for good,
        from the contact point [m] (soft contacts; ``rupture_distance`` is that point only when the return is
        a step, a rupture; a gradual return is no rupture)
    """

    found: bool
    force: float = _u("N")
    deflection: float = _u("m")
    index: int = _u("")
    distance: float = _u("m")
    noise: float = _u("N")
    nsigma: float = _u("")
    rupture_distance: float = _u("m")
    steps: tuple[UnbindingStep, ...]
    verdict: str
    tethers: tuple[TetherRupture, ...] = ()
    detach_position: float = _u("m", 0.0)
    dip_sigmas: float = _u("", math.nan)
    dip_force: float = _u("N", math.nan)
    baseline_spread: float = _u("N", math.nan)
    return_distance: float = _u("m", math.nan)

    @property
    def tether_count(self) -> int:
        """Tethers: ruptures after the retract came back to its free baseline [-]."""
        return sum(1 for t in self.tethers if t.tether)


def retract_adhesion(d: np.ndarray, position: np.ndarray, run: RunRegions, spring_constant: float, *,
                     nsigma: float = _A.nsigma, smooth: int | None = None, pull_off: int = -1,
                     separation: np.ndarray | None = None, hard: bool = False, time: np.ndarray | None = None,
                     temperature: float = DEFAULT_TEMPERATURE, wlc_model: str = _A.wlc_model) -> Adhesion:
    """The retract's deepest dip below its own baseline, last rupture and unbinding steps.

    Parameters
    ----------
    d : ndarray
        Deflection [m] of the whole curve.
    position : ndarray
        Position relative to the contact point [m] (0 at contact, negative away from the sample).
    run : RunRegions
        The retract run (``zero_force`` marks its free part).
    spring_constant : float
        [N/m]; NaN gives forces as NaN (deflections stay).
    nsigma : float
        Multiple of the baseline noise [-].
    smooth : int, optional
        Running-median window for the steps [samples] (default: about 1/400 of the run, at least 3).
    pull_off : int
        Sample of the curve at a hard contact's pull-off jump (the jumps step's last contact sample;
        -1: none). The rise that contains it is the end of the dip, the adhesion itself, not an
        unbinding step (the Asylum SiN curve in air: its pull-off and the lever's settling after it
        were counted as one step).
    separation : ndarray, optional
        Tip--sample separation [m] of the whole curve (with ``hard``).
    hard : bool
        A hard (rigid) contact: the adhesion is the tip--surface detachment, the dip before the retract
        comes back to its free baseline; later dips are tethers (:mod:`.tethers`), every rupture counted;
        the last rupture is given as a separation (the pull-off's when no tether holds the tip: a monotone
        relaxation back to the baseline after a large snap-off is no attachment).
    time : ndarray, optional
        Times of the whole curve [s] (None: no time base; the tethers' loading rates are then undetermined).
    temperature : float
        [K] of the tethers' worm-like-chain fits (:mod:`.wlc`).
    wlc_model : str
        Their chain model (:data:`~.wlc.WLC_MODELS`).
    """
    idx = run.index
    pull_off = int(np.searchsorted(idx, pull_off)) if pull_off >= 0 and idx[0] <= pull_off <= idx[-1] else -1
    k = spring_constant if math.isfinite(spring_constant) else math.nan
    x, y = position[idx], d[idx]
    free = run.zero_force & ~run.saturated
    fast = True
    if np.count_nonzero(free) < 10:  # no free part found: the farthest 30 % of the run
        fast = False  # (few baseline samples: the numpy path, which also treats an empty one)
        far = x <= np.quantile(x, 0.3)
        free = far & ~run.saturated
    xf = x[free]
    xm = float(xf.mean())
    xc, yf = xf - xm, y[free]
    ok, mad = False, -1.0
    if COMPILED and fast and xc.size <= 4001:  # robust_line's a and b, selected in place (robust_line_thin: <= 4001)
        a, b, mad, ok = robust_line_ab(xc, yf)
    if not ok:
        a, b, *_ = robust_line_thin(xc, yf)
    hint = float(mad) if ok and math.isfinite(b) else -1.0  # the line's residual MAD (none for the median's flat line)
    if not math.isfinite(b):
        a, b = float(np.median(y[free])), 0.0
    w = smooth or max(3, (idx.size // 400) | 1)
    tail = None
    if COMPILED and fast and w % 2 == 1 and x.dtype == np.float64 and y.dtype == np.float64:
        ok, sigma, j, depth, found, last, at, rise = adhesion_core(
            x, y, free, run.saturated, float(a), float(b), xm, float(nsigma), int(w), pull_off, hint)
        if ok:
            back = min(last + 1, x.size - 1) if found else -1
            rupture = float(-x[back]) if found else math.nan
            kk = k if math.isfinite(k) else 1.0
            steps = [UnbindingStep(int(idx[min(s, idx.size - 1)]), float(-x[min(s, x.size - 1)]), float(r * kk))
                     for s, r in zip(at.tolist(), rise.tolist())]
            tail = float(sigma), int(j), float(depth), bool(found), rupture, steps, int(back)
    if tail is None:
        tail = _tail_numpy(x, y, free, run.saturated, idx, a, b, xm, nsigma, w, k, pull_off)
    sigma, j, depth, found, rupture, steps, back = tail
    if steps:   # each step where it is (the running median's rise placed it up to a window late)
        steps = _locate_steps(y - (a + b * (x - xm)), x, idx, steps, w)
    base = (a, b, xm, free)   # the baseline the dip is measured from (refitted below on a hard contact's tethers)
    tethers: tuple[TetherRupture, ...] = ()
    within = False
    if hard and separation is not None and sigma > 0:
        u = y - (a + b * (x - xm))
        if np.all(np.isfinite(u)):
            hh = separation[idx]
            out = _hard(u, x, hh, idx, run, sigma, nsigma, w, k, pull_off, j, depth, found)
            if out[5] and any(t.tether for t in out[5]):
                # the tethers lie in the free part the baseline was fitted on: fitted again on the samples
                # after the last rupture (a virtual curve's tethers pulled its baseline 40-60 pN down)
                after = free & (np.arange(x.size) > int(np.searchsorted(idx, out[5][-1].index)) + w)
                if np.count_nonzero(after) >= 10:
                    xa = x[after]
                    a2, b2, *_ = robust_line_thin(xa - xa.mean(), y[after])
                    if math.isfinite(b2):
                        u2 = y - (a2 + b2 * (x - xa.mean()))
                        r2 = u2[after]
                        s2 = float(1.4826 * np.median(np.abs(r2 - np.median(r2))))
                        if s2 > 0 and np.all(np.isfinite(u2)):
                            sigma, base = s2, (a2, b2, float(xa.mean()), after)
                            j, depth, found = int(np.argmin(u2)), min(float(u2.min()), 0.0), False
                            found = -depth > nsigma * sigma
                            out = _hard(u2, x, hh, idx, run, sigma, nsigma, w, k, pull_off, j, depth, found)
            j, depth, found, rupture, steps, tethers, within = out
            if tethers:   # each rupture's rise: a worm-like-chain fit and the loading rate (analysis.wlc), on
                # the deflection from the curve's zero of force (the figure's force; the retract's own baseline,
                # refitted on the free part after the last rupture, tilts over a short free part: a virtual
                # tether's L_c came out 1.2-2.5 nm, 2-4 standard errors, long on it)
                tethers = tuple(fit_tethers(list(tethers), y, x, hh,
                                            None if time is None else time[idx], idx, _left_at(run, pull_off), w,
                                            k, sigma * (k if math.isfinite(k) else 1.0), temperature, wlc_model))
    hard_path = hard and separation is not None
    ref, unplaced = 0.0, False
    returned, gradual = math.nan, False
    if not hard_path:  # a hard contact's distances are separations (:func:`_hard`)
        ref = _detach_position(x, y - (a + b * (x - xm)), j)
        ref = ref if ref > 0.0 else 0.0
        if found and back >= 0:   # the return to the baseline is a rupture only when it is a step (not a slope)
            returned = rupture
            gradual = not _abrupt_return(y - (a + b * (x - xm)), back, w, nsigma * sigma)
            if gradual:   # the last rupture is the last unbinding step before it (none: undetermined)
                before = [st_ for st_ in steps if -st_.distance >= x[back]]
                rupture = before[-1].distance if before else math.nan
        if ref > 0.0:  # the retract left the contact inside the approach's contact point: distances from there
            rupture = rupture + ref if math.isfinite(rupture) else rupture
            returned = returned + ref if math.isfinite(returned) else returned
            steps = [dataclasses.replace(s, distance=s.distance + ref) for s in steps]
    kk = k if math.isfinite(k) else 1.0
    spread = baseline_spread(x, y, base[3], base[0], base[1], base[2], j, nsigma * sigma) * kk if sigma > 0 else math.nan
    distance = float(ref - x[j])
    unplaced = not hard_path and found and not distance >= 0.0  # the dip inside the contact point, no contact
    if unplaced:  # seen before it (a retract cut short: PyJibe's invalid_dataset.jpk-force, 53 of 5000 samples)
        distance, rupture, returned = math.nan, math.nan, math.nan
        steps = [dataclasses.replace(s, distance=math.nan) for s in steps]
    force = depth * k
    unit, scale, val = ("nN", 1e9, force) if math.isfinite(k) else ("nm", 1e9, depth)
    noise_v = sigma * (k if math.isfinite(k) else 1.0)
    nt = sum(1 for t in tethers if t.tether)
    more = (f"; {nt} tether(s) after the tip left the surface, ruptures at "
            + ", ".join(f"{t.separation * 1e9:.4g} nm ({t.force * scale:.3g} {unit})" for t in tethers if t.tether)
            if nt else "")
    where = " separation" if hard_path else ""
    if unplaced:
        verdict = (f"adhesion {val * scale:.3g} {unit} ({-depth / sigma:.3g} x the baseline noise "
                   f"{noise_v * scale:.2g} {unit}), {(x[j] - ref) * 1e9:.4g} nm inside the contact point with no "
                   "contact recorded before it on the retract (a retract cut short?): its distance, the last "
                   f"rupture's and the steps' undetermined; {len(steps)} unbinding step(s)")
    elif found:
        last_words = (f"last rupture at {rupture * 1e9:.4g} nm{where}" if math.isfinite(rupture) else
                      "last rupture undetermined")
        verdict = (f"adhesion {val * scale:.3g} {unit} ({-depth / sigma:.3g} x the baseline noise "
                   f"{noise_v * scale:.2g} {unit}) at {(ref - x[j]) * 1e9:.4g} nm from contact; {last_words}; "
                   f"{len(steps)} unbinding step(s){more}")
        if gradual:
            verdict += (f"; the retract comes back to its baseline gradually at {returned * 1e9:.4g} nm (no step: "
                        "a long-range attraction or a slow release, not a rupture)")
        if ref > 0.0:
            verdict += (f" (distances from where the retract leaves its contact, {ref * 1e9:.4g} nm inside the "
                        "approach's contact point: the sample relaxed)")
    elif within:
        verdict = (f"no tip-surface adhesion above {nsigma:g} x the baseline noise ({noise_v * scale:.2g} {unit}): "
                   f"{val * scale:.2g} {unit} before the retract came back to its baseline; last rupture at "
                   f"{rupture * 1e9:.4g} nm{where}; {len(steps)} unbinding step(s){more}")
    else:
        verdict = (f"no adhesion above {nsigma:g} x the baseline noise ({noise_v * scale:.2g} {unit}, "
                   f"adhesion.nsigma): the deepest dip, {val * scale:.2g} {unit}, is "
                   f"{-depth / sigma if sigma > 0 else 0:.2g} x the noise")
    if ((found or within) and math.isfinite(spread) and spread > noise_v
            and spread > BASELINE_SPREAD_NOTE * abs(depth * kk)):
        verdict += (f"; baseline model +-{spread * scale:.2g} {unit} (the dip from the free part's line, its "
                    "quadratic and its far half's line differ: the free baseline bends)")
    keep = found or within   # with tethers, an adhesion within the noise is a number: about 0, not the tethers'
    return Adhesion(bool(found), float(force) if keep else math.nan, float(depth) if keep else math.nan,
                    int(idx[j]), distance, float(noise_v), float(nsigma), float(rupture), tuple(steps), verdict,
                    tethers=tuple(tethers), detach_position=float(ref),
                    dip_sigmas=float(-depth / sigma) if sigma > 0 else math.nan, dip_force=float(depth * kk),
                    baseline_spread=float(spread) if keep else math.nan, return_distance=float(returned))


#: The verdict names the baseline model's systematic (:func:`baseline_spread`) when it exceeds the baseline
#: noise and this fraction of the adhesion [-] (always given: ``baseline_spread``, the table's
#: ``adhesion_baseline_spread``; on the shared real curves it exceeds the noise on 376 of 412, mostly by
#: about 1 % of a large adhesion: the verdict would say it on nearly every curve).
BASELINE_SPREAD_NOTE = 0.05
#: A return to the baseline is a rupture (a step) when the retract's median over the ``RETURN_SPAN`` samples
#: after it (at least one running-median window) lies more than ``BACK_FRACTION`` of the threshold above its
#: median over as many samples before it [-].
RETURN_SPAN = 10


def _locate_steps(u: np.ndarray, x: np.ndarray, idx: np.ndarray, steps: list, w: int) -> list:
    """The unbinding steps moved to where each is: the run sample, among the ``w + 2`` up to the one the running
    median's rise gave (the first after its largest rise over ``w`` samples: up to a window late; the JPK cell
    map, w = 31: 21-27 samples after a two-window step detector's), where the mean of ``u`` over the
    ``max(2, w // 2)`` samples from it less the mean over as many before it is largest (a step's matched
    filter). ``u``: the residual about the baseline [m]; the steps' heights stay."""
    h = max(2, int(w) // 2)
    n = u.size
    c = np.concatenate(([0.0], np.cumsum(u)))
    out = []
    for st_ in steps:
        s = int(np.searchsorted(idx, st_.index))
        lo, hi = max(s - int(w) - 1, h), min(s, n - h)
        if hi < lo:
            out.append(st_)
            continue
        i = np.arange(lo, hi + 1)
        jump = (c[i + h] - c[i]) - (c[i] - c[i - h])
        at = int(i[int(np.argmax(jump))])
        out.append(dataclasses.replace(st_, index=int(idx[at]), distance=float(-x[at])))
    return out


def _abrupt_return(u: np.ndarray, back: int, w: int, thr: float) -> bool:
    """Whether the retract's return to its baseline at run sample ``back`` is a step (a rupture).

    ``u``: the residual about the baseline [m]; ``thr``: the significance threshold [m]. The median of the
    ``max(w, RETURN_SPAN)`` samples after ``back`` must lie more than ``BACK_FRACTION thr`` above the median of
    as many before it: a rupture drops from below ``-thr`` to about zero at once; a gradual return (a long-range
    attraction, a slow release) rises by its slope times the span (the PicoForce colloid curve in water: 0.3 x
    the threshold over 25 nm, where its running median crossed the threshold 323 nm out and was called the
    last rupture)."""
    m = max(int(w), RETURN_SPAN)
    lo, hi = max(back - m, 0), min(back + m, u.size)
    if back - lo < 2 or hi - back < 2:
        return True   # at an end of the record: nothing to tell a step from
    return float(median(u[back:hi]) - median(u[lo:back])) > BACK_FRACTION * thr   # np.median's numbers


def baseline_spread(x: np.ndarray, y: np.ndarray, free: np.ndarray, a: float, b: float, xm: float, j: int,
                    thr: float) -> float:
    """The baseline model's systematic on the dip at run sample ``j`` [m of deflection].

    The adhesion is read from a robust line through the retract's free part, extrapolated to the dip. When
    the free baseline bends (a long-range force at its near end, a slowly relaxing lever, interference), other
    reasonable baselines give other depths: a quadratic through the whole free part and a line through its
    far half (the part farthest from the surface, where a surface-force experimentalist takes the zero of
    force). The result is the largest difference between their value at the dip and the line's ``a + b (x -
    xm)``; the samples more than ``thr`` off the line (glitches, tethers) are left out of both. NaN when the
    free part has fewer than 10 samples.

    Parameters
    ----------
    x, y : ndarray  the run's positions [m] and deflections [m]
    free : ndarray of bool  its baseline samples
    a, b, xm : float  the reported baseline line: ``a + b (x - xm)`` [m], [-], [m]
    j : int  the dip's run sample
    thr : float  the significance threshold [m]
    """
    if COMPILED and x.dtype == y.dtype == np.float64 and free.dtype == np.bool_ and x.size == y.size == free.size:
        out, ok = baseline_spread_core(x, y, free, float(a), float(b), float(xm), int(j), float(thr))
        if ok:   # (one compiled call: its fits equal numpy's to rounding; issue 35)
            return float(out)
    xf, yf = x[free], y[free]
    keep = np.abs(yf - (a + b * (xf - xm))) <= thr
    xf, yf = xf[keep], yf[keep]
    if xf.size < 10:
        return math.nan
    c = float(xf.mean())
    span = float(np.ptp(xf)) or 1.0
    s, sj = (xf - c) / span, (float(x[j]) - c) / span
    line = a + b * (float(x[j]) - xm)
    out = math.nan
    quad = _lstsq_at(s, yf, 2, sj)   # (the normal equations of s scaled to unit span: np.polyfit's numbers, 5x faster)
    if math.isfinite(quad):
        out = abs(quad - line)
    far = xf <= np.median(xf) if float(x[j]) > c else xf >= np.median(xf)   # the half away from the dip
    if np.count_nonzero(far) >= 5:
        lin = _lstsq_at(s[far], yf[far], 1, sj)
        if math.isfinite(lin):
            out = abs(lin - line) if not out >= abs(lin - line) else out
    return out


def _lstsq_at(s: np.ndarray, y: np.ndarray, deg: int, at: float) -> float:
    """The least-squares polynomial of degree ``deg`` through ``(s, y)`` read at ``at`` (NaN when singular)."""
    sm = float(s.mean())
    t = s - sm
    p = [np.ones_like(t)]
    for _ in range(deg):
        p.append(p[-1] * t)
    A = np.array([[float(np.dot(p[i], p[k])) for k in range(deg + 1)] for i in range(deg + 1)])
    r = np.array([float(np.dot(p[i], y)) for i in range(deg + 1)])
    try:
        coef = np.linalg.solve(A, r)
    except np.linalg.LinAlgError:
        return math.nan
    return float(sum(coef[i] * (at - sm) ** i for i in range(deg + 1)))


def _left_at(run: RunRegions, pull_off: int) -> int:
    """Run sample where the tip leaves a hard surface: the pull-off jump's, else the contact's last [-]."""
    contact = np.flatnonzero(run.contact)
    return pull_off if pull_off >= 0 else (int(contact.max()) if contact.size else int(run.split))


def _hard(u, x, h, idx, run, sigma, nsigma, w, k, pull_off, j, depth, found):
    """The adhesion of a hard contact and its tethers (:mod:`.tethers`).

    The tip leaves the surface at the pull-off (``pull_off``, run sample; else at the end of the contact
    line); the surface's adhesion is the deepest dip before the retract's running median comes back to its
    free baseline (above :data:`~.tethers.BACK_FRACTION` of the threshold below it, for
    :data:`~.tethers.BACK_HOLD` windows) or, sooner, before a renewed pull (:func:`~.tethers.renewed_pull`:
    a tether already taut when the tip snaps off). Every rupture after the pull-off is an unbinding step; those after
    the return are tethers. The last rupture is the last of them, else the pull-off (the separation there).

    Returns ``(j, depth, found, rupture, steps, tethers, within)``; ``within``: tethers hold the tip and the
    surface's adhesion is within the noise (its number is kept: about 0).
    """
    thr = nsigma * sigma
    us = running_median(u, w)
    start = _left_at(run, pull_off)
    back = min(baseline_return(us, start + 1, BACK_FRACTION * thr, BACK_HOLD * w),
               renewed_pull(us, start + 1, thr, BACK_HOLD * w))
    found_all = found
    tail = us[back:]
    if back >= u.size or not np.any(tail < -thr):
        # no dip after the retract came back: the deepest dip is the surface's (the old answer); a monotone
        # relaxation after the pull-off holds no tether: the last rupture is the pull-off, unless a rupture
        # (a renewed pull that let go) lies between the pull-off and the return
        rs = ruptures(u, us, x, h, idx, start, back, thr, w, k, skip=pull_off)
        steps = tuple(UnbindingStep(r.index, r.distance, r.drop) for r in rs)
        if not found_all:
            return j, depth, found, math.nan, steps, tuple(rs), False
        end = rs[-1].separation if rs else float(h[min(max(start, j), h.size - 1)])
        return j, depth, found, end, steps, tuple(rs), False
    ok = ~run.saturated[:back] | (u[:back] < 0)
    jj = int(np.argmin(np.where(ok, u[:back], np.inf)))
    dd = min(float(u[jj]), 0.0)
    ff = -dd > thr
    rs = ruptures(u, us, x, h, idx, start, back, thr, w, k, skip=pull_off if ff else -1)
    steps = tuple(UnbindingStep(r.index, r.distance, r.drop) for r in rs)
    end = rs[-1].separation if rs else math.nan
    return jj, dd, ff, end, steps, tuple(rs), not ff


def _detach_position(x: np.ndarray, u: np.ndarray, j: int) -> float:
    """Where the retract leaves its repulsive contact [m, the position relative to the approach's contact
    point]: the first sample before the deepest dip ``j`` whose deflection ``u`` (above the retract's own
    baseline) falls below zero. On a soft, relaxing sample (a cell) the retract crosses zero force inside
    the approach's contact point (the surface did not come back with the tip), and the dip and the last
    rupture measured from the approach's contact point would come out negative: a rupture "before
    contact". The distances are measured from this point when it lies inside the contact point (> 0)."""
    below = np.flatnonzero(u[: j + 1] < 0.0)
    if not below.size or below[0] == 0:  # the run starts below its baseline: no contact part to leave
        return math.nan
    return float(x[below[0]])


def _tail_numpy(x, y, free, saturated, idx, a, b, xm, nsigma, w, k, pull_off):
    """What :func:`~._adhesion_kernel.adhesion_core` computes, in numpy (the reference; used when the
    kernels are not compiled, or a residual is not finite): ``(sigma, j, depth, found, rupture, steps, back)``
    (``back``: the run sample where the retract is back at its baseline, -1 when no dip counts)."""
    u = y - (a + b * (x - xm))
    sigma = float(1.4826 * np.median(np.abs(u[free] - np.median(u[free]))))
    if not sigma > 0:
        sigma = float(mad_sigma(np.diff(u[free])) / math.sqrt(2.0))
    ok = ~saturated | (u < 0)  # a clipped bottom is still a dip (a lower bound)
    j = int(np.argmin(np.where(ok, u, np.inf)))
    depth = min(float(u[j]), 0.0)
    thr = nsigma * sigma
    found = -depth > thr
    from scipy.ndimage import median_filter  # here: its import costs 0.25 s of every command
    us = median_filter(u, size=w, mode="nearest")
    steps: list[UnbindingStep] = []
    rupture = math.nan
    back = -1
    if found:
        below = np.flatnonzero(us[j:] < -thr) + j
        last = int(below[-1]) if below.size else j
        back = min(last + 1, x.size - 1)
        rupture = float(-x[back])
        seg = us[j: min(last + w + 1, us.size)]
        if seg.size > w:
            rise = seg[w:] - seg[:-w]
            cand = np.flatnonzero(rise > thr)
            i = 0
            while i < cand.size:  # one step per run of candidates: its largest rise
                group = [cand[i]]
                while i + 1 < cand.size and cand[i + 1] - cand[i] <= w:
                    i += 1
                    group.append(cand[i])
                i += 1
                if pull_off >= 0 and j + group[0] - w <= pull_off <= j + group[-1] + w:
                    continue  # the hard contact's pull-off jump (its tail included) ends the dip: not a step of it
                g = max(group, key=lambda q: rise[q])
                s_idx = j + g + w
                steps.append(UnbindingStep(int(idx[min(s_idx, idx.size - 1)]),
                                           float(-x[min(s_idx, x.size - 1)]),
                                           float(rise[g] * (k if math.isfinite(k) else 1.0))))
    return sigma, j, depth, found, rupture, steps, back
