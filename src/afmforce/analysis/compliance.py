"""Constant compliance: robust lines, calibration factor, run shift, friction signature.

* The constant-compliance line of each run (signal against position in contact)
  is fitted robustly (Tukey bisquare, :func:`~._numeric.robust_line`).
* Its slope calibrates the deflection: for a signal in volts the calibration
  factor (InvOLS) is ``1 / slope`` [m/V] (paper section 3.1: the optical lever
  is calibrated by the constant-compliance slope; the calibration factor beta
  of eq 15 is the same number per radian).
* The inward run is shifted along z to overlay the outward line (Fig 9: "+2,
  +4, +7 nm"; Fig 7C: "+57 nm"); the shift is the hysteresis.
* The two lines carry friction's signature (sections 2.2.2-2.2.4): a parallel
  offset (constant friction, eq 16), different slopes (friction proportional to
  load, eqs 18-19), a negative slope (pinned tip, eqs 20-21), or coincident lines:
  friction not detected, with the largest friction the lines allow (never "no friction").
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Mapping

import numpy as np

from ..errors import AnalysisError, ParameterError
from ..io.deflection import signal_factor
from ._smooth_kernel import compliance_line
from .regions import RunRegions
from ._units import unit as _u
from .options import CALIBRATION_SOURCES, CalibrationOptions as _C, FrictionOptions as _F  # declared once

if TYPE_CHECKING:
    from ..cantilever import InclinedCantilever

__all__ = ["ComplianceLine", "ComplianceResult", "fit_compliance", "CalibrationResult", "calibrate",
           "ShiftResult", "compliance_shift", "FrictionSignature", "friction_signature"]


@dataclass(frozen=True)
class ComplianceLine:
    """Constant-compliance line ``s = intercept + slope z`` of one run.

    Attributes
    ----------
    intercept : float  [unit]
    slope : float  [unit/m]
    intercept_se, slope_se : float  standard errors [unit], [unit/m]
    sigma : float  robust residual scale [unit]
    n_points : int  samples with non-zero weight [-]
    z_min, z_max : float  position range fitted [m]
    s_min, s_max : float  signal range fitted [unit]
    """

    intercept: float = _u("{signal}")
    slope: float = _u("{signal}/m")
    intercept_se: float = _u("{signal}")
    slope_se: float = _u("{signal}/m")
    sigma: float = _u("{signal}")
    n_points: int = _u("")
    z_min: float = _u("m")
    z_max: float = _u("m")
    s_min: float = _u("{signal}")
    s_max: float = _u("{signal}")

    @property
    def found(self) -> bool:
        """The run had a constant-compliance region (False: NaN line)."""
        return self.n_points > 0 and math.isfinite(self.slope)

    @classmethod
    def missing(cls) -> "ComplianceLine":
        """The line of a run without a constant-compliance region (all NaN)."""
        nan = math.nan
        return cls(nan, nan, nan, nan, nan, 0, nan, nan, nan, nan)

    def position_at(self, s: float) -> float:
        """Position [m] where the line reaches signal ``s``."""
        return (s - self.intercept) / self.slope

    def position_se(self) -> float:
        """Standard error of the line's position at its centre [m]."""
        return self.sigma / (abs(self.slope) * math.sqrt(max(self.n_points, 1)))


@dataclass(frozen=True)
class ComplianceResult:
    """Both constant-compliance lines (before any shift) and the signal unit."""

    approach: ComplianceLine
    retract: ComplianceLine
    unit: str
    #: why a run has no line although it has a compliance region (a degenerate line)
    notes: tuple[str, ...] = ()


def _fit_line(z: np.ndarray, s: np.ndarray, run: RunRegions) -> ComplianceLine:
    if not run.has_compliance:
        return ComplianceLine.missing()
    # one compiled call: the robust line of the region's unsaturated samples against their centred position
    (n, intercept, b, se_a, se_b, sigma, n_used, z_min, z_max, s_min, s_max, xm) = compliance_line(
        np.ascontiguousarray(z, dtype=np.float64), np.ascontiguousarray(s, dtype=np.float64),
        np.ascontiguousarray(run.index, dtype=np.int64), np.ascontiguousarray(run.compliance, dtype=np.bool_),
        np.ascontiguousarray(run.saturated, dtype=np.bool_))
    if n < 3:
        raise AnalysisError(f"the {run.kind} constant-compliance region has {int(n)} samples; need 3")
    if not np.isfinite(b) or b == 0:
        raise AnalysisError(f"the {run.kind} constant-compliance line is degenerate (zero or undefined slope)")
    return ComplianceLine(intercept=float(intercept), slope=float(b),
                          intercept_se=float(math.hypot(se_a, se_b * xm)), slope_se=float(se_b),
                          sigma=float(sigma), n_points=int(n_used), z_min=float(z_min),
                          z_max=float(z_max), s_min=float(s_min), s_max=float(s_max))


