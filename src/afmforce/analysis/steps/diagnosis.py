"""The ``diagnosis`` step: dynamic diagnosis: inertia parameter, lag, jump-in distance.

Declared once by its record :data:`DIAGNOSIS` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ...errors import AnalysisError
from .._glue_kernel import COMPILED, first_below, median_abs_step
from .._numeric import polyfit, ptp
from .._step_helpers import _kind
from ..dynamic import diagnose_curve
from ..jumps import pull_off_estimate
from ..options import DiagnosisOptions
from ..registry import AnalysisStep, ResultField
from ..state import State

__all__ = ["diagnosis", "DIAGNOSIS"]


def _force_gradient(st: State, window: int = 5) -> tuple[float, str]:
    """Measured |dF/dh| [N/m] where the tip meets the surface, and how it was measured."""
    if st.force is None or not math.isfinite(st.spring_constant):
        return math.nan, "no force (spring constant unknown)"
    idx = st.approach.index
    if _kind(st) == "soft":
        cp = st.details["contact_point"]
        k = int(np.searchsorted(idx, cp.index))
        limit = -0.1 * max(cp.indentation, 0.0)
        if COMPILED and _f64(st.separation) and idx.dtype == np.int64:
            end = first_below(st.separation, idx, k, limit)
        else:
            stop = np.flatnonzero((np.arange(idx.size) > k) & (st.separation[idx] < limit))
            end = int(stop[0]) if stop.size else idx.size
        sel = idx[k:max(end, k + 3)]
        what = "contact stiffness over the first 10 % of the indentation"
    else:
        ji = st.details["jumps"].jump_in
        if not ji.found:
            return math.nan, "no jump into contact: the attraction's gradient is below the noise"
        k = int(np.searchsorted(idx, ji.index))
        sel = idx[max(k - window + 1, 0):k + 1]
        what = f"attraction over the last {window} samples before the jump"
    hs, fs = st.separation[sel], st.force[sel]
    if hs.size < 3 or ptp(hs) == 0:
        return math.nan, "too few samples to measure the force gradient"
    return float(abs(polyfit(hs - hs.mean(), fs, 1)[0])), what


def _f64(a) -> bool:
    return isinstance(a, np.ndarray) and a.dtype == np.float64


def _median_step(z: np.ndarray, idx: np.ndarray) -> float:
    """Median position step of the run ``idx`` [m] (0 for a single sample)."""
    if idx.size < 2:
        return 0.0
    if COMPILED and _f64(z) and idx.dtype == np.int64:
        return float(median_abs_step(z, idx))
    return float(np.median(np.abs(np.diff(z[idx]))))


def diagnosis(st: State, o: DiagnosisOptions) -> State:
    """Dynamic diagnosis: eq 3, eq 4, jump-in distance, friction and adhesion consistency.

    Flags the van der Waals fit as unreliable when the run is judged dynamic.
    """
    j = st.details.get("jumps")
    if j is None:
        raise AnalysisError("step 'diagnosis' needs the jumps")
    idx = st.approach.index
    v = st.velocity(idx) if st.time_known else math.nan
    f = st.probe.value("resonance_frequency", st.metadata)
    dx = o.resolution if o.resolution is not None else max(abs(st.noise * st.factor), o.min_resolution)
    fit = st.details.get("vdw")
    fit = fit if fit is not None and hasattr(fit, "static_jump_in_separation") else None
    h_static = fit.static_jump_in_separation if fit is not None else math.nan
    step = _median_step(st.z, idx)
    fr = st.details.get("friction")
    z0 = st.details["zero"].contact_separation if "zero" in st.details else math.nan
    grad, grad_how = _force_gradient(st)
    res = diagnose_curve(velocity=v, spring_constant=st.spring_constant, resonance_frequency=f, resolution=dx,
                         force_gradient=grad, force_gradient_method=grad_how,
                         jump_in_separation=j.jump_in.separation if j.jump_in.found else math.nan,
                         static_jump_in_separation=h_static,
                         sample_step=step, friction=None if fr is None else fr.kind,
                         friction_verdict="" if fr is None else fr.verdict,
                         hamaker_radius=fit.hamaker_radius if fit is not None else math.nan,
                         pull_off_force=pull_off_estimate(j.pull_off, st.spring_constant), contact_separation=z0,
                         attraction_ratio=o.attraction_ratio,
                         quality_factor=float(st.metadata.get("quality_factor", math.nan) or math.nan))
    ret = st.retract
    if ret is not None and not ret.has_compliance and ret.contact.any() and bool(
            np.all(st.signal[ret.index[ret.contact]] > 0)):
        # static pull-off needs adhesion (negative deflection): leaving while pushed is dynamics
        res = dataclasses.replace(res, dynamic=True, verdict=res.verdict + "; " + (
            "the tip left the surface while the cantilever was still pushed (deflection above the photodiode's "
            "saturation on the whole retract contact), where a static pull-off needs adhesion: drag or friction "
            "held the cantilever bent -- a dynamic run, not a static force curve"))
    new = st.update("diagnosis", res)
    if res.dynamic and fit is not None:
        new = new.update("vdw", dataclasses.replace(fit, reliable=False),
                         warn="dynamic run: the van der Waals fit is NOT a static force law (see diagnosis)")
    return new


def _diagnosis_fields(st: State) -> dict:
    g = st.details["diagnosis"]
    return dict(velocity=g.velocity, inertia_parameter=g.inertia_parameter, force_gradient=g.force_gradient,
                resonance_frequency=g.resonance_frequency, dynamic=g.dynamic, verdict=g.verdict,
                dynamic_assessed=g.assessed)


DIAGNOSIS = AnalysisStep(
    "diagnosis", "Dynamic diagnosis: inertia parameter, lag, jump-in distance", diagnosis, DiagnosisOptions,
    requires=("jumps", "adhesion", "vdw", "friction"), reference="eqs 3, 4; sections 2.3, 3.2",
    fields=(ResultField("velocity", "m/s", "approach speed", summary=True, column=True),
            ResultField("force_gradient", "N/m", "force gradient at contact", summary=True, column=True),
            ResultField("resonance_frequency", "Hz", "resonance frequency used for eq 3", column=True),
            ResultField("inertia_parameter", "", "inertia parameter", summary=True, column=True),
            ResultField("dynamic", None, default=False), ResultField("dynamic_assessed", None, default=False),
            ResultField("verdict", None, default="")),
    collect=_diagnosis_fields)
