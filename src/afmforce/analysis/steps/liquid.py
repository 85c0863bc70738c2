"""The ``liquid`` step (its record :data:`LIQUID`): a colloid-probe curve measured in a liquid,
from the raw signal (docs/liquid.md).

Built on :mod:`afmforce.analysis.liquid` (P. Attard, arXiv 1212.3019, 2012; Vinogradova et al.
2001): the photodiode calibrated with a quadratic on the compliance region and the zero of
separation put on it without a human (:func:`~afmforce.analysis.liquid.calibrate_liquid_curve`), the
approach and retract far-field baselines and the lever drag from their gap and the speed
(:func:`~afmforce.analysis.liquid.drag_baselines`, the colloid's long-ranged drainage at that
distance subtracted), force against separation per run, the static and velocity-dependent forces at
equal separation (:func:`~afmforce.analysis.liquid.split_drainage`,
:func:`~afmforce.analysis.liquid.velocity_force_fit`), and a DLVO fit of the static force
(:func:`~afmforce.analysis.liquid.fit_dlvo`). It works on the raw signal (not the drift-corrected
one: the drift step would take the drag offset for drift) and, when it applies, replaces the
result's separation and force arrays by its own.

Skipped with the reason: no liquid medium given (or air), no spring constant or radius, no
compliance region; a curve without double-layer repulsion above the noise keeps the calibration and
the drag and is reported skipped for the DLVO fit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ...constants import MEDIA
from ...errors import AnalysisError
from .._step_helpers import _skip
from .._units import unit as _u
from ..liquid import (calibrate_liquid_curve, drag_baselines, fit_dlvo, retract_free_mask, split_drainage,
                      velocity_force_fit)
from ..options import LiquidOptions
from ..regions import run_indices
from ..registry import AnalysisStep, ResultField
from ..state import State

__all__ = ["LiquidResult", "liquid", "LIQUID"]

_EPS0 = 8.8541878128e-12
#: Slip length the DLVO fit is re-run with to see whether the drainage's unknown slip matters [m]
#: (hydrophilic surfaces: b ~ 0-2 nm; a shift beyond the standard errors warns).
SLIP_PROBE = 1e-9


@dataclass(frozen=True)
class LiquidResult:
    """The liquid analysis of one curve (SI; NaN where a part did not apply).

    Attributes
    ----------
    medium, geometry, double_layer : str  what was assumed
    viscosity : float  [Pa s]
    permittivity : float  relative [-]
    radius, spring_constant : float  [m], [N/m]
    velocity_approach, velocity_retract : float  run speeds [m/s]
    sensitivity : float  linear term a of ``d = a u + c u^2``, u = signal - v0 [m/signal]
    nonlinearity : float  quadratic term c [m/signal^2]
    nonlinearity_length : float  ``L = -a^2 / c``: the photodiode reads ``(d + d^2/L)/s`` [m]
    signal_zero : float  v0, the signal at zero force (mean of the two far lines) [signal]
    compliance_rms : float  rms residual of the quadratic compliance fit [m]
    compliance_points : int  samples of the compliance region [-]
    contact_position : float  piezo position of zero separation on the compliance line [m]
    drag_offset : float  approach minus retract far-field deflection [m]
    drag_separation : float  separation where the offset is measured [m]
    lever_drag : float  ``k offset / (v_app + v_ret)`` less the drainage there ``6 pi eta R_eff^2 / h`` [N s/m];
        NaN (undetermined, a warning says why) where its 95 % interval reaches 0 or below
    lever_drag_se : float  its standard error, from the far lines' scatter [N s/m]
    lever_drag_total : float  ``k offset / (v_app + v_ret)`` (lever drag plus that drainage) [N s/m]
    lever_drag_fit, drainage_coefficient : float  ``F_v = v (c + beta / h)`` fitted: c [N s/m], beta [N s]
        (NaN when undetermined: ``velocity_fit_undetermined`` says why)
    lever_drag_fit_se, drainage_coefficient_se : float  their standard errors [N s/m], [N s]
    velocity_fit_undetermined : str  why the velocity force cannot determine c and beta ("" when it does)
    drainage_coefficient_expected : float  ``6 pi eta R_eff^2`` (Reynolds) [N s]
    force_noise : float  rms of the static force far out [N]
    surface_potential, surface_potential_se : float  psi and its standard error [V]
    debye_length, debye_length_se : float  1/kappa [m]
    hamaker, hamaker_se : float  A [J]
    dlvo_redchi : float  reduced chi-square of the DLVO fit [-]
    dlvo_min_separation, dlvo_max_separation : float  range fitted [m]
    dlvo_points : int  [-]
    static_separation, static_force, velocity_force : ndarray  the split at equal separation [m], [N], [N]
    dlvo_separation, dlvo_force : ndarray  the approach's static force fitted (velocity force taken off) [m], [N]
    fit_force : ndarray  the DLVO model at ``dlvo_separation`` [N] (empty without a fit)
    """

    medium: str
    geometry: str
    double_layer: str
    viscosity: float = _u("Pa s")
    permittivity: float = _u("")
    radius: float = _u("m")
    spring_constant: float = _u("N/m")
    velocity_approach: float = _u("m/s")
    velocity_retract: float = _u("m/s")
    sensitivity: float = _u("m/{signal}")
    nonlinearity: float = _u("m/{signal}^2")
    nonlinearity_length: float = _u("m")
    signal_zero: float = _u("{signal}")
    compliance_rms: float = _u("m")
    compliance_points: int = _u("")
    contact_position: float = _u("m")
    drag_offset: float = _u("m")
    drag_separation: float = _u("m")
    lever_drag: float = _u("N s/m")
    lever_drag_total: float = _u("N s/m")
    lever_drag_se: float = _u("N s/m", math.nan)
    lever_drag_fit: float = _u("N s/m", math.nan)
    lever_drag_fit_se: float = _u("N s/m", math.nan)
    drainage_coefficient: float = _u("N s", math.nan)
    drainage_coefficient_se: float = _u("N s", math.nan)
    velocity_fit_undetermined: str = ""
    drainage_coefficient_expected: float = _u("N s", math.nan)
    force_noise: float = _u("N", math.nan)
    surface_potential: float = _u("V", math.nan)
    surface_potential_se: float = _u("V", math.nan)
    debye_length: float = _u("m", math.nan)
    debye_length_se: float = _u("m", math.nan)
    hamaker: float = _u("J", math.nan)
    hamaker_se: float = _u("J", math.nan)
    dlvo_redchi: float = _u("", math.nan)
    dlvo_min_separation: float = _u("m", math.nan)
    dlvo_max_separation: float = _u("m", math.nan)
    dlvo_points: int = _u("", 0)
    static_separation: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False, metadata={"unit": "m"})
    static_force: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False, metadata={"unit": "N"})
    velocity_force: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False, metadata={"unit": "N"})
    dlvo_separation: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False, metadata={"unit": "m"})
    dlvo_force: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False, metadata={"unit": "N"})
    fit_force: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False, metadata={"unit": "N"})


def _robust_std(x: np.ndarray) -> float:
    x = x[np.isfinite(x)]
    return float(1.4826 * np.median(np.abs(x - np.median(x)))) if x.size >= 5 else math.nan


def liquid(st: State, o: LiquidOptions) -> State:
    """Analyse a colloid-probe curve in a liquid (module docstring); skip it with the reason elsewhere."""
    from ...forces import effective_radius

    if o.medium in ("none", "air"):
        why = ("no liquid medium given (`medium`, e.g. water)" if o.medium == "none"
               else "measured in air: no double layer, and drainage and lever drag are negligible")
        return _skip(st, "liquid", why)
    md = st.metadata
    eta = o.viscosity if o.viscosity is not None else MEDIA[o.medium]["viscosity"]
    eps = o.permittivity if o.permittivity is not None else MEDIA[o.medium]["permittivity"]
    k = st.spring_constant if math.isfinite(st.spring_constant) else float(
        st.probe.value("spring_constant", md) or math.nan)
    radius = float(st.probe.value("radius", md) or math.nan)
    if not math.isfinite(k) or not math.isfinite(radius):
        return _skip(st, "liquid", "needs the spring constant and the probe radius (`spring_constant`, `radius`)")
    seg = np.asarray(st.curve.segment)
    ia, ir = run_indices(seg, 0), run_indices(seg, 1)
    z = np.asarray(st.curve.position("auto"), float)
    far = float(z[ia].min() + o.far_fraction * np.ptp(z[ia]))
    sig = np.asarray(st.curve.deflection_signal, float)
    try:   # the retract's far baseline: only after its pull-off (a lever in contact is no baseline)
        free = retract_free_mask(z[ia], sig[ia], z[ir], sig[ir], far)
    except AnalysisError as exc:
        return _skip(st, "liquid", str(exc))
    try:
        cal_curve = calibrate_liquid_curve(st.curve, far=far)
    except AnalysisError as exc:
        return _skip(st, "liquid", f"no liquid calibration: {exc}")
    from ..liquid import ComplianceCalibration

    cal = ComplianceCalibration(**cal_curve.metadata["liquid_calibration"])
    d = cal.deflection(sig)
    h = cal.separation(z, sig, o.contact_separation)
    va, vr = st.velocity(ia), st.velocity(ir)
    try:
        db = drag_baselines(z[ia], d[ia], z[ir][free], d[ir][free], far, spring_constant=k, v_app=va, v_ret=vr)
    except AnalysisError as exc:
        return _skip(st, "liquid", str(exc))
    stuck = [w for w, (_, slope) in (("approach", db.approach), ("retract after its pull-off", db.retract))
             if abs(slope) > 0.3]
    if stuck:  # a free lever barely follows the piezo; in contact d ~ z
        return _skip(st, "liquid", f"the {' and the '.join(stuck)} follows the piezo over the far region "
                     f"(baseline slope above 0.3: in contact or jumping in there): no drag baseline; start "
                     "the approach further out")
    base = 0.5 * (db.approach[0] + db.retract[0] + (db.approach[1] + db.retract[1]) * z)  # zero static force
    force = k * (d - base)
    r_eff = float(effective_radius(radius, o.geometry))
    beta0 = 6.0 * math.pi * eta * r_eff ** 2
    zm = 0.5 * (max(z[ia][z[ia] < far].min(), z[ir][free & (z[ir] < far)].min()) + far)
    h_drag = cal.z_contact - zm + o.contact_separation
    hs, fs, fv = split_drainage(h[ia], force[ia], h[ir][free], force[ir][free])
    h_far = cal.z_contact - far + o.contact_separation
    noise = _robust_std(fs[hs > h_far])
    vmean = 0.5 * (va + vr)
    vf = velocity_force_fit(hs, fv, vmean, max(10 * o.min_separation, 0.25 * h_far),
                            float(hs.max()) if hs.size else math.nan)
    drag = drag_estimate = db.lever_drag - beta0 / h_drag
    warn = []
    if vf.undetermined:
        warn.append(f"liquid: lever drag and drainage coefficient of the velocity force undetermined: {vf.undetermined}")
    if not drag - 1.96 * db.lever_drag_se > 0:
        # a drag the offset does not resolve (too slow, too noisy) is no result; a negative one is impossible
        warn.append(f"liquid: lever drag undetermined: {drag:.3g} +- {db.lever_drag_se:.2g} N s/m (the drag "
                    f"offset {db.gap * 1e9:.3g} +- {db.gap_se * 1e9:.2g} nm, the Reynolds drainage at "
                    f"{h_drag * 1e9:.3g} nm taken off) reaches 0 at 95 %: measure faster or further out")
        drag = math.nan
    common = dict(medium=o.medium, geometry=o.geometry, double_layer=o.double_layer, viscosity=eta,
                  permittivity=eps, radius=radius, spring_constant=k, velocity_approach=va, velocity_retract=vr,
                  sensitivity=cal.a, nonlinearity=cal.c,
                  nonlinearity_length=-cal.a ** 2 / cal.c if cal.c != 0 else math.inf, signal_zero=cal.v0,
                  compliance_rms=cal.rms, compliance_points=cal.n, contact_position=-cal.z_contact,
                  drag_offset=db.gap, drag_separation=h_drag, lever_drag=drag,
                  lever_drag_total=db.lever_drag, lever_drag_se=db.lever_drag_se, lever_drag_fit=vf.lever_drag,
                  lever_drag_fit_se=vf.lever_drag_se, drainage_coefficient=vf.drainage_coefficient,
                  drainage_coefficient_se=vf.drainage_coefficient_se, velocity_fit_undetermined=vf.undetermined,
                  drainage_coefficient_expected=beta0, force_noise=noise,
                  static_separation=hs, static_force=fs, velocity_force=fv)
    st = st.update(separation=h, force=force, deflection=d - base)
    # the approach's static force: the velocity force (lever drag and Reynolds drainage) taken off; the
    # retract jumps out from contact, so near the surface only the approach has the double layer
    ha, fa = h[ia], force[ia] - va * (drag_estimate + beta0 / np.maximum(h[ia], 1e-10))
    # contact: the first sample inside min_separation (a lever the drainage damps creeps in without a jump,
    # and the steepest step was then a noise step far out: the fit had nothing left, "no double layer")
    inside = np.flatnonzero(ha < o.min_separation)
    jump = int(inside[0]) if inside.size else int(np.argmin(np.diff(ha)))
    why = _no_double_layer(ha[:jump], fa[:jump], noise * math.sqrt(2.0), o, h_far)
    if isinstance(why, str):
        return _skip(st.update(warn=warn) if warn else st, "liquid", why, LiquidResult(**common))
    lam0, f0, hi = why  # weak overlap at h = 0: F0 = 4 pi R_eff eps eps0 kappa psi^2
    psi0 = float(np.clip(math.sqrt(f0 * lam0 / (4 * math.pi * r_eff * eps * _EPS0)), 0.005, 0.2))
    sel = (np.arange(ha.size) < jump) & (ha >= o.min_separation) & (ha <= hi)
    sign = -1.0 if o.potential_sign == "negative" else 1.0
    fit = fit_dlvo(ha[sel], fa[sel], radius, sigma=noise * math.sqrt(2.0), geometry=o.geometry,
                   law=o.double_layer, permittivity=eps, z0=o.z0, guess=(sign * psi0, lam0, 1e-20))
    if fit.note:   # a parameter the profile likelihood leaves open, or wider than its error says
        warn.append(f"liquid: DLVO fit: {fit.note}")
    # the drainage taken off assumes no slip; a slip length b lowers it by about 2b/h: refitted with b = 1 nm,
    # a shift beyond the standard errors is a systematic the errors do not hold (README's run at 10 um/s:
    # 1/kappa 10.3 +- 0.12 nm for 9.62; at 1 um/s 9.69 +- 0.08)
    alt = fit_dlvo(ha[sel], (force[ia] - va * drag_estimate)[sel], radius, sigma=noise * math.sqrt(2.0),
                   geometry=o.geometry, law=o.double_layer, permittivity=eps, z0=o.z0,
                   guess=(fit.surface_potential, fit.debye_length, fit.hamaker) if all(
                       math.isfinite(x) for x in (fit.surface_potential, fit.debye_length, fit.hamaker))
                   else (sign * psi0, lam0, 1e-20), h_dot=-va, viscosity=eta, slip_length=SLIP_PROBE)
    moved = [f"{n} {getattr(fit, n):.3g} -> {getattr(alt, n):.3g}"
             for n in ("surface_potential", "debye_length", "hamaker")
             if abs(getattr(alt, n) - getattr(fit, n)) > fit.stderr[n]]
    if moved:
        warn.append(f"liquid: DLVO fit: the Reynolds drainage taken off the approach assumes no slip; with a slip "
                    f"length of {SLIP_PROBE * 1e9:g} nm the fit moves beyond its standard errors ({', '.join(moved)}"
                    "): the values carry that systematic error; record the approach slower or fit the slip "
                    "with `afmforce fit`")
    from ...forces import double_layer_force, paper_radius, vdw_force

    hf = ha[sel]
    model = np.asarray(vdw_force(hf, float(paper_radius(radius, o.geometry)), fit.hamaker, o.z0)) + np.asarray(
        double_layer_force(hf, radius, fit.surface_potential, fit.debye_length, None, eps, o.double_layer,
                           o.geometry))
    res = LiquidResult(**common, surface_potential=fit.surface_potential,
                       surface_potential_se=fit.stderr["surface_potential"], debye_length=fit.debye_length,
                       debye_length_se=fit.stderr["debye_length"], hamaker=fit.hamaker,
                       hamaker_se=fit.stderr["hamaker"], dlvo_redchi=fit.redchi,
                       dlvo_min_separation=o.min_separation, dlvo_max_separation=hi, dlvo_points=int(sel.sum()),
                       dlvo_separation=hf, dlvo_force=fa[sel], fit_force=model)
    return st.update("liquid", res, warn=warn)


def _no_double_layer(hs, fs, noise, o: LiquidOptions, h_far: float):
    """The reason there is nothing to fit, or (Debye length, force at contact, upper end of the fit)."""
    if not math.isfinite(noise) or noise <= 0:
        return "no far-field static force to measure the noise on (drive the approach further out)"
    up = (hs >= o.min_separation) & (hs < h_far) & (fs > o.nsigma * noise)
    if up.sum() < 5:
        return (f"no double-layer repulsion above {o.nsigma:g}x the noise ({noise * 1e12:.3g} pN) before "
                "contact: nothing for a DLVO fit")
    slope, icpt = np.polyfit(hs[up], np.log(fs[up]), 1)
    if not slope < 0:
        return "the repulsion before contact does not decay with separation: no double layer to fit"
    lam0 = float(np.clip(-1.0 / slope, 0.3e-9, 1e-6))
    hi = o.max_separation if o.max_separation is not None else min(h_far, 10.0 * lam0)
    return lam0, float(np.exp(icpt)), hi


def _liquid_fields(st: State) -> dict:
    q = st.details["liquid"]
    return dict(drag_offset=q.drag_offset, lever_drag=q.lever_drag, surface_potential=q.surface_potential,
                surface_potential_se=q.surface_potential_se, debye_length=q.debye_length,
                debye_length_se=q.debye_length_se, dlvo_hamaker=q.hamaker, dlvo_hamaker_se=q.hamaker_se)


LIQUID = AnalysisStep(
    "liquid", "Colloid probe in a liquid: quadratic compliance, lever drag, drainage vs static force, DLVO fit",
    liquid, LiquidOptions, reference="Attard, arXiv 1212.3019 (2012); Vinogradova et al., RSI 72, 2330 (2001)",
    fields=(ResultField("drag_offset", "m", "drag offset (approach - retract far out; liquid)", summary=True,
                        column=True),
            ResultField("lever_drag", "N s/m", "lever drag (liquid)", summary=True, column=True),
            ResultField("surface_potential", "V", "surface potential (DLVO fit)", summary=True, column=True),
            ResultField("surface_potential_se", "V", "standard error of the surface potential", column=True),
            ResultField("debye_length", "m", "Debye length (DLVO fit)", summary=True, column=True),
            ResultField("debye_length_se", "m", "standard error of the Debye length", column=True),
            ResultField("dlvo_hamaker", "J", "Hamaker constant (DLVO fit)", summary=True, column=True),
            ResultField("dlvo_hamaker_se", "J", "standard error of the DLVO Hamaker constant", column=True)),
    collect=_liquid_fields)