def fit_compliance(z: np.ndarray, s: np.ndarray, approach: RunRegions | None, retract: RunRegions | None,
                   unit: str) -> ComplianceResult:
    """Fit the constant-compliance line of both runs (a NaN line for a run without one, or absent: None).

    A run whose line is degenerate (no spread of its positions: a stepped, backlashing position
    sensor that barely moves over the region) gets a NaN line and a note, and the other run's
    line serves (as for a run without a compliance region); both degenerate raise.
    """
    lines, notes = {"approach": ComplianceLine.missing(), "retract": ComplianceLine.missing()}, []
    for run in (approach, retract):
        if run is None:  # a curve of one run: the missing run has no line
            continue
        try:
            lines[run.kind] = _fit_line(z, s, run)
        except AnalysisError as exc:
            if "degenerate" not in str(exc):
                raise
            lines[run.kind], why = ComplianceLine.missing(), str(exc)
            notes.append(f"{why}: the {run.kind} run has no compliance line (its positions barely move "
                         "there: a stepped or backlashing position sensor); the other run's line is used")
    if not (lines["approach"].found or lines["retract"].found) and notes:
        raise AnalysisError("; ".join(notes).replace("; the other run's line is used", ""))
    return ComplianceResult(approach=lines["approach"], retract=lines["retract"], unit=unit, notes=tuple(notes))


@dataclass(frozen=True)
class CalibrationResult:
    """Deflection calibration: deflection [m] = signal x ``factor``.

    ``calibration_factor`` is *not* used here: in afmforce it means beta of
    eq 15 [m/rad] only. The optical-lever sensitivity (InvOLS) is
    ``sensitivity`` (the file's or user's) and ``sensitivity_fit`` (from the
    compliance slope), both [m/V], as afmformats and the vendors name them.

    Attributes
    ----------
    factor : float
        Metres of deflection per signal unit used [m/V, m/m or m/N].
    factor_fit : float
        ``1 / compliance slope`` [m per signal unit] (hard contact assumed).
    factor_given : float
        From the file or the user (sensitivity [m/V], 1 [m/m], or 1/k [m/N]); NaN if unknown.
    source : str
        ``"fit"`` or ``"metadata"``: which factor is used.
    sensitivity : float
        The file's or user's sensitivity [m/V] (NaN if none).
    sensitivity_fit : float
        The sensitivity the compliance slope implies [m/V]: ``1 / slope`` for a
        signal in volts, ``sensitivity / (deflection slope)`` for a signal the
        instrument calibrated (NaN without a sensitivity to scale).
    compliance_slope : float
        Slope used for ``factor_fit`` [signal unit/m].
    slope_ratio : float
        Approach slope / retract slope [-].
    spring_constant_from_slope : float
        For force signals: the slope itself [N/m] (NaN otherwise).
    unit : str
    requested : str
        The source asked for (``calibration.source``: ``"auto"``, ``"fit"`` or ``"metadata"``).
    determined : bool
        False when the slope calibrates although its line does not determine an InvOLS
        (:func:`afmforce.analysis.invols.line_notes`, the rule of ``afmforce calibrate invols``) and no other
        sensitivity is known: every separation and force rests on an undetermined InvOLS.
    """

    factor: float = _u("m/{signal}")
    factor_fit: float = _u("m/{signal}")
    factor_given: float = _u("m/{signal}")
    source: str
    sensitivity: float = _u("m/V")
    sensitivity_fit: float = _u("m/V")
    compliance_slope: float = _u("{signal}/m")
    slope_ratio: float = _u("")
    spring_constant_from_slope: float = _u("N/m")
    unit: str
    requested: str = "auto"
    determined: bool = True


def _metadata_factor(unit: str, metadata: Mapping[str, Any]) -> float:
    return signal_factor(unit, metadata.get("sensitivity"), metadata.get("spring_constant"))


