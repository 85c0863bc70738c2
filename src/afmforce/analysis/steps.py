"""The pipeline steps that calibrate a curve: compliance, calibration, contact kind, shift, zero, force.

Each step takes a :class:`~.state.State` and its options record and returns a new State, its
result dataclass stored under its identifier in ``state.details``; each is declared once, by its
:class:`~.registry.AnalysisStep` record at the end of this module (requirements, options, result
fields and how they are read off the details). The other steps: :mod:`.steps_prepare` (smooth,
contact, drift, fringes), :mod:`.steps_results` (jumps, adhesion, surface energy, van der Waals,
oscillation, friction), :mod:`.indentation_step`, :mod:`.diagnosis_step`, :mod:`.liquid_step`.
"""

from __future__ import annotations

import dataclasses
import math

from ..errors import AnalysisError
from . import compliance as cc
from .contact_point import CONTACT_POINT_METHODS, classify_contact, curvature_ratio
from .jumps import find_jump_in
from .options import (CalibrationOptions, ComplianceOptions, ForceOptions, KindOptions, ShiftOptions,
                      ZeroOptions)
from .separation import ZeroResult, effective_spring_constant, zero_of_separation
from .registry import AnalysisStep, ResultField
from .state import State
from ._step_helpers import _kind, _skip

__all__ = ["compliance", "calibration", "kind", "shift", "zero", "force", "COMPLIANCE", "CALIBRATION", "KIND",
           "SHIFT", "ZERO", "FORCE"]


def compliance(st: State, o: ComplianceOptions) -> State:
    """Robust constant-compliance line of each run."""
    res = cc.fit_compliance(st.z, st.signal, st.approach, st.retract, st.unit)
    return st.update("compliance", res, warn=res.notes)


def calibration(st: State, o: CalibrationOptions) -> State:
    """Calibration factor (InvOLS) and the deflection in metres (the probe's sensitivity, if given, over the file's)."""
    comp = st.details.get("compliance")
    if comp is None:
        raise AnalysisError("step 'calibration' needs the compliance lines")
    run = o.run
    md = st.metadata if st.probe.sensitivity is None else {**st.metadata, "sensitivity": st.probe.sensitivity}
    res = cc.calibrate(comp, md, source=o.source, run=run)
    warn = []
    if not (comp.approach.found and comp.retract.found):
        used = "approach" if comp.approach.found else "retract"
        if run != used:
            warn.append(f"calibration from the {used} run's compliance line (the only one)")
    if res.source == "metadata" and math.isfinite(res.factor_fit) and res.factor_fit > 0:
        ratio = res.factor_fit / res.factor
        if abs(ratio - 1) > 0.1:
            warn.append(f"the compliance slope gives a calibration {ratio:.3g} x the file's: a soft contact, or a "
                        "stale sensitivity (calibration source 'fit', `calibration` fit, uses the slope)")
    if not (math.isfinite(res.factor) and res.factor != 0):
        raise AnalysisError("no usable calibration factor (compliance slope zero or undefined)")
    res = dataclasses.replace(res, requested=o.source)
    return st.update("calibration", res, warn=warn, factor=res.factor, deflection=st.signal * res.factor)


