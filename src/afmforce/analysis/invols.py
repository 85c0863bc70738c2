"""The optical-lever sensitivity (InvOLS) from the constant-compliance region of a force curve
(``afmforce calibrate invols``; docs/calibration.md).

The analysis pipeline's steps up to ``calibration`` find the contact and fit the robust
constant-compliance line of each run (:mod:`.compliance`); the InvOLS is ``1 / slope``
[m/V] of the chosen run (approach by default), its standard error from the slope's. A
calibration curve is only trustworthy when the line is one: the approach and retract lines
agree and the region holds enough samples. Otherwise the result says so
(``determined`` False and a verdict), instead of a number with a tight interval.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import AnalysisError
from ._units import unit as _u
from .options import CalibrationOptions

__all__ = ["InvolsResult", "measure_invols", "line_notes", "MIN_POINTS", "MAX_RUN_MISMATCH"]

#: fewest samples in the compliance line for a determined InvOLS
MIN_POINTS = 10
#: largest relative difference of the approach and retract InvOLS for a determined one
MAX_RUN_MISMATCH = 0.10


def line_notes(comp, run: str, scale: float = 1.0) -> list[str]:
    """Why the compliance line of ``run`` does not determine an InvOLS (empty: it does).

    The one rule of ``afmforce calibrate invols`` (:func:`measure_invols`, which adds a soft contact's note) and
    of ``afmforce analyze`` where the slope would calibrate (step ``calibration``): fewer than
    :data:`MIN_POINTS` samples in the line, or approach and retract lines more than :data:`MAX_RUN_MISMATCH`
    apart.

    Parameters
    ----------
    comp : ComplianceResult
        The compliance lines (:mod:`.compliance`).
    run : str
        ``approach``, ``retract`` or ``both`` (both lines' samples counted).
    scale : float
        Metres of deflection per signal unit times the signal per metre of a unit slope: ``scale / slope`` is the
        InvOLS [m/V] (1 for a signal in volts).
    """
    lines = {"approach": comp.approach, "retract": comp.retract}
    notes = []
    for name in (("approach", "retract") if run == "both" else (run,)):
        line = lines[name]
        if line.found and line.n_points < MIN_POINTS:
            notes.append(f"only {line.n_points} samples in the {name} compliance line (need {MIN_POINTS}): "
                         "record the calibration curve slower or further into contact")
    inv = {k: scale / v.slope if v.found and v.slope != 0 else math.nan for k, v in lines.items()}
    both = [v for v in inv.values() if math.isfinite(v)]
    if len(both) == 2:
        mismatch = abs(both[0] - both[1]) / min(abs(both[0]), abs(both[1]))
        if mismatch > MAX_RUN_MISMATCH:
            notes.append(f"approach and retract lines give {inv['approach'] * 1e9:.4g} and "
                         f"{inv['retract'] * 1e9:.4g} nm/V ({mismatch:.0%} apart): the contact is not a "
                         "constant-compliance line (a curved or sliding contact)")
    return notes


@dataclass(frozen=True)
class InvolsResult:
    """The InvOLS of one curve.

    Attributes
    ----------
    sensitivity : float  InvOLS of the chosen run [m/V]
    sensitivity_se : float  its standard error [m/V]
    sensitivity_approach, sensitivity_retract : float  each run's [m/V] (NaN: no line)
    n_points : int  samples in the chosen run's line [-]
    run : str  ``approach`` or ``retract``
    file_sensitivity : float  the file's own InvOLS [m/V] (NaN: none stored)
    determined : bool  a hard contact, enough samples, and both runs agree within :data:`MAX_RUN_MISMATCH`
    verdict : str  why (not) determined
    """

    sensitivity: float = _u("m/V")
    sensitivity_se: float = _u("m/V")
    sensitivity_approach: float = _u("m/V")
    sensitivity_retract: float = _u("m/V")
    n_points: int = _u("")
    run: str = _u("")
    file_sensitivity: float = _u("m/V")
    determined: bool = _u("")
    verdict: str = _u("")


def measure_invols(curve, *, run: str = "approach", channel: str = "auto") -> InvolsResult:
    """The InvOLS [m/V] from the compliance line of ``curve`` (a RawCurve, deflection in volts
    or calibrated with a stored sensitivity).

    Raises
    ------
    AnalysisError
        No contact or no compliance line in the chosen run.
    """
    from .pipeline import analyze

    if run not in ("approach", "retract"):
        raise AnalysisError(f"run must be approach or retract, got {run!r}")
    res = analyze(curve, steps=["calibration"], options=[CalibrationOptions(source="fit", run=run)],
                  channel=channel)
    if "compliance" not in res.details or "calibration" not in res.details:
        why = res.not_applicable.get("compliance") or res.not_applicable.get("calibration") or "no contact"
        raise AnalysisError(f"no constant-compliance line to calibrate on: {why}")
    comp, cal = res.details["compliance"], res.details["calibration"]
    scale = _scale(cal)
    inv = {}
    for name in ("approach", "retract"):
        line = getattr(comp, name)
        inv[name] = scale / line.slope if line.found else math.nan
    line = getattr(comp, run)
    if not line.found:
        raise AnalysisError(f"the {run} has no constant-compliance line; try the other run")
    value = inv[run]
    se = abs(value) * line.slope_se / abs(line.slope)
    notes = []
    # the contact's kind with the file's own calibration (the slope's makes every line follow the position)
    kind = analyze(curve, steps=["kind"], channel=channel)
    if kind.contact_kind == "soft":  # the slope is the lever and the sample in series: not the lever's
        notes.append(f"the contact is soft ({kind.contact_kind_reason}): the slope is the sample's and the "
                     "lever's in series, not the lever's; calibrate on a hard, clean surface")
    notes += line_notes(comp, run, scale)
    determined = not notes
    file_s = float(curve.metadata.get("sensitivity") or math.nan)
    verdict = ("determined: " + f"{line.n_points} samples, both runs agree" if determined
               else "not determined: " + "; ".join(notes))
    if math.isfinite(file_s) and abs(value / file_s - 1) > MAX_RUN_MISMATCH:
        verdict += (f"; {value / file_s:.3g} x the file's {file_s * 1e9:.4g} nm/V (a soft sample the tip "
                    "indents, a changed laser alignment, or a position channel that is not the tip-sample "
                    "distance: an InvOLS needs a hard, clean surface)")
    return InvolsResult(sensitivity=float(value), sensitivity_se=float(se),
                        sensitivity_approach=float(inv["approach"]), sensitivity_retract=float(inv["retract"]),
                        n_points=int(line.n_points), run=run, file_sensitivity=file_s,
                        determined=determined, verdict=verdict)


def _scale(cal) -> float:
    """Metres per (signal unit / slope): 1 for a signal in volts; the stored sensitivity for a
    signal the instrument calibrated (``sensitivity_fit = sensitivity / deflection slope``)."""
    if cal.unit == "V":
        return 1.0
    if math.isfinite(cal.sensitivity_fit) and math.isfinite(cal.compliance_slope):
        return cal.sensitivity_fit * cal.compliance_slope
    raise AnalysisError(f"the deflection is in {cal.unit} without a stored sensitivity: no InvOLS to measure")