def calibrate(compliance: ComplianceResult, metadata: Mapping[str, Any], *, source: str = _C.source,
              run: str = _C.run) -> CalibrationResult:
    """Calibration factor from the compliance slope and/or the metadata.

    ``source="auto"`` uses the file's or user's calibration when there is one
    (sensitivity for volts; none needed for metres; 1/k for newtons) and the
    fitted slope otherwise. ``run`` picks the slope: ``"approach"``,
    ``"retract"`` or ``"both"`` (inverse-variance mean).
    """
    if source not in CALIBRATION_SOURCES:
        raise ParameterError(f"calibration source must be one of {', '.join(CALIBRATION_SOURCES)}, got {source!r}")
    if run not in ("approach", "retract", "both"):
        raise ParameterError(f"calibration run must be approach, retract or both, got {run!r}")
    a, r = compliance.approach, compliance.retract
    if not (a.found and r.found):  # one line only: that one
        run = "approach" if a.found else "retract"
    if run == "approach":
        slope = a.slope
    elif run == "retract":
        slope = r.slope
    else:
        wa = 1.0 / a.slope_se**2 if a.slope_se > 0 else 1.0
        wr = 1.0 / r.slope_se**2 if r.slope_se > 0 else 1.0
        slope = (wa * a.slope + wr * r.slope) / (wa + wr)
    unit = compliance.unit
    # a "compliance line" the deflection falls along while the tip pushes in is none (a noisy or drifting
    # contact, a FluidFM cell curve gave -38470 nm/V): no calibration, no sensitivity from it
    f_fit = 1.0 / slope if slope > 0 else math.nan
    f_meta = _metadata_factor(unit, metadata)
    if source == "metadata" and not math.isfinite(f_meta):
        raise AnalysisError("no calibration in the file: give the sensitivity (`sensitivity`) "
                            "or use the fitted compliance slope (source='fit')")
    use_meta = source == "metadata" or (source == "auto" and math.isfinite(f_meta))
    if not use_meta and not math.isfinite(f_fit):
        raise AnalysisError(f"the compliance line's slope is {slope:.3g} (the deflection does not rise as the tip "
                            "pushes in): no calibration from it; give the sensitivity (`sensitivity`)")
    sens = float(metadata.get("sensitivity", math.nan) or math.nan)
    if unit == "V":
        sens_fit = f_fit
    elif math.isfinite(f_meta) and slope > 0:  # deflection per position on the line, times the file's sensitivity
        sens_fit = sens / (slope * f_meta)
    else:
        sens_fit = math.nan
    return CalibrationResult(factor=f_meta if use_meta else f_fit, factor_fit=f_fit, factor_given=f_meta,
                             source="metadata" if use_meta else "fit", sensitivity=sens,
                             sensitivity_fit=float(sens_fit), compliance_slope=slope,
                             slope_ratio=a.slope / r.slope,
                             spring_constant_from_slope=slope if unit == "N" else math.nan, unit=unit)


@dataclass(frozen=True)
class ShiftResult:
    """Shift of the inward run along z that overlays the compliance lines.

    Attributes
    ----------
    shift : float
        Added to the inward positions [m] (``z_out - z_in`` at equal signal); NaN when
        a run has no constant-compliance line.
    shift_se : float
        Standard error [m].
    reference_signal : float
        Signal level where the lines are compared [signal unit].
    applied : bool
        Whether the inward run was moved.
    shift_drift : float
        Bound on the shift from the drift lines [m]: the range of drift rates the free parts allow,
        extrapolated to the compliance lines (:func:`afmforce.analysis.steps.shift.drift_position_error`);
        it adds to ``shift_se`` (the lines' noise alone); NaN when not assessed.
    determined : bool
        False when ``shift_drift`` exceeds both the shift and the resolution it is read to
        (:func:`afmforce.analysis.plausibility.undetermined`): the result's ``shift`` is then NaN (undetermined)
        and ``shift`` here is the lines' offset alone, within +- ``shift_drift`` of the truth.
    """

    shift: float = _u("m")
    shift_se: float = _u("m")
    reference_signal: float = _u("{signal}")
    applied: bool
    shift_drift: float = _u("m", math.nan)
    determined: bool = True


