"""The pipeline steps: each takes a :class:`~.state.State` and options, returns a new State.

The registry that names them, gives their options and requirements lives in
:mod:`afmforce.analysis.pipeline`. Each function stores its result dataclass under its
step identifier in ``state.details``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..constants import HAMAKER, Z0
from ..errors import AnalysisError, ParameterError
from . import compliance as cc
from ._numeric import robust_line, running_mean
from .drift import remove_drift
from .dynamic import diagnose_curve, run_velocity
from .fringes import FringeResult, fit_fringes, fringe_baseline, fringe_signal, loop_width, position_map
from .contact_point import CONTACT_POINT_METHODS, classify_contact, curvature_ratio
from .jumps import JumpIn, PullOff, adhesion, find_jump_in, find_pull_off, jump_warnings, pull_off_estimate
from .oscillation import OscillationResult, both_runs, find_peak
from .regions import check_compliance, find_run_regions, run_indices, saturated_mask
from .separation import ZeroResult, effective_spring_constant, zero_of_separation
from .state import ContactSummary, NoContact, SmoothResult, State
from .unbinding import retract_adhesion
from .vdw import fit_vdw

__all__ = ["smooth", "contact", "drift", "fringes", "compliance", "calibration", "kind", "shift", "zero", "force",
           "jumps", "adhesion_step", "surface_energy", "vdw", "oscillation", "friction", "diagnosis"]


def _kind(st: State) -> str:
    """``"hard"``, ``"soft"`` (or ``"hard"`` when the kind step did not run)."""
    k = st.details.get("kind")
    return k.kind if k is not None else "hard"


def _skip(st: State, step: str, why: str, detail=None) -> State:
    """Record that ``step`` does not apply to this curve, and why."""
    skipped = {**st.details.get("skipped", {}), step: why}
    new = st.update("skipped", skipped)
    return new.update(step, detail) if detail is not None else new


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


def smooth(st: State, *, window: int | str = "auto") -> State:
    """Running average of the position channel, each run separately (Fig 7C).

    ``window="auto"``: the paper's 11 points, or two digitization steps of a
    stepped (digitized) channel if those are longer, so that the average
    interpolates linearly between levels as in the paper. On a stepped channel,
    within half a window of a run's ends the position continues the line of the
    averaged samples next to them (a shrinking window would leave the steps there).
    """
    staircase = False
    if window == "auto":
        window = _staircase_window(st.z)
        staircase = window > 11
    try:
        window = int(window)
    except (TypeError, ValueError):
        raise ParameterError(f"smoothing window must be 'auto' or an odd number of points, got {window!r}") from None
    if window < 1 or window % 2 == 0:
        raise ParameterError(f"smoothing window must be a positive odd number of points, got {window}")
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


def contact(st: State, *, min_points: int = 5, baseline_fraction: float = 0.7,
            compliance_fraction: float = 0.5, flat_ratio: float = 0.05,
            max_slope_ratio: float | str = "auto") -> State:
    """Contact, constant-compliance and zero-force regions of both runs.

    A run clipped at its turning point whose contact region is no
    constant-compliance line (see :func:`~.regions.check_compliance`: not
    ``1 / flat_ratio`` times steeper than its free part, or, on the measured
    channel, ``max_slope_ratio`` times shallower than the other run's;
    ``"auto"``: 2 on the measured channel, no limit on the nominal one, whose
    creep changes the local gain) keeps no compliance line; later steps use
    the other run's and say what could not be measured.
    """
    if not (0 < baseline_fraction <= 1 and 0 < compliance_fraction <= 1):
        raise ParameterError("baseline_fraction and compliance_fraction must lie in (0, 1]")
    if max_slope_ratio == "auto":
        max_slope_ratio = 2.0 if st.channel == "measured" else math.inf
    try:
        max_slope_ratio = float(max_slope_ratio)
    except (TypeError, ValueError):
        raise ParameterError(f"max_slope_ratio must be 'auto' or a number > 1, got {max_slope_ratio!r}") from None
    if not (max_slope_ratio > 1 and flat_ratio > 0):
        raise ParameterError("contact: max_slope_ratio must exceed 1 and flat_ratio must be positive")
    sat = saturated_mask(st.signal)
    kw = dict(saturated=sat, min_points=int(min_points), baseline_fraction=baseline_fraction,
              compliance_fraction=compliance_fraction)
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


def drift(st: State, *, order: int = 1, tail: bool = True) -> State:
    """Subtract a baseline line in time fitted in each run's zero-force region."""
    st.require("approach", step="drift")
    if order not in (0, 1):
        raise ParameterError(f"drift order must be 0 (offset) or 1 (line), got {order}")
    signal, res = remove_drift(st.time, st.signal, st.curve.segment, st.approach, st.retract, st.unit, order,
                               z=st.z if tail else None)
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
    return st.update("drift", res, warn=warn, signal=signal)


