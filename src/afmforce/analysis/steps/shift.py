"""The ``shift`` step: inward/outward shift overlaying the compliance lines.

Declared once by its record :data:`SHIFT` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from .. import compliance as cc
from ...errors import AnalysisError
from .._numeric import robust_line
from ..plausibility import UNDETERMINED, undetermined
from .._step_helpers import _kind, _skip
from ..options import ShiftOptions
from ..registry import AnalysisStep, ResultField
from ..state import State

__all__ = ["shift", "SHIFT"]


#: A shift whose drift bound (:func:`drift_position_error`) exceeds this is warned of [m]: half a nanometre, under
#: the smallest shift the paper reads off its lines (Figs 7-8: the backlash of 2.7-57 nm).
SHIFT_DRIFT_WARN = 0.5e-9


def _rate_spread(st: State, base: np.ndarray) -> float:
    """How well one drift rate holds over the baseline samples ``base`` [signal/s]: the larger of the spreads
    of the robust rates of its two halves and of its three thirds (NaN with fewer than 24 samples).

    On the ``typical`` preset the rate a free part gives is off the truth by up to 0.025 V/s (the fringe of
    the interference, 8 mV over 335 nm, and the 1/f noise look like a rate over 0.4 s), far beyond its
    statistical error (~1e-4 V/s); the spread of the parts' rates (0.015-0.036 V/s on the approach) is of
    that size."""
    if base.size < 24:
        return math.nan
    t, s = st.time[base], st.signal[base]
    spread = 0.0
    for parts in (2, 3):
        r = [robust_line(t[c] - t[c].mean(), s[c])[1] for c in np.array_split(np.arange(base.size), parts)]
        spread = max(spread, float(max(r) - min(r)))
    return spread


def _rate_noise(st: State, base: np.ndarray) -> float:
    """The spread of :func:`_rate_spread` that the samples' own scatter gives [signal/s]: sqrt(2) x the largest
    standard error of the parts' rates (NaN with fewer than 24 samples). A spread within a few of it measures no
    rate: a free part ringing after the pull-off (+-4.9 V aliased on a virtual curve: rates of its halves -16
    and -3.4 V/s, each +-40 V/s or so)."""
    if base.size < 24:
        return math.nan
    t, s = st.time[base], st.signal[base]
    se = max(robust_line(t[c] - t[c].mean(), s[c])[3] for parts in (2, 3)
             for c in np.array_split(np.arange(base.size), parts))
    return math.sqrt(2.0) * float(se)


def drift_position_error(st: State, comp) -> float:
    """The shift's bound from the drift lines [m]: how far the range of drift rates the data allow moves the
    two compliance lines apart.

    Each run's drift line is extrapolated from its free part to its compliance line, ``dt`` away in time
    (0.41 s on the approach of the ``typical`` preset, 1.83 s back from the retract's free part after a 180 nm
    adhesive line). A rate wrong by ``dr`` [signal/s] moves the line by ``dr dt / slope``; ``dr`` is the
    spread of the rates of the parts of the free part (:func:`_rate_spread`), on the retract over the second
    half of its free part only (its first samples ring or relax after the pull-off: the whole free part gives
    1.5 V/s). The two runs' errors add in quadrature. Where the drift step drew the retract's line from the
    approach's (its free part rang or was too short: ``retract_from_approach``) and the retract's own spread is
    within 3 x its samples' scatter (:func:`_rate_noise`: it measures no rate), one rate error moves both lines
    and the bound is the approach's spread times the time between the two compliance lines (a virtual curve whose
    retract rings at +-4.9 V after the pull-off: 200 nm from the ringing's "rates" before, 0.066 nm now, the shift
    true to 0.006 nm). NaN without a time base or a free part of 24 samples.
    """
    if not st.time_known or st.approach is None or st.retract is None:
        return math.nan
    slope = abs(comp.approach.slope)
    if not slope > 0:
        return math.nan
    spans, spreads = [], []
    for run in (st.approach, st.retract):
        base = run.index[run.zero_force & ~run.saturated]
        line = run.index[run.compliance]
        if not (line.size and base.size):
            return math.nan
        spans.append((float(np.median(st.time[base])), float(np.median(st.time[line]))))
        spreads.append(_rate_spread(st, base if run is st.approach else base[base.size // 2:]))
    (ta_base, ta_line), (tr_base, tr_line) = spans
    d = getattr(st, "details", {}).get("drift")
    borrowed = getattr(d, "retract_line", "separate") if d is not None else "separate"
    rbase = st.retract.index[st.retract.zero_force & ~st.retract.saturated]
    rbase = rbase[rbase.size // 2:]
    noise = _rate_noise(st, rbase)
    mute = math.isfinite(spreads[1]) and math.isfinite(noise) and spreads[1] <= 3.0 * noise   # no rate: ringing
    if d is not None and (d.retract_from_approach or borrowed == "approach") and mute:
        # one line for both runs (the retract's free part rang or was too short): one rate error moves both
        # compliance lines, from the approach's free part, so the shift moves by dr (tr_line - ta_line)
        return spreads[0] * abs(tr_line - ta_line) / slope if math.isfinite(spreads[0]) else math.nan
    if borrowed == "approach slope" and mute:   # the retract's own offset, the approach's rate: one rate error, signed
        err = spreads[0] * abs((tr_line - tr_base) - (ta_line - ta_base))
        return err / slope if math.isfinite(err) else math.nan
    if mute:   # no rate measured on the retract: the approach's spread stands for its error
        spreads[1] = spreads[0]
    if not all(math.isfinite(x) for x in spreads):
        return math.nan
    return math.hypot(spreads[0] * (ta_line - ta_base), spreads[1] * (tr_line - tr_base)) / slope


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
    if math.isfinite(res.shift):
        res = replace(res, shift_drift=drift_position_error(st, comp))
    if not math.isfinite(res.shift):
        missing = "retract" if comp.approach.found else "approach"
        return st.update("shift", res, warn=(
            f"inward/outward shift (hysteresis) not measured: the {missing} run has no unclipped "
            "constant-compliance line; the runs are not overlaid"))
    warn = None
    if undetermined(res.shift, res.shift_drift, max(SHIFT_DRIFT_WARN, 3.0 * res.shift_se)):
        res = replace(res, determined=False)
        warn = (f"inward/outward shift {UNDETERMINED}: the compliance lines are {res.shift * 1e9:.3g} nm apart, but the "
                f"drift lines extrapolated from the free parts to the compliance lines allow +-{res.shift_drift * 1e9:.3g} nm "
                f"(shift_drift), more than the shift itself: the interval [{(res.shift - res.shift_drift) * 1e9:.3g}, "
                f"{(res.shift + res.shift_drift) * 1e9:.3g}] nm holds both signs; record a longer, settled free part "
                "(or a slower drift) to measure it")
    elif res.shift_drift > max(SHIFT_DRIFT_WARN, 3.0 * res.shift_se):
        warn = (f"inward/outward shift {res.shift * 1e9:.3g} nm is known only to +-{res.shift_drift * 1e9:.3g} nm "
                "(shift_drift): the drift lines extrapolated from the free parts to the compliance lines allow that "
                "range of rates; its standard error (+-{:.2g} nm) is the lines' noise alone".format(res.shift_se * 1e9))
    if not apply:
        return st.update("shift", res, warn=warn)
    z = st.z.copy()
    z[st.approach.index] += res.shift
    return st.update("shift", res, z=z, warn=warn)


SHIFT = AnalysisStep("shift", "Inward/outward shift overlaying the compliance lines", shift, ShiftOptions,
                     requires=("kind",), reference="section 3.2, Fig 9; Fig 7C",
                     fields=(ResultField("shift", "m", "inward shift", summary=True, column=True, bound="shift_drift"),
                             ResultField("shift_drift", "m", "the shift's bound from the drift lines", column=True)),
                     collect=lambda st: {"shift": st.details["shift"].shift if st.details["shift"].determined
                                                  else math.nan,
                                         "shift_drift": st.details["shift"].shift_drift})
