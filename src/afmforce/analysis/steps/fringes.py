"""The ``fringes`` step: interferometric calibration from baseline fringes.

Declared once by its record :data:`FRINGES` (:mod:`afmforce.analysis.registry`).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .._numeric import ptp
from .._step_helpers import _zero_deflection_position
from ..fringes import FringeResult, fit_fringes, fringe_baseline, fringe_signal, loop_width, position_map
from ..options import FringesOptions
from ..registry import AnalysisStep
from ..state import State
from .contact import contact_summary, regions_again

__all__ = ["fringes", "FRINGES", "SPLIT_MOVE_PERIODS"]

#: The contact regions are replaced by those found on the signal without its fringes when a run's contact
#: split moves by more than this fraction of the fringe period [-] (a fringe's flank: a quarter period; the
#: virtual curve with fringes 15 nm deep moved 197 nm, 0.6 period; the paper preset's 17 um/s run, fringes
#: 4 nm deep, moves by the split's own scatter, 3 samples).
SPLIT_MOVE_PERIODS = 0.25


def fringes(st: State, o: FringesOptions) -> State:
    """Fit interference fringes in the baseline; remove them, remap nominal positions.

    ``apply="auto"``: when both runs show fringes, subtract them from the signal,
    and remap the positions if they are the piezo's *nominal* ones (a measured
    position is taken as linear, as the paper found for its detector, Fig 7B);
    ``"always"``: subtract and remap; ``"never"``: report only.

    The fit carries a line in time (what the drift step's line, pulled by the
    fringes, left of the baseline); it is subtracted with the fringes. In
    contact the fringe term is held at its value where the run's own contact
    line crosses zero signal (the separation no longer changes there).
    """
    apply, margin = o.apply, o.margin
    runs, base = {}, {}
    for run in (st.approach, st.retract):
        idx = run.index[run.zero_force & ~run.saturated]  # the baseline: not the attraction, nor a settling tail
        zf = st.z[idx]
        z_split = st.z[run.index[min(run.split, run.index.size - 1)]]
        far = np.abs(zf - z_split) > margin * (ptp(zf) if zf.size else 0.0)  # not the attraction near contact
        if run.kind == "retract" and not runs["approach"].found and apply != "always":
            # fringes are a property of the optics, present on both runs: without them on the
            # approach nothing is changed whatever the retract shows, so it is not searched
            runs["retract"] = dataclasses.replace(runs["approach"], found=False, explained=math.nan,
                                                  period=math.nan, cycles=math.nan, residual=math.nan)
            searched = False
            continue
        base[run.kind] = (zf[far], st.signal[idx][far], st.time[idx][far] if st.time_known else None)
        runs[run.kind] = fit_fringes(*base[run.kind][:2], period=o.period, order=o.order, t=base[run.kind][2])
        searched = True
    fa, fr = runs["approach"], runs["retract"]
    # real fringes are periodic in the true position: both runs show the same period
    both = fa.found and fr.found and abs(fa.period - fr.period) < 0.05 * 0.5 * (fa.period + fr.period)
    alone, on_retract = (None, None) if both or apply != "auto" or not fa.found or fr.found else \
        approach_only(fa, *base["retract"])
    if alone:   # fringes the retract cannot show (the approach's fit removes them there too), or does not show
        fr = on_retract if on_retract is not None else dataclasses.replace(fr, period=math.nan)
    remove = apply == "always" or (apply == "auto" and (both or bool(alone)))
    remap = apply == "always" or (apply == "auto" and both and st.channel == "nominal")
    z, s = _remove(st, st.approach, st.retract, fa, fr, o, remove, remap)
    regions, notes = {}, []
    if remove and (both or alone):
        # fringes as deep as the contact's rise put the contact split on a fringe's flank (a virtual curve's
        # 15 nm fringes gave a sensitivity of 214 nm/V for 50): the regions are found again without them
        # on the signal with the fringe term removed everywhere (the baseline clean, the contact bent a little)
        zf, sf = _remove(st, st.approach, st.retract, fa, fr, dataclasses.replace(o, in_contact="follow"), remove,
                         remap)
        again = regions_again(st, zf, sf)
        period = fa.period if alone else 0.5 * (fa.period + fr.period)
        at = lambda run: st.z[run.index[min(run.split, run.index.size - 1)]]  # noqa: E731
        moved = 0.0 if again is None else max(abs(at(run) - at(new))
                                              for run, new in zip((st.approach, st.retract), again))
        if moved > SPLIT_MOVE_PERIODS * period:
            z, s = _remove(st, *again, fa, fr, o, remove, remap)
            regions = dict(approach=again[0], retract=again[1], noise=again[0].noise)
            notes.append(f"fringes of amplitude {fa.amplitude if alone else max(fa.amplitude, fr.amplitude):.3g} {st.unit} "
                         "hid the contact: "
                         "its regions were found again on the signal without them")
    if alone:
        notes.append(f"interference fringes on the approach only (period {fa.period * 1e9:.4g} nm, amplitude "
                     f"{fa.amplitude:.3g} {st.unit}): {alone}")
    applied = remap
    width = loop_width(fa, fr, st.z[np.concatenate([st.approach.index, st.retract.index])]) if fa.found and fr.found else math.nan  # (loop_width's own NaN)
    if alone:
        verdict = f"fringes of period {fa.period * 1e9:.4g} nm found on the approach only: {alone}"
    elif both:
        verdict = (f"fringes of period {0.5 * (fa.period + fr.period) * 1e9:.4g} nm; position nonlinearity "
                   f"{max(fa.nonlinearity, fr.nonlinearity) * 100:.3g} %; loop width {width * 1e9:.3g} nm "
                   "(modulo one period)")
    elif fa.found or fr.found:
        verdict = "periodic baseline on one run only, or periods that differ: not fringes; nothing changed"
    elif not searched:
        why = "" if fa.converged else "; the fit wanders: no clean period"
        verdict = (f"no interference fringes in the approach baseline (a periodic term explains "
                   f"{max(fa.explained, 0.0):.2g} of its variance{why}); the retract was not "
                   "searched (fringes come from the optics and show on both runs)")
    else:
        verdict = "no interference fringes detected in the baseline"
    res = FringeResult(fa, fr, width, applied, verdict)
    if regions:
        st = st.update("contact", contact_summary(regions["approach"], regions["retract"],
                                                  st.details["contact"].saturated))
    return st.update("fringes", res, warn=notes, z=z, signal=s, **regions)


#: Fringes on the approach only are removed when its fit explains at least this fraction of its baseline [-] ...
ALONE_EXPLAINED = 0.8
#: ... over at least this many periods [-], and the retract's free baseline spans less than one period (too
#: short to show one) or holds, at the approach's period, at most this fraction of the approach's amplitude [-]
#: (fringes come from the optics and show on both runs, so a retract long enough to show them and showing
#: a periodic baseline that the fit does not take for fringes (a chirped or wandering one: the Nanosurf
#: Tap150 map's curves) leaves the curve as recorded).
ALONE_CYCLES = 1.5
ALONE_RETRACT_FRACTION = 0.1


def approach_only(fa, z: np.ndarray, r: np.ndarray, t: np.ndarray | None):
    """Why the fringes ``fa`` found on the approach alone are removed from it (None: they are not), and the fit
    that removes them from the retract (None: the retract is left as recorded).

    ``z, r, t``: the retract's free baseline (position [m], signal, times [s] or None) the fringe fit saw.
    A baseline shorter than a period cannot show them, one longer may hold none at the approach's period:
    either way the retract keeps its signal. (The approach's fringes subtracted from a short retract, with its
    phase, moved its contact by the error of the held fringe value: the virtual curve's adhesion under 50 nm
    fringes went from 9 % to 31 % off.)"""
    if not (fa.explained >= ALONE_EXPLAINED and fa.cycles >= ALONE_CYCLES and math.isfinite(fa.period)):
        return None, None
    span = float(ptp(z)) if z.size else 0.0
    v = t if t is not None else z
    if span < fa.period:   # the retract's share of them cannot be fitted: left, and said
        return (f"the retract's free baseline spans {span / fa.period:.2g} of a period, too short to show them: "
                f"removed from the approach; the retract is left as recorded, its baseline (and the adhesion, the "
                f"pull-off) uncertain by up to their amplitude"), None
    th = 2 * math.pi * z / fa.period
    X = np.column_stack([np.cos(th), np.sin(th), np.ones_like(z), v - v.mean()])
    coef, *_ = np.linalg.lstsq(X, r, rcond=None)
    amp = math.hypot(coef[0], coef[1])
    if amp <= ALONE_RETRACT_FRACTION * fa.amplitude:
        return (f"the retract's free baseline, {span / fa.period:.2g} periods long, holds {amp / fa.amplitude:.2g} "
                "of their amplitude at that period: removed from the approach, the retract left as recorded"), None
    return None, None


def _remove(st: State, approach, retract, fa, fr, o: FringesOptions, remove: bool, remap: bool):
    """The position and signal with the fringes removed from each run (held at the contact value over the
    run's contact region with ``in_contact="hold"``) and the positions remapped."""
    z, s = st.z.copy(), st.signal.copy()
    for run, fit in ((approach, fa), (retract, fr)):
        if not (remove and math.isfinite(fit.period)):
            continue
        idx = run.index
        term = fringe_signal(st.z[idx], fit)
        if o.in_contact == "hold":
            z_contact = _zero_deflection_position(st, run if run.has_compliance else approach)
            term = np.where(run.contact, fringe_signal(np.array([z_contact]), fit)[0], term)
        s[idx] = st.signal[idx] - term - fringe_baseline(st.time[idx], st.z[idx], fit)
        if remap:
            z[idx] = position_map(st.z[idx], fit)
    return z, s


FRINGES = AnalysisStep("fringes", "Interferometric calibration from baseline fringes", fringes, FringesOptions,
                       requires=("drift",), channels=("approach",), reference="section 3.1, Fig 7A; spec section 6")
