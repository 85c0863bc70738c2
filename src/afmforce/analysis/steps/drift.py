"""The ``drift`` step: thermal drift: line in time in the zero-force region, per run.

Declared once by its record :data:`DRIFT` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import math
from dataclasses import replace

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
    climb = _baseline_climb(st, signal)
    if climb is not None:
        res = replace(res, baseline_climb=climb[0])
        warn = [warn, climb[1]]
    return st.update("drift", res, warn=warn, signal=signal)


#: The drift line may climb over the approach after its free part by at most this fraction of the signal's own
#: rise there: past it the "free" part is itself a slow contact (an indenter that starts on a soft sample).
MAX_BASELINE_CLIMB = 0.5


def _baseline_climb(st: State, signal) -> tuple[float, str] | None:
    """The fraction climbed [-] and a warning when the baseline line, fitted before contact, takes away most of
    the approach's rise after it (the indentation step then widens the modulus's interval: see
    :func:`afmforce.analysis.indentation.indentation`).

    An Optics11 Piuma export of a 338 Pa sample (NanoPrepare's ``new.txt``) presses on it from its first
    samples: the line fitted over the first 3.4 um rises with the contact and, carried on in time, removed
    ~75 % of the 120 nN load; the contact point and the modulus then came out of a quarter of the force. The JPK
    stress-relaxation cell curves (afmformats' ``cell1-0001``/``-0008``) press from the start of their extend too
    (after a pause in contact): 54-56 %."""
    app = st.approach
    if app is None:
        return None
    free = app.index[app.zero_force]
    if free.size < 2 or app.index.size < 2:
        return None
    end, last = int(free[-1]), int(app.index[-1])
    line = st.signal - signal
    climb, rise = float(line[last] - line[end]), float(st.signal[last] - st.signal[end])
    if not (rise > 0 and climb > MAX_BASELINE_CLIMB * rise and climb > 10 * abs(st.noise)):
        return None
    return climb / rise, (
        f"the baseline line fitted before contact climbs by {climb / rise:.0%} of the signal's own rise over the "
        "rest of the approach: its \"free\" part is likely a slow contact already (a tip that starts on a soft "
        "sample), so the contact point, the force and the modulus are uncertain; record the approach from "
        "further away")


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
