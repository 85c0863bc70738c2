"""Pipeline steps that read physics off a calibrated curve: jumps, adhesion, surface energy,
van der Waals fit, oscillations, friction signature (each declared by its record at the end;
the dynamic diagnosis is :mod:`.diagnosis_step`)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..constants import Z0
from ..errors import AnalysisError
from . import compliance as cc
from ._numeric import robust_line
from .contact_point import curvature_ratio
from .jumps import JumpIn, Jumps, PullOff, adhesion, find_jump_in, find_pull_off, jump_warnings, pull_off_estimate
from .options import (AdhesionOptions, FrictionOptions, JumpsOptions, OscillationOptions, SurfaceEnergyOptions,
                      VdwOptions)
from .oscillation import OscillationResult, both_runs, find_peak
from .plausibility import IMPOSSIBLE
from .registry import AnalysisStep, ResultField
from .state import State
from .unbinding import retract_adhesion
from .vdw import fit_vdw

from ._step_helpers import _kind, _skip

__all__ = ["jumps", "adhesion_step", "surface_energy", "vdw", "oscillation", "friction", "JUMPS", "ADHESION",
           "SURFACE_ENERGY", "VDW", "OSCILLATION", "FRICTION"]


def jumps(st: State, o: JumpsOptions) -> State:
    """Jump into contact and pull-off, near each run's contact split.

    Warns when the first contact sample lies more than ``o.onset_tolerance`` (or
    ``o.nsigma`` noise) off the compliance line the zero of separation was put on.
    """
    nsigma, window = o.nsigma, int(o.window)
    if _kind(st) == "soft":
        nan = math.nan
        return _skip(st, "jumps", "soft contact: no jump into contact and no single pull-off jump (see adhesion)",
                     Jumps(JumpIn(False, -1, nan, nan, nan, nan, nan, nan, 0.0),
                           PullOff(False, -1, nan, nan, nan, nan, 0.0, False)))
    noise = abs(st.noise * st.factor)
    if not noise > 0:  # a quiet signal on a coarse ADC: its noise is the quantisation's, not zero
        steps = np.abs(np.diff(np.asarray(st.curve.deflection_signal, float)))  # as recorded: ADC steps
        steps = steps[steps > 0]
        noise = float(steps.min()) * abs(st.factor) / math.sqrt(12.0) if steps.size else noise
    k = st.spring_constant
    ji = find_jump_in(st.deflection, st.separation, st.position, st.approach, noise, k, nsigma, window)
    ret = st.retract
    clipped = not ret.has_compliance and bool(ret.contact.any())  # its whole contact is clipped
    if clipped:  # the pull-off is not in the record
        po = PullOff(False, -1, math.nan, math.nan, math.nan, math.nan, 0.0, False)
    else:
        po = find_pull_off(st.deflection, st.position, ret, noise, k, nsigma, window)
    tol = nsigma * noise
    bad_in, bad_off = _repulsive(ji, None, tol), _repulsive(None, po, tol)
    if bad_in and bad_off:  # no number: the jumps found are not there (the later steps see none)
        nan = math.nan
        return _skip(st, "jumps", _repulsive(ji, po, tol), Jumps(JumpIn(False, -1, nan, nan, nan, nan, nan, nan, 0.0),
                                                                 PullOff(False, -1, nan, nan, nan, nan, 0.0, False)))
    if bad_in:  # the one impossible number goes, the other stays; the reason is kept under its name
        st = st.update(skipped={**st.skipped, "jump_in": bad_in})
        ji = JumpIn(False, -1, *([math.nan] * 6), 0.0)
    if bad_off:
        st = st.update(skipped={**st.skipped, "pull_off": bad_off})
        po = PullOff(False, -1, math.nan, math.nan, math.nan, math.nan, 0.0, False)
    warn = jump_warnings(ji, po, k, clipped)
    z0 = st.details["zero"].contact_separation if "zero" in st.details else Z0
    if 0 <= ji.index < st.separation.size - 1:
        # at a rigid contact the first contact sample lies on the compliance line (h = z0)
        off = float(st.separation[ji.index + 1] - z0)
        if abs(off) > max(nsigma * noise, o.onset_tolerance):
            warn.append(f"the first contact sample lies {off * 1e9:.3g} nm off the compliance line: a soft or "
                        "nonlinear contact, or a line displaced by friction or hysteresis (dynamic run); "
                        "separations near contact are uncertain by about that much")
    return st.update("jumps", Jumps(ji, po), warn=warn)


def _repulsive(ji: JumpIn | None, po: PullOff | None, tolerance: float) -> str | None:
    """Why the jumps are physically impossible: a jump into contact or a pull-off landing at a repulsive
    (positive) deflection beyond ``tolerance`` [m]. Both are attractions (F < 0): the zero of force or the
    contact point is misplaced (None: both plausible, or not given)."""
    bad = []
    if ji is not None and ji.found and ji.deflection_after > tolerance:
        bad.append(f"the jump into contact lands at {ji.force_after * 1e9:+.4g} nN")
    if po is not None and po.found and po.deflection > tolerance:
        bad.append(f"the pull-off is at {po.force * 1e9:+.4g} nN")
    if not bad:
        return None
    return (f"{IMPOSSIBLE}: {' and '.join(bad)}, repulsive, where both are attractions (F < 0, the lever bent "
            "towards the surface): the zero of force or the contact point is misplaced (a curved contact onset "
            "taken for the free branch, a baseline fitted in contact); suspect input: the contact region")


def adhesion_step(st: State, o: AdhesionOptions) -> State:
    """Adhesion for every contact kind: the retract's deepest dip below its own baseline (<= 0).

    See :mod:`~afmforce.analysis.unbinding`; the dip counts above ``o.nsigma``
    baseline noise, with its position, the last rupture and the unbinding steps.
    """
    po = st.details["jumps"].pull_off if "jumps" in st.details else None
    hard = po is not None and po.found and _kind(st) == "hard"  # the paper's pull-off jump ends the dip
    res = retract_adhesion(st.deflection, st.position, st.retract, st.spring_constant, nsigma=o.nsigma,
                           pull_off=po.index if hard else -1)
    warn = None
    if (po is not None and po.found and math.isfinite(po.force) and po.force < 0 and math.isfinite(res.force)
            and abs(res.force) < 0.5 * abs(po.force)):
        # both are below zero force; they differ only by the baseline each is measured from
        warn = (f"adhesion {res.force * 1e9:.3g} nN (from the retract's own baseline) is under half the pull-off "
                f"force {po.force * 1e9:.3g} nN (from the drift-corrected zero): the retract's free part does not "
                "return to the approach's baseline (still relaxing, drift, or an offset at the turn); "
                "trust the pull-off only with a settled baseline")
    return st.update("adhesion", res, warn=warn)


def surface_energy(st: State, o: SurfaceEnergyOptions) -> State:
    """Surface energy from the pull-off and the probe's R, and R from the jump-out distance (hard contacts)."""
    j = st.details.get("jumps")
    if j is None:
        raise AnalysisError("step 'surface_energy' needs the jumps")
    if _kind(st) == "soft":
        return _skip(st, "surface_energy", "soft contact: JKR/DMT from a pull-off jump need a rigid contact")
    if "jumps" in st.skipped or "pull_off" in st.skipped:
        return _skip(st, "surface_energy", f"no pull-off: {st.skipped.get('jumps') or st.skipped['pull_off']}")
    if not j.pull_off.found:
        return _skip(st, "surface_energy", "no pull-off found")
    radius = st.probe.value("radius", st.metadata)
    return st.update("surface_energy", adhesion(j.pull_off, st.spring_constant, radius=radius, model=o.model,
                                                hamaker=o.hamaker, z0=o.z0))


