"""The ``calibration`` step: deflection sensitivity (InvOLS): the file's, or from the compliance slope.

Declared once by its record :data:`CALIBRATION` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import dataclasses
import math

from .. import compliance as cc
from ...errors import AnalysisError
from ..options import CalibrationOptions
from ..registry import AnalysisStep, ResultField
from ..state import State

__all__ = ["calibration", "CALIBRATION"]


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
    if not (comp.approach.found and comp.retract.found):
        used = "approach" if comp.approach.found else "retract"
        if run != used:
            warn.append(f"calibration from the {used} run's compliance line (the only one)")
    if res.source == "metadata" and math.isfinite(res.factor_fit) and res.factor_fit > 0:
        ratio = res.factor_fit / res.factor
        if abs(ratio - 1) > 0.1:     # whose sensitivity: the user's (--sensitivity, a calibration file) or the file's
            whose = "the file's" if st.probe.sensitivity is None else "the given one"
            warn.append(f"the compliance slope gives a calibration {ratio:.3g} x {whose} (a soft sample the tip "
                        "indents, a changed laser alignment, or a position channel that is not the tip-sample "
                        f"distance): {whose} is used; `calibration` fit uses the slope (and rescales a thermal "
                        "spring constant)")
    if not (math.isfinite(res.factor) and res.factor != 0):
        raise AnalysisError("no usable calibration factor (compliance slope zero or undefined)")
    res = dataclasses.replace(res, requested=o.source)
    return st.update("calibration", res, warn=warn, factor=res.factor, deflection=st.signal * res.factor)


def _calibration_fields(st: State) -> dict:
    c = st.details["calibration"]
    return dict(sensitivity=c.sensitivity, sensitivity_fit=c.sensitivity_fit, calibration_source=c.source)


CALIBRATION = AnalysisStep(
    "calibration", "Deflection sensitivity (InvOLS): the file's, or from the compliance slope", calibration,
    CalibrationOptions, requires=("compliance",), reference="section 3.1; eq 15", runs=(),
    fields=(ResultField("sensitivity_used", "m/V", "sensitivity used (the forces'; calibration source says which)",
                        summary=True, column=True, compute=lambda r: r.sensitivity_fit
                        if r.calibration_source == "fit" else r.sensitivity),
            ResultField("sensitivity", "m/V", "sensitivity (file or user)", summary=True, column=True),
            ResultField("sensitivity_fit", "m/V", "sensitivity from the compliance slope", summary=True, column=True),
            ResultField("calibration_source", None, default="")),
    collect=_calibration_fields)