def kind(st: State, o: KindOptions) -> State:
    """Contact kind (hard with jump-in or straight line / soft curved) and a soft contact's contact point.

    See :mod:`~afmforce.analysis.contact_point`: hard when the approach jumps
    into contact (above ``nsigma`` step noise) or its contact is a straight line
    the deflection follows (late/early slope ratio at most ``max_curvature``,
    deflection per position at least ``min_stiffness`` when the calibration is
    the file's); soft otherwise, with the contact point by ``method``.
    """
    nsigma, method, force_fraction, window = o.nsigma, o.method, o.force_fraction, o.window
    o.check_method(CONTACT_POINT_METHODS)
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
                           min_stiffness=o.min_stiffness, max_curvature=o.max_curvature)
    new = st.update("kind", res)
    if res.kind == "hard":
        new = _recalibrate_hard(new, cal, curv, o.max_curvature)
    if res.kind == "soft":
        cp = CONTACT_POINT_METHODS[method](st.z, st.deflection, app.index, force_fraction=force_fraction,
                                           window=window)
        if cp.index < 0:
            raise AnalysisError("soft contact: no contact point found on the approach (too few samples before "
                                "the largest deflection)")
        warn = None
        width = cp.position_high - cp.position_low
        steep = _steep_contact(st, cp, method, window) if width > max(100e-9, 0.1 * abs(cp.indentation)) else None
        if steep is not None:  # a slow rise, then a distinct steep contact: the contact is where it steepens
            warn = (f"slowly rising approach before contact: fitted over the whole approach the contact lies anywhere "
                    f"in [{cp.position_low * 1e6:.4g}, {cp.position_high * 1e6:.4g}] um (2 sigma); the steep contact "
                    f"after it begins at {steep.position * 1e6:.4g} um (indentation {steep.indentation * 1e6:.3g} um), "
                    "taken as the contact point")
            cp = steep
        elif width > max(100e-9, 0.1 * abs(cp.indentation)):
            warn = (f"contact point uncertain: {cp.position * 1e6:.4g} um, but fits with the contact anywhere in "
                    f"[{cp.position_low * 1e6:.4g}, {cp.position_high * 1e6:.4g}] um are as good within 2 sigma "
                    f"({width * 1e6:.3g} um, {width / abs(cp.indentation):.0%} of the {cp.indentation * 1e6:.3g} um "
                    "indentation): a slowly rising baseline or a long-range force before contact makes the onset "
                    "ambiguous")
        elif force_fraction < 1.0:  # how much the point depends on the fitted range: the whole approach
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


#: A hard contact's straight compliance line this far from the file's sensitivity (ratio) recalibrates it.
STALE_SENSITIVITY = 1.25


def _recalibrate_hard(st: State, cal, curvature: float, max_curvature: float) -> State:
    """A hard contact on a measured (linear) position channel whose straight compliance line disagrees
    with the file's sensitivity by more than :data:`STALE_SENSITIVITY`: on a rigid contact the
    deflection follows the position one to one, so the file's sensitivity is stale (a realigned laser)
    and the compliance slope is the calibration (the paper's, section 3.1). Not with a sensitivity the
    user gave, nor with ``calibration.source=metadata`` (the result's source stays the file's then)."""
    ratio = cal.factor_fit / cal.factor if cal.source == "metadata" and cal.factor else math.nan
    straight = math.isfinite(curvature) and 1 / max_curvature <= curvature <= max_curvature
    if (st.probe.sensitivity is not None or st.channel != "measured" or not straight or not math.isfinite(ratio)
            or ratio <= 0 or 1 / STALE_SENSITIVITY <= ratio <= STALE_SENSITIVITY
            or cal.requested == "metadata"):
        return st
    new = dataclasses.replace(cal, factor=cal.factor_fit, source="fit")
    warn = (f"hard contact whose straight compliance line follows the position {1 / ratio:.3g} x with the file's "
            f"sensitivity (1 on a rigid contact): the file's sensitivity is stale, the compliance slope calibrates ("
            f"{cal.sensitivity_fit * 1e9:.4g} nm/V instead of {cal.sensitivity * 1e9:.4g}; "
            "`calibration` metadata keeps the file's)")
    return st.update("calibration", new, warn=warn, factor=new.factor, deflection=st.signal * new.factor)


#: The repeated fit's baseline spans this many times the steep contact's own position travel (see _steep_contact).
LOCAL_BASELINE = 4.0
#: At most this many refits on the shortened run.
LOCAL_ROUNDS = 3