def vdw(st: State, o: VdwOptions) -> State:
    """van der Waals fit of the approach before the jump (eq 2; A R, or A with the probe's R)."""
    j = st.details.get("jumps")
    if j is None:
        raise AnalysisError("step 'vdw' needs the jumps")
    if _kind(st) == "soft":
        return _skip(st, "vdw", "soft contact: the van der Waals law of eq 2 is for a rigid contact with a jump")
    if "jumps" in st.skipped or "jump_in" in st.skipped:
        return _skip(st, "vdw", f"no jump into contact to fit before: "
                                f"{st.skipped.get('jumps') or st.skipped['jump_in']}")
    radius = st.probe.value("radius", st.metadata)
    idx = st.approach.index
    ji = j.jump_in
    end = int(np.searchsorted(idx, ji.index)) + 1 if ji.found else st.approach.split
    pre = idx[:end]
    res = fit_vdw(st.separation[pre], st.force[pre], spring_constant=st.spring_constant, radius=radius, z0=o.z0,
                  max_separation=o.max_separation, baseline=o.baseline,
                  fit_separation_offset=bool(o.fit_separation_offset))
    if math.isfinite(res.hamaker_radius) and not res.hamaker_radius > 0:  # a repulsion: no vdW law to draw
        return _skip(st, "vdw", f"no attraction before contact (fitted A R = {res.hamaker_radius:.3g} J m <= 0): "
                                "no van der Waals law to report or draw")
    warn = None if res.status == "ok" else f"van der Waals fit: {res.status}"
    return st.update("vdw", res, warn=warn)


