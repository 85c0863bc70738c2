"""Pipeline steps that prepare a curve: smoothing of the position, contact regions, drift, fringes."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..errors import AnalysisError
from ._numeric import running_mean
from .drift import remove_drift
from .fringes import FringeResult, fit_fringes, fringe_baseline, fringe_signal, loop_width, position_map
from .options import ContactOptions, DriftOptions, FringesOptions, SmoothOptions
from .registry import AnalysisStep
from .regions import check_compliance, find_run_regions, run_indices, saturated_mask
from .state import ContactSummary, NoContact, SmoothResult, State

from ._step_helpers import _zero_deflection_position

__all__ = ["smooth", "contact", "drift", "fringes", "retract_dip", "SMOOTH", "CONTACT", "DRIFT", "FRINGES"]


def _staircase_window(z: np.ndarray, minimum: int = 11) -> int:
    """Odd window covering two digitization steps of a stepped position channel (at least ``minimum``)."""
    same = np.diff(z) == 0
    if same.mean() < 0.3:  # no staircase
        return minimum
    edges = np.flatnonzero(np.diff(np.concatenate([[False], same, [False]]).astype(np.int8)))
    runs = edges[1::2] - edges[::2] + 1  # samples per plateau
    step = int(np.median(runs)) if runs.size else 1
    return max(minimum, 2 * step + 1)


def _smooth_run(z: np.ndarray, window: int, staircase: bool = False) -> np.ndarray:
    """Running mean of one run; for a ``staircase`` (digitized) channel, within half a window
    of the run's ends, the line through the next ``window`` fully averaged samples.

    The symmetric window shrinks at the ends, and a shrunken window cannot average out a
    digitization staircase: the last half window (5 nm of a 5 nm-step detector) would keep
    its steps, which bends the constant-compliance line that ends at the turning point.
    A smooth channel keeps the shrinking window (a line would overshoot a decelerating turn).
    """
    out = running_mean(z, window)
    half = window // 2
    if not staircase or half < 1 or z.size < 2 * window + 2 * half:
        return out
    k = np.arange(z.size, dtype=float)
    for inner, edge in ((slice(half, half + window), slice(0, half)),
                        (slice(z.size - half - window, z.size - half), slice(z.size - half, z.size))):
        b, a = np.polyfit(k[inner], out[inner], 1)
        out[edge] = a + b * k[edge]
    return out


def smooth(st: State, o: SmoothOptions) -> State:
    """Running average of the position channel, each run separately (Fig 7C).

    ``o.window="auto"``: the paper's 11 points, or two digitization steps of a
    stepped (digitized) channel if those are longer, so that the average
    interpolates linearly between levels as in the paper. On a stepped channel,
    within half a window of a run's ends the position continues the line of the
    averaged samples next to them (a shrinking window would leave the steps there).
    """
    staircase = False
    if o.window == "auto":  # the record checked a given window (a positive odd number)
        window = _staircase_window(st.z)
        staircase = window > 11
    else:
        window = int(o.window)
    z = st.z.copy()
    for which in (0, 1, 2):
        idx = run_indices(st.curve.segment, which)
        if idx.size:
            z[idx] = _smooth_run(st.z[idx], window, staircase)
    change = float(np.max(np.abs(z - st.z))) if z.size else 0.0
    return st.update("smooth", SmoothResult(window, st.channel, change), z=z)


def retract_dip(signal: np.ndarray, idx: np.ndarray) -> tuple[float, float]:
    """Depth of the retract's pull-off below its own far baseline, and the noise [signal units].

    Depth: the retract's last 30 % (median) less the lowest level held for two consecutive
    samples (a single spike does not count; a stiff lever rings after the release, the first
    swing is the pull-off); noise: from sample-to-sample differences there (blind to drift).
    Evidence of a contact the approach does not show (a stiff lever, an attractive approach end).
    """
    if idx.size < 50:
        return math.nan, math.nan
    s = signal[idx]
    far = s[int(0.7 * s.size):]
    sigma = float(np.median(np.abs(np.diff(far)))) / (0.6745 * math.sqrt(2.0))
    low = float(np.min(np.maximum(s[:-1], s[1:])))
    return float(np.median(far)) - low, sigma


def contact(st: State, o: ContactOptions) -> State:
    """Contact, constant-compliance and zero-force regions of both runs.

    A run clipped at its turning point whose contact region is no
    constant-compliance line (see :func:`~.regions.check_compliance`: not
    ``1 / flat_ratio`` times steeper than its free part, or, on the measured
    channel, ``max_slope_ratio`` times shallower than the other run's;
    ``"auto"``: 2 on the measured channel, no limit on the nominal one, whose
    creep changes the local gain) keeps no compliance line; later steps use
    the other run's and say what could not be measured.
    """
    max_slope_ratio = o.max_slope_ratio  # the record checked the ranges (> 1; flat_ratio in (0, 1])
    if max_slope_ratio == "auto":
        max_slope_ratio = 2.0 if st.channel == "measured" else math.inf
    max_slope_ratio, flat_ratio = float(max_slope_ratio), o.flat_ratio
    sat = saturated_mask(st.signal)
    kw = dict(saturated=sat, min_points=int(o.min_points), baseline_fraction=o.baseline_fraction,
              compliance_fraction=o.compliance_fraction)
    try:
        app = find_run_regions(st.z, st.signal, run_indices(st.curve.segment, 0), "approach", **kw)
    except AnalysisError as exc:
        if not str(exc).startswith("no contact region"):
            raise
        app = None
        try:  # a stiff lever barely deflects on the approach: the retract's adhesion shows the contact
            find_run_regions(st.z, st.signal, run_indices(st.curve.segment, 1), "retract", **kw)
            app = find_run_regions(st.z, st.signal, run_indices(st.curve.segment, 0), "approach",
                                   min_contrast=5.0, **kw)
        except AnalysisError:
            pass
        if app is None:
            raise NoContact(str(exc).replace("no contact region found on the approach run", "no contact reached")
                            ) from None
    ret = find_run_regions(st.z, st.signal, run_indices(st.curve.segment, 1), "retract", noise=app.noise, **kw)
    app, ret = check_compliance(st.z, st.signal, app, ret, flat_ratio=flat_ratio, max_slope_ratio=max_slope_ratio)
    summary = ContactSummary(int(app.index[app.split]), int(ret.index[min(ret.split, ret.index.size - 1)]),
                             int(app.zero_force.sum()), int(ret.zero_force.sum()), int(app.compliance.sum()),
                             int(ret.compliance.sum()), int(sat.sum()))
    warn = []
    if sat.any():
        warn.append(f"{int(sat.sum())} saturated samples (photodiode clipped) left out of the fits")
    warn += [r.note for r in (app, ret) if r.note]
    # noise of the signal from sample-to-sample differences in the approach's free part: blind to
    # slow structure (drift, fringes), so it measures the resolution the jump tests need
    return st.update("contact", summary, warn=warn, approach=app, retract=ret, noise=app.noise)


#: Retract baselines of a free part too noisy for its own line (:func:`~.drift.borrowed_line`), in words.
_BORROWED = {"offset": "no slope", "approach slope": "the approach's drift rate",
             "position tilt": "the approach baseline's tilt in position"}


def drift(st: State, o: DriftOptions) -> State:
    """Subtract a baseline line in time fitted in each run's zero-force region."""
    signal, res = remove_drift(st.time, st.signal, st.curve.segment, st.approach, st.retract, st.unit,
                               int(o.order), z=st.z if o.tail else None)
    warn = None
    if res.retract_settling:
        warn = ("the retract's free part is still relaxing after the pull-off (a curved tail, not a drift line: "
                "an overdamped cantilever): the approach baseline was used for both runs")
    elif res.retract_from_approach and not st.retract.has_compliance:
        warn = ("the retract run has no baseline of its own (its free cantilever had not settled): the approach "
                "baseline was used for both runs")
    elif res.retract_from_approach:
        warn = ("retract baseline too short or too noisy after the pull-off (free ringing?): the approach "
                "baseline was used for both runs")
    elif res.retract_line in _BORROWED:
        warn = ("the retract's free part is too noisy for a baseline line of its own (ringing, unbinding events): "
                f"its own offset with {_BORROWED[res.retract_line]}")
    return st.update("drift", res, warn=warn, signal=signal)