def _steep_contact(st: State, cp, method: str, window: float):
    """On an approach whose whole-run fit leaves the onset ambiguous (a slow rise over many um before a
    steep contact, e.g. a long cell-adhesion curve), the same fit once more on the approach after that
    onset, up to the largest deflection: its contact point when it lies clearly after the ambiguous range
    and is itself well defined (its range within 2.5 x the usual bound, max(10 % of its indentation, 100 nm)),
    else None.

    The fit's baseline is a straight line; the slow rise curves (convex) over the ~10 um before the
    contact, so a line through all of it lies below the rise just before the contact and the power
    term starts early to make up the difference (the 2016 CellHesion curve: 0.26 um before nanite's
    gradient_zero_crossing). The fit is therefore repeated on a local run, the baseline spanning
    :data:`LOCAL_BASELINE` times the steep contact's own position travel before it (over which the rise is
    straight), until the point moves less than half its 2-sigma range (at most :data:`LOCAL_ROUNDS`
    times). On that curve spans of 2-8 times give -25.93..-25.99 um; 1.5 times leaves too little
    baseline (-25.81 um)."""
    idx = st.approach.index
    sub = idx[st.z[idx] >= cp.position]
    if sub.size < 64:
        return None
    new = CONTACT_POINT_METHODS[method](st.z, st.deflection, sub, force_fraction=1.0, window=window)
    if new.index < 0 or not new.position > cp.position_high or not new.indentation > 0:
        return None
    z_end = float(st.z[sub].max())
    for _ in range(LOCAL_ROUNDS):  # the baseline line local: a slow rise curves over the um before the contact
        start = new.position - LOCAL_BASELINE * (z_end - new.position)
        local = idx[st.z[idx] >= start]
        if local.size < 64 or local.size >= sub.size:
            break
        again = CONTACT_POINT_METHODS[method](st.z, st.deflection, local, force_fraction=1.0, window=window)
        if again.index < 0 or not again.indentation > 0:
            break
        moved = abs(again.position - new.position)
        sub, new = local, again
        if moved <= 0.5 * (new.position_high - new.position_low):
            break
    if new.position_high - new.position_low > max(0.1 * new.indentation, 100e-9) * 2.5:
        return None
    return new


def shift(st: State, o: ShiftOptions) -> State:
    """Shift the inward run to overlay the outward compliance line (Fig 9)."""
    comp = st.details.get("compliance")
    if comp is None:
        raise AnalysisError("step 'shift' needs the compliance lines")
    if _kind(st) == "soft":
        nan = math.nan
        return _skip(st, "shift", "soft contact: no constant-compliance lines to overlay",
                     cc.ShiftResult(nan, nan, nan, False))
    apply = bool(o.apply)
    res = cc.compliance_shift(comp, applied=apply)
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


def zero(st: State, o: ZeroOptions) -> State:
    """Zero of separation: the compliance line at h = contact_separation.

    ``run="auto"``: the outward (retract) line as in the paper, unless the
    retract had no baseline of its own (drift step) or no compliance line, or
    the two lines' slopes differ by more than ``parallel_tolerance``, more than
    friction makes (a creeping piezo on the nominal channel, a soft contact):
    then the inward line, which carries the jump-in and the van der Waals
    attraction.
    """
    if _kind(st) == "soft":
        cp = st.details["contact_point"]
        c0 = cp.deflection - cp.position
        sep = st.deflection - st.z - c0
        res = ZeroResult(0.0, cp.position, "approach", math.nan)
        return st.update("zero", res, separation=sep, position=st.z - cp.position)
    run = o.run
    warn = []
    if run == "auto":
        dr = st.details.get("drift")
        comp = st.details.get("compliance")
        run = "approach" if dr is not None and dr.retract_from_approach else "retract"
        if comp is not None and comp.approach.found and comp.retract.found:
            ratio = comp.approach.slope / comp.retract.slope
            if abs(ratio - 1) > o.parallel_tolerance:
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
    h, pos, res = zero_of_separation(st.z, st.deflection, regions, o.contact_separation)
    return st.update("zero", res, warn=warn, separation=h, position=pos)


