"""The ``jumps`` step: jump into contact and pull-off.

Declared once by its record :data:`JUMPS` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import math

import numpy as np

from ...constants import Z0
from .._step_helpers import _kind, _skip
from ..jumps import JumpIn, Jumps, PullOff, find_jump_in, find_pull_off, jump_warnings
from ..options import JumpsOptions
from ..plausibility import IMPOSSIBLE
from ..registry import AnalysisStep, ResultField
from ..state import State

__all__ = ["jumps", "JUMPS"]


def jumps(st: State, o: JumpsOptions) -> State:
    """Jump into contact and pull-off, near each run's contact split.

    Warns when the first contact sample lies more than ``o.onset_tolerance`` (or
    ``o.nsigma`` noise) off the compliance line the zero of separation was put on.
    """
    nsigma, window = o.nsigma, int(o.window)
    if _kind(st) == "soft":
        nan = math.nan
        return _skip(st, "jumps", "soft contact: no jump into contact and no single pull-off jump (see adhesion)",
                     Jumps(JumpIn(False, -1, nan, nan, nan, nan, nan, nan, 0.0),
                           PullOff(False, -1, nan, nan, nan, nan, 0.0, False)))
    noise = abs(st.noise * st.factor)
    if not noise > 0:  # a quiet signal on a coarse ADC: its noise is the quantisation's, not zero
        steps = np.abs(np.diff(np.asarray(st.curve.deflection_signal, float)))  # as recorded: ADC steps
        steps = steps[steps > 0]
        noise = float(steps.min()) * abs(st.factor) / math.sqrt(12.0) if steps.size else noise
    k = st.spring_constant
    ji = find_jump_in(st.deflection, st.separation, st.position, st.approach, noise, k, nsigma, window,
                      attractive_below=nsigma * noise)  # a step in contact is a slip, not the jump
    ret = st.retract
    clipped = ret is not None and not ret.has_compliance and bool(ret.contact.any())  # its whole contact is clipped
    if ret is None:
        st = st.update(skipped={**st.skipped, "pull_off": "not available: no retract run"})
    if clipped or ret is None:  # the pull-off is not in the record
        po = PullOff(False, -1, math.nan, math.nan, math.nan, math.nan, 0.0, False)
    else:
        po = find_pull_off(st.deflection, st.position, ret, noise, k, nsigma, window,
                           attractive_below=nsigma * noise)  # a pull-off at a repulsive load is no pull-off
    tol = nsigma * noise
    bad_in, bad_off = _repulsive(ji, None, tol), _repulsive(None, po, tol)
    if bad_in and bad_off:  # no number: the jumps found are not there (the later steps see none)
        nan = math.nan
        return _skip(st, "jumps", _repulsive(ji, po, tol), Jumps(JumpIn(False, -1, nan, nan, nan, nan, nan, nan, 0.0),
                                                                 PullOff(False, -1, nan, nan, nan, nan, 0.0, False)))
    if bad_in:  # the one impossible number goes, the other stays; the reason is kept under its name
        st = st.update(skipped={**st.skipped, "jump_in": bad_in})
        ji = JumpIn(False, -1, *([math.nan] * 6), 0.0)
    if bad_off:
        st = st.update(skipped={**st.skipped, "pull_off": bad_off})
        po = PullOff(False, -1, math.nan, math.nan, math.nan, math.nan, 0.0, False)
    warn = jump_warnings(ji, po, k, clipped, retract=ret is not None)  # an approach alone: no pull-off looked for
    z0 = st.details["zero"].contact_separation if "zero" in st.details else Z0
    if 0 <= ji.index < st.separation.size - 1:
        # at a rigid contact the first contact sample lies on the compliance line (h = z0)
        off = float(st.separation[ji.index + 1] - z0)
        if abs(off) > max(nsigma * noise, o.onset_tolerance):
            warn.append(f"the first contact sample lies {off * 1e9:.3g} nm off the compliance line: a soft or "
                        "nonlinear contact, or a line displaced by friction or hysteresis (dynamic run); "
                        "separations near contact are uncertain by about that much")
    return st.update("jumps", Jumps(ji, po), warn=warn)


def _repulsive(ji: JumpIn | None, po: PullOff | None, tolerance: float) -> str | None:
    """Why the jumps are physically impossible: a jump into contact or a pull-off landing at a repulsive
    (positive) deflection beyond ``tolerance`` [m]. Both are attractions (F < 0): the zero of force or the
    contact point is misplaced (None: both plausible, or not given).

    A jump through a repulsive barrier (``JumpIn.through_barrier``: a fall of the deflection from a
    repulsive force the approach rose to) may land repulsive on a hard contact: it is physics, not
    judged here. What stays impossible is a jump-in that lands repulsive any other way: a step away from
    the surface, or one on a free branch that never came down to zero force (a misplaced zero)."""
    bad = []
    if ji is not None and ji.found and ji.deflection_after > tolerance and not ji.through_barrier:
        bad.append(f"the jump into contact lands at {ji.force_after * 1e9:+.4g} nN")
    if po is not None and po.found and po.deflection > tolerance:
        bad.append(f"the pull-off is at {po.force * 1e9:+.4g} nN")
    if not bad:
        return None
    return (f"{IMPOSSIBLE}: {' and '.join(bad)}, repulsive, where both are attractions (F < 0, the lever bent "
            "towards the surface): the zero of force or the contact point is misplaced (a curved contact onset "
            "taken for the free branch, a baseline fitted in contact); suspect input: the contact region")


def _jumps_fields(st: State) -> dict:
    if "jumps" in st.skipped:
        return {}
    d = st.details
    ji, po = d["jumps"].jump_in, d["jumps"].pull_off
    out = dict(contact_onset_separation=ji.separation, pull_off_force=po.force, pull_off_position=po.position,
               jump_out_distance=po.jump_out_distance, pull_off_saturated=po.saturated,
               pull_off_force_extrapolated=(po.deflection_extrapolated * d["force"].spring_constant
                                            if "force" in d else math.nan))
    if ji.found:  # without a significant jump the tip crept in: only the onset of contact
        out.update(jump_in_separation=ji.separation, jump_in_force=ji.force_after,
                   jump_in_deflection=ji.deflection_after)
    if ji.through_barrier:  # the jump starts on a repulsive barrier: its height and how far the tip jumps
        out.update(barrier_force=ji.force_before, barrier_jump_distance=ji.jump_distance)
    return out


JUMPS = AnalysisStep(
    "jumps", "Jump into contact and pull-off", jumps, JumpsOptions, requires=("zero", "force"),
    channels=("separation",), reference="section 2.1, Fig 9", runs=("approach",),
    fields=(ResultField("jump_in_separation", "m", "jump-in separation", summary=True, column=True),
            ResultField("jump_in_force", "N", "jump-in force", summary=True, column=True),
            ResultField("jump_in_deflection", "m", "jump-in deflection", column=True),
            ResultField("barrier_force", "N", "repulsive barrier the jump-in crossed (force at its start)",
                        summary=True, column=True),
            ResultField("barrier_jump_distance", "m", "jump through the barrier (deflection's fall)",
                        summary=True, column=True),
            ResultField("contact_onset_separation", "m", "contact onset separation", summary=True),
            ResultField("pull_off_force", "N", "pull-off force", summary=True, column=True),
            ResultField("pull_off_saturated", None, default=False),
            ResultField("pull_off_force_extrapolated", "N", "pull-off force (extrapolated past clipping)",
                        summary=True),
            ResultField("pull_off_position", "m", "pull-off position", summary=True, column=True),
            ResultField("jump_out_distance", "m", "jump-out distance", summary=True, column=True)),
    collect=_jumps_fields)
