"""The ``shift`` step: inward/outward shift overlaying the compliance lines.

Declared once by its record :data:`SHIFT` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import math

from .. import compliance as cc
from ...errors import AnalysisError
from .._step_helpers import _kind, _skip
from ..options import ShiftOptions
from ..registry import AnalysisStep, ResultField
from ..state import State

__all__ = ["shift", "SHIFT"]


def shift(st: State, o: ShiftOptions) -> State:
    """Shift the inward run to overlay the outward compliance line (Fig 9)."""
    comp = st.details.get("compliance")
    if comp is None:
        raise AnalysisError("step 'shift' needs the compliance lines")
    if _kind(st) == "soft":
        nan = math.nan
        return _skip(st, "shift", "soft contact: no constant-compliance lines to overlay",
                     cc.ShiftResult(nan, nan, nan, False))
    apply = bool(o.apply)
    res = cc.compliance_shift(comp, applied=apply)
    if not math.isfinite(res.shift):
        missing = "retract" if comp.approach.found else "approach"
        return st.update("shift", res, warn=(
            f"inward/outward shift (hysteresis) not measured: the {missing} run has no unclipped "
            "constant-compliance line; the runs are not overlaid"))
    if not apply:
        return st.update("shift", res)
    z = st.z.copy()
    z[st.approach.index] += res.shift
    return st.update("shift", res, z=z)


SHIFT = AnalysisStep("shift", "Inward/outward shift overlaying the compliance lines", shift, ShiftOptions,
                     requires=("kind",), reference="section 3.2, Fig 9; Fig 7C",
                     fields=(ResultField("shift", "m", "inward shift", summary=True, column=True),),
                     collect=lambda st: {"shift": st.details["shift"].shift})