def force(st: State, o: ForceOptions) -> State:
    """Force = k x deflection, tilt-corrected (eq 13/14) when theta0 is given.

    k, theta0 and the lengths are the probe's (:class:`~.options.ProbeCalibration`),
    k and theta0 from the file when the user gives none. A thermal spring constant (the
    instruments' usual one, ``thermal_k``) is ``kB T / <d^2>`` with the deflection ``d`` in the
    file's sensitivity: when the sensitivity is refitted from the compliance slope the file's k
    scales by (file's / fitted sensitivity)^2 (the deflections by fitted / file's, so forces by
    file's / fitted), never by one factor alone.
    """
    md, p = st.metadata, st.probe
    k = p.value("spring_constant", md)
    theta0 = p.value("theta0", md)
    cal = st.details.get("calibration")
    slope_k = cal.spring_constant_from_slope if cal is not None else math.nan
    warn = []
    if (o.thermal_k and p.spring_constant is None and k is not None and cal is not None and cal.source == "fit"
            and math.isfinite(cal.sensitivity) and math.isfinite(cal.sensitivity_fit) and cal.sensitivity_fit > 0):
        k_new = float(k) * (cal.sensitivity / cal.sensitivity_fit) ** 2
        warn.append(f"spring constant rescaled with the refitted sensitivity: {float(k):.4g} -> {k_new:.4g} N/m "
                    f"(a thermal k goes as 1/InvOLS^2: {cal.sensitivity * 1e9:.4g} -> {cal.sensitivity_fit * 1e9:.4g} "
                    "nm/V); give `spring_constant` if the file's k did not come from a thermal tune "
                    "(or set `force.thermal_k` to false)")
        k = k_new
    conv = effective_spring_constant(k, theta0=theta0, L0=p.L0, L1=p.L1, L2=p.L2, from_slope=slope_k)
    if conv.method == "none":
        warn.append("no spring constant (give `spring_constant`): forces not computed")
    elif conv.method == "compliance slope":
        warn.append("spring constant taken from the compliance slope of the force signal (rigid contact assumed)")
    return st.update("force", conv, warn=warn, spring_constant=conv.spring_constant,
                     force=st.deflection * conv.spring_constant)


# --- the registry's records (afmforce.analysis.registry) -------------------------------------------
COMPLIANCE = AnalysisStep("compliance", "Constant-compliance lines (robust fit)", compliance, ComplianceOptions,
                          requires=("drift",), after=("fringes",), channels=("approach",), reference="section 3.1")


def _calibration_fields(st: State) -> dict:
    c = st.details["calibration"]
    return dict(sensitivity=c.sensitivity, sensitivity_fit=c.sensitivity_fit, calibration_source=c.source)


CALIBRATION = AnalysisStep(
    "calibration", "Deflection sensitivity (InvOLS): the file's, or from the compliance slope", calibration,
    CalibrationOptions, requires=("compliance",), reference="section 3.1; eq 15",
    fields=(ResultField("sensitivity_used", "m/V", "sensitivity used (the forces'; calibration source says which)",
                        summary=True, column=True, compute=lambda r: r.sensitivity_fit
                        if r.calibration_source == "fit" else r.sensitivity),
            ResultField("sensitivity", "m/V", "sensitivity (file or user)", summary=True, column=True),
            ResultField("sensitivity_fit", "m/V", "sensitivity from the compliance slope", summary=True, column=True),
            ResultField("calibration_source", None, default="")),
    collect=_calibration_fields)


def _kind_fields(st: State) -> dict:
    k, cp = st.details["kind"], st.details.get("contact_point")
    return dict(contact_kind=k.kind, contact_kind_reason=k.reason,
                **({"indentation": cp.indentation} if cp is not None else {}))


KIND = AnalysisStep(
    "kind", "Contact kind (hard: jump-in or straight line; soft: curved) and a soft contact point", kind, KindOptions,
    requires=("calibration",), channels=("deflection",),
    reference="afmforce (baseline line + power-law contact term; checked against nanite's fit_line_polynomial)",
    fields=(ResultField("contact_kind", None, default=""), ResultField("contact_kind_reason", None, default=""),
            ResultField("indentation", "m", "indentation (soft contact)", summary=True, column=True)),
    collect=_kind_fields)
SHIFT = AnalysisStep("shift", "Inward/outward shift overlaying the compliance lines", shift, ShiftOptions,
                     requires=("kind",), reference="section 3.2, Fig 9; Fig 7C",
                     fields=(ResultField("shift", "m", "inward shift", summary=True, column=True),),
                     collect=lambda st: {"shift": st.details["shift"].shift})
ZERO = AnalysisStep("zero", "Zero of separation at the compliance line", zero, ZeroOptions, requires=("kind",),
                    after=("shift",), channels=("deflection",), reference="section 3.2, Fig 9",
                    fields=(ResultField("contact_separation", "m", "separation given to the compliance line",
                                        column=True),),
                    collect=lambda st: {"contact_separation": st.details["zero"].contact_separation})
FORCE = AnalysisStep("force", "Deflection to force (tilt-corrected spring constant)", force, ForceOptions,
                     requires=("calibration",), channels=("deflection",), reference="eqs 13, 14",
                     fields=(ResultField("spring_constant", "N/m", "spring constant", summary=True, column=True),),
                     collect=lambda st: {"spring_constant": st.details["force"].spring_constant})