def fringes(st: State, o: FringesOptions) -> State:
    """Fit interference fringes in the baseline; remove them, remap nominal positions.

    ``apply="auto"``: when both runs show fringes, subtract them from the signal,
    and remap the positions if they are the piezo's *nominal* ones (a measured
    position is taken as linear, as the paper found for its detector, Fig 7B);
    ``"always"``: subtract and remap; ``"never"``: report only.

    The fit carries a line in time (what the drift step's line, pulled by the
    fringes, left of the baseline); it is subtracted with the fringes. In
    contact the fringe term is held at its value where the run's own contact
    line crosses zero signal (the separation no longer changes there).
    """
    apply, margin = o.apply, o.margin
    runs = {}
    for run in (st.approach, st.retract):
        idx = run.index[run.zero_force & ~run.saturated]  # the baseline: not the attraction, nor a settling tail
        zf = st.z[idx]
        z_split = st.z[run.index[min(run.split, run.index.size - 1)]]
        far = np.abs(zf - z_split) > margin * (np.ptp(zf) if zf.size else 0.0)  # not the attraction near contact
        if run.kind == "retract" and not runs["approach"].found and apply != "always":
            # fringes are a property of the optics, present on both runs: without them on the
            # approach nothing is changed whatever the retract shows, so it is not searched
            runs["retract"] = dataclasses.replace(runs["approach"], found=False, explained=math.nan,
                                                  period=math.nan, cycles=math.nan, residual=math.nan)
            searched = False
            continue
        runs[run.kind] = fit_fringes(zf[far], st.signal[idx][far], period=o.period, order=o.order,
                                     t=st.time[idx][far] if st.time_known else None)
        searched = True
    fa, fr = runs["approach"], runs["retract"]
    # real fringes are periodic in the true position: both runs show the same period
    both = fa.found and fr.found and abs(fa.period - fr.period) < 0.05 * 0.5 * (fa.period + fr.period)
    z, s = st.z.copy(), st.signal.copy()
    remove = apply == "always" or (apply == "auto" and both)
    remap = apply == "always" or (apply == "auto" and both and st.channel == "nominal")
    for run, fit in ((st.approach, fa), (st.retract, fr)):
        if not (remove and math.isfinite(fit.period)):
            continue
        idx = run.index
        term = fringe_signal(st.z[idx], fit)
        if o.in_contact == "hold":
            z_contact = _zero_deflection_position(st, run if run.has_compliance else st.approach)
            term = np.where(run.contact, fringe_signal(np.array([z_contact]), fit)[0], term)
        s[idx] = st.signal[idx] - term - fringe_baseline(st.time[idx], st.z[idx], fit)
        if remap:
            z[idx] = position_map(st.z[idx], fit)
    applied = remap
    width = loop_width(fa, fr, st.z[np.concatenate([st.approach.index, st.retract.index])])
    if both:
        verdict = (f"fringes of period {0.5 * (fa.period + fr.period) * 1e9:.4g} nm; position nonlinearity "
                   f"{max(fa.nonlinearity, fr.nonlinearity) * 100:.3g} %; loop width {width * 1e9:.3g} nm "
                   "(modulo one period)")
    elif fa.found or fr.found:
        verdict = "periodic baseline on one run only, or periods that differ: not fringes; nothing changed"
    elif not searched:
        why = "" if fa.converged else "; the fit wanders: no clean period"
        verdict = (f"no interference fringes in the approach baseline (a periodic term explains "
                   f"{max(fa.explained, 0.0):.2g} of its variance{why}); the retract was not "
                   "searched (fringes come from the optics and show on both runs)")
    else:
        verdict = "no interference fringes detected in the baseline"
    res = FringeResult(fa, fr, width, applied, verdict)
    return st.update("fringes", res, z=z, signal=s)



# --- the registry's records (afmforce.analysis.registry) -------------------------------------------
SMOOTH = AnalysisStep("smooth", "Digitization smoothing of the position (running average)", smooth, SmoothOptions,
                      reference="section 3.1, Fig 7C")
CONTACT = AnalysisStep("contact", "Contact, constant-compliance and zero-force regions", contact, ContactOptions,
                       after=("smooth",), reference="section 3.1, Fig 7")
DRIFT = AnalysisStep("drift", "Thermal drift: line in time in the zero-force region, per run", drift, DriftOptions,
                     requires=("contact",), channels=("approach",), reference="section 3.1, Fig 7")
FRINGES = AnalysisStep("fringes", "Interferometric calibration from baseline fringes", fringes, FringesOptions,
                       requires=("drift",), channels=("approach",), reference="section 3.1, Fig 7A; spec section 6")
