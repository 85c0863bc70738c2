"""The ``contact`` step: contact, constant-compliance and zero-force regions.

Declared once by its record :data:`CONTACT` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import math

import numpy as np

from ...errors import AnalysisError
from ..options import ContactOptions
from ..regions import check_compliance, find_run_regions, saturated_mask, without_baseline_step
from ..registry import AnalysisStep
from .._numeric import ptp
from .._step_helpers import line_slope
from ..state import ContactSummary, NoContact, State

__all__ = ["retract_dip", "approach_end_rise", "FALLBACK_RISE_SIGMAS", "contact_rise", "contact", "contact_summary",
           "regions_again", "CONTACT", "CONTACT_RISE_SIGMAS", "REGIONS_KEY"]


def retract_dip(signal: np.ndarray, idx: np.ndarray) -> tuple[float, float]:
    """Depth of the retract's pull-off below its own far baseline, and the noise [signal units].

    Depth: the retract's last 30 % (median) less the lowest level held for two consecutive
    samples (a single spike does not count; a stiff lever rings after the release, the first
    swing is the pull-off); noise: from sample-to-sample differences there (blind to drift).
    Evidence of a contact the approach does not show (a stiff lever, an attractive approach end).
    """
    if idx.size < 50:
        return math.nan, math.nan
    s = signal[idx]
    far = s[int(0.7 * s.size):]
    sigma = float(np.median(np.abs(np.diff(far)))) / (0.6745 * math.sqrt(2.0))
    low = float(np.min(np.maximum(s[:-1], s[1:])))
    return float(np.median(far)) - low, sigma


#: A zero-force baseline whose signal climbs with the position at this fraction of the contact line's
#: slope or more [-] is no free baseline: the run starts on its contact line (a hard contact: 0.86-1.0).
#: Measured on the 785 curves of tests/data, its corpus and the shared real files whose approach has
#: regions: at most 0.58 (JPK stress-relaxation cells, whose two lines leave the early indentation of the
#: soft cell on the free side), 0.28 the next; a free baseline's tilt, fringes and drift are a few per
#: cent. A soft sample indented from the first sample (Hertz: the early part climbs at a third to a half
#: of the later) is not told apart from those cells by this ratio and is not refused.
NO_BASELINE_RATIO = 0.75
#: ... when it climbs by this many noise sigmas over the baseline's positions [-].
NO_BASELINE_SIGMAS = 20.0
#: A "baseline" climbing this many times as steeply as the contact is no contact line either: a transient
#: or a drift (a JPK 2013 creep curve, matfiz/afm-curve-procesing ``force-save-2013.05.10-14.38.05``: the
#: approach's first half rises 1.3 nN as it settles, its contact 0.2 nN; ratio 13), and is refused as one [-].
STEEPER_THAN_CONTACT = 1.5


def _baseline_parts(z: np.ndarray, signal: np.ndarray, run) -> tuple:
    """What :func:`free_baseline_ratio` and :func:`contact_rise` both read off a run: its positions and
    signal, its zero-force samples' count, positions and slope (NaN under 3 samples); computed once when
    the contact step runs both checks."""
    idx = run.index
    zz, ss = z[idx], signal[idx]
    base = run.zero_force
    n_base = int(np.count_nonzero(base))
    zb = zz[base]
    sb = line_slope(zb, ss[base]) if n_base >= 3 else math.nan
    return zz, ss, n_base, zb, sb


def free_baseline_ratio(z: np.ndarray, signal: np.ndarray, run, parts: tuple | None = None) -> tuple[float, float]:
    """The slope of a run's zero-force region over its contact region's [-], and the baseline's climb over
    its positions in noise sigmas [-] (NaN when either region has fewer than 3 samples). ``parts``:
    :func:`_baseline_parts` of the same arguments, when known."""
    zz, ss, n_base, zb, sb = parts if parts is not None else _baseline_parts(z, signal, run)
    touch = run.contact
    if n_base < 3 or touch.sum() < 3:
        return math.nan, math.nan
    sc = line_slope(zz[touch], ss[touch])
    climb = abs(sb) * float(ptp(zb)) / run.noise if run.noise > 0 else math.inf
    return sb / sc if sc != 0 else math.nan, climb


#: The weaker contact test (an approach whose contact only the retract shows: a stiff lever) needs the approach
#: to end this many noise sigmas above its free baseline line [-]: a lever pressed on the surface bends away
#: from it. Measured: the JPK QI curves of tests/data/corpus that take this path end 7-10 sigmas above; two
#: JPK map curves that never reached the surface (nanite's `fmt-jpk-fd_map_bad_2013-05-27_*`, flagged
#: setpoint-out-of-range by the instrument) end 1-2 sigmas *below* it, 30 um of drift read as a soft contact.
FALLBACK_RISE_SIGMAS = 3.0


def approach_end_rise(z: np.ndarray, signal: np.ndarray, run) -> float:
    """How far the approach's last samples lie above the line through its zero-force samples, in the run's
    noise sigmas [-] (NaN when the regions are too small): the push of a repulsive contact."""
    idx = run.index
    base = idx[run.zero_force]
    if base.size < 3 or idx.size < 6 or not run.noise > 0:
        return math.nan
    zb, sb = z[base], signal[base]
    zm = float(zb.mean())
    slope, icpt = np.polyfit(zb - zm, sb, 1)
    tail = idx[-max(3, idx.size // 50):]
    end = float(np.median(signal[tail])) - (icpt + slope * (float(np.median(z[tail])) - zm))
    return end / run.noise


def _check_free_baseline(z: np.ndarray, signal: np.ndarray, run, parts: tuple | None = None) -> None:
    """Refuse an approach with no free part: its "baseline" climbs like its contact line
    (:data:`NO_BASELINE_RATIO`, :data:`NO_BASELINE_SIGMAS`): the zero of force, and every force, adhesion,
    sensitivity and contact point measured from it, would be a number taken in contact."""
    ratio, climb = free_baseline_ratio(z, signal, run, parts)
    if ratio >= STEEPER_THAN_CONTACT and climb >= NO_BASELINE_SIGMAS:
        raise AnalysisError(
            f"the approach has no free baseline: its far part climbs {ratio:.2g} times as steeply as its "
            f"contact ({climb:.3g} noise sigmas), a transient or a drift rather than a contact (the lever "
            "settling after the ramp's start?), so the zero of force is undetermined; record the approach "
            "from farther out or after the lever has settled")
    if ratio >= NO_BASELINE_RATIO and climb >= NO_BASELINE_SIGMAS:
        raise AnalysisError(
            f"the approach has no free baseline: its far part climbs with the position at {ratio:.2g} of the "
            f"contact's slope ({climb:.3g} noise sigmas), so the curve starts in contact and the zero of force "
            "is undetermined; record the approach from farther out (a baseline off the surface)")


#: An approach reaches the surface when its contact region climbs above its baseline's line by this many
#: noise sigmas over the contact region's positions [-] (every contact pushes the lever away, even the
#: adhesive line a jump lands on: a slope of about 1 in deflection; a virtual static curve's approach turned
#: 0.5-3 nm before its jump-in bends down by the attraction alone, -14 to -7 sigma, where its "compliance
#: line" gave a sensitivity of -0.25 to -0.69 um/V; the intact approach climbs 416 sigma).
CONTACT_RISE_SIGMAS = 5.0


def contact_rise(z: np.ndarray, signal: np.ndarray, run, parts: tuple | None = None) -> float:
    """How far the approach's unclipped compliance region climbs above its zero-force line's slope over its
    positions, in noise sigmas [-] (NaN when either region has fewer than 3 samples or no noise is known).
    ``parts``: :func:`_baseline_parts` of the same arguments, when known."""
    zz, ss, n_base, _, sb = parts if parts is not None else _baseline_parts(z, signal, run)
    top = run.compliance & ~run.saturated
    if n_base < 3 or top.sum() < 3 or not run.noise > 0:
        return math.nan
    zt = zz[top]
    sc = line_slope(zt, ss[top])
    return (sc - sb) * float(ptp(zt)) / run.noise


def _check_contact_reached(z: np.ndarray, signal: np.ndarray, run, parts: tuple | None = None) -> None:
    """Say :class:`NoContact` (contact kind "none") when the approach's contact region does not climb
    (:data:`CONTACT_RISE_SIGMAS`): the approach stopped short of the surface, and the "compliance line" the
    regions found is the attraction's bend or the noise."""
    rise = contact_rise(z, signal, run, parts)
    if rise < CONTACT_RISE_SIGMAS and not approach_end_rise(z, signal, run) > CONTACT_RISE_SIGMAS:
        # (an approach whose last samples push the lever off its baseline's line touched, whatever its
        # contact region's slope says: NSFopen 1.1.18's FluidFM cell curve 1 ends 9 nN up at its trigger)
        how = "bends down (an attraction only)" if rise < -CONTACT_RISE_SIGMAS else "stays on its baseline"
        raise NoContact(f"no contact reached: the approach's end {how}, {rise:.3g} noise sigmas from its baseline's "
                        f"line where a contact climbs {CONTACT_RISE_SIGMAS:g} or more; the approach stops short of "
                        "the surface, so there is no contact point, sensitivity, modulus or adhesion")


