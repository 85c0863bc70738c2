"""The ``calibration`` step: deflection sensitivity (InvOLS): the file's, or from the compliance slope.

Declared once by its record :data:`CALIBRATION` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import dataclasses
import math

from .. import compliance as cc
from ...errors import AnalysisError
from ..options import CalibrationOptions, origin_words
from ..registry import AnalysisStep, ResultField
from ..state import State

__all__ = ["calibration", "CALIBRATION"]


#: The start of the warning that gives the compliance slope's calibration as a factor of the one used.
SLOPE_FACTOR = "the compliance slope gives a calibration"


def calibration(st: State, o: CalibrationOptions) -> State:
    """Calibration factor (InvOLS) and the deflection in metres (the probe's sensitivity, if given, over the file's).

    ``source=auto`` (the default) uses the user's or the file's sensitivity wherever there is one and reports
    the compliance slope's beside it (``sensitivity_fit``, with a warning beyond 10 %); the slope calibrates
    only without one, or when asked (``fit``), or where the file's is impossible on a hard contact (step
    ``kind``). See :class:`~afmforce.analysis.options.CalibrationOptions`.
    """
    comp = st.details.get("compliance")
    if comp is None:
        raise AnalysisError("step 'calibration' needs the compliance lines")
    run = o.run
    md = st.metadata if st.probe.sensitivity is None else {**st.metadata, "sensitivity": st.probe.sensitivity}
    res = cc.calibrate(comp, md, source=o.source, run=run)
    warn = []
    if res.source == "fit":
        res, why = _undetermined_slope(comp, md, res, run, st)
        warn += why
    if not (comp.approach.found and comp.retract.found):
        used = "approach" if comp.approach.found else "retract"
        if run != used:
            warn.append(f"calibration from the {used} run's compliance line (the only one)")
    if res.source == "metadata" and math.isfinite(res.factor_fit) and res.factor_fit > 0:
        ratio = res.factor_fit / res.factor
        whose, owner = origin_words(st.probe, "sensitivity")
        if abs(ratio - 1) > 0.1:
            warn.append(f"{SLOPE_FACTOR} {ratio:.3g} x {whose} (a soft sample the tip "
                        "indents, a changed laser alignment, or a position channel that is not the tip-sample "
                        f"distance): {owner} is used; `calibration` fit uses the slope (and rescales a thermal "
                        "spring constant)")
        elif st.channel == "nominal" and _piezo_gain_shows(comp, res, ratio):
            warn.append(NOMINAL_GAIN.format(start=SLOPE_FACTOR, ratio=ratio, whose=whose, owner=owner,
                                            scale=ratio ** 2))
    if not (math.isfinite(res.factor) and res.factor != 0):
        raise AnalysisError("no usable calibration factor (compliance slope zero or undefined)")
    res = dataclasses.replace(res, requested=o.source)
    return st.update("calibration", res, warn=warn, factor=res.factor, deflection=st.signal * res.factor)


#: How the warning starts when the slope would calibrate but does not determine an InvOLS.
INVOLS_UNDETERMINED = "InvOLS from the compliance slope undetermined"


def _undetermined_slope(comp, md, res, run: str, st: State):
    """The calibration when the slope would calibrate: refused for the file's or user's sensitivity where its
    line does not determine an InvOLS (:func:`afmforce.analysis.invols.line_notes`, the rule of ``afmforce
    calibrate invols``), or kept and marked undetermined (``determined`` False) where none is known."""
    from ..invols import line_notes

    used = run if comp.approach.found and comp.retract.found else ("approach" if comp.approach.found else "retract")
    scale = res.sensitivity_fit * res.compliance_slope
    notes = line_notes(comp, used, scale if math.isfinite(scale) and scale > 0 else 1.0)
    if not notes:
        return res, []
    what = (f"{INVOLS_UNDETERMINED} ({res.sensitivity_fit * 1e9:.4g} nm/V, the rule of `afmforce calibrate invols`): "
            + "; ".join(notes))
    if math.isfinite(res.factor_given) and res.factor_given > 0:
        owner = origin_words(st.probe, "sensitivity")[1]
        kept = cc.calibrate(comp, md, source="metadata", run=run)
        given = (f" ({res.sensitivity * 1e9:.4g} nm/V)" if math.isfinite(res.sensitivity) else "")
        return kept, [f"{what}: `calibration` fit refused, {owner}{given} is used"]
    return dataclasses.replace(res, determined=False), [
        f"{what}: it is used, as the curve has no other (no sensitivity in the file), so every separation and force "
        "rests on an undetermined InvOLS; give the lever's sensitivity measured on a hard surface (`sensitivity`)"]


#: On the piezo's nominal position (no position sensor) the compliance slope's calibration is said when it
#: differs from the file's or the user's by more than this fraction [-] (beyond 10 % it is said on any channel) ...
NOMINAL_GAIN_TOLERANCE = 0.01
#: ... and by more than this many standard errors of the slope [-].
NOMINAL_GAIN_SIGMAS = 5.0
#: The words: a piezo hysteresis loop that closes at the turn (the virtual AFM's ``Piezo(hysteresis=h)``, 1 um
#: span, turning 190 nm after a rest) leaves both runs' lines straight and coincident, its local gain near the
#: turn 1 / (1 - h) of the nominal one; the slope says 1.02, 1.05, 1.11 x the lever's sensitivity for h = 2, 5,
#: 10 %, and with the file's sensitivity the separations scale by that factor and A R came out 1.07, 1.15,
#: 1.33 x the truth (standard error 0.05-0.07), said nowhere below 10 %.
NOMINAL_GAIN = ("{start} {ratio:.3g} x {whose}, on the piezo's nominal position (no position sensor): either the "
                "piezo's gain near the turn differs from its nominal one by that factor (a hysteresis loop that "
                "closes at the turn: both runs' lines stay straight and agree, so nothing else shows it) or the "
                "sensitivity is off by it; {owner} is used, and then the separations are uncertain by that factor "
                "and A R by about {scale:.3g} x (a systematic uncertainty its standard error leaves out; a "
                "position sensor, or fringes of a known period, fix the length scale)")


def _piezo_gain_shows(comp, res, ratio: float) -> bool:
    """Whether the slope's calibration ``ratio`` x the one used is beyond :data:`NOMINAL_GAIN_TOLERANCE` and
    :data:`NOMINAL_GAIN_SIGMAS` standard errors of the line it came from."""
    if not abs(ratio - 1) > NOMINAL_GAIN_TOLERANCE:
        return False
    for line in (comp.approach, comp.retract):
        if line.found and math.isclose(line.slope, res.compliance_slope, rel_tol=1e-12) and line.slope:
            return abs(ratio - 1) > NOMINAL_GAIN_SIGMAS * abs(line.slope_se / line.slope)
    return False


def soft_slope_not_a_sensitivity(st: State) -> bool:
    """Whether the compliance slope's sensitivity is undetermined on this curve: a soft contact (step ``kind``)
    calibrated by the file's or the user's sensitivity. The tip indents the sample there, so the contact's slope
    is the lever's bending and the sample's indentation together (9-19 x the lever's sensitivity on the virtual
    AFM's 5 kPa Hertz contacts), not the lever's sensitivity: ``sensitivity_fit`` is reported NaN (the CLI's
    "sens. fit" column "-", the web's and the summary's the same field) and :data:`SOFT_SLOPE` says why."""
    k = st.details.get("kind")
    c = st.details.get("calibration")
    return k is not None and c is not None and k.kind == "soft" and c.source == "metadata"


#: Said instead of the slope's factor on a soft contact (:func:`soft_slope_not_a_sensitivity`).
SOFT_SLOPE = ("sensitivity from the compliance slope undetermined: the contact is soft (the tip indents the "
              "sample), so its slope is the sample's and the lever's together, not the lever's sensitivity; "
              "{owner} is used (calibrate the lever on a hard surface)")


def soft_slope(st: State) -> State:
    """On a soft contact calibrated by the file's or the user's sensitivity (:func:`soft_slope_not_a_sensitivity`):
    the slope's factor (:data:`SLOPE_FACTOR`, a number the user could take for a sensitivity) replaced by
    :data:`SOFT_SLOPE`. The ``kind`` step calls it once the contact is known to be soft."""
    if not soft_slope_not_a_sensitivity(st):
        return st
    kept = tuple(w for w in st.warnings if not w.startswith(SLOPE_FACTOR))
    if len(kept) == len(st.warnings) and not math.isfinite(st.details["calibration"].sensitivity_fit):
        return st       # no slope's number to take back (a deflection in metres within 10 % of its line)
    return st.update(warnings=kept + (SOFT_SLOPE.format(owner=origin_words(st.probe, "sensitivity")[1]),))


def _calibration_fields(st: State) -> dict:
    c = st.details["calibration"]
    fit = math.nan if soft_slope_not_a_sensitivity(st) else c.sensitivity_fit
    return dict(sensitivity=c.sensitivity, sensitivity_fit=fit, calibration_source=c.source)


CALIBRATION = AnalysisStep(
    "calibration", "Deflection sensitivity (InvOLS): the file's, or from the compliance slope", calibration,
    CalibrationOptions, requires=("compliance",), reference="section 3.1; eq 15", runs=(),
    fields=(ResultField("sensitivity_used", "m/V", "sensitivity used (the forces'; calibration source says which)",
                        summary=True, column=True, compute=lambda r: r.sensitivity_fit
                        if r.calibration_source == "fit" else r.sensitivity),
            ResultField("sensitivity", "m/V", "sensitivity (file or user)", summary=True, column=True),
            ResultField("sensitivity_fit", "m/V", "sensitivity from the compliance slope (NaN on a soft contact: "
                        "the slope is not the lever's there)", summary=True, column=True),
            ResultField("calibration_source", None, default="")),
    collect=_calibration_fields)