def compliance_shift(compliance: ComplianceResult, applied: bool = True) -> ShiftResult:
    """``z_out(s*) - z_in(s*)`` at the middle ``s*`` of the signal range both lines share."""
    a, r = compliance.approach, compliance.retract
    if not (a.found and r.found):
        nan = math.nan
        return ShiftResult(shift=nan, shift_se=nan, reference_signal=nan, applied=False)
    lo, hi = max(a.s_min, r.s_min), min(a.s_max, r.s_max)
    if hi < lo:
        lo, hi = min(a.s_min, r.s_min), max(a.s_max, r.s_max)
    s_ref = 0.5 * (lo + hi)
    shift = r.position_at(s_ref) - a.position_at(s_ref)
    se = math.hypot(a.position_se(), r.position_se())
    return ShiftResult(shift=float(shift), shift_se=float(se), reference_signal=float(s_ref), applied=applied)


@dataclass(frozen=True)
class FrictionSignature:
    """What the two compliance lines say about friction (paper sections 2.2.2-2.2.4).

    Coincident lines do not exclude friction: friction smaller than the lines resolve hides
    in them (and in Figs 5-6 viscous friction underestimates the precontact attraction with
    lines 0.05-0.5 nm apart). So no kind says "no friction": coincident lines are
    ``"not detected"``, with the largest friction the data allow (the ``*_bound`` fields; see
    :func:`friction_signature` for their derivation).

    Attributes
    ----------
    kind : str
        ``"not detected"`` (the lines coincide within the resolution: friction up to the
        bounds is compatible), ``"constant"`` (parallel, inward line at larger z),
        ``"opposite"`` (parallel, inward line at smaller z: an instrument artefact, Fig 7B),
        ``"load-proportional"`` (slopes differ by up to ``friction_slope_limit``),
        ``"nonlinear"`` (slopes differ by more than friction makes: the position channel
        or a soft contact), ``"pinned"`` (negative slope), ``"undetermined"`` (one line
        only) or ``"not assessed"`` (set by the step: a soft or curved contact).
    offset : float
        ``z_in - z_out`` at equal deflection [m] (friction makes it positive, spec 7).
    offset_se : float  [m]
    slope_ratio : float
        Approach / retract compliance slope [-].
    slope_ratio_se : float  [-]
    verdict : str
        Plain words.
    offset_bound : float
        Largest ``|offset|`` compatible with the lines: ``|offset| + nsigma offset_se`` plus
        the drift's systematic offset, at least the offset tolerance [m] (NaN unless the kind
        is ``"not detected"``, ``"constant"`` or ``"load-proportional"``).
    slope_difference_bound : float
        Largest ``|slope_ratio - 1|`` compatible, likewise [-].
    friction_force_bound : float
        Largest constant friction ``mu`` (``Fy = +-mu``) the offset bound allows, eq 16 [N];
        NaN without the lever's geometry (``theta0``, ``L0``, ``L1``, ``L2``).
    viscous_friction_bound : float
        Largest viscous coefficient ``xi`` (eq 28) the offset bound allows at the approach
        speed, in steady sliding ``mu = xi |dy2/dz2| v`` [kg/s]; NaN without the geometry
        or the speed.
    load_friction_bound : float
        Largest ``lambda`` (``Fy = +-lambda Fz``) the slope bound allows, eqs 18-19 [-]; NaN
        without the geometry or when the slope bound reaches no lambda below the lever's
        stability limit (lambda undetermined).
    """

    kind: str
    offset: float = _u("m")
    offset_se: float = _u("m")
    slope_ratio: float = _u("")
    slope_ratio_se: float = _u("")
    verdict: str
    offset_bound: float = _u("m", math.nan)
    slope_difference_bound: float = _u("", math.nan)
    friction_force_bound: float = _u("N", math.nan)
    viscous_friction_bound: float = _u("kg/s", math.nan)
    load_friction_bound: float = _u("", math.nan)


#: Kinds whose lines bound friction from above (the others: no line pair, an artefact, not friction).
BOUNDED_KINDS = ("not detected", "constant", "load-proportional")


def _friction_bounds(lever: "InclinedCantilever | None", offset_bound: float, slope_bound: float,
                     velocity: float) -> tuple[float, float, float]:
    """(mu, xi, lambda) bounds of :func:`friction_signature` (NaN where not determined)."""
    nan = math.nan
    if lever is None:
        return nan, nan, nan
    from ..statics import constant_friction_for_offset, load_friction_for_slope_ratio

    mu = constant_friction_for_offset(lever, offset_bound)
    slide = abs(lever.slide_ratio)
    xi = mu / (slide * velocity) if math.isfinite(velocity) and velocity > 0 and slide > 0 else nan
    lam = min(load_friction_for_slope_ratio(lever, 1.0 - slope_bound),
              load_friction_for_slope_ratio(lever, 1.0 + slope_bound))
    return float(mu), float(xi), float(lam) if math.isfinite(lam) else nan


