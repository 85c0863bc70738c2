"""The ``kind`` step: contact kind (hard: jump-in or straight line; soft: curved) and a soft contact point.

Declared once by its record :data:`KIND` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import dataclasses
import math

from ...errors import AnalysisError
import numpy as np

from ..contact_point import CONTACT_POINT_METHODS, ContactKind, classify_contact, curvature_ratio
from ..jumps import BARRIER_KEEPS, find_jump_in
from ..options import KindOptions
from ..regions import SURFACE_MIN_NSIGMA, _surface_force_like
from ..registry import AnalysisStep, ResultField
from ..state import State
from .calibration import soft_slope

__all__ = ["kind", "KIND"]


def kind(st: State, o: KindOptions) -> State:
    """Contact kind (hard with jump-in or straight line / soft curved) and a soft contact's contact point.

    See :mod:`~afmforce.analysis.contact_point`: hard when the approach jumps
    into contact (above ``nsigma`` step noise; a jump through a repulsive barrier
    does not count, :attr:`~afmforce.analysis.jumps.JumpIn.through_barrier`) or its contact is a straight line
    the deflection follows (late/early slope ratio at most ``max_curvature``,
    deflection per position at least ``min_stiffness`` when the calibration is
    the file's); soft otherwise, with the contact point by ``method``.
    """
    nsigma, method, force_fraction, window = o.nsigma, o.method, o.force_fraction, o.window
    o.check_method(CONTACT_POINT_METHODS)
    noise = abs(st.noise * st.factor)
    app = st.approach
    # a jump through a repulsive barrier that keeps most of its load (a surface layer that yields: a gel's
    # breakthrough, Egel force volume curve 22: +4.38 -> +3.58 nm) says nothing of the contact after it: it
    # does not make the contact hard; its line then decides ...
    ji = find_jump_in(st.deflection, st.z, st.z, app, noise, math.nan, nsigma)
    jb = find_jump_in(st.deflection, st.z, st.z, app, noise, math.nan, nsigma, attractive_below=nsigma * noise)
    # ... unless it releases most of the load the barrier held: a tip that falls from the barrier into the
    # attraction or onto the contact (the DLVO jump; a drag-loaded jump at speed) has jumped into contact
    barrier = (jb.through_barrier and jb.index == ji.index     # the largest step near the split, through a barrier
               and jb.deflection_after > BARRIER_KEEPS * jb.deflection_before)
    sig = ji.significance if ji.index >= 0 and not barrier else 0.0
    cal = st.details["calibration"]
    comp = st.details["compliance"]
    stiff = (comp.approach.slope * cal.factor if cal.source == "metadata" and comp.approach.found else math.nan)
    contact_idx = app.index[app.contact & ~app.saturated]
    curv = curvature_ratio(st.z, st.deflection, contact_idx)
    min_stiffness = o.min_stiffness
    if st.metadata.get("deflection_interferometric") and min_stiffness == KindOptions.min_stiffness:
        min_stiffness = INTERFEROMETRIC_MIN_STIFFNESS  # the reader's word: no InvOLS error to allow for
    res = classify_contact(jump_significance=sig, stiffness_ratio=stiff, curvature=curv, nsigma=nsigma,
                           min_stiffness=min_stiffness, max_curvature=o.max_curvature)
    if res.kind == "soft" and not (math.isfinite(stiff) and stiff < min_stiffness):  # curved, not shallow
        decay = _surface_force_before_line(st, noise, o.max_curvature)
        if decay is not None:
            res = ContactKind("hard", SURFACE_FORCE_CONTACT.format(curvature=curv, decay=decay * 1e9),
                              sig, stiff, curv)
    new = st.update("kind", res)
    if res.kind == "hard":
        new = _recalibrate_hard(new, cal, curv, o.max_curvature)
        if cal.source == "fit" and not sig > nsigma and (not math.isfinite(curv) or curv > o.max_curvature):
            why = (f"the contact curves (slope ratio late/early {curv:.3g}), read as a surface force before a straight "
                   "line, which a soft sample the tip indents shows too" if math.isfinite(curv) else
                   "too few samples in contact to see whether the contact curves")
            new = new.update(warn=SLOPE_HARD_UNVERIFIED.format(
                sens=cal.factor * 1e9, why=why))
    if res.kind == "soft":
        cp = CONTACT_POINT_METHODS[method](st.z, st.deflection, app.index, force_fraction=force_fraction,
                                           window=window)
        if cp.index < 0:
            raise AnalysisError("soft contact: no contact point found on the approach (too few samples before "
                                "the largest deflection)")
        warn = None
        width = cp.position_high - cp.position_low
        steep = _steep_contact(st, cp, method, window) if width > max(100e-9, 0.1 * abs(cp.indentation)) else None
        if steep is not None:  # a slow rise, then a distinct steep contact: the contact is where it steepens
            warn = (f"slowly rising approach before contact: fitted over the whole approach the contact lies anywhere "
                    f"in [{cp.position_low * 1e6:.4g}, {cp.position_high * 1e6:.4g}] um (2 sigma); the steep contact "
                    f"after it begins at {steep.position * 1e6:.4g} um (indentation {steep.indentation * 1e6:.3g} um), "
                    "taken as the contact point")
            cp = steep
        elif width > max(100e-9, 0.1 * abs(cp.indentation)):
            warn = (f"contact point uncertain: {cp.position * 1e6:.4g} um, but fits with the contact anywhere in "
                    f"[{cp.position_low * 1e6:.4g}, {cp.position_high * 1e6:.4g}] um are as good within 2 sigma "
                    f"({width * 1e6:.3g} um, {width / abs(cp.indentation):.0%} of the {cp.indentation * 1e6:.3g} um "
                    "indentation): a slowly rising baseline or a long-range force before contact makes the onset "
                    "ambiguous")
        elif force_fraction < 1.0:  # how much the point depends on the fitted range: the whole approach
            alt = CONTACT_POINT_METHODS[method](st.z, st.deflection, app.index, force_fraction=1.0, window=window)
            if alt.index >= 0:
                gap = alt.position - cp.position
                if abs(gap) > max(100e-9, 0.5 * abs(cp.indentation)):  # the indentation uncertain by ~2x
                    warn = (f"contact point uncertain: fitted up to {force_fraction:.0%} of the deflection it lies at "
                            f"{cp.position * 1e6:.4g} um (indentation {cp.indentation * 1e6:.3g} um), fitted to the "
                            f"whole approach at {alt.position * 1e6:.4g} um ({gap * 1e6:+.3g} um): a slowly rising "
                            "baseline or a long-range force before contact makes the onset ambiguous")
                    # the interval holds both fits (it was the first fit's 2 sigma alone: tight, and wrong)
                    cp = dataclasses.replace(cp, position_low=min(cp.position_low, alt.position),
                                             position_high=max(cp.position_high, alt.position))
        if not cp.indentation > 0:  # the deflection rose more than the position travelled: no indentation
            warn = [warn, NEGATIVE_INDENTATION.format(rise=(cp.indentation * -1e9))]
        new = soft_slope(new.update("contact_point", cp, warn=warn))
    return new


#: Said where the compliance slope calibrates (no sensitivity in the file or given, or ``calibration`` fit) on a
#: contact called hard without a jump-in or a straight line: the slope is the lever's sensitivity only on a hard
#: contact, and nothing in the curve shows this one is (the virtual AFM's 2 kPa Hertz contact, 5 um sphere,
#: 0.1 N/m lever, 50 nm/V, its sensitivity removed: "hard", 795 nm/V, every force 16 x too large, said nowhere).
SLOPE_HARD_UNVERIFIED = (
    "calibration unverified: the compliance slope calibrates ({sens:.4g} nm/V), which holds only on a hard "
    "contact, and this one is called hard with no jump into contact and {why}: if the tip indents the sample, "
    "the sensitivity and every force are overestimated (no modulus is given); give the lever's sensitivity "
    "measured on a hard surface (`sensitivity`)")

#: Least deflection per position of a hard contact where the deflection is measured interferometrically
#: (Optics11 indenters, ``deflection_interferometric`` from the reader): no sensitivity (InvOLS) error widens it,
#: so a straight line the deflection follows at 0.78 of the piezo is an indentation (a Hertz contact stiffer than
#: the lever), not a rigid contact; the default ``min_stiffness`` (0.7) allows for an InvOLS off by ~30 %.
INTERFEROMETRIC_MIN_STIFFNESS = 0.9

#: A contact region curved only because a long-range repulsive surface force lifts the approach before a straight
#: contact line (a double layer in water: the two lines' split falls within its last decay lengths).
SURFACE_FORCE_CONTACT = (
    "no jump into contact; the contact region curves (slope ratio late/early {curvature:.3g}) only because a "
    "repulsive surface force rises before a straight contact line: the rise grows exponentially with the "
    "separation (decay length {decay:.3g} nm: a double layer, hydration or steric force; an indentation grows as "
    "a power), so it is a force before contact, not a soft sample the tip indents; the contact is the straight "
    "line's")


def _surface_force_before_line(st: State, noise: float, max_curvature: float) -> float | None:
    """Decay length [m] of a repulsive surface force rising before the approach's straight contact line, or
    None when the rise before that line has a contact's shape (a power of the indentation), or no line.

    The approach's compliance samples (the top of its contact region) must form a straight line; the
    samples before them in time, less the baseline line through the zero-force samples, must grow like a
    surface force of the separation (taken as the position less that rise: the deflection widens the gap) (:func:`afmforce.analysis.regions._surface_force_like`: the logarithmic
    slope does not fall towards the line, a decay length in its range). A Hertz onset's logarithmic slope
    falls as ``1.5 / delta``; an exponential's (a double layer, hydration, steric) stays ``1 / lambda``.
    """
    app = st.approach
    ok = ~app.saturated
    comp = app.index[app.compliance & ok]
    base = app.index[app.zero_force & ok]
    if comp.size < 3 or base.size < 3 or not noise > 0:
        return None
    line_curv = curvature_ratio(st.z, st.deflection, comp, min_points=12)
    if math.isfinite(line_curv) and not 1 / max_curvature <= line_curv <= max_curvature:
        return None
    first = comp.min()
    before = app.index[ok & (app.index < first) & ~app.zero_force]
    if before.size < 6:
        return None
    z, d = st.z, st.deflection
    zb = z[base] - z[base].mean()
    b, a = np.polyfit(zb, d[base], 1)
    rise = d[before] - (a + b * (z[before] - z[base].mean()))
    toward = 1.0 if z[comp].mean() > z[before].mean() else -1.0
    # the separation's change, less a constant: the position less the deflection (which widens the gap; a stiff
    # force gradient near the line would otherwise bend an exponential of the separation in the position)
    x = z[before] - toward * rise
    x_line = float(x.max() if toward > 0 else x.min())  # the side of the line (the test takes its direction)
    if not _surface_force_like(x, rise, x_line, noise):
        return None
    up = rise > SURFACE_MIN_NSIGMA * noise
    slope = np.polyfit(x[up], np.log(rise[up]), 1)[0]
    return float(1.0 / abs(slope))


#: A soft contact whose deflection rises more than its position travels after the contact point (the
#: indentation, their difference, negative): the deflection is overestimated, so no indentation is reported.
NEGATIVE_INDENTATION = (
    "physically impossible: after the contact point the deflection rises {rise:.3g} nm more than the position "
    "travels (a negative indentation): the deflection is overestimated, so the indentation is not reported; "
    "suspect input: sensitivity (an uncalibrated or stale InvOLS; `calibration` fit uses the compliance slope)")


#: The deflection may move at most this many times the position on a hard contact's straight compliance
#: line with the file's sensitivity before the file's is taken for impossible and the slope calibrates.
STALE_SENSITIVITY = 1.25


def _recalibrate_hard(st: State, cal, curvature: float, max_curvature: float) -> State:
    """The one case ``calibration.source=auto`` replaces the file's sensitivity by the compliance slope's:
    a hard contact on a measured (linear) position channel whose straight compliance line, with the file's
    sensitivity, has the deflection moving more than :data:`STALE_SENSITIVITY` times the position. In
    contact the position's travel is the deflection's plus the indentation's, and no sample indents
    backwards, so no contact lets the deflection outrun the position: the file's sensitivity is too large
    (a placeholder, such as an uncalibrated 100 nm/V, or a stale one) and the slope is the only calibration
    the curve allows. The opposite disagreement (the deflection moving less than the position: the
    Asylum SiN curve in air, 0.47 x) is possible (a soft sample the tip indents, a changed laser
    alignment, a position channel that is not the tip-sample distance): the file's sensitivity is kept
    and the calibration step warns. Never with a sensitivity the user gave, nor with
    ``calibration.source=metadata``; ``fit`` uses the slope anyway (compliance.calibrate)."""
    ratio = cal.factor_fit / cal.factor if cal.source == "metadata" and cal.factor else math.nan
    straight = math.isfinite(curvature) and 1 / max_curvature <= curvature <= max_curvature
    if (st.probe.sensitivity is not None or st.channel != "measured" or not straight or not math.isfinite(ratio)
            or not 0 < ratio < 1 / STALE_SENSITIVITY or cal.requested == "metadata"):
        return st
    new = dataclasses.replace(cal, factor=cal.factor_fit, source="fit")
    warn = (f"hard contact whose straight compliance line moves the deflection {1 / ratio:.3g} x the position with "
            f"the file's sensitivity (at most 1 on any contact): the file's sensitivity is impossible here (a "
            f"placeholder or stale InvOLS), the compliance slope calibrates ({cal.sensitivity_fit * 1e9:.4g} nm/V "
            f"instead of {cal.sensitivity * 1e9:.4g}; `calibration` metadata keeps the file's)")
    return st.update("calibration", new, warn=warn, factor=new.factor, deflection=st.signal * new.factor)


#: The repeated fit's baseline spans this many times the steep contact's own position travel (see _steep_contact).
LOCAL_BASELINE = 4.0


#: At most this many refits on the shortened run.
LOCAL_ROUNDS = 3


def _steep_contact(st: State, cp, method: str, window: float):
    """On an approach whose whole-run fit leaves the onset ambiguous (a slow rise over many um before a
    steep contact, e.g. a long cell-adhesion curve), the same fit once more on the approach after that
    onset, up to the largest deflection: its contact point when it lies clearly after the ambiguous range
    and is itself well defined (its range within 2.5 x the usual bound, max(10 % of its indentation, 100 nm)),
    else None.

    The fit's baseline is a straight line; the slow rise curves (convex) over the ~10 um before the
    contact, so a line through all of it lies below the rise just before the contact and the power
    term starts early to make up the difference (the 2016 CellHesion curve: 0.26 um before nanite's
    gradient_zero_crossing). The fit is therefore repeated on a local run, the baseline spanning
    :data:`LOCAL_BASELINE` times the steep contact's own position travel before it (over which the rise is
    straight), until the point moves less than half its 2-sigma range (at most :data:`LOCAL_ROUNDS`
    times). On that curve spans of 2-8 times give -25.93..-25.99 um; 1.5 times leaves too little
    baseline (-25.81 um)."""
    idx = st.approach.index
    sub = idx[st.z[idx] >= cp.position]
    if sub.size < 64:
        return None
    new = CONTACT_POINT_METHODS[method](st.z, st.deflection, sub, force_fraction=1.0, window=window)
    if new.index < 0 or not new.position > cp.position_high or not new.indentation > 0:
        return None
    z_end = float(st.z[sub].max())
    for _ in range(LOCAL_ROUNDS):  # the baseline line local: a slow rise curves over the um before the contact
        start = new.position - LOCAL_BASELINE * (z_end - new.position)
        local = idx[st.z[idx] >= start]
        if local.size < 64 or local.size >= sub.size:
            break
        again = CONTACT_POINT_METHODS[method](st.z, st.deflection, local, force_fraction=1.0, window=window)
        if again.index < 0 or not again.indentation > 0:
            break
        moved = abs(again.position - new.position)
        sub, new = local, again
        if moved <= 0.5 * (new.position_high - new.position_low):
            break
    if new.position_high - new.position_low > max(0.1 * new.indentation, 100e-9) * 2.5:
        return None
    return new


#: A soft contact's indentation is undetermined (NaN in the summary; the contact point and its interval stay
#: in the details) when the contact point's interval spans more than this fraction of it [-]: the same
#: "uncertain by ~2x" the contact point's warning names. A FluidFM cell curve whose baseline wanders by
#: nN over tens of um (NSFopen 1.1.18's `spec.nid`) gave 21.9 um where the whole-approach fit gives 3.2 um.
UNDETERMINED_INDENTATION_RATIO = 0.5


def indentation_determined(cp) -> bool:
    """Whether a soft contact point fixes its indentation: positive, its interval within
    :data:`UNDETERMINED_INDENTATION_RATIO` of it."""
    width = cp.position_high - cp.position_low
    return cp.indentation > 0 and not width > UNDETERMINED_INDENTATION_RATIO * cp.indentation


def _kind_fields(st: State) -> dict:
    k, cp = st.details["kind"], st.details.get("contact_point")
    return dict(contact_kind=k.kind, contact_kind_reason=k.reason,
                **({"indentation": cp.indentation if indentation_determined(cp) else math.nan}
                   if cp is not None else {}))


KIND = AnalysisStep(
    "kind", "Contact kind (hard: jump-in or straight line; soft: curved) and a soft contact point", kind, KindOptions,
    requires=("calibration",), channels=("deflection",), runs=("approach",),
    reference="afmforce (baseline line + power-law contact term; checked against nanite's fit_line_polynomial)",
    fields=(ResultField("contact_kind", None, default=""), ResultField("contact_kind_reason", None, default=""),
            ResultField("indentation", "m", "indentation (soft contact)", summary=True, column=True)),
    collect=_kind_fields)
