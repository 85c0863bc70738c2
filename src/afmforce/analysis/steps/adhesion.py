"""The ``adhesion`` step: the deepest retract dip below its own baseline, last rupture, unbinding steps;
on a hard contact the tip--surface detachment, with the tethers pulled after it (:mod:`..tethers`).

Declared once by its record :data:`ADHESION` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..._fields import check
from ...constants import DEFAULT_TEMPERATURE
from .._median import median
from .._step_helpers import _kind, line_slope
from ..options import AdhesionOptions
from ..registry import AnalysisStep, ResultField
from ..state import State
from ..unbinding import retract_adhesion

__all__ = ["adhesion_step", "ADHESION"]


#: A retract whose last tenth climbs with the position at this fraction of the approach's contact line or
#: more, below zero force, is still on its (adhesive) contact line at its end [-].
ATTACHED_SLOPE_RATIO = 0.5
#: ... its last tenth lying this many deflection noise sigmas below zero force [-].
ATTACHED_SIGMAS = 10.0


def attached_at_end(st: State) -> str | None:
    """Why no adhesion is reported when the retract ends before the pull-off (the record stops while the tip
    is still held on its contact line, below zero force), else None.

    Read off the recorded signal against the position (the drift line may have been fitted through that
    line, taken for the retract's baseline): the retract's last tenth (at least 5 samples) climbs with the
    position at :data:`ATTACHED_SLOPE_RATIO` of the approach's compliance line or more and lies
    :data:`ATTACHED_SIGMAS` noise sigmas below the approach's zero-force level. The pull-off lies beyond
    the record, and the adhesion is larger than the pull at its last samples (a lower bound, given in the
    reason). Before, the retract's own "baseline" was taken on that line: a static curve of known truth
    whose record stops 100 nm into its 267 nm adhesive line reported an adhesion of 0.11 nN at -3.2 um
    "from contact" (the truth: more than 21 nN; 56 nN at the pull-off).
    """
    app, ret = st.approach, st.retract
    if app is None or ret is None or ret.index.size < 20 or not st.noise > 0.0:
        return None
    comp, base = app.index[app.compliance], app.index[app.zero_force]
    if comp.size < 3 or base.size < 3:
        return None
    z, s = st.z, np.asarray(st.curve.deflection_signal, float)
    tail = ret.index[-max(5, ret.index.size // 10):]
    line, end = line_slope(z[comp], s[comp]), line_slope(z[tail], s[tail])
    zt, st_ = z[tail], s[tail]   # the tail's line at its last sample: the pull where the record stops
    level = float(st_.mean() + end * (zt[-1] - zt.mean()) - median(s[base]))
    if not (line != 0.0 and end / line >= ATTACHED_SLOPE_RATIO and level * math.copysign(1.0, line)
            < -ATTACHED_SIGMAS * st.noise):
        return None
    pull = abs(level * st.factor) * st.spring_constant if math.isfinite(st.factor) else math.nan
    bound = f"{pull * 1e9:.3g} nN" if math.isfinite(pull) and pull > 0 else f"{abs(level):.3g} {st.unit} of signal"
    return (f"not available: the retract ends before the pull-off (its last samples are still on the contact "
            f"line, {abs(level) / st.noise:.3g} noise sigmas below zero force): the adhesion is larger than "
            f"{bound}, the pull at the end of the record; record a longer retract")


def tether_temperature(st: State) -> float:
    """The temperature of the tethers' worm-like-chain fits [K]: the file's (``temperature`` in its metadata,
    ``--meta temperature=...``), checked against its declared range, else
    :data:`~afmforce.constants.DEFAULT_TEMPERATURE` (295 K)."""
    t = st.metadata.get("temperature")
    return DEFAULT_TEMPERATURE if t is None else float(check("temperature", float(t)))


def adhesion_step(st: State, o: AdhesionOptions) -> State:
    """Adhesion for every contact kind: the retract's deepest dip below its own baseline (<= 0).

    See :mod:`~afmforce.analysis.unbinding`; the dip counts above ``o.nsigma``
    baseline noise, with its position, the last rupture and the unbinding steps. On a hard contact the
    dip is the tip--surface detachment's (before the retract comes back to its baseline) and later dips
    are tethers, every rupture counted (:mod:`~afmforce.analysis.tethers`).
    """
    po = st.details["jumps"].pull_off if "jumps" in st.details else None
    attached = None if po is not None and po.found else attached_at_end(st)
    if attached:   # no free part after the pull-off: the retract's "baseline" would be its contact line
        return st.update(skipped={**st.skipped, "adhesion": attached}, warn=attached)
    # the tip leaves a rigid surface, then may pull tethers (analysis.tethers); a kind not known (a retract
    # exported alone) keeps the deepest dip
    rigid = "kind" in st.details and _kind(st) == "hard"
    hard = po is not None and po.found and rigid  # the paper's pull-off jump ends the dip
    res = retract_adhesion(st.deflection, st.position, st.retract, st.spring_constant, nsigma=o.nsigma,
                           pull_off=po.index if hard else -1, separation=st.separation, hard=rigid,
                           time=st.time if st.time_known else None, temperature=tether_temperature(st),
                           wlc_model=o.wlc_model)
    warn = None
    if (po is not None and po.found and math.isfinite(po.force) and po.force < 0 and res.found and math.isfinite(res.force)
            and abs(res.force) < 0.5 * abs(po.force)):
        # both are below zero force; they differ only by the baseline each is measured from
        warn = (f"adhesion {res.force * 1e9:.3g} nN (from the retract's own baseline) is under half the pull-off "
                f"force {po.force * 1e9:.3g} nN (from the drift-corrected zero): the retract's free part does not "
                "return to the approach's baseline (still relaxing, drift, or an offset at the turn); "
                "trust the pull-off only with a settled baseline")
    negative, withhold = _negative_rupture(st, res, hard)
    if withhold:   # beyond its uncertainty a rupture inside the compliance line is no distance: not reported
        res = dataclasses.replace(res, rupture_distance=math.nan)
    return st.update("adhesion", res, warn=[warn, negative])


#: A negative rupture separation within this many deflection noise sigmas (beside the drift bound) is the
#: noise of the one sample it is read at [-].
NEGATIVE_RUPTURE_SIGMAS = 3.0


def rupture_drift(st: State) -> float:
    """The bound on a hard contact's rupture (pull-off) separation from the drift lines [m]: the shift's
    (``shift_drift``, :func:`afmforce.analysis.steps.shift.drift_position_error`): the retract's separation
    is read against the approach's compliance line through the shift, so a drift line that moves one moves
    the other; NaN when the shift was not assessed."""
    sh = st.details.get("shift")
    return float(sh.shift_drift) if sh is not None else math.nan


def _negative_rupture(st: State, res, hard: bool) -> tuple[str | None, bool]:
    """A warning for a hard contact's rupture at a negative separation, and whether to withhold the number:
    physically the tip cannot leave the surface inside its compliance line, so the number is the drift
    lines' error (within ``rupture_drift`` and :data:`NEGATIVE_RUPTURE_SIGMAS` noise: reported, with the
    warning) or not a result (beyond them: withheld, ``rupture_distance`` NaN, the warning says why).
    JSotres/FSAS' NanoScope 8.15 force volume reported 132 of its 256 ruptures at -0.02 to -9.9 nm beside a
    warning; beyond the bound they are now NaN."""
    r = getattr(res, "rupture_distance", math.nan)
    if not (hard and res.found and math.isfinite(r) and r < 0):
        return None, False
    b = rupture_drift(st)
    # one sample's separation carries the deflection's noise: NEGATIVE_RUPTURE_SIGMAS of it, beside the bound
    sigma = abs(st.noise * st.factor) if math.isfinite(st.factor) else math.nan
    allowed = math.hypot(b, NEGATIVE_RUPTURE_SIGMAS * sigma) if math.isfinite(sigma) else b
    if math.isfinite(allowed) and -r <= allowed:
        return (f"rupture at {r * 1e9:.3g} nm, inside the compliance line (physically impossible), within the "
                f"drift lines' bound of +-{b * 1e9:.3g} nm (rupture_distance_drift) and "
                f"{NEGATIVE_RUPTURE_SIGMAS:g} deflection noise sigmas ({sigma * 1e9:.2g} nm): the tip left at about "
                "zero separation; the separation is not resolved better than that"), False
    bound = f"the drift lines' bound +-{b * 1e9:.3g} nm" if math.isfinite(b) else "no drift bound assessed"
    head = (f"rupture at {r * 1e9:.3g} nm, inside the compliance line (physically impossible) and beyond "
            f"{bound}: not reported (rupture_distance NaN): ")
    steep = _retract_contact_rate(st)
    if steep is not None:  # the sensitivity, not the zero: in contact the separation itself runs backwards
        return (head + f"on the retract's contact line the deflection moves {steep:.3g} x the position with the "
                "sensitivity used, so the separation runs backwards in contact and the rupture's is no distance; "
                "suspect input: sensitivity (`calibration` fit uses the compliance slope)"), True
    return head + "the separation's zero or the retract's baseline is wrong on this curve", True


def _retract_contact_rate(st: State) -> float | None:
    """The retract's compliance line as deflection per position with the sensitivity used, where it runs
    backwards (above :data:`~afmforce.analysis.plausibility.MAX_CONTACT_SLOPE`); None otherwise. JSotres/FSAS'
    NanoScope 8.15 force volume (DeflSens 41.14 nm/V, its contact lines 1.35-1.38 x the ramp): 132 of 256
    ruptures at -0.02 to -9.9 nm, blamed on "the separation's zero or the retract's baseline"."""
    from ..plausibility import MAX_CONTACT_SLOPE

    comp = st.details.get("compliance")
    line = getattr(comp, "retract", None)
    if line is None or not getattr(line, "found", False) or not math.isfinite(st.factor):
        return None
    rate = line.slope * st.factor
    return float(rate) if math.isfinite(rate) and rate > MAX_CONTACT_SLOPE else None


def _adhesion_fields(st: State) -> dict:
    a = st.details["adhesion"]
    ts = [t for t in a.tethers if t.tether]
    top = min(ts, key=lambda t: t.force) if ts else None   # the tether of tether_force: its fit in the table
    fit = top.wlc if top is not None and top.wlc is not None else None
    nan = math.nan
    return dict(adhesion_force=a.force, adhesion_deflection=a.deflection, adhesion_distance=a.distance,
                adhesion_noise=a.noise, adhesion_significance=a.dip_sigmas,
                adhesion_baseline_spread=a.baseline_spread, rupture_distance=a.rupture_distance,
                adhesion_return_distance=a.return_distance,
                rupture_distance_drift=rupture_drift(st) if a.found and "kind" in st.details and _kind(st) == "hard"
                else nan, unbinding_steps=len(a.steps),
                tethers=len(ts), tether_force=top.force if top else nan,
                tether_contour_length=fit.contour_length if fit else nan,
                tether_contour_length_se=fit.contour_length_se if fit else nan,
                tether_persistence_length=fit.persistence_length if fit else nan,
                tether_persistence_length_se=fit.persistence_length_se if fit else nan,
                tether_loading_rate=top.loading_rate if top else nan,
                tether_fits=tether_lines(ts), adhesion_verdict=a.verdict)


def _pm(v: float, se: float, scale: float, unit: str) -> str:
    return f"{v * scale:.4g} +- {se * scale:.2g} {unit}" if math.isfinite(v) else "undetermined"


def tether_lines(ts) -> str:
    """One clause per tether (its rupture, worm-like-chain fit and loading rate), joined by `` | ``: the table's
    ``tether_fits`` column and the lines ``afmforce analyze`` prints under its table."""
    out = []
    for n, t in enumerate(ts, 1):
        f = t.wlc
        line = (f"tether {n} at {t.separation * 1e9:.4g} nm: rupture {t.force * 1e12:.4g} pN, loading rate "
                f"{_pm(t.loading_rate, t.loading_rate_se, 1e9, 'nN/s')}")
        why = [t.loading_rate_reason] if t.loading_rate_reason else []
        how = ""
        if f is not None:
            line += (f"; WLC L_c {_pm(f.contour_length, f.contour_length_se, 1e9, 'nm')}, l_p "
                     f"{_pm(f.persistence_length, f.persistence_length_se, 1e9, 'nm')}")
            why = ([f.reason] if f.reason else []) + why
            how = f" ({f.model}, {f.temperature:g} K, {f.points} samples)"
        out.append(line + "".join(f"; {w}" for w in why) + how)
    return " | ".join(out)


ADHESION = AnalysisStep(
    "adhesion", "Adhesion: deepest retract dip below its own baseline, last rupture, unbinding steps",
    adhesion_step, AdhesionOptions, requires=("zero", "force"), channels=("position",),
    reference="afmforce (every contact kind)", runs=("retract",),
    fields=(ResultField("adhesion_force", "N", "adhesion (deepest retract dip)", summary=True, column=True),
            ResultField("adhesion_deflection", "m", "adhesion as a deflection"),
            ResultField("adhesion_distance", "m", "adhesion position from contact", summary=True, column=True),
            ResultField("adhesion_noise", "N", "baseline noise of the retract", column=True),
            ResultField("adhesion_significance", "", "deepest retract dip in baseline noise sigmas (also under "
                        "the threshold)", column=True),
            ResultField("adhesion_baseline_spread", "N", "the baseline model's systematic on the adhesion (+-)",
                        column=True),
            ResultField("rupture_distance", "m", "last rupture from contact (hard contact: its separation)",
                        summary=True, column=True),
            ResultField("adhesion_return_distance", "m", "soft contact: where the retract comes back to its "
                        "baseline for good, from contact", column=True),
            ResultField("rupture_distance_drift", "m", "its bound from the drift lines (hard contact: the shift's)",
                        column=True),
            ResultField("unbinding_steps", "", "unbinding steps", default=0, column=True),
            ResultField("tethers", "", "tethers pulled after the tip left a hard surface", default=0, column=True,
                        map=True),
            ResultField("tether_force", "N", "largest tether pull at its rupture (hard contact)", column=True,
                        map=True),
            ResultField("tether_contour_length", "m", "contour length L_c of that tether's worm-like-chain fit",
                        column=True, map=True),
            ResultField("tether_contour_length_se", "m", "its standard error", column=True),
            ResultField("tether_persistence_length", "m", "persistence length l_p of that tether's fit",
                        column=True, map=True),
            ResultField("tether_persistence_length_se", "m", "its standard error", column=True),
            ResultField("tether_loading_rate", "N/s", "loading rate at that tether's rupture", column=True,
                        map=True),
            ResultField("tether_fits", None, "every tether: rupture, worm-like-chain fit, loading rate",
                        default=""),
            ResultField("adhesion_verdict", None, default="")),
    collect=_adhesion_fields)