def contact(st: State, o: ContactOptions) -> State:
    """Contact, constant-compliance and zero-force regions of both runs.

    A run clipped at its turning point whose contact region is no
    constant-compliance line (see :func:`~afmforce.analysis.regions.check_compliance`: not
    ``1 / flat_ratio`` times steeper than its free part, or, on the measured
    channel, ``max_slope_ratio`` times shallower than the other run's;
    ``"auto"``: 2 on the measured channel, no limit on the nominal one, whose
    creep changes the local gain) keeps no compliance line; later steps use
    the other run's and say what could not be measured.
    """
    max_slope_ratio = o.max_slope_ratio  # the record checked the ranges (> 1; flat_ratio in (0, 1])
    if max_slope_ratio == "auto":
        max_slope_ratio = 2.0 if st.channel == "measured" else math.inf
    max_slope_ratio, flat_ratio = float(max_slope_ratio), o.flat_ratio
    sat = saturated_mask(st.signal)
    kw = dict(saturated=sat, min_points=int(o.min_points), baseline_fraction=o.baseline_fraction,
              compliance_fraction=o.compliance_fraction)
    if st.missing_run:
        return _one_run(st, sat, kw)
    try:
        app = find_run_regions(st.z, st.signal, st.run_index(0), "approach", **kw)
    except AnalysisError as exc:
        if not str(exc).startswith("no contact region"):
            raise
        app = None
        try:  # a stiff lever barely deflects on the approach: the retract's adhesion shows the contact
            find_run_regions(st.z, st.signal, st.run_index(1), "retract", **kw)
            app = find_run_regions(st.z, st.signal, st.run_index(0), "approach",
                                   min_contrast=5.0, **kw)
        except AnalysisError:
            pass
        rise = approach_end_rise(st.z, st.signal, app) if app is not None else math.nan
        if app is not None and not rise > FALLBACK_RISE_SIGMAS:
            # a "contact" the approach does not push into: drift or a wandering baseline (the lever ends the
            # approach at or below its free baseline line), not a touch of the surface
            app = None
            where = "below" if rise < 0 else "above"
            exc = AnalysisError(f"no contact reached: the approach ends {abs(rise):.2g} noise sigmas {where} its "
                                "free baseline line (a lever pressed on the surface bends away from it): drift, "
                                "not a contact")
        if app is None:
            raise NoContact(str(exc).replace("no contact region found on the approach run", "no contact reached")
                            ) from None
    app, stepped = without_baseline_step(st.signal, app, st.unit)  # a glitch's level step: the part after it
    parts = _baseline_parts(st.z, st.signal, app)  # the approach's baseline line, read once by both checks
    _check_free_baseline(st.z, st.signal, app, parts)
    _check_contact_reached(st.z, st.signal, app, parts)
    ret = find_run_regions(st.z, st.signal, st.run_index(1), "retract", noise=app.noise, **kw)
    app, ret = check_compliance(st.z, st.signal, app, ret, flat_ratio=flat_ratio, max_slope_ratio=max_slope_ratio)
    summary = contact_summary(app, ret, int(sat.sum()))
    st.cache[REGIONS_KEY] = (kw, flat_ratio, max_slope_ratio)   # for the fringes step's second look
    warn = [stepped] if stepped else []
    if sat.any():
        warn.append(f"{int(sat.sum())} saturated samples (photodiode clipped) left out of the fits")
    warn += [r.note for r in (app, ret) if r.note]
    # noise of the signal from sample-to-sample differences in the approach's free part: blind to
    # slow structure (drift, fringes), so it measures the resolution the jump tests need
    return st.update("contact", summary, warn=warn, approach=app, retract=ret, noise=app.noise)


