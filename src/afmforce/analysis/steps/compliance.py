"""The ``compliance`` step: constant-compliance lines (robust fit).

Declared once by its record :data:`COMPLIANCE` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

from .. import compliance as cc
from ..options import ComplianceOptions
from ..registry import AnalysisStep
from ..state import State

__all__ = ["compliance", "COMPLIANCE"]


def compliance(st: State, o: ComplianceOptions) -> State:
    """Robust constant-compliance line of each run."""
    res = cc.fit_compliance(st.z, st.signal, st.approach, st.retract, st.unit)
    return st.update("compliance", res, warn=res.notes)


COMPLIANCE = AnalysisStep("compliance", "Constant-compliance lines (robust fit)", compliance, ComplianceOptions,
                          requires=("drift",), after=("fringes",), reference="section 3.1", runs=())