def fringes(st: State, *, apply: str = "auto", period: float | None = None, order: int | str = "auto",
            in_contact: str = "hold", margin: float = 0.1) -> State:
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
    st.require("approach", step="fringes")
    if apply not in ("auto", "always", "never") or in_contact not in ("hold", "follow"):
        raise ParameterError("fringes: apply must be auto/always/never and in_contact hold/follow")
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
        runs[run.kind] = fit_fringes(zf[far], st.signal[idx][far], period=period, order=order,
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
        if in_contact == "hold":
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


def _zero_deflection_position(st: State, run=None) -> float:
    """Where a run's (default: the approach's) contact line crosses zero signal: contact at zero load.

    Interference depends on the separation, constant in contact: its value there
    is the free-branch fringe at this position.
    """
    run = st.approach if run is None else run
    idx = run.index[run.contact & ~run.saturated]
    z_first = float(st.z[run.index[run.split]])
    if idx.size < 3:
        return z_first
    x0 = st.z[idx].mean()
    a, b, *_ = robust_line(st.z[idx] - x0, st.signal[idx])
    return float(x0 - a / b) if np.isfinite(b) and b != 0 else z_first


def compliance(st: State) -> State:
    """Robust constant-compliance line of each run."""
    st.require("approach", step="compliance")
    return st.update("compliance", cc.fit_compliance(st.z, st.signal, st.approach, st.retract, st.unit))


def calibration(st: State, *, source: str = "auto", run: str = "approach") -> State:
    """Calibration factor (InvOLS) and the deflection in metres."""
    comp = st.details.get("compliance")
    if comp is None:
        raise AnalysisError("step 'calibration' needs the compliance lines")
    res = cc.calibrate(comp, st.metadata, source=source, run=run)
    warn = []
    if not (comp.approach.found and comp.retract.found):
        used = "approach" if comp.approach.found else "retract"
        if run != used:
            warn.append(f"calibration from the {used} run's compliance line (the only one)")
    if res.source == "metadata" and math.isfinite(res.factor_fit) and res.factor_fit > 0:
        ratio = res.factor_fit / res.factor
        if abs(ratio - 1) > 0.1:
            warn.append(f"the compliance slope gives a calibration {ratio:.3g} x the file's: a soft contact, or a "
                        "stale sensitivity (calibration source 'fit', --calibration fit, uses the slope)")
    if not (math.isfinite(res.factor) and res.factor != 0):
        raise AnalysisError("no usable calibration factor (compliance slope zero or undefined)")
    return st.update("calibration", res, warn=warn, factor=res.factor, deflection=st.signal * res.factor)


def kind(st: State, *, nsigma: float = 5.0, min_stiffness: float = 0.7, max_curvature: float = 1.6,
         method: str = "hertz_local", force_fraction: float = 0.55, window: float = 0.15) -> State:
    """Contact kind (hard with jump-in or straight line / soft curved) and a soft contact's contact point.

    See :mod:`~afmforce.analysis.contact_point`: hard when the approach jumps
    into contact (above ``nsigma`` step noise) or its contact is a straight line
    the deflection follows (late/early slope ratio at most ``max_curvature``,
    deflection per position at least ``min_stiffness`` when the calibration is
    the file's); soft otherwise, with the contact point by ``method``.
    """
    st.require("deflection", step="kind")
    if method not in CONTACT_POINT_METHODS:
        raise ParameterError(f"contact point method {method!r} unknown; choose from {', '.join(CONTACT_POINT_METHODS)}")
    noise = abs(st.noise * st.factor)
    app = st.approach
    ji = find_jump_in(st.deflection, st.z, st.z, app, noise, math.nan, nsigma)
    sig = ji.significance if ji.index >= 0 else 0.0
    cal = st.details["calibration"]
    comp = st.details["compliance"]
    stiff = (comp.approach.slope * cal.factor if cal.source == "metadata" and comp.approach.found else math.nan)
    contact_idx = app.index[app.contact & ~app.saturated]
    curv = curvature_ratio(st.z, st.deflection, contact_idx)
    res = classify_contact(jump_significance=sig, stiffness_ratio=stiff, curvature=curv, nsigma=nsigma,
                           min_stiffness=min_stiffness, max_curvature=max_curvature)
    new = st.update("kind", res)
    if res.kind == "soft":
        cp = CONTACT_POINT_METHODS[method](st.z, st.deflection, app.index, force_fraction=force_fraction,
                                           window=window)
        if cp.index < 0:
            raise AnalysisError("soft contact: no contact point found on the approach (too few samples before "
                                "the largest deflection)")
        warn = None
        if force_fraction < 1.0:  # how much the point depends on the fitted range: the whole approach
            alt = CONTACT_POINT_METHODS[method](st.z, st.deflection, app.index, force_fraction=1.0, window=window)
            if alt.index >= 0:
                gap = alt.position - cp.position
                if abs(gap) > max(100e-9, 0.5 * abs(cp.indentation)):  # the indentation uncertain by ~2x
                    warn = (f"contact point uncertain: fitted up to {force_fraction:.0%} of the deflection it lies at "
                            f"{cp.position * 1e6:.4g} um (indentation {cp.indentation * 1e6:.3g} um), fitted to the "
                            f"whole approach at {alt.position * 1e6:.4g} um ({gap * 1e6:+.3g} um): a slowly rising "
                            "baseline or a long-range force before contact makes the onset ambiguous")
        new = new.update("contact_point", cp, warn=warn)
    return new


def shift(st: State, *, apply: bool = True) -> State:
    """Shift the inward run to overlay the outward compliance line (Fig 9)."""
    comp = st.details.get("compliance")
    if comp is None:
        raise AnalysisError("step 'shift' needs the compliance lines")
    if _kind(st) == "soft":
        nan = math.nan
        return _skip(st, "shift", "soft contact: no constant-compliance lines to overlay",
                     cc.ShiftResult(nan, nan, nan, False))
    res = cc.compliance_shift(comp, applied=bool(apply))
    if not math.isfinite(res.shift):
        missing = "retract" if comp.approach.found else "approach"
        return st.update("shift", res, warn=(
            f"inward/outward shift (hysteresis) not measured: the {missing} run has no unclipped "
            "constant-compliance line; the runs are not overlaid"))
    if not apply:
        return st.update("shift", res)
    z = st.z.copy()
    z[st.approach.index] += res.shift
    return st.update("shift", res, z=z)


def zero(st: State, *, contact_separation: float = Z0, run: str = "auto", parallel_tolerance: float = 0.25) -> State:
    """Zero of separation: the compliance line at h = contact_separation.

    ``run="auto"``: the outward (retract) line as in the paper, unless the
    retract had no baseline of its own (drift step) or no compliance line, or
    the two lines' slopes differ by more than ``parallel_tolerance``, more than
    friction makes (a creeping piezo on the nominal channel, a soft contact):
    then the inward line, which carries the jump-in and the van der Waals
    attraction.
    """
    st.require("deflection", step="zero")
    if _kind(st) == "soft":
        cp = st.details["contact_point"]
        c0 = cp.deflection - cp.position
        sep = st.deflection - st.z - c0
        res = ZeroResult(0.0, cp.position, "approach", math.nan)
        return st.update("zero", res, separation=sep, position=st.z - cp.position)
    if run not in ("auto", "approach", "retract"):
        raise ParameterError(f"zero: run must be auto, approach or retract, got {run!r}")
    warn = []
    if run == "auto":
        dr = st.details.get("drift")
        comp = st.details.get("compliance")
        run = "approach" if dr is not None and dr.retract_from_approach else "retract"
        if comp is not None and comp.approach.found and comp.retract.found:
            ratio = comp.approach.slope / comp.retract.slope
            if abs(ratio - 1) > parallel_tolerance:
                run = "approach"
                warn.append(f"compliance lines not parallel (slope ratio {ratio:.3g}): zero of separation from "
                            "the inward line; the outward run's separations are approximate")
    regions = st.retract if run == "retract" else st.approach
    if not regions.has_compliance:  # that run's contact is clipped: the other line
        regions = st.approach if run == "retract" else st.retract
    if not (st.approach.has_compliance and st.retract.has_compliance):
        warn.append(f"zero of separation from the {regions.kind} run's compliance line alone: friction or "
                    f"hysteresis between the runs would offset it by up to half their distance (not measured), "
                    f"and the other run's separations are not corrected for the shift")
    h, pos, res = zero_of_separation(st.z, st.deflection, regions, contact_separation)
    return st.update("zero", res, warn=warn, separation=h, position=pos)


def force(st: State, *, spring_constant: float | None = None, theta0: float | None = None,
          L0: float | None = None, L1: float | None = None, L2: float | None = None) -> State:
    """Force = k x deflection, tilt-corrected (eq 13/14) when theta0 is given."""
    st.require("deflection", step="force")
    md = st.metadata
    k = spring_constant if spring_constant is not None else md.get("spring_constant")
    theta0 = theta0 if theta0 is not None else md.get("theta0")
    cal = st.details.get("calibration")
    slope_k = cal.spring_constant_from_slope if cal is not None else math.nan
    conv = effective_spring_constant(k, theta0=theta0, L0=L0, L1=L1, L2=L2, from_slope=slope_k)
    warn = None
    if conv.method == "none":
        warn = "no spring constant (give --spring-constant): forces not computed"
    elif conv.method == "compliance slope":
        warn = "spring constant taken from the compliance slope of the force signal (rigid contact assumed)"
    return st.update("force", conv, warn=warn, spring_constant=conv.spring_constant,
                     force=st.deflection * conv.spring_constant)


def jumps(st: State, *, nsigma: float = 5.0, window: int = 3, onset_tolerance: float = 3e-9) -> State:
    """Jump into contact and pull-off, near each run's contact split.

    Warns when the first contact sample lies more than ``onset_tolerance`` (or
    ``nsigma`` noise) off the compliance line the zero of separation was put on.
    """
    st.require("separation", step="jumps")
    if _kind(st) == "soft":
        nan = math.nan
        return _skip(st, "jumps", "soft contact: no jump into contact and no single pull-off jump (see adhesion)",
                     {"jump_in": JumpIn(False, -1, nan, nan, nan, nan, nan, nan, 0.0),
                      "pull_off": PullOff(False, -1, nan, nan, nan, nan, 0.0, False)})
    noise = abs(st.noise * st.factor)
    k = st.spring_constant
    ji = find_jump_in(st.deflection, st.separation, st.position, st.approach, noise, k, nsigma, window)
    ret = st.retract
    clipped = not ret.has_compliance and bool(ret.contact.any())  # its whole contact is clipped
    if clipped:  # the pull-off is not in the record
        po = PullOff(False, -1, math.nan, math.nan, math.nan, math.nan, 0.0, False)
    else:
        po = find_pull_off(st.deflection, st.position, ret, noise, k, nsigma, window)
    warn = jump_warnings(ji, po, k, clipped)
    z0 = st.details["zero"].contact_separation if "zero" in st.details else Z0
    if 0 <= ji.index < st.separation.size - 1:
        # at a rigid contact the first contact sample lies on the compliance line (h = z0)
        off = float(st.separation[ji.index + 1] - z0)
        if abs(off) > max(nsigma * noise, onset_tolerance):
            warn.append(f"the first contact sample lies {off * 1e9:.3g} nm off the compliance line: a soft or "
                        "nonlinear contact, or a line displaced by friction or hysteresis (dynamic run); "
                        "separations near contact are uncertain by about that much")
    return st.update("jumps", {"jump_in": ji, "pull_off": po}, warn=warn)


def adhesion_step(st: State, *, nsigma: float = 5.0) -> State:
    """Adhesion for every contact kind: the retract's deepest dip below its own baseline (<= 0).

    See :mod:`~afmforce.analysis.unbinding`; the dip counts above ``nsigma``
    baseline noise, with its position, the last rupture and the unbinding steps.
    """
    st.require("position", step="adhesion")
    res = retract_adhesion(st.deflection, st.position, st.retract, st.spring_constant, nsigma=nsigma)
    return st.update("adhesion", res)


def surface_energy(st: State, *, radius: float | None = None, model: str = "jkr", hamaker: float = HAMAKER,
                   z0: float = Z0) -> State:
    """Surface energy from the pull-off and R, and R from the jump-out distance (hard contacts)."""
    j = st.details.get("jumps")
    if j is None:
        raise AnalysisError("step 'surface_energy' needs the jumps")
    if _kind(st) == "soft":
        return _skip(st, "surface_energy", "soft contact: JKR/DMT from a pull-off jump need a rigid contact")
    if not j["pull_off"].found:
        return _skip(st, "surface_energy", "no pull-off found")
    radius = radius if radius is not None else st.metadata.get("radius")
    return st.update("surface_energy", adhesion(j["pull_off"], st.spring_constant, radius=radius, model=model,
                                                hamaker=hamaker, z0=z0))


def vdw(st: State, *, radius: float | None = None, z0: float = Z0, max_separation: float = 30e-9,
        baseline: str = "line", fit_separation_offset: bool = False) -> State:
    """van der Waals fit of the approach before the jump (eq 2)."""
    j = st.details.get("jumps")
    if j is None:
        raise AnalysisError("step 'vdw' needs the jumps")
    if _kind(st) == "soft":
        return _skip(st, "vdw", "soft contact: the van der Waals law of eq 2 is for a rigid contact with a jump")
    radius = radius if radius is not None else st.metadata.get("radius")
    idx = st.approach.index
    ji = j["jump_in"]
    end = int(np.searchsorted(idx, ji.index)) + 1 if ji.found else st.approach.split
    pre = idx[:end]
    res = fit_vdw(st.separation[pre], st.force[pre], spring_constant=st.spring_constant, radius=radius, z0=z0,
                  max_separation=max_separation, baseline=baseline,
                  fit_separation_offset=fit_separation_offset)
    warn = None if res.status == "ok" else f"van der Waals fit: {res.status}"
    return st.update("vdw", res, warn=warn)


def oscillation(st: State, *, false_alarm: float = 1e-3, min_cycles: float = 3.0) -> State:
    """Post-contact oscillation of each run; temporal versus spatial origin."""
    st.require("deflection", step="oscillation")
    peaks = {}
    for run in (st.approach, st.retract):
        idx = run.index[run.compliance & ~run.saturated]
        v = run_velocity(st.time[run.index], st.z[run.index]) if st.time_known else math.nan
        if not st.time_known or idx.size < 8:
            nyq = math.nan
            if st.time_known and run.index.size > 1:
                nyq = 0.5 / float(np.median(np.diff(st.time[run.index])))
            peaks[run.kind] = dataclasses.replace(find_peak(np.array([]), np.array([]), v, run.kind), nyquist=nyq)
            continue
        x = st.z[idx] - st.z[idx].mean()
        a, b, *_ = robust_line(x, st.deflection[idx])
        resid = st.deflection[idx] - (a + b * x)
        peaks[run.kind] = find_peak(st.time[idx], resid, v, run.kind, min_cycles=min_cycles,
                                    false_alarm=false_alarm)
    origin, verdict, _ = both_runs(peaks["approach"], peaks["retract"])
    return st.update("oscillation", OscillationResult(peaks["approach"], peaks["retract"], origin, verdict))


def friction(st: State, *, nsigma: float = 3.0, slope_tolerance: float = 0.02,
             offset_tolerance: float = 0.2e-9, max_curvature: float = 1.25) -> State:
    """Friction signature of the two compliance lines (before the shift).

    Assessed only on a hard contact whose two compliance regions are straight
    lines (late/early slope ratio within ``max_curvature``); otherwise the
    signature is ``"not assessed"`` with the reason and its numbers.
    """
    comp = st.details.get("compliance")
    if comp is None:
        raise AnalysisError("step 'friction' needs the compliance lines")
    nan = math.nan
    why = None
    if _kind(st) == "soft":
        why = "not assessed: soft contact (curved; friction's signature needs straight compliance lines)"
    else:
        for run in (st.approach, st.retract):
            if not run.has_compliance:
                continue
            idx = run.index[run.compliance & ~run.saturated]
            c = curvature_ratio(st.z, st.signal, idx, min_points=12)
            if not math.isfinite(c):
                why = (f"not assessed: the {run.kind} compliance region has {idx.size} samples, too few to tell "
                       "a straight line from a curved one")
                break
            if not (1 / max_curvature <= c <= max_curvature):
                why = (f"not assessed: the {run.kind} compliance line is not straight (late/early slope ratio "
                       f"{c:.3g}, outside {1 / max_curvature:.3g}-{max_curvature:.3g})")
                break
    dr = st.details.get("drift")
    if why is None and dr is not None and dr.retract_settling and comp.approach.found and comp.retract.found:
        # the retract carries the approach's drift line: its slope and offset are off by the change of
        # drift between the runs, which the 2 % slope test cannot tell from friction
        why = ("not assessed: the retract has no drift line of its own (its free part is still relaxing after "
               "the pull-off), so its compliance line is not comparable to 2 %")
    if why is not None:
        return _skip(st, "friction", why, cc.FrictionSignature("not assessed", nan, nan, nan, nan, why))
    sh = st.details.get("shift") or cc.compliance_shift(comp, applied=False)
    slope_unc, offset_unc, rate_gap = _drift_uncertainty(st, comp)
    sig = cc.friction_signature(comp, sh, nsigma=nsigma, slope_tolerance=max(slope_tolerance, slope_unc),
                                offset_tolerance=max(offset_tolerance, offset_unc), channel=st.channel)
    if rate_gap > 0 and (slope_unc > slope_tolerance or offset_unc > offset_tolerance):
        bounds = (f"the drift rate holds to {rate_gap:.3g} {st.unit}/s between the halves of the baselines, so "
                  f"the lines are known to a slope of {slope_unc * 100:.2g} % and an offset of "
                  f"{offset_unc * 1e9:.3g} nm")
        if sig.kind == "none":
            sig = dataclasses.replace(sig, verdict=f"{sig.verdict} within the drift uncertainty ({bounds})")
        else:
            sig = dataclasses.replace(sig, verdict=f"{sig.verdict} (beyond the drift uncertainty: {bounds})")
    return st.update("friction", sig)


def _drift_uncertainty(st: State, comp) -> tuple[float, float, float]:
    """How far an imperfect drift line can move the compliance lines.

    Each run's drift line is a line in time through its own zero-force region. How well
    that line holds is measured on the region itself: the drift-corrected baseline of each
    half of it has its own slope, and the larger difference between the halves ``dr``
    [signal/s] is what slow structure (a fraction of a fringe, a relaxation) leaves in a
    rate. ``dr`` tilts a compliance line by ``dr / (v s)`` of its slope ``s`` and moves it
    by ``dr dt / s`` over the time ``dt`` between the line and its baseline.

    Returns
    -------
    slope : float  relative slope uncertainty [-]
    offset : float  offset uncertainty [m]
    rate : float  ``dr`` [signal/s]
    """
    if not st.time_known:
        return 0.0, 0.0, 0.0
    rate, lever = 0.0, 0.0
    for run in (st.approach, st.retract):
        base = run.index[run.zero_force & ~run.saturated]
        line = run.index[run.compliance]
        if base.size >= 24:
            half = base.size // 2
            slopes = [robust_line(st.time[part] - st.time[part].mean(), st.signal[part])[1]
                      for part in (base[:half], base[half:])]
            rate = max(rate, abs(float(slopes[1] - slopes[0])))
        if line.size and base.size:
            lever += abs(float(np.median(st.time[line])) - float(np.median(st.time[base])))
    idx = st.approach.index
    v = run_velocity(st.time[idx], st.z[idx])
    slope = abs(comp.approach.slope)
    if not (rate > 0 and math.isfinite(v) and v > 0 and slope > 0):
        return 0.0, 0.0, rate
    return rate / (v * slope), rate * lever / slope, rate


def _force_gradient(st: State, window: int = 5) -> tuple[float, str]:
    """Measured |dF/dh| [N/m] where the tip meets the surface, and how it was measured."""
    if st.force is None or not math.isfinite(st.spring_constant):
        return math.nan, "no force (spring constant unknown)"
    idx = st.approach.index
    h, f = st.separation[idx], st.force[idx]
    if _kind(st) == "soft":
        cp = st.details["contact_point"]
        k = int(np.searchsorted(idx, cp.index))
        stop = np.flatnonzero((np.arange(idx.size) > k) & (h < -0.1 * max(cp.indentation, 0.0)))
        end = int(stop[0]) if stop.size else idx.size
        sel = slice(k, max(end, k + 3))
        what = "contact stiffness over the first 10 % of the indentation"
    else:
        ji = st.details["jumps"]["jump_in"]
        if not ji.found:
            return math.nan, "no jump into contact: the attraction's gradient is below the noise"
        k = int(np.searchsorted(idx, ji.index))
        sel = slice(max(k - window + 1, 0), k + 1)
        what = f"attraction over the last {window} samples before the jump"
    hs, fs = h[sel], f[sel]
    if hs.size < 3 or np.ptp(hs) == 0:
        return math.nan, "too few samples to measure the force gradient"
    return float(abs(np.polyfit(hs - hs.mean(), fs, 1)[0])), what


def diagnosis(st: State, *, resonance_frequency: float | None = None, resolution: float | None = None,
              min_resolution: float = 0.01e-9, attraction_ratio: float = 0.75) -> State:
    """Dynamic diagnosis: eq 3, eq 4, jump-in distance, friction and adhesion consistency.

    Flags the van der Waals fit as unreliable when the run is judged dynamic.
    """
    j = st.details.get("jumps")
    if j is None:
        raise AnalysisError("step 'diagnosis' needs the jumps")
    idx = st.approach.index
    v = run_velocity(st.time[idx], st.z[idx]) if st.time_known else math.nan
    f = resonance_frequency if resonance_frequency is not None else st.metadata.get("resonance_frequency")
    dx = resolution if resolution is not None else max(abs(st.noise * st.factor), min_resolution)
    fit = st.details.get("vdw")
    fit = fit if fit is not None and hasattr(fit, "static_jump_in_separation") else None
    h_static = fit.static_jump_in_separation if fit is not None else math.nan
    step = float(np.median(np.abs(np.diff(st.z[idx])))) if idx.size > 1 else 0.0
    fr = st.details.get("friction")
    z0 = st.details["zero"].contact_separation if "zero" in st.details else math.nan
    grad, grad_how = _force_gradient(st)
    res = diagnose_curve(velocity=v, spring_constant=st.spring_constant, resonance_frequency=f, resolution=dx,
                         force_gradient=grad, force_gradient_method=grad_how,
                         jump_in_separation=j["jump_in"].separation if j["jump_in"].found else math.nan,
                         static_jump_in_separation=h_static,
                         sample_step=step, friction=None if fr is None else fr.kind,
                         friction_verdict="" if fr is None else fr.verdict,
                         hamaker_radius=fit.hamaker_radius if fit is not None else math.nan,
                         pull_off_force=pull_off_estimate(j["pull_off"], st.spring_constant), contact_separation=z0,
                         attraction_ratio=attraction_ratio)
    ret = st.retract
    if ret is not None and not ret.has_compliance and ret.contact.any() and bool(
            np.all(st.signal[ret.index[ret.contact]] > 0)):
        # static pull-off needs adhesion (negative deflection): leaving while pushed is dynamics
        res = dataclasses.replace(res, dynamic=True, verdict=res.verdict + "; " + (
            "the tip left the surface while the cantilever was still pushed (deflection above the photodiode's "
            "saturation on the whole retract contact), where a static pull-off needs adhesion: drag or friction "
            "held the cantilever bent -- a dynamic run, not a static force curve"))
    new = st.update("diagnosis", res)
    if res.dynamic and fit is not None:
        new = new.update("vdw", dataclasses.replace(fit, reliable=False),
                         warn="dynamic run: the van der Waals fit is NOT a static force law (see diagnosis)")
    return new