def oscillation(st: State, o: OscillationOptions) -> State:
    """Post-contact oscillation of each run; temporal versus spatial origin."""
    peaks = {}
    for run in (st.approach, st.retract):
        idx = run.index[run.compliance & ~run.saturated]
        v = st.velocity(run.index) if st.time_known else math.nan
        if not st.time_known or idx.size < 8:
            nyq = math.nan
            if st.time_known and run.index.size > 1:
                dt = float(np.median(np.diff(st.time[run.index])))
                nyq = 0.5 / dt if dt > 0 else math.nan   # repeated time stamps: no Nyquist frequency
            peaks[run.kind] = dataclasses.replace(find_peak(np.array([]), np.array([]), v, run.kind), nyquist=nyq)
            continue
        x = st.z[idx] - st.z[idx].mean()
        a, b, *_ = robust_line(x, st.deflection[idx])
        resid = st.deflection[idx] - (a + b * x)
        peaks[run.kind] = find_peak(st.time[idx], resid, v, run.kind, min_cycles=o.min_cycles,
                                    false_alarm=o.false_alarm)
    origin, verdict, _ = both_runs(peaks["approach"], peaks["retract"])
    return st.update("oscillation", OscillationResult(peaks["approach"], peaks["retract"], origin, verdict))


def friction(st: State, o: FrictionOptions) -> State:
    """Friction signature of the two compliance lines (before the shift).

    Assessed only on a hard contact whose two compliance regions are straight
    lines (late/early slope ratio within ``o.max_curvature``); otherwise the
    signature is ``"not assessed"`` with the reason and its numbers.
    """
    nsigma, slope_tolerance, offset_tolerance, max_curvature = (o.nsigma, o.slope_tolerance, o.offset_tolerance,
                                                                o.max_curvature)
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
    v = st.velocity(idx)
    slope = abs(comp.approach.slope)
    if not (rate > 0 and math.isfinite(v) and v > 0 and slope > 0):
        return 0.0, 0.0, rate
    return rate / (v * slope), rate * lever / slope, rate


# --- the registry's records (afmforce.analysis.registry) -------------------------------------------
def _jumps_fields(st: State) -> dict:
    if "jumps" in st.skipped:
        return {}
    d = st.details
    ji, po = d["jumps"].jump_in, d["jumps"].pull_off
    out = dict(contact_onset_separation=ji.separation, pull_off_force=po.force, pull_off_position=po.position,
               jump_out_distance=po.jump_out_distance, pull_off_saturated=po.saturated,
               pull_off_force_extrapolated=(po.deflection_extrapolated * d["force"].spring_constant
                                            if "force" in d else math.nan))
    if ji.found:  # without a significant jump the tip crept in: only the onset of contact
        out.update(jump_in_separation=ji.separation, jump_in_force=ji.force_after,
                   jump_in_deflection=ji.deflection_after)
    return out


JUMPS = AnalysisStep(
    "jumps", "Jump into contact and pull-off", jumps, JumpsOptions, requires=("zero", "force"),
    channels=("separation",), reference="section 2.1, Fig 9",
    fields=(ResultField("jump_in_separation", "m", "jump-in separation", summary=True, column=True),
            ResultField("jump_in_force", "N", "jump-in force", summary=True, column=True),
            ResultField("jump_in_deflection", "m", "jump-in deflection", column=True),
            ResultField("contact_onset_separation", "m", "contact onset separation", summary=True),
            ResultField("pull_off_force", "N", "pull-off force", summary=True, column=True),
            ResultField("pull_off_saturated", None, default=False),
            ResultField("pull_off_force_extrapolated", "N", "pull-off force (extrapolated past clipping)",
                        summary=True),
            ResultField("pull_off_position", "m", "pull-off position", summary=True, column=True),
            ResultField("jump_out_distance", "m", "jump-out distance", summary=True, column=True)),
    collect=_jumps_fields)


