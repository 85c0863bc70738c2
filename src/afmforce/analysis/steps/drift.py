"""The ``drift`` step: thermal drift: line in time in the zero-force region, per run.

Declared once by its record :data:`DRIFT` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import math

from ...errors import AnalysisError
from ..drift import DriftResult, fit_baseline, remove_drift
from ..options import DriftOptions
from ..registry import AnalysisStep
from ..state import State

__all__ = ["drift", "DRIFT"]


#: Retract baselines of a free part too noisy for its own line
#: (:func:`~afmforce.analysis.drift.borrowed_line`), in words.
_BORROWED = {"offset": "no slope", "approach slope": "the approach's drift rate",
             "position tilt": "the approach baseline's tilt in position"}


def drift(st: State, o: DriftOptions) -> State:
    """Subtract a baseline line in time fitted in each run's zero-force region."""
    if st.missing_run:
        return _one_run(st, o)
    signal, res = remove_drift(st.time, st.signal, st.curve.segment, st.approach, st.retract, st.unit,
                               int(o.order), z=st.z if o.tail else None)
    warn = None
    if res.retract_settling:
        warn = ("the retract's free part is still relaxing after the pull-off (a curved tail, not a drift line: "
                "an overdamped cantilever): the approach baseline was used for both runs")
    elif res.retract_from_approach and not st.retract.has_compliance:
        warn = ("the retract run has no baseline of its own (its free cantilever had not settled): the approach "
                "baseline was used for both runs")
    elif res.retract_from_approach:
        warn = ("retract baseline too short or too noisy after the pull-off (free ringing?): the approach "
                "baseline was used for both runs")
    elif res.retract_line in _BORROWED:
        warn = ("the retract's free part is too noisy for a baseline line of its own (ringing, unbinding events): "
                f"its own offset with {_BORROWED[res.retract_line]}")
    return st.update("drift", res, warn=warn, signal=signal)


def _one_run(st: State, o: DriftOptions) -> State:
    """A curve of one run: the line of its own zero-force region (:func:`~afmforce.analysis.drift.fit_baseline`,
    the retract's with the settling transient as :func:`~afmforce.analysis.drift.remove_drift` fits it), subtracted
    from every sample; the missing run's numbers NaN."""
    run = st.retract if st.approach is None else st.approach
    idx = run.index[run.zero_force]
    if idx.size < 2:
        raise AnalysisError(f"the {run.kind} run has {idx.size} samples of its free part: no baseline (zero of force)")
    order = int(o.order)
    off, slope, noise = fit_baseline(st.time[idx], st.signal[idx], order, transient=run.kind == "retract" and order != 1)
    t0 = st.time[idx[0]]
    at_start = off + slope * (st.time[run.index[0]] - t0)
    nan = math.nan
    own = dict(offset_retract=at_start, slope_retract=slope) if run.kind == "retract" else dict(
        offset_approach=at_start, slope_approach=slope)
    res = DriftResult(**{"offset_approach": nan, "slope_approach": nan, "offset_retract": nan, "slope_retract": nan,
                         **own}, noise=noise, retract_from_approach=False, unit=st.unit)
    return st.update("drift", res, signal=st.signal - (off + slope * (st.time - t0)))


DRIFT = AnalysisStep("drift", "Thermal drift: line in time in the zero-force region, per run", drift, DriftOptions,
                     requires=("contact",), reference="section 3.1, Fig 7", runs=())
