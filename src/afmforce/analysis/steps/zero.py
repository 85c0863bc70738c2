"""The ``zero`` step: zero of separation at the compliance line.

Declared once by its record :data:`ZERO` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import math

from .._step_helpers import _kind
from ..options import ZeroOptions
from ..position_bend import bend_note, position_bend
from ..registry import AnalysisStep, ResultField
from ..separation import ZeroResult, zero_of_separation
from ..state import State

__all__ = ["zero", "ZERO"]


def zero(st: State, o: ZeroOptions) -> State:
    """Zero of separation: the compliance line at h = contact_separation.

    ``run="auto"``: the outward (retract) line as in the paper, unless the
    retract had no baseline of its own (drift step) or no compliance line, or
    the two lines' slopes differ by more than ``parallel_tolerance``, more than
    friction makes (a creeping piezo on the nominal channel, a soft contact), or
    the position bends differently on the two runs (:mod:`..position_bend`):
    then the inward line, which carries the jump-in and the van der Waals
    attraction.
    """
    if _kind(st) == "soft":
        cp = st.details["contact_point"]
        c0 = cp.deflection - cp.position
        sep = st.deflection - st.z - c0
        res = ZeroResult(0.0, cp.position, "approach", math.nan)
        return st.update("zero", res, separation=sep, position=st.z - cp.position)
    run = o.run
    warn = []
    if run == "auto":
        dr = st.details.get("drift")
        comp = st.details.get("compliance")
        run = "approach" if dr is not None and dr.retract_from_approach else "retract"
        if comp is not None and comp.approach.found and comp.retract.found:
            ratio = comp.approach.slope / comp.retract.slope
            if abs(ratio - 1) > o.parallel_tolerance:
                run = "approach"
                warn.append(f"compliance lines not parallel (slope ratio {ratio:.3g}): zero of separation from "
                            "the inward line; the outward run's separations are approximate")
            # a nominal position that bends differently on the runs: the outward line misplaces the inward zero
            bend = position_bend(st.z, st.signal, st.approach, st.retract) if st.channel == "nominal" else None
            if bend is not None and bend.detected:
                run = "approach"
                cal = st.details.get("calibration")
                warn.append(bend_note(bend, st.unit, cal is not None and cal.source == "fit"))
    regions = st.retract if run == "retract" else st.approach
    if regions is None or not regions.has_compliance:  # that run's contact is clipped (or not recorded): the other
        regions = st.approach if run == "retract" else st.retract
    if st.missing_run:  # a curve of one run: its own line, no other run to correct
        pass
    elif not (st.approach.has_compliance and st.retract.has_compliance):
        warn.append(f"zero of separation from the {regions.kind} run's compliance line alone: friction or "
                    f"hysteresis between the runs would offset it by up to half their distance (not measured), "
                    f"and the other run's separations are not corrected for the shift")
    h, pos, res = zero_of_separation(st.z, st.deflection, regions, o.contact_separation)
    return st.update("zero", res, warn=warn, separation=h, position=pos)


ZERO = AnalysisStep("zero", "Zero of separation at the compliance line", zero, ZeroOptions, requires=("kind",),
                    after=("shift",), channels=("deflection",), reference="section 3.2, Fig 9", runs=(),
                    fields=(ResultField("contact_separation", "m", "separation given to the compliance line",
                                        column=True),),
                    collect=lambda st: {"contact_separation": st.details["zero"].contact_separation})
