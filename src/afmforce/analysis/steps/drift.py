"""The ``drift`` step: thermal drift: line in time in the zero-force region, per run.

Declared once by its record :data:`DRIFT` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

from ..drift import remove_drift
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


DRIFT = AnalysisStep("drift", "Thermal drift: line in time in the zero-force region, per run", drift, DriftOptions,
                     requires=("contact",), channels=("approach",), reference="section 3.1, Fig 7")