#: Where the contact step leaves its region options in the state's cache (the fringes step finds the regions
#: again on a signal whose fringes hid them).
REGIONS_KEY = "contact_regions"


def contact_summary(app, ret, saturated: int) -> ContactSummary:
    """The :class:`ContactSummary` of both runs' regions (``saturated``: the curve's clipped samples)."""
    return ContactSummary(int(app.index[app.split]), int(ret.index[min(ret.split, ret.index.size - 1)]),
                          int(app.zero_force.sum()), int(ret.zero_force.sum()), int(app.compliance.sum()),
                          int(ret.compliance.sum()), int(saturated))


def regions_again(st: State, z: np.ndarray, signal: np.ndarray):
    """Both runs' regions found on another position and signal with the contact step's options (``(approach,
    retract)``), or None when the contact step left none (a curve of one run) or they cannot be found."""
    spec = st.cache.get(REGIONS_KEY)
    if spec is None or st.approach is None or st.retract is None:
        return None
    kw, flat_ratio, max_slope_ratio = spec
    try:
        app = find_run_regions(z, signal, st.approach.index, "approach", **kw)
        app = without_baseline_step(signal, app, st.unit)[0]   # (the contact step said it)
        ret = find_run_regions(z, signal, st.retract.index, "retract", noise=app.noise, **kw)
        return check_compliance(z, signal, app, ret, flat_ratio=flat_ratio, max_slope_ratio=max_slope_ratio)
    except AnalysisError:
        return None


