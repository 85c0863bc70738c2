"""The fit's inputs taken from the analysis steps: calibration, contact kind, jump-in and contact.

One preprocessing (issue 23, item 4): the dynamic fit prepares a curve with the
same steps as ``afmforce analyze`` (:mod:`afmforce.analysis.pipeline`: ``contact``,
``drift``, ``compliance``, ``calibration``, ``kind``), so that a fix to an artefact
in one place serves both:

* **Calibration.** The analysis's deflection in metres, by its one rule
  (``calibration.source``, :class:`afmforce.analysis.options.CalibrationOptions`; the fit's
  ``calibration`` takes the same words): the file's sensitivity (or spring constant for a
  force) wherever the file has one; the slope of the approach's constant-compliance line (the
  paper's section 3.1; the rigid contact the dynamic model assumes anyway) where the file has
  none, where it is asked for (``fit``), or where the file's is impossible on a hard contact
  (the deflection outrunning the position more than 1.25x on a straight line:
  :func:`afmforce.analysis.steps.kind._recalibrate_hard`). Each change is said in a note with
  its numbers.
* **Contact kind.** A soft (curved) contact is refused with the analysis's reason: the
  dynamic model's surfaces are rigid (eq 2); ``afmforce analyze`` fits the indentation.
* **Jump-in and contact.** The analysis's jump-in (:func:`afmforce.analysis.jumps.find_jump_in`,
  the largest significant drop next to the contact split) and contact onset (the split of
  :func:`afmforce.analysis.regions.find_run_regions`); without a significant jump, the onset.
* **Rigid-contact test.** The approach's compliance line (:func:`afmforce.analysis.compliance.fit_compliance`)
  in calibrated units: the deflection must follow the position with slope ~1.

An approach-only curve (the analysis needs both runs) gets the same functions on its
one run, with the file's calibration (``calibration`` "fit" is refused there, not ignored).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import AnalysisError, MissingMetadataError, ParameterError
from ..io.curve import RawCurve

__all__ = ["AnalysisInputs", "analysis_inputs", "calibration_source"]


@dataclass(frozen=True)
class AnalysisInputs:
    """What the fit takes from the analysis for one curve (indices into the approach run).

    Attributes
    ----------
    factor : float
        Deflection signal to metres [m / signal unit].
    source : str
        ``"file"`` (the file's calibration, or metres), ``"compliance"`` (no calibration
        in the file: the compliance slope) or ``"recalibrated"`` (the file's sensitivity
        replaced by the compliance slope: asked for, or impossible on a hard contact).
    sensitivity, file_sensitivity : float
        Sensitivity used and the file's [m/V] (NaN unless the signal is in volts).
    jump : int
        First approach sample after the jump-in (the contact onset without a jump).
    jump_found : bool
        A significant jump-in (else a creeping contact).
    contact : int
        First contact sample of the approach (the analysis's split).
    slope, slope_se : float
        Deflection per position on the approach's constant-compliance line, calibrated [-].
    kind : str
        The analysis's contact kind (``"hard"``; ``"approach only"`` without a retract).
    unit : str
        The file's deflection unit.
    spring_constant : float
        The analysis's spring constant [N/m] (step ``force``: the file's, rescaled with a refitted
        sensitivity as a thermal k; from the compliance slope of a force without one; NaN: none).
    notes : tuple of str
        What the fit should warn about (calibration changes).
    """

    factor: float
    source: str
    sensitivity: float
    file_sensitivity: float
    jump: int
    jump_found: bool
    contact: int
    slope: float
    slope_se: float
    kind: str
    notes: tuple[str, ...] = ()
    unit: str = "m"
    spring_constant: float = math.nan

    def as_metadata(self) -> dict:
        """The calibration as the fit reports it (JSON-ready, SI)."""
        return {"source": self.source, "factor": self.factor, "sensitivity": _num(self.sensitivity),
                "file_sensitivity": _num(self.file_sensitivity), "contact_slope": _num(self.slope),
                "contact_kind": self.kind, "jump_found": self.jump_found, "unit": self.unit,
                "spring_constant": _num(self.spring_constant)}


def _num(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _extra_segments(curve: RawCurve) -> str:
    seg = np.asarray(curve.segment)
    n = int(np.sum(seg >= 2))
    return (f"; the file also holds {n} samples of a dwell/pause segment (stress relaxation), which "
            "the dynamic model does not describe") if n else ""


def _refuse_soft(name: str, curve: RawCurve, reason: str) -> AnalysisError:
    return AnalysisError(
        f"{name}: soft contact ({reason}): the sample deforms, but the dynamic model assumes rigid "
        f"surfaces (eq 2), so this curve cannot be fitted{_extra_segments(curve)}; analyse it with "
        f"`afmforce analyze {name.split('#')[0]}` (its indentation step fits Young's modulus)")


def calibration_source(calibration: str) -> str:
    """The analysis's ``calibration.source`` for the fit's ``calibration``: the same words
    (:data:`afmforce.analysis.options.CALIBRATION_SOURCES`), and ``"file"``, the fit's former word
    for ``"metadata"``.

    Raises
    ------
    ParameterError
        Any other word.
    """
    from ..analysis.options import CALIBRATION_SOURCES

    word = "metadata" if calibration == "file" else calibration
    if word not in CALIBRATION_SOURCES:
        raise ParameterError(f"calibration must be one of {', '.join(CALIBRATION_SOURCES)}, got {calibration!r}")
    return word


def analysis_inputs(curve: RawCurve, name: str, idx: np.ndarray, soft: str = "refuse",
                    calibration: str = "auto") -> AnalysisInputs:
    """Run the analysis steps up to ``kind`` on ``curve`` and take the fit's inputs from them.

    Parameters
    ----------
    curve : RawCurve
        The curve as loaded.
    name : str
        Its label in messages.
    idx : ndarray of int
        The approach samples the fit uses (the first run of segment 0).

    Raises
    ------
    AnalysisError
        No contact reached, a soft contact, or an analysis step that fails on the curve
        (its message, prefixed by ``name``).
    MissingMetadataError
        An approach-only curve in volts or newtons without the file's calibration.
    ParameterError
        ``calibration`` "fit" on an approach-only curve (calibrated with the file's only).
    """
    from ..analysis.pipeline import STEPS, resolve_options, resolve_steps
    from ..analysis.regions import run_indices
    from ..analysis.state import NoContact, prepare

    from ..analysis.options import CalibrationOptions

    opts, _ = resolve_options([CalibrationOptions(source=calibration_source(calibration))])
    if run_indices(np.asarray(curve.segment), 1).size == 0:
        if opts["calibration"].source == "fit":   # never the file's in silence where the slope was asked for
            raise ParameterError(
                f"{name}: calibration 'fit' (the compliance slope, with a thermal spring constant rescaled) is "
                "not available on a curve without a retract run, which the fit calibrates with the file's "
                "sensitivity: use calibration auto or metadata, or give the sensitivity (`sensitivity`)")
        return _approach_only(curve, name, idx, opts["kind"].nsigma, int(opts["jumps"].window))
    try:
        st = prepare(curve)
        for step in resolve_steps(["kind", "force"]):
            st = STEPS[step].func(st, opts[step])
    except NoContact as exc:
        why = str(exc).rstrip("?").replace("; is the surface reached", ": the surface is not reached")
        raise AnalysisError(f"{name}: {why}; the fit needs curves that reach contact (a "
                            "constant-compliance region at the end of the approach)") from None
    except AnalysisError as exc:
        raise AnalysisError(f"{name}: the analysis steps that prepare the curve fail: {exc}") from None
    kind = st.details["kind"]
    soft_note = []
    if kind.kind == "soft" and soft == "refuse":
        raise _refuse_soft(name, curve, kind.reason)
    if kind.kind == "soft":
        soft_note.append(f"{name}: the analysis sees a soft contact ({kind.reason}); in a liquid the "
                         "drainage and double-layer forces the model has bend the approach like that, "
                         "so the curve is fitted and the fit's adequacy test judges it")
    cal, comp = st.details["calibration"], st.details["compliance"]
    factor = float(st.factor)
    sens = factor if st.unit == "V" else math.nan
    source = "file"
    notes = soft_note
    if cal.source == "fit" and math.isfinite(cal.factor_given):
        source = "recalibrated"    # asked for (`fit`), or the kind step found the file's impossible (hard, straight)
        why = ("as asked (calibration 'fit')" if cal.requested == "fit" else
               f"the file's is impossible on this hard contact (its compliance line moves the deflection "
               f"{cal.factor_given / factor:.3g} x the position, at most 1 on any contact), as `afmforce analyze` does")
        notes.append(f"{name}: the compliance slope calibrates, {why}: {cal.sensitivity_fit * 1e9:.4g} nm/V "
                     f"instead of the file's {cal.sensitivity * 1e9:.4g} nm/V")
    elif cal.source == "fit":
        source = "compliance"
        from ..analysis.plausibility import SPRING_CONSTANT_RANGE

        lo, hi = SPRING_CONSTANT_RANGE
        if st.unit == "N" and not lo <= 1.0 / factor <= hi:
            raise AnalysisError(
                f"{name}: the force has no spring constant in the file, and its compliance slope, the "
                f"spring constant of a rigid contact, is {1.0 / factor:.3g} N/m: outside the range of "
                f"cantilevers made ({lo:g}..{hi:g} N/m), so the contact is not rigid (a soft sample) or "
                "the force column is not in newtons; give the lever's (`spring_constant`)")
        what = (f"no sensitivity in the file: {factor * 1e9:.4g} nm/V" if st.unit == "V" else
                f"no spring constant in the file: the force converts with {1 / factor:.4g} N/m"
                if st.unit == "N" else f"the deflection is scaled by {factor:.4g}")
        notes.append(f"{name}: {what} from the slope of the approach's constant-compliance line, as "
                     "`afmforce analyze` calibrates (it assumes a rigid contact); give yours "
                     f"(`{'sensitivity' if st.unit == 'V' else 'spring_constant'}`)")
    k_file = float((curve.metadata or {}).get("spring_constant") or math.nan)
    if math.isfinite(k_file) and abs(st.spring_constant / k_file - 1.0) > 1e-9:
        notes.append(f"{name}: spring constant rescaled with the refitted sensitivity as `afmforce analyze` "
                     f"does (a thermal k goes as 1/InvOLS^2): {k_file:.4g} -> {st.spring_constant:.4g} N/m")
    # the analysis's own checks of the calibration (few contact samples, a contact line steeper than 1)
    from ..analysis.plausibility import plausibility_warnings

    notes += [f"{name}: {w}" for w in plausibility_warnings(st)]
    line = comp.approach if comp.approach.found else comp.retract
    jump, found, contact = _jump(st.deflection, st.z, st.approach, abs(st.noise * factor),
                                 opts["kind"].nsigma, int(idx[0]), int(opts["jumps"].window))
    return AnalysisInputs(factor, source, sens, float(cal.sensitivity), jump, found, contact,
                          line.slope * factor, line.slope_se * abs(factor), kind.kind, tuple(notes),
                          st.unit, float(st.spring_constant))


def _jump(deflection, z, run, noise: float, nsigma: float, start: int, window: int = 3
          ) -> tuple[int, bool, int]:
    """The analysis's jump-in (first sample after it) and contact split, relative to ``start``.

    Without a significant jump (:func:`~afmforce.analysis.jumps.find_jump_in`: none above
    ``nsigma`` step noises within ``window`` samples of the split) the fit still leaves out
    the largest drop before the constant-compliance region (after the run's first tenth, where
    a lever's drag sets in in a liquid; the analysis's
    :func:`~afmforce.analysis._numeric.largest_step`): a jump hidden in the noise, 15 samples
    away from a split that a stepped, backlashing position sensor moved (the ``paper`` preset).
    """
    from ..analysis import largest_step
    from ..analysis.jumps import find_jump_in

    # as the analysis's jumps step: a step in contact (starting and landing above nsigma noises) is a slip,
    # the jump is the step into the attraction before it
    ji = find_jump_in(deflection, z, z, run, noise, math.nan, nsigma, window, attractive_below=nsigma * noise)
    contact = int(run.index[min(run.split, run.index.size - 1)]) - start
    if ji.found:
        return int(ji.index) + 1 - start, True, contact
    comp = np.flatnonzero(run.compliance)
    hi = int(comp[0]) + 1 if comp.size else run.index.size
    lo = min(hi // 10, max(run.split - window, 0))   # not the first tenth: a lever's drag onset
    hi = max(hi, lo + 2)
    i = largest_step(np.asarray(deflection)[run.index], lo, hi, -1.0)
    return (int(run.index[i]) + 1 - start if i >= 0 else contact), False, contact


def _approach_only(curve: RawCurve, name: str, idx: np.ndarray, nsigma: float,
                   window: int) -> AnalysisInputs:
    """The same analysis functions on an approach-only curve, with the file's calibration."""
    from ..analysis import compliance_line
    from ..analysis.regions import find_run_regions, saturated_mask

    unit = curve.deflection_unit
    factor = curve.deflection_factor()
    if not math.isfinite(factor):
        need = "sensitivity" if unit == "V" else "spring_constant"
        raise MissingMetadataError(
            f"{name}: the deflection is in {unit}, the file has no {need} and the curve has no retract "
            f"run to check a calibration from its compliance line against: give it (`{need}`)", keys=(need,))
    zz = np.asarray(curve.position(), float)
    s = np.asarray(curve.deflection_signal, float)
    try:
        run = find_run_regions(zz, s, idx, "approach", saturated=saturated_mask(s))
        line = compliance_line(zz, s, run)
    except AnalysisError as exc:
        raise AnalysisError(f"{name}: {exc}; the fit needs curves that reach contact") from None
    jump, found, contact = _jump(s * factor, zz, run, abs(run.noise * factor), nsigma, int(idx[0]),
                                 window)
    return AnalysisInputs(factor, "file", factor if unit == "V" else math.nan,
                          factor if unit == "V" else math.nan, jump, found, contact,
                          line.slope * factor, line.slope_se * abs(factor), "approach only", (), unit)


#: The files' spring constant and the model's may differ by this fraction before a warning.
SPRING_CONSTANT_TOLERANCE = 0.02


def preparation_warnings(curves, base) -> list[str]:
    """The fit's warnings from the preparation: calibration notes of each curve, and a model
    lever whose spring constant differs from the files' (A*R and friction scale with k).

    ``curves``: prepared :class:`~afmforce.fit.data.FitCurve` objects; ``base``: the model's
    :class:`~afmforce.dynamics.SimulationConfig`.
    """
    out = [w for c in curves for w in c.metadata.get("preparation_notes", ())]
    # the analysis's k (the file's, rescaled with a refitted sensitivity, or a force's compliance slope)
    ks = [(c.metadata.get("calibration") or {}).get("spring_constant") or c.metadata.get("spring_constant")
          for c in curves]
    ks = [float(k) for k in ks if k]
    k_model = float(base.force_constant)
    if ks and abs(float(np.median(ks)) / k_model - 1.0) > SPRING_CONSTANT_TOLERANCE:
        k = float(np.median(ks))
        how = (f"the spring model's spring constant, {k:.4g} N/m" if base.model == "spring" else
               f"`k0` {base.cantilever.k0 * k / k_model:.4g}N/m, the beam's k0 for this k; or `model` spring "
               f"with the spring constant {k:.4g} N/m")
        out.append(f"the curves' spring constant is {k:.4g} N/m but the model's lever has "
                   f"{k_model:.4g} N/m ({base.model} model): the fitted A*R and friction scale with "
                   f"k, so they describe another lever; give the model your lever ({how})")
    cal = [(c.name, c.metadata["calibration"]) for c in curves if c.metadata.get("calibration")]
    for unit in ("V", "N"):
        f = [(nm, m["factor"]) for nm, m in cal if m.get("unit") == unit]
        if len(f) > 1 and max(v for _, v in f) > (1 + SPRING_CONSTANT_TOLERANCE) * min(v for _, v in f):
            lo, hi = min(f, key=lambda t: t[1]), max(f, key=lambda t: t[1])
            what = "sensitivities" if unit == "V" else "force calibrations (1/k)"
            out.append(f"the curves' {what} differ: {lo[1]:.4g} ({lo[0]}) to {hi[1]:.4g} ({hi[0]}) "
                       f"m/{unit} (the compliance slope recalibrated some): a joint fit assumes one lever "
                       "and one laser alignment; check the curves' calibrations")
    out += [f"{c.name}: no significant jump into contact (none above the analysis's threshold of "
            "5 step noises at the contact; the largest drop before the compliance region is left out "
            "as the jump): the attraction before contact is barely resolved, so A*R rests mostly on "
            "the approach's curvature" for c in curves
            if (c.metadata.get("calibration") or {}).get("jump_found") is False]
    return out


def result_warnings(params: dict, base) -> list[str]:
    """Warnings on the fitted numbers: a Hamaker constant outside the physical range of the
    analysis (:data:`afmforce.analysis.plausibility.HAMAKER_RANGE`, same wording)."""
    from ..analysis.plausibility import hamaker_warning

    e = params.get("hamaker")
    if e is None:
        return []
    note = hamaker_warning(float(e.value), f"with the model's radius {base.radius * 1e9:.3g} nm",
                           float(e.value) * float(base.radius))
    return [note] if note else []
