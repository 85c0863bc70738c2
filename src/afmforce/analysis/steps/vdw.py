"""The ``vdw`` step: van der Waals fit before the jump (A R or A).

Declared once by its record :data:`VDW` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import math

import numpy as np

from ...errors import AnalysisError
from .._step_helpers import _kind, _skip
from ..options import VdwOptions
from ..registry import AnalysisStep, ResultField
from ..state import State
from ..vdw import fit_vdw

__all__ = ["vdw", "VDW"]


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


def _vdw_fields(st: State) -> dict:
    if "vdw" in st.skipped:
        return {}
    v = st.details["vdw"]
    return dict(hamaker_radius=v.hamaker_radius, hamaker_radius_se=v.hamaker_radius_se, hamaker=v.hamaker,
                hamaker_se=v.hamaker_se)


VDW = AnalysisStep(
    "vdw", "van der Waals fit before the jump (A R or A)", vdw, VdwOptions, requires=("jumps",), reference="eq 2", runs=("approach",),
    fields=(ResultField("hamaker_radius", "J m", "A R", summary=True, column=True),
            ResultField("hamaker_radius_se", "J m", "standard error of A R", column=True),
            ResultField("hamaker", "J", "Hamaker constant", summary=True, column=True),
            ResultField("hamaker_se", "J", "standard error of A", column=True)),
    collect=_vdw_fields)