def _one_run(st: State, sat: np.ndarray, kw: dict) -> State:
    """The regions of a curve of one run (the other is None; its region sizes -1): the run's own noise."""
    which, word = (1, "retract") if st.missing_run == "approach" else (0, "approach")
    try:
        run = find_run_regions(st.z, st.signal, st.run_index(which), word, **kw)
    except AnalysisError as exc:
        if not str(exc).startswith("no contact region"):
            raise
        raise NoContact(str(exc)) from None
    stepped = None
    if word == "approach":
        run, stepped = without_baseline_step(st.signal, run, st.unit)
    split = int(run.index[min(run.split, run.index.size - 1)])
    own = (split, int(run.zero_force.sum()), int(run.compliance.sum()))
    app, ret = (own, (-1, -1, -1)) if word == "approach" else ((-1, -1, -1), own)
    summary = ContactSummary(app[0], ret[0], app[1], ret[1], app[2], ret[2], int(sat.sum()))
    warn = [f"{int(sat.sum())} saturated samples (photodiode clipped) left out of the fits"] if sat.any() else []
    warn += [run.note] if run.note else []
    warn += [stepped] if stepped else []
    return st.update("contact", summary, warn=warn, noise=run.noise, **{word: run})


CONTACT = AnalysisStep("contact", "Contact, constant-compliance and zero-force regions", contact, ContactOptions,
                       after=("smooth",), reference="section 3.1, Fig 7", runs=())