def _adhesion_fields(st: State) -> dict:
    a = st.details["adhesion"]
    return dict(adhesion_force=a.force, adhesion_deflection=a.deflection, adhesion_distance=a.distance,
                adhesion_noise=a.noise, rupture_distance=a.rupture_distance, unbinding_steps=len(a.steps),
                adhesion_verdict=a.verdict)


ADHESION = AnalysisStep(
    "adhesion", "Adhesion: deepest retract dip below its own baseline, last rupture, unbinding steps",
    adhesion_step, AdhesionOptions, requires=("zero", "force"), channels=("position",),
    reference="afmforce (every contact kind)",
    fields=(ResultField("adhesion_force", "N", "adhesion (deepest retract dip)", summary=True, column=True),
            ResultField("adhesion_deflection", "m", "adhesion as a deflection"),
            ResultField("adhesion_distance", "m", "adhesion position from contact", summary=True, column=True),
            ResultField("adhesion_noise", "N", "baseline noise of the retract", column=True),
            ResultField("rupture_distance", "m", "last rupture from contact", summary=True, column=True),
            ResultField("unbinding_steps", "", "unbinding steps", default=0, column=True),
            ResultField("adhesion_verdict", None, default="")),
    collect=_adhesion_fields)
SURFACE_ENERGY = AnalysisStep(
    "surface_energy", "Surface energy and radius from the pull-off (JKR/DMT; hard contacts)", surface_energy,
    SurfaceEnergyOptions, requires=("jumps",), reference="section 2.1",
    fields=(ResultField("surface_energy", "J/m^2", "surface energy", summary=True, column=True),
            ResultField("radius", "m", "radius", summary=True, column=True)),
    collect=lambda st: {"surface_energy": st.details["surface_energy"].surface_energy,
                        "radius": st.details["surface_energy"].radius})


def _vdw_fields(st: State) -> dict:
    if "vdw" in st.skipped:
        return {}
    v = st.details["vdw"]
    return dict(hamaker_radius=v.hamaker_radius, hamaker_radius_se=v.hamaker_radius_se, hamaker=v.hamaker,
                hamaker_se=v.hamaker_se)


VDW = AnalysisStep(
    "vdw", "van der Waals fit before the jump (A R or A)", vdw, VdwOptions, requires=("jumps",), reference="eq 2",
    fields=(ResultField("hamaker_radius", "J m", "A R", summary=True, column=True),
            ResultField("hamaker_radius_se", "J m", "standard error of A R", column=True),
            ResultField("hamaker", "J", "Hamaker constant", summary=True, column=True),
            ResultField("hamaker_se", "J", "standard error of A", column=True)),
    collect=_vdw_fields)


def _oscillation_fields(st: State) -> dict:
    o = st.details["oscillation"]
    out = {"oscillation_verdict": o.verdict}
    if o.origin != "none" and o.approach.found and o.retract.found:
        out["oscillation_frequency"] = 0.5 * (o.approach.frequency + o.retract.frequency)
    return out


OSCILLATION = AnalysisStep(
    "oscillation", "Post-contact oscillation: frequency, temporal or spatial", oscillation, OscillationOptions,
    requires=("calibration",), channels=("deflection",), reference="section 3.2",
    fields=(ResultField("oscillation_frequency", "Hz", "oscillation", summary=True, column=True),
            ResultField("oscillation_verdict", None, default="")),
    collect=_oscillation_fields)
FRICTION = AnalysisStep(
    "friction", "Friction signature of the compliance lines (hard contacts, straight lines)", friction,
    FrictionOptions, requires=("kind",), after=("shift",), reference="sections 2.2.2-2.2.4, eqs 16-21",
    fields=(ResultField("friction", None, default=""), ResultField("friction_verdict", None, default="")),
    collect=lambda st: {"friction": st.details["friction"].kind, "friction_verdict": st.details["friction"].verdict})
