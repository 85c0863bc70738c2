"""The indentation step: Young's modulus (and work of adhesion) of a soft contact.

The laws and the fit are :mod:`afmforce.contact` (docs/contact.md); this step takes the
calibrated run (position ``z`` [m], deflection [m], force [N]), forms the tip depth
``u = z - deflection`` and fits the chosen model with the contact point, the modulus and the
force baseline together, starting near the ``kind`` step's soft contact point. The sample's Poisson ratio is the user's,
else the file's own (metadata ``poisson``), else 0.5; the result says which (``poisson_source``). Hard contacts
(a constant-compliance line: the tip does not indent) are skipped with the reason, as are
curves without a spring constant or without the geometry the model needs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..contact.fit import fit_fixed_baseline, fit_indentation, model_force
from ..contact.registry import indentation_model
from ..errors import AnalysisError, ParameterError
from ..io.deflection import signal_factor
from ._median import median
from ._numeric import mad_sigma
from ._step_helpers import _kind, _skip
from ._units import unit as _u
from .options import DEFAULT_POISSON, IndentationOptions, ProbeCalibration
from .plausibility import impossible_modulus
from .state import State

__all__ = ["IndentationResult", "indentation", "fast_modulus", "tip_geometry", "fit_warnings", "poisson_warnings"]


@dataclass(frozen=True)
class IndentationResult:
    """The indentation fit of one curve (SI).

    Attributes
    ----------
    model : str  the indentation model's key
    run : str  ``approach`` or ``retract``
    youngs_modulus, youngs_modulus_se : float  E and its standard error [Pa]
    youngs_modulus_low, youngs_modulus_high : float  95 % interval [Pa]
    contact_point, contact_point_se : float  piezo position z at contact, and its standard error [m]
    contact_depth : float  tip depth u = z - deflection at contact [m]
    baseline : float  fitted force before contact [N]
    work_of_adhesion, work_of_adhesion_se : float  w (adhesive models) [J/m^2]
    max_indentation : float  deepest indentation fitted [m]
    max_force : float  force there above the baseline [N]
    n_points, n_contact : int  points fitted, in contact [-]
    rms : float  rms residual [N]
    tip_radius, half_angle, poisson : float  geometry used [m], [rad], [-] (NaN: not used)
    poisson_source : str  where the Poisson ratio came from: ``user`` (given), ``file`` (the file's
        own, metadata ``poisson``) or ``default`` (0.5, neither gave one)
    indentation, fit_force, residuals : ndarray  per fitted point: indentation [m], model force [N],
        data minus model [N]
    warnings : tuple of str  the model's validity check
    """

    model: str
    run: str
    youngs_modulus: float = _u("Pa")
    youngs_modulus_se: float = _u("Pa")
    youngs_modulus_low: float = _u("Pa")
    youngs_modulus_high: float = _u("Pa")
    contact_point: float = _u("m")
    contact_point_se: float = _u("m")
    contact_depth: float = _u("m")
    baseline: float = _u("N")
    work_of_adhesion: float = _u("J/m^2")
    work_of_adhesion_se: float = _u("J/m^2")
    max_indentation: float = _u("m")
    max_force: float = _u("N")
    n_points: int = _u("")
    n_contact: int = _u("")
    rms: float = _u("N")
    tip_radius: float = _u("m")
    half_angle: float = _u("rad")
    poisson: float = _u("")
    poisson_source: str = "default"
    indentation: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False, metadata={"unit": "m"})
    fit_force: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False, metadata={"unit": "N"})
    residuals: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False, metadata={"unit": "N"})
    warnings: tuple[str, ...] = ()


def indentation(st: State, o: IndentationOptions) -> State:
    """Fit the indentation model ``o.model`` to the approach (or retract) of a soft contact."""
    if _kind(st) != "soft":
        return _skip(st, "indentation", "hard contact: the tip does not indent the sample (a constant-compliance "
                     "line), so there is no modulus to fit")
    if st.force is None or not math.isfinite(st.spring_constant):
        return _skip(st, "indentation", "no spring constant (give `spring_constant`): no force to fit")
    m = indentation_model(o.model)
    radius, geom = tip_geometry(o, st.probe, st.metadata)
    missing = [g for g in m.geometry if geom.get(g) is None]
    if missing:
        keys = {"radius": "tip_radius", "half_angle": "half_angle", "thickness": "indentation.thickness"}
        return _skip(st, "indentation", f"the {m.name} model needs the " + " and the ".join(
            f"{g.replace('_', ' ')} (`{keys[g]}`)" for g in missing))
    regions = st.approach if o.run == "approach" else st.retract
    idx = regions.index[~regions.saturated]   # a clipped deflection is no force: its samples are left out
    if regions.cut:   # a level step of the free baseline (a glitch): the samples before it are off the zero
        idx = idx[idx >= regions.index[regions.cut]]
    if o.run == "retract":
        idx = idx[::-1]  # the retract read backwards: into the sample, as the fit expects
    z, d, f = st.z[idx], st.deflection[idx], st.force[idx]
    u = z - d
    guess = None
    cp = st.details.get("contact_point")
    if cp is not None and math.isfinite(cp.position):
        guess = cp.position - cp.deflection
    nu, nu_source = o.sample_poisson(st.metadata)
    try:
        fit = fit_indentation(u, f, o.model, {k: v for k, v in geom.items() if v is not None}, nu=nu,
                              weight_width=o.weight_width, contact_guess=guess, thickness=o.thickness,
                              max_indentation=o.max_indentation if o.max_indentation is not None else math.inf,
                              transition=o.transition, branch=o.run, contact_point=o.contact_point)
    except (AnalysisError, ParameterError) as exc:
        return _skip(st, "indentation", f"no modulus: {exc}")
    impossible = impossible_modulus(fit.youngs_modulus)
    if impossible:
        return _skip(st, "indentation", impossible)
    res = _result(fit, u, o, geom, radius, st.spring_constant, nu, nu_source)
    warn = fit_warnings(o, fit)
    if o.run == "approach" and o.contact_point is None:
        inside = _free_part_in_contact(st, res, o, {k: v for k, v in geom.items() if v is not None}, nu)
        res, note = _baseline_systematic(st, res, idx, z, d, lambda uu, ff: fit_indentation(
            uu, ff, o.model, {k: v for k, v in geom.items() if v is not None}, nu=nu, weight_width=o.weight_width,
            contact_guess=guess, thickness=o.thickness,
            max_indentation=o.max_indentation if o.max_indentation is not None else math.inf,
            transition=o.transition, branch=o.run), inside)
        if note:
            warn.append(note)
    if o.run == "approach" and o.contact_point is None and m.linear:
        res, note = _baseline_offset(st, res, fit, u, f, lambda uu, ff, b: fit_fixed_baseline(
            uu, ff, o.model, {k: v for k, v in geom.items() if v is not None}, b, nu=nu,
            weight_width=o.weight_width, contact_guess=fit.contact))
        if note:
            warn.append(note)
    warn += poisson_warnings(nu, nu_source)
    return st.update("indentation", res, warn=warn)


def fit_warnings(o: IndentationOptions, fit) -> list[str]:
    """The indentation fit's own warnings as the per-curve table words them (``indentation (model): ...``):
    one wording for ``analyze`` and the fast map (``--fast-map``'s ``warnings`` column)."""
    return [f"indentation ({o.model}): {w}" for w in fit.warnings]


def poisson_warnings(nu: float, nu_source: str) -> list[str]:
    """The note that E is for the file's Poisson ratio ``nu`` [-] (none when it is the default or the user's)."""
    if nu_source == "file" and nu != DEFAULT_POISSON:     # the user sees which ratio E is for
        return [f"indentation: the sample's Poisson ratio {nu:g} is the file's (not {DEFAULT_POISSON:g}; E "
                "scales as 1 - nu^2): give `poisson` to change it"]
    return []


#: The drift line's "free" part holds the fitted contact when the model's force on its samples past the fitted
#: contact point reaches this many force-noise sigmas: the line was then partly fitted on the contact and, carried
#: on in time, takes some of it away (a contact 10 % of the ramp inside the record: the model's force there 13
#: sigma, E 4535 [4529, 4540] Pa for 5 kPa). On the real soft curves (tests/data, the shared files) no free
#: sample lies past the fitted contact point.
MAX_FREE_CONTACT_NSIGMA = 3.0


def _free_part_in_contact(st: State, res: IndentationResult, o: IndentationOptions, geom: dict,
                          nu: float) -> tuple[float, float] | None:
    """The share of the drift line's free samples past the fitted contact point [-] and the model's largest
    force on them [force-noise sigmas], when that force reaches :data:`MAX_FREE_CONTACT_NSIGMA`; else None.

    The drift step fits its line on the approach's zero-force region (the far part of the two lines' split);
    on a contact that starts just inside the record that region reaches into the contact, the line climbs with
    it (by less than :data:`~afmforce.analysis.steps.drift.MAX_BASELINE_CLIMB` of the rise, so the drift step
    does not warn) and the modulus comes out low with an interval of its noise alone.
    """
    app = st.approach
    if app is None or not math.isfinite(res.contact_depth):
        return None
    free = app.index[app.zero_force & ~app.saturated]
    if free.size == 0:
        return None
    delta = st.z[free] - st.deflection[free] - res.contact_depth
    past = delta > 0
    sigma = abs(st.noise * st.factor) * st.spring_constant
    if not (past.any() and sigma > 0):
        return None
    w = 0.0 if math.isnan(res.work_of_adhesion) else res.work_of_adhesion
    f = np.asarray(model_force(o.model, delta[past], res.youngs_modulus, geom, nu, w, o.transition, o.run))
    top = float(np.max(f)) / sigma if f.size else 0.0
    if not top >= MAX_FREE_CONTACT_NSIGMA:
        return None
    return float(past.mean()), top


def _baseline_systematic(st: State, res: IndentationResult, idx: np.ndarray, z: np.ndarray, d: np.ndarray,
                         refit, inside: tuple[float, float] | None = None) -> tuple[IndentationResult, str | None]:
    """The modulus's interval widened to the fit without the drift slope, when the drift line climbs with the
    contact (the drift step's ``baseline_climb``: its "free" part is likely a slow contact already), or when the
    drift line's free part holds the fitted contact (``inside``: :func:`_free_part_in_contact`).

    The data cannot tell a drift line from a contact that starts before the run does: the line fitted before
    contact and carried on in time (the fit ``res``) and a constant baseline (the slope put back: the fit
    ``refit`` gives) are both read from the same samples. Neither is preferred, so the 95 % interval is widened
    to cover both fits' intervals and the standard errors add half their difference in quadrature (a systematic
    uncertainty, said in the warning); E stays the drift-corrected fit's. Where the fit without the slope has no
    modulus, E is undetermined ([0, open]). On a curve whose drift line does not climb nothing changes.
    """
    dr = st.details.get("drift")
    climb = getattr(dr, "baseline_climb", math.nan)
    if (not math.isfinite(climb) and inside is None) or st.approach is None or not math.isfinite(dr.slope_approach):
        return res, None
    t0 = st.time[st.approach.index[0]]
    d2 = d + dr.slope_approach * (st.time[idx] - t0) * st.factor   # the deflection [m] the drift slope took away
    k = st.spring_constant
    if math.isfinite(climb):
        what = (f"the drift line climbs by {climb:.0%} of the approach's rise after its free part (a slow contact "
                "already?): the modulus depends on the baseline")
    else:
        what = (f"the fitted contact point lies inside the approach's free part the drift line was fitted on "
                f"({inside[0]:.0%} of its samples past it, the model's force there up to {inside[1]:.3g} noise "
                "sigmas): the line climbs with the contact and takes some of it away, so the modulus (with the "
                "drift line) is biased low and depends on the baseline")
    try:
        alt = refit(z - d2, d2 * k)
        bad = impossible_modulus(alt.youngs_modulus)
    except (AnalysisError, ParameterError) as exc:
        alt, bad = None, str(exc)
    if alt is None or bad:
        return replace(res, youngs_modulus_low=0.0, youngs_modulus_high=math.nan), (
            f"indentation: {what}; without the drift slope (a constant baseline) no modulus fits ({bad}): E is "
            "undetermined (interval [0, open]); record the approach from further away")
    E, E2 = res.youngs_modulus, alt.youngs_modulus
    z2 = alt.contact + alt.baseline / k
    low, high = min(res.youngs_modulus_low, alt.youngs_modulus_low), max(res.youngs_modulus_high,
                                                                        alt.youngs_modulus_high)
    if math.isnan(res.youngs_modulus_high) or math.isnan(alt.youngs_modulus_high):
        high = math.nan
    new = replace(res, youngs_modulus_low=low, youngs_modulus_high=high,
                  youngs_modulus_se=math.hypot(res.youngs_modulus_se, (E - E2) / 2),
                  contact_point_se=math.hypot(res.contact_point_se, (res.contact_point - z2) / 2))
    span = f"[{low:.4g}, {high:.4g}] Pa" if math.isfinite(high) else f"[{low:.4g} Pa, open]"
    return new, (f"indentation: {what}: with the drift line E = {E:.4g} Pa, without its slope (a constant "
                 f"baseline) E = {E2:.4g} Pa (contact point {(z2 - res.contact_point) * 1e9:+.4g} nm away); the "
                 f"95 % interval {span} covers both fits (a systematic uncertainty of the baseline, its standard "
                 "error adds half their difference); record the approach from further away")


#: The free fit's force baseline may lie at most this many noise standard deviations (of the drift-corrected
#: approach's free samples near the contact) from their measured level. On a curve the contact law describes,
#: the fitted baseline is the mean of hundreds of free samples: 30 virtual Hertz curves (5 moduli and radii, 6
#: seeds) stay within 0.24 sigma, the 44 nanite-reference fits and the 16 HeLa curves within 3.2 sigma, the
#: PLSys Catalyst curves agreeing with nanite within 4.2 (cr00043), the 100 Egel force-volume curves within 5.2
#: (curvature near the contact, not noise): 8 leaves 1.5 x the largest. A fit that needs its baseline further away (the PLSys Catalyst chromosome
#: curve cr00041: -5.47 nN, 395 sigma) bends the baseline to make a non-Hertzian contact look like the law.
MAX_BASELINE_OFFSET_NSIGMA = 8.0

#: When the baseline is off (:data:`MAX_BASELINE_OFFSET_NSIGMA`), the fit with the baseline held at the measured
#: level and the free fit may give moduli at most this factor apart for the modulus to be reported with an
#: interval covering both; further apart, the law does not describe the curve well enough to give one number
#: and E is undetermined ([0, open]).
MAX_FIXED_BASELINE_FACTOR = 2.0


def measured_baseline(st: State) -> tuple[float, float] | None:
    """The measured free-baseline force [N] and its noise standard deviation [N]: the median and the robust
    (MAD) spread of the drift-corrected approach's free samples nearest the contact (the last third of the
    free part, at least 10 samples); None where the approach has fewer than 10 free samples or no spread."""
    app = st.approach
    if app is None or st.force is None:
        return None
    free = app.index[app.zero_force & ~app.saturated]
    if free.size < 10:
        return None
    near = np.sort(free)[-max(10, free.size // 3):]
    f = st.force[near]
    f = f[np.isfinite(f)]
    if f.size < 10:
        return None
    level = float(median(f))
    sigma = float(mad_sigma(f))
    if not sigma > 0:
        sigma = float(np.std(f))
    return (level, sigma) if sigma > 0 else None


def _baseline_offset(st: State, res: IndentationResult, fit, u: np.ndarray, f: np.ndarray,
                     refit) -> tuple[IndentationResult, str | None]:
    """The modulus's interval widened, or E undetermined, when the fit's force baseline lies more than
    :data:`MAX_BASELINE_OFFSET_NSIGMA` noise sigmas from the measured free baseline (:func:`measured_baseline`):
    the contact law does not describe the curve (docs/contact.md, "The baseline check").

    The fit with the baseline held at the measured level (``refit(u, f, level)``, on the same samples: the fit
    range) is the other reading of the same data. Within :data:`MAX_FIXED_BASELINE_FACTOR` of each other, the
    95 % interval covers both fits' intervals and the standard error adds half their difference in quadrature
    (E stays the free fit's); further apart, or no modulus with the baseline held: E is undetermined."""
    meas = measured_baseline(st)
    if meas is None:
        return res, None
    level, sigma = meas
    off = fit.baseline - level
    nsig = abs(off) / sigma
    if not nsig > MAX_BASELINE_OFFSET_NSIGMA:
        return res, None
    keep = fit.fitted   # the free fit's samples (its fit range)
    what = (f"the {res.model} law does not describe the curve: the fit needed a force baseline {nsig:.3g} noise "
            f"sigmas ({off * 1e9:+.3g} nN) away from the measured free baseline")
    E = res.youngs_modulus
    try:
        alt = refit(u[keep], f[keep], level)
    except (AnalysisError, ParameterError) as exc:
        return replace(res, youngs_modulus_low=0.0, youngs_modulus_high=math.nan), (
            f"indentation: {what}; with the baseline held there no modulus fits ({exc}): E is undetermined "
            "(interval [0, open])")
    E2 = alt.youngs_modulus
    ratio = max(E, E2) / min(E, E2)
    if ratio > MAX_FIXED_BASELINE_FACTOR:
        return replace(res, youngs_modulus_low=0.0, youngs_modulus_high=math.nan), (
            f"indentation: {what}; with the baseline held there E = {E2:.4g} Pa, {ratio:.3g} x the free fit's "
            f"{E:.4g} Pa (more than {MAX_FIXED_BASELINE_FACTOR:g} x): E is undetermined (interval [0, open]); "
            "fit another law or a smaller range (indentation.max_indentation)")
    low = min(res.youngs_modulus_low, alt.youngs_modulus_low)
    high = max(res.youngs_modulus_high, alt.youngs_modulus_high)
    if math.isnan(res.youngs_modulus_high) or math.isnan(alt.youngs_modulus_high):
        high = math.nan
    new = replace(res, youngs_modulus_low=low, youngs_modulus_high=high,
                  youngs_modulus_se=math.hypot(res.youngs_modulus_se, (E - E2) / 2))
    span = f"[{low:.4g}, {high:.4g}] Pa" if math.isfinite(high) else f"[{low:.4g} Pa, open]"
    return new, (f"indentation: {what}; with the baseline held there E = {E2:.4g} Pa: the 95 % interval {span} "
                 "covers both fits (a systematic uncertainty of the law, its standard error adds half their "
                 "difference); fit another law or a smaller range (indentation.max_indentation)")


def _result(fit, u: np.ndarray, o: IndentationOptions, geom: dict, radius, k: float, nu: float,
            nu_source: str) -> IndentationResult:
    # z at contact: where u = c, i.e. z = c + d with d the deflection of the fitted baseline force
    z_c = fit.contact + fit.baseline / k
    delta = u[fit.fitted] - fit.contact
    w = 0.0 if math.isnan(fit.work_of_adhesion) else fit.work_of_adhesion
    model_f = model_force(o.model, delta, fit.youngs_modulus, geom, nu, w, o.transition, o.run)
    return IndentationResult(
        model=o.model, run=o.run, youngs_modulus=fit.youngs_modulus, youngs_modulus_se=fit.youngs_modulus_se,
        youngs_modulus_low=fit.youngs_modulus_low, youngs_modulus_high=fit.youngs_modulus_high,
        contact_point=z_c, contact_point_se=fit.contact_se, contact_depth=fit.contact, baseline=fit.baseline,
        work_of_adhesion=fit.work_of_adhesion, work_of_adhesion_se=fit.work_of_adhesion_se,
        max_indentation=fit.max_indentation, max_force=fit.max_force, n_points=fit.n_points,
        n_contact=fit.n_contact, rms=fit.rms, tip_radius=float(radius) if radius is not None else math.nan,
        half_angle=float(o.half_angle) if o.half_angle is not None else math.nan, poisson=nu,
        poisson_source=nu_source,
        indentation=delta, fit_force=np.asarray(model_f + fit.baseline), residuals=fit.residuals,
        warnings=fit.warnings)


def tip_geometry(o: IndentationOptions, probe: ProbeCalibration, metadata) -> tuple[Any, dict[str, Any]]:
    """The tip's radius [m] (``o.tip_radius``, else the probe's ``radius``, else the file's) and the model's
    geometry (radius [m], half-angle [rad], layer thickness [m], bonded): one place for ``analyze``'s
    indentation step and :func:`fast_modulus` (``--fast-map``)."""
    radius = o.tip_radius if o.tip_radius is not None else probe.value("radius", metadata)
    return radius, {"radius": radius, "half_angle": o.half_angle, "thickness": o.thickness, "bonded": bool(o.bonded)}


def fast_modulus(curve, options: IndentationOptions | None = None,
                 probe: ProbeCalibration | None = None, channel: str = "auto") -> IndentationResult:
    """The modulus of one curve without the pipeline's other steps (a QI pixel's fast path).

    What nanite's preprocessing and fit do: the deflection [m] and force [N] from the file's (or
    the probe's) sensitivity and spring constant, the tip depth, and :func:`fit_indentation` with
    the contact point, E and the force baseline together. No smoothing, drift line, contact kind
    or hard-contact check: :func:`~afmforce.analysis.pipeline.analyze` with the ``indentation``
    step does those (and gives the same modulus on a curve without drift).

    ``channel``: the position channel (``"auto"``, ``"measured"``, ``"nominal"``), as ``analyze``'s.

    Raises
    ------
    AnalysisError
        No approach (retract) samples, no spring constant or sensitivity, the channel asked for is not
        recorded, or the fit fails.
    ParameterError
        The model's geometry is missing.
    """
    from ..io.given import apply_given

    o = options if options is not None else IndentationOptions()
    p = probe if probe is not None else ProbeCalibration()
    curve = apply_given(curve, p)      # the user's calibration over the file's, as analyze does
    md = curve.metadata
    seg = np.asarray(curve.segment)
    idx = np.flatnonzero(seg == (0 if o.run == "approach" else 1))
    if idx.size < 8:
        raise AnalysisError(f"the curve has {idx.size} {o.run} samples: nothing to fit")
    if o.run == "retract":
        idx = idx[::-1]
    z = curve.position(channel)[idx]
    sig = np.asarray(curve.deflection_signal, dtype=float)[idx]
    k = p.value("spring_constant", md)
    if not k:
        raise AnalysisError("no spring constant (give `spring_constant`): no force to fit")
    unit = curve.deflection_unit
    sens = p.value("sensitivity", md) if unit == "V" else None
    if unit == "V" and not sens:
        raise AnalysisError("the deflection is in volts and no sensitivity is known (give `sensitivity`)")
    d = sig * signal_factor(unit, sens, k)  # the deflection [m]
    radius, geom = tip_geometry(o, p, md)
    u = z - d
    nu, nu_source = o.sample_poisson(md)
    fit = fit_indentation(u, d * float(k), o.model, {g: v for g, v in geom.items() if v is not None},
                          nu=nu, weight_width=o.weight_width, thickness=o.thickness,
                          max_indentation=o.max_indentation if o.max_indentation is not None else math.inf,
                          transition=o.transition, branch=o.run, contact_point=o.contact_point)
    return _result(fit, u, o, geom, radius, float(k), nu, nu_source)
