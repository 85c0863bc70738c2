"""The ``friction`` step: friction signature of the compliance lines (hard contacts, straight lines).

Declared once by its record :data:`FRICTION` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .. import compliance as cc
from ...errors import AnalysisError
from .._numeric import robust_line
from .._step_helpers import _kind, _skip
from ..contact_point import curvature_ratio
from ..options import FrictionOptions
from ..registry import AnalysisStep, ResultField
from ..state import State

__all__ = ["friction", "FRICTION"]


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
                                offset_tolerance=max(offset_tolerance, offset_unc), channel=st.channel,
                                offset_systematic=offset_unc, slope_systematic=slope_unc, lever=_lever(st),
                                velocity=st.velocity(st.approach.index) if st.time_known else math.nan)
    if rate_gap > 0 and (slope_unc > slope_tolerance or offset_unc > offset_tolerance):
        bounds = (f"the drift rate holds to {rate_gap:.3g} {st.unit}/s between the halves of the baselines, so "
                  f"the lines are known to a slope of {slope_unc * 100:.2g} % and an offset of "
                  f"{offset_unc * 1e9:.3g} nm")
        if sig.kind == "not detected":
            sig = dataclasses.replace(sig, verdict=f"{sig.verdict} (the bounds include the drift uncertainty: "
                                                   f"{bounds})")
        else:
            sig = dataclasses.replace(sig, verdict=f"{sig.verdict} (beyond the drift uncertainty: {bounds})")
    return st.update("friction", sig)


def _lever(st: State):
    """The lever of eq 13 when the probe's geometry is given (theta0, L0, L1, L2 and k), else None.

    The same lever the force step converts with (``k`` given is the intrinsic k0, rescaled when
    the force step rescaled a thermal k).
    """
    p = st.probe
    conv = st.details.get("force")
    if conv is None or conv.method != "eq 13" or None in (p.L0, p.L1, p.L2):
        return None
    from ...cantilever import InclinedCantilever

    return InclinedCantilever(L0=p.L0, L1=p.L1, L2=p.L2, theta0=conv.theta0, k0=conv.spring_constant_given)


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


FRICTION = AnalysisStep(
    "friction", "Friction signature of the compliance lines (hard contacts, straight lines)", friction,
    FrictionOptions, requires=("kind",), after=("shift", "force"), reference="sections 2.2.2-2.2.4, eqs 16-21",
    fields=(ResultField("friction", None, default=""), ResultField("friction_verdict", None, default=""),
            ResultField("friction_offset_bound", "m", "largest friction offset the lines allow", column=True, map=True),
            ResultField("friction_force_bound", "N", "largest constant friction the lines allow (eq 16)",
                        column=True, map=True),
            ResultField("viscous_friction_bound", "kg/s", "largest viscous friction the lines allow (eq 28)",
                        column=True, map=True),
            ResultField("load_friction_bound", "", "largest load-proportional friction the lines allow (eqs 18-19)",
                        column=True, map=True)),
    collect=lambda st: {"friction": st.details["friction"].kind, "friction_verdict": st.details["friction"].verdict,
                        "friction_offset_bound": st.details["friction"].offset_bound,
                        "friction_force_bound": st.details["friction"].friction_force_bound,
                        "viscous_friction_bound": st.details["friction"].viscous_friction_bound,
                        "load_friction_bound": st.details["friction"].load_friction_bound})