def _bound_words(sig_bounds: tuple[float, float, float], lever, velocity: float) -> str:
    mu, xi, lam = sig_bounds
    if lever is None:
        return ("no friction force follows without the lever's geometry (`theta0`, `L0`, `L1`, `L2`: eq 16's "
                "offset vanishes for a tip on the beam's axis)")
    parts = [f"constant friction mu up to {mu * 1e9:.3g} nN (eq 16)" if math.isfinite(mu) else
             "no constant friction bound (this geometry makes no eq-16 offset)"]
    if math.isfinite(xi):
        parts.append(f"viscous xi up to {xi:.3g} kg/s at {velocity * 1e6:.3g} um/s (eq 28, steady sliding)")
    parts.append(f"load-proportional lambda up to {lam:.3g} (eqs 18-19)" if math.isfinite(lam) else
                 "load-proportional lambda undetermined (any lambda below the lever's stability limit fits "
                 "the slopes, eqs 18-19)")
    return "; ".join(parts)


def friction_signature(compliance: ComplianceResult, shift: ShiftResult, *, nsigma: float = _F.nsigma,
                       slope_tolerance: float = _F.slope_tolerance, offset_tolerance: float = _F.offset_tolerance,
                       friction_slope_limit: float = 0.25, channel: str = "", offset_systematic: float = 0.0,
                       slope_systematic: float = 0.0, lever: "InclinedCantilever | None" = None,
                       velocity: float = math.nan) -> FrictionSignature:
    """Classify the pair of compliance lines and bound the friction they allow.

    Parameters
    ----------
    nsigma : float
        Significance in standard errors [-].
    slope_tolerance : float
        Relative slope difference below which lines count as parallel [-].
    offset_tolerance : float
        Offset below which parallel lines count as coincident [m].
    friction_slope_limit : float
        Largest relative slope difference friction proportional to load explains [-]
        (Fig 4: 7 % for lambda = 2, spec section 4.2); beyond it the kind is ``"nonlinear"``.
    channel : str
        Position channel (``"nominal"``: a creeping piezo changes the slopes).
    offset_systematic, slope_systematic : float
        How far a systematic error (the drift line's, see the step) can move the offset [m]
        and the slope ratio [-]: added to the bounds.
    lever : InclinedCantilever or None
        The lever's geometry and stiffness (eqs 7-12): converts the bounds into friction
        parameters. None: the bounds stay in the lines' units.
    velocity : float
        Approach speed [m/s] (the viscous bound).

    Notes
    -----
    The bounds (kinds ``"not detected"``, ``"constant"``, ``"load-proportional"``):

    * offset: ``|offset| + nsigma offset_se + offset_systematic``, at least ``offset_tolerance``
      (the largest offset the data allow at the chosen significance; below the tolerance the
      lines count as coincident whatever their standard errors);
    * slopes: ``|slope_ratio - 1| + nsigma slope_ratio_se + slope_systematic``, at least
      ``slope_tolerance``.

    Converted with the lever, each law alone:

    * constant friction ``Fy = +-mu`` (eqs 16, 17): at fixed theta the inward and outward
      positions differ by ``z+ - z- = (cos th0 / 2B)[(2/3 L0^3 cos th0 + a L0^2)(Fz+ - Fz-)
      + 2 mu (2/3 L0^3 sin th0 + b L0^2)]`` with ``Fz+ - Fz- = -2 mu (L0^2 sin th0 + 2 b L0) /
      (L0^2 cos th0 + 2 a L0)`` (eq 17): linear in mu, ``z+ - z- = mu D``, so
      ``mu <= offset_bound / D`` (:func:`afmforce.statics.constant_friction_for_offset`;
      Fig 3: D = 0.152 nm/nN). In hard contact the substrate position differs as the tip's.
    * viscous friction ``Fy = -xi dy2/dt`` (eq 28) in steady sliding along the compliance
      line: ``|Fy| = xi |dy2/dz2| v`` (spec section 7: xi v = 1e-8 N gives 0.454 nm), so
      ``xi <= mu_bound / (|dy2/dz2| v)``.
    * friction proportional to load ``Fy = +-lambda Fz`` (eqs 18, 19): the compliance slope
      of a run goes as ``1 / beta``, so the slope ratio is ``beta_out / beta_in``, a ratio of
      linear functions of lambda; ``|ratio - 1| <= slope_bound`` holds up to the smallest
      root of a quadratic (:func:`afmforce.statics.load_friction_for_slope_ratio`), the bound
      on lambda (NaN: undetermined below the stability limit).

    The bounds assume the position channel adds no offset or slope of its own: an opposite
    backlash (Fig 7B) could hide more friction than they say.
    """
    a, r = compliance.approach, compliance.retract
    nan = math.nan
    if not (a.found and r.found):
        missing = "approach" if not a.found else "retract"
        return FrictionSignature("undetermined", nan, nan, nan, nan, (
            f"one constant-compliance line only (the {missing} run's contact is clipped or absent): "
            "friction cannot be judged"))
    instrument = ("the nonlinear, creeping piezo of the nominal position channel (section 3.1, Fig 7A)"
                  if channel == "nominal" else "a nonlinear position channel")
    ratio = a.slope / r.slope
    ratio_se = abs(ratio) * math.hypot(a.slope_se / a.slope, r.slope_se / r.slope)
    offset, off_se = -shift.shift, shift.shift_se
    if a.slope < 0 and r.slope < 0:
        kind = "pinned"
        verdict = ("negative calibration slope: a pinned tip (eqs 20-21) would make a precontact "
                   "attraction look repulsive; check the photodiode sign before trusting forces")
    elif abs(ratio - 1.0) > max(nsigma * ratio_se, slope_tolerance, friction_slope_limit):
        kind = "nonlinear"
        verdict = (f"compliance lines are not parallel (slope ratio {ratio:.4g}), by more than friction "
                   f"proportional to load makes (a few per cent, eqs 18-19, Fig 4): the instrument "
                   f"({instrument}) or a soft, nonlinear contact, not friction")
    elif abs(ratio - 1.0) > max(nsigma * ratio_se, slope_tolerance):
        kind = "load-proportional"
        verdict = (f"compliance lines are not parallel (slope ratio {ratio:.4f}): friction proportional "
                   f"to load (eqs 18-19), or the instrument ({instrument}), or a nonlinear contact")
    elif abs(offset) > max(nsigma * off_se, offset_tolerance):
        if offset > 0:
            kind = "constant"
            verdict = (f"parallel lines, inward {offset * 1e9:.3g} nm to the right of outward: constant "
                       "friction (eq 16) or piezo/detector hysteresis; only interferometry can tell")
        else:
            kind = "opposite"
            verdict = (f"parallel lines, inward {-offset * 1e9:.3g} nm to the left of outward: opposite to "
                       "friction, an instrument artefact (backlash or piezo hysteresis, Fig 7B)")
    else:
        kind = "not detected"
        verdict = ""
    if kind not in BOUNDED_KINDS:
        return FrictionSignature(kind=kind, offset=float(offset), offset_se=float(off_se),
                                 slope_ratio=float(ratio), slope_ratio_se=float(ratio_se), verdict=verdict)
    off_bound = max(abs(offset) + nsigma * off_se + abs(offset_systematic), offset_tolerance)
    slope_bound = max(abs(ratio - 1.0) + nsigma * ratio_se + abs(slope_systematic), slope_tolerance)
    bounds = _friction_bounds(lever, off_bound, slope_bound, velocity)
    allow = (f"offset up to {off_bound * 1e9:.3g} nm and slopes differing by up to {slope_bound * 100:.3g} % "
             f"({nsigma:g} standard errors)")
    if kind == "not detected":
        verdict = (f"compliance lines coincide within the resolution: friction not detected, not excluded "
                   f"(Figs 5-6: friction hides without separated lines); the lines allow an {allow}: "
                   f"{_bound_words(bounds, lever, velocity)}")
    elif lever is not None:
        verdict = f"{verdict}; at most (the lines allow an {allow}): {_bound_words(bounds, lever, velocity)}"
    return FrictionSignature(kind=kind, offset=float(offset), offset_se=float(off_se), slope_ratio=float(ratio),
                             slope_ratio_se=float(ratio_se), verdict=verdict, offset_bound=float(off_bound),
                             slope_difference_bound=float(slope_bound), friction_force_bound=bounds[0],
                             viscous_friction_bound=bounds[1], load_friction_bound=bounds[2])
