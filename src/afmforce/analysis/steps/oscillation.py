"""The ``oscillation`` step: post-contact oscillation: frequency, temporal or spatial.

Declared once by its record :data:`OSCILLATION` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import math

import numpy as np

from .._numeric import robust_line
from .._oscillation_kernel import median_step
from ..options import OscillationOptions
from ..oscillation import OscillationResult, _compiled as compiled, _no_peak, both_runs, find_peak
from ..registry import AnalysisStep, ResultField
from ..state import State

__all__ = ["oscillation", "OSCILLATION"]


def _median_step(t: np.ndarray, index: np.ndarray) -> float:
    """``np.median(np.diff(t[index]))``: one compiled call (numpy's when the kernels run as Python)."""
    if t.dtype == np.float64 and t.flags.c_contiguous and index.dtype == np.int64 and compiled():
        return float(median_step(t, index))
    return float(np.median(np.diff(t[index])))


def oscillation(st: State, o: OscillationOptions) -> State:
    """Post-contact oscillation of each run; temporal versus spatial origin."""
    peaks = {}
    for run in (st.approach, st.retract):
        idx = run.index[run.compliance & ~run.saturated]
        v = st.velocity(run.index) if st.time_known else math.nan
        if not st.time_known or idx.size < 8:
            nyq = math.nan
            if st.time_known and run.index.size > 1:
                dt = _median_step(st.time, run.index)
                nyq = 0.5 / dt if dt > 0 else math.nan   # repeated time stamps: no Nyquist frequency
            peaks[run.kind] = _no_peak(run.kind, v, nyquist=nyq)  # find_peak's answer for no samples
            continue
        zi = st.z[idx]
        di = st.deflection[idx]
        x = zi - zi.mean()
        a, b, *_ = robust_line(x, di)
        resid = di - (a + b * x)
        peaks[run.kind] = find_peak(st.time[idx], resid, v, run.kind, min_cycles=o.min_cycles,
                                    false_alarm=o.false_alarm)
    origin, verdict, _ = both_runs(peaks["approach"], peaks["retract"])
    return st.update("oscillation", OscillationResult(peaks["approach"], peaks["retract"], origin, verdict))


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
