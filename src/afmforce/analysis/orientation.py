"""The order of a curve's samples: one approach-retract cycle, each run in the order it was acquired.

Files store curves in the ways their instruments and export scripts chose, and some break afmforce's
conventions (:mod:`afmforce.io.curve`: the approach, segment 0, first, its position growing towards the
sample; the retract, segment 1, after it, moving away) in ways the readers cannot see:

* several approach-retract cycles in one record (a force-clamp or a repeated ramp): only the first cycle
  is kept, with a warning (the pipeline analyses one cycle; before, the cycles were pooled into one
  "approach" and one "retract" and the contact came out soft, the jumps and the adhesion lost);
* a run stored from its end to its start: with a time column that runs backwards in it, or (a fresh time
  column) a retract whose position moves towards the sample while the approach's does too: the run is put
  back in acquisition order (before: "no contact region found on the retract run");
* the labels swapped (the approach's samples marked retract and the retract's approach): the position
  then moves the way a position stored as the distance from the sample would, and the pipeline turned it
  round, analysing the retract as the approach (a static curve's 56 nN pull-off came out 0.03 nN).

Which end of the position is the contact is read off the deflection signal: the contact end is where the
signal changes steeply with the position (the compliance or indentation line), the far end where it is
flat (the free baseline). Only when that is clear (:data:`CONTACT_SIDE_RATIO`, and a rise of
:data:`CONTACT_SIDE_SIGMAS` noise sigmas) are labels or runs changed; otherwise the curve is left as it
is (the pipeline's own checks follow: a position stored as the distance from the sample is turned round
there, :func:`afmforce.analysis.state.prepare`).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..io.curve import RawCurve
from ._glue_kernel import COMPILED, orient_scan
from ._median import median
from ._numeric import ptp

__all__ = ["orient", "plain_scan", "contact_side", "CONTACT_SIDE_RATIO", "CONTACT_SIDE_SIGMAS", "MIN_BLOCK"]

#: The steeper end's slope must exceed the flatter end's this many times to name the contact end [-].
CONTACT_SIDE_RATIO = 4.0
#: ... and the signal must change across the steeper end's window by this many noise sigmas [-].
CONTACT_SIDE_SIGMAS = 20.0
#: A block of one segment label shorter than this [samples] is not a run of its own (a label glitch).
MIN_BLOCK = 5
#: The fraction of the position's range at each end in which the slopes are compared [-].
_WINDOW = 0.15
#: A run's position step this many times its median step, among its first or last :data:`END_SAMPLES`
#: steps, is no ramp: the scanner moving on after the run (or before it) [-].
END_JUMP_STEPS = 50.0
#: ... looked for among this many steps at each end of a run [samples].
END_SAMPLES = 3


def _blocks(segment: np.ndarray) -> list[tuple[int, int, int]]:
    """(label, start, stop) of each stretch of one label, in array order."""
    seg = np.asarray(segment)
    if seg.size == 0:
        return []
    cut = np.flatnonzero(seg[1:] != seg[:-1]) + 1
    starts = np.concatenate(([0], cut))
    stops = np.concatenate((cut, [seg.size]))
    return [(int(seg[a]), int(a), int(b)) for a, b in zip(starts, stops)]


def _take(curve: RawCurve, index: np.ndarray, *, keep_time: bool = False) -> RawCurve:
    """The curve with its samples in the order ``index`` (the time column kept in place with ``keep_time``:
    a column written fresh, in array order, after the samples were stored out of order)."""
    pick = lambda a: None if a is None else np.asarray(a)[index]  # noqa: E731
    return dataclasses.replace(
        curve, time=np.asarray(curve.time)[:index.size] if keep_time else pick(curve.time),
        piezo_nominal=pick(curve.piezo_nominal), piezo_measured=pick(curve.piezo_measured),
        deflection_signal=pick(curve.deflection_signal), segment=pick(curve.segment))


def _first_cycle(curve: RawCurve, notes: list[str]) -> RawCurve:
    """The first approach-retract cycle of a record that holds several (blocks of fewer than
    :data:`MIN_BLOCK` samples ignored)."""
    runs = [b for b in _blocks(curve.segment) if b[0] in (0, 1) and b[2] - b[1] >= MIN_BLOCK]
    labels = [b[0] for b in runs]
    if labels.count(0) <= 1 and labels.count(1) <= 1:
        return curve
    if labels[:2] != [0, 1]:
        return curve      # not approach-then-retract cycles: left to the other checks
    cycles = sum(1 for a, b in zip(labels, labels[1:]) if (a, b) == (0, 1))
    stop = runs[1][2]
    notes.append(f"the curve holds {cycles} approach-retract cycles ({len(runs)} runs); the first cycle "
                 f"(samples 0-{stop - 1} of {len(curve)}) is analysed: split the record into one curve per "
                 "cycle to analyse the others")
    return _take(curve, np.arange(stop))


def _noise(s: np.ndarray) -> float:
    """Robust sample-to-sample noise of ``s`` [its unit] (MAD of the differences / sqrt 2)."""
    d = np.diff(s)
    if d.size < 2:
        return 0.0
    return 1.4826 * median(np.abs(d - median(d))) / math.sqrt(2.0)


def contact_side(z: np.ndarray, s: np.ndarray) -> int:
    """Which end of the position ``z`` [m] the contact is at, read off the signal ``s``: +1 the high end,
    -1 the low end, 0 unclear.

    The signal's least-squares slope against the position is taken in the top and the bottom
    :data:`_WINDOW` of the position's range; the contact end's is :data:`CONTACT_SIDE_RATIO` times the
    other's or more, and the signal changes across it by :data:`CONTACT_SIDE_SIGMAS` noise sigmas or more
    (a curve that never reaches the surface is flat at both ends: unclear).
    """
    z, s = np.asarray(z, float), np.asarray(s, float)
    if z.size < 20:
        return 0
    lo, hi = float(z.min()), float(z.max())
    span = hi - lo
    if not span > 0.0:
        return 0
    slopes = []
    for mask in (z >= hi - _WINDOW * span, z <= lo + _WINDOW * span):
        zz, ss = z[mask], s[mask]
        if zz.size < 5 or not np.ptp(zz) > 0.0:
            return 0
        zc = zz - zz.mean()
        slopes.append(abs(float(np.dot(zc, ss - ss.mean()) / np.dot(zc, zc))))
    top, bottom = slopes
    noise = _noise(s)
    steep = max(top, bottom)
    if not steep * _WINDOW * span > CONTACT_SIDE_SIGMAS * max(noise, 1e-300):
        return 0
    if top > CONTACT_SIDE_RATIO * bottom:
        return 1
    if bottom > CONTACT_SIDE_RATIO * top:
        return -1
    return 0


def _trend(z: np.ndarray) -> float:
    """How a run's position moves from its start to its end (medians of its first and last tenth) [m]."""
    n = max(1, z.size // 10)
    return float(median(z[-n:]) - median(z[:n]))


def _reverse_runs(curve: RawCurve, which: tuple[int, ...], keep_time: bool) -> RawCurve:
    """The curve with the samples of the runs (segment labels) ``which`` each reversed in place."""
    index = np.arange(len(curve))
    seg = np.asarray(curve.segment)
    for label in which:
        pos = np.flatnonzero(seg == label)
        index[pos] = pos[::-1]
    return _take(curve, index, keep_time=keep_time)


def _end_jumps(curve: RawCurve, z: np.ndarray, notes: list[str]) -> np.ndarray | None:
    """The samples to keep (None: all) of a curve without the samples at a run's end taken while the scanner jumped on (or before a run,
    while it jumped to the start): a position step :data:`END_JUMP_STEPS` times the run's median step
    among its first or last :data:`END_SAMPLES` steps; those samples and the ones beyond it are dropped,
    with a warning (a ramp moves the position by about the same step every sample).

    Was: a JPK 2014 retract (matfiz/afm-curve-procesing ``force-save-2014.02.20-15.54.10``, header flag
    z-start-out-of-range) whose last 2 samples were taken as the head moved on, 0.17 and 6.5 um in 0.5 ms
    (the ramp's steps ~1 nm) with the deflection at -8.5 nN: reported an adhesion of -7.1 nN off a curve
    with none."""
    seg = np.asarray(curve.segment)
    drop = np.zeros(seg.size, dtype=bool)
    for label, word in ((0, "approach"), (1, "retract")):
        idx = np.flatnonzero(seg == label)
        if idx.size < 4 * END_SAMPLES + 4 or np.any(np.diff(idx) != 1):
            continue      # short runs, or runs split by other samples: left as they are
        steps = np.abs(np.diff(z[idx]))
        typical = float(median(steps))
        if not typical > 0.0:
            continue
        big = steps > END_JUMP_STEPS * typical
        tail = np.flatnonzero(big[-END_SAMPLES:])
        head = np.flatnonzero(big[:END_SAMPLES])
        for cut, part in ((idx[steps.size - END_SAMPLES + tail[0] + 1:] if tail.size else idx[:0], "last"),
                          (idx[:head[-1] + 1] if head.size else idx[:0], "first")):
            if cut.size:
                drop[cut] = True
                jump = float(np.max(steps[-END_SAMPLES:] if part == "last" else steps[:END_SAMPLES]))
                notes.append(f"the {word}'s {part} {cut.size} sample{'s lie' if cut.size > 1 else ' lies'} past a position jump of {jump * 1e9:.4g} nm "
                             f"({jump / typical:.0f} x the run's median step of {typical * 1e9:.3g} nm): taken while the "
                             "scanner moved on, not on the ramp; dropped")
    return ~drop if drop.any() else None


#: Fewest samples of each run :func:`orient` reads the order of (a shorter run is left as it is).
MIN_ORIENT_RUN = 20


def plain_scan(curve: RawCurve, channel: str = "auto") -> tuple | None:
    """:func:`~._glue_kernel.orient_scan` of ``curve`` (its result when it shows that :func:`orient` leaves the
    curve as it is, without a note: the readers' curves), or None (not shown, or numba's JIT off: the caller
    runs :func:`orient`'s own steps). The same decision as those steps, for every curve it is given on; what it
    reads off the curve (the runs' sample ranges and position spans, the sign check's screen) serves
    :func:`~afmforce.analysis.state.prepare`."""
    if not COMPILED:
        return None
    seg, t, s = curve.segment, curve.time, curve.deflection_signal
    try:
        z = curve.position(channel)
    except Exception:   # an absent channel: prepare() says so
        return None
    for a, dtype in ((seg, np.int8), (t, np.float64), (z, np.float64), (s, np.float64)):
        if not (isinstance(a, np.ndarray) and a.ndim == 1 and a.dtype == dtype):
            return None
    out = orient_scan(seg, t, z, s, not curve.metadata.get("time_is_sample_index", False), MIN_BLOCK,
                      MIN_ORIENT_RUN, END_SAMPLES, END_JUMP_STEPS)
    return out if out[0] else None


def orient(curve: RawCurve, channel: str = "auto") -> tuple[RawCurve, tuple[str, ...]]:
    """The curve with one approach-retract cycle, each run in acquisition order and labelled as what it is.

    Returns the curve itself when nothing is changed (the readers' curves), else a new one (the input is
    never edited) and the warnings saying what was changed and why.

    Parameters
    ----------
    curve : RawCurve
    channel : str  the position channel the analysis reads (``"auto"``, ``"measured"``, ``"nominal"``)
    """
    if plain_scan(curve, channel) is not None:   # the readers' curves: nothing to change, shown in one pass
        return curve, ()
    notes: list[str] = []
    out = _first_cycle(curve, notes)
    seg = np.asarray(out.segment)
    app, ret = np.flatnonzero(seg == 0), np.flatnonzero(seg == 1)
    if app.size < MIN_ORIENT_RUN or ret.size < MIN_ORIENT_RUN:
        return out, tuple(notes)
    # a run stored backwards in time (its time column running down): put back in time order
    if not out.metadata.get("time_is_sample_index", False):
        t = np.asarray(out.time, float)
        # (a run whose first step does not fall is not backwards: the whole test skipped, the same answer)
        back = tuple(label for label, idx in ((0, app), (1, ret))
                     if t[idx[1]] - t[idx[0]] < 0 and np.isfinite(t[idx]).all() and np.all(np.diff(t[idx]) < 0))
        if back:
            out = _reverse_runs(out, back, keep_time=False)
            notes.append(f"the {' and the '.join('approach' if b == 0 else 'retract' for b in back)} "
                         f"{'is' if len(back) == 1 else 'are'} stored backwards in time (the time column "
                         "falls): put back in the order of acquisition")
    try:
        z = np.asarray(out.position(channel), float)
    except Exception:   # an absent channel: prepare() says so
        return out, tuple(notes)
    s = np.asarray(out.deflection_signal, float)
    # a finite sum says every sample is finite (one that overflows is checked sample by sample)
    if not (math.isfinite(float(np.add.reduce(z)) + float(np.add.reduce(s)))
            or (np.isfinite(z).all() and np.isfinite(s).all())):
        return out, tuple(notes)   # prepare() refuses non-finite samples
    if ptp(z[app]) <= 0.0 or ptp(z[ret]) <= 0.0:
        nominal = np.asarray(out.piezo_nominal, float)
        if not (np.isfinite(nominal).all() and ptp(nominal[app]) > 0.0 and ptp(nominal[ret]) > 0.0):
            return out, tuple(notes)
        z = nominal      # prepare() falls back to it the same way
    keep = _end_jumps(out, z, notes)
    if keep is not None:
        out, z, s = _take(out, np.flatnonzero(keep)), z[keep], s[keep]
        seg = np.asarray(out.segment)
        app, ret = np.flatnonzero(seg == 0), np.flatnonzero(seg == 1)
        if app.size < MIN_ORIENT_RUN or ret.size < MIN_ORIENT_RUN:
            return out, tuple(notes)
    if _trend(z[app]) > 0.0 and _trend(z[ret]) < 0.0:
        return out, tuple(notes)     # the conventions' order (the readers' curves): nothing to read off the signal
    side = contact_side(z, s)
    if side == 0:
        return out, tuple(notes)
    zs = side * z            # growing towards the sample
    wrong_app = _trend(zs[app]) < 0.0    # the approach moves away from the sample
    wrong_ret = _trend(zs[ret]) > 0.0    # the retract moves towards it
    where = "" if side > 0 else " (the position measured from the sample)"
    if wrong_app and wrong_ret:
        if ret[0] < app[0]:     # the block labelled retract comes first: the approach's samples
            out = dataclasses.replace(out, segment=np.where(seg == 0, 1, np.where(seg == 1, 0, seg)).astype(seg.dtype))
            notes.append("the segment labels are swapped: the run labelled retract moves towards the sample and "
                         f"comes first, the one labelled approach moves away{where}: relabelled")
        else:                   # both runs stored from their end to their start
            out = _reverse_runs(out, (0, 1), keep_time=True)
            notes.append("both runs are stored from their end to their start (each moves the other way from "
                         f"its label{where}): put back in the order of acquisition")
    elif wrong_app or wrong_ret:
        word = "approach" if wrong_app else "retract"
        out = _reverse_runs(out, (0 if wrong_app else 1,), keep_time=True)
        notes.append(f"the {word} is stored from its end to its start (it moves {'away from' if wrong_app else 'towards'} "
                     f"the sample{where}): put back in the order of acquisition")
    return out, tuple(notes)
