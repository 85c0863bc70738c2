"""Contact, constant-compliance and zero-force regions of each run.

Each run (approach, retract; in time order) is split where two independent
straight lines fit it best (:func:`~._numeric.two_line_split`): on the approach
the split falls at the jump into contact, on the retract at the pull-off. The
far part is the zero-force region (its farthest ``baseline_fraction`` is used
for the baseline, leaving the attraction near contact out); the near part is
the contact region (its ``compliance_fraction`` nearest the turning point is
used for the constant-compliance line). Saturated samples (the photodiode
clipped at its extreme value) are left out of both.

A contact region found this way is not necessarily a constant-compliance line:
when the photodiode is saturated over the whole contact of a run (the tip
leaves the surface while the signal is clipped, Fig 7) the two lines split a
free cantilever that is still relaxing. :func:`check_compliance` rejects such
a region of a run clipped at its turning point: a compliance line must be much
steeper than the run's own free part (which is flat: drift and fringes only),
and, on a linear position channel, about as steep as the other run's
(friction changes the slope by a few per cent, eqs 18-19 and Fig 4). A run
that is not clipped at its turning point keeps its contact region: the
contact begins there.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..errors import AnalysisError
from ._numeric import mad_sigma, polyfit, ptp, robust_line_thin, two_line_split
from ._regions_kernel import OK, region_slope, run_index, run_regions_kernel, saturated_kernel

__all__ = ["RunRegions", "find_run_regions", "saturated_mask", "run_indices", "check_compliance",
           "contact_slopes", "baseline_steps", "without_baseline_step", "BASELINE_STEP_SIGMAS"]


@dataclass(frozen=True)
class RunRegions:
    """Regions of one run; boolean masks are over the run's samples in time order.

    Attributes
    ----------
    kind : str
        ``"approach"`` or ``"retract"``.
    index : ndarray of int
        Indices of the run's samples in the curve [-].
    split : int
        Position in the run of the first contact sample (approach) or of the first
        free sample after the pull-off (retract) [-].
    contact, zero_force, compliance, saturated : ndarray of bool
        In contact; used for the baseline; used for the compliance line; clipped.
    noise : float
        Robust noise of the free part's signal [signal unit].
    has_compliance : bool
        The contact region is a constant-compliance line (see :func:`check_compliance`);
        False: the run's contact is not in the record (clipped) and ``compliance`` is empty.
    note : str
        Why the contact region was rejected (empty if it was not).
    reason : str
        ``""``, ``"unsettled"`` (the free part is not flat: the cantilever was still
        relaxing) or ``"shallow"`` (much shallower than the other run's line).
    cut : int
        Position in the run of the first sample after a level step of its free baseline
        (:func:`without_baseline_step`): the samples before it are off the zero of force by the step and
        left out of the baseline and of the indentation fit [-]; 0 without a step.
    """

    kind: str
    index: np.ndarray
    split: int
    contact: np.ndarray
    zero_force: np.ndarray
    compliance: np.ndarray
    saturated: np.ndarray
    noise: float = float("nan")
    has_compliance: bool = True
    note: str = ""
    reason: str = ""
    cut: int = 0


def run_indices(segment: np.ndarray, which: int) -> np.ndarray:
    """Indices of segment ``which`` (0 approach, 1 retract), in time order."""
    segment = np.asarray(segment)
    if segment.dtype == np.int8 and segment.ndim == 1:  # the readers' segments: one compiled pass
        return run_index(segment, int(which))
    return np.flatnonzero(segment == which)


def saturated_mask(signal: np.ndarray, min_run: int = 3) -> np.ndarray:
    """Samples stuck at the extreme values of the signal (a clipped photodiode).

    A sample is saturated when it equals the global maximum (or minimum) and at
    least ``min_run`` samples share that exact value.
    """
    if signal.dtype == np.float64 and signal.ndim == 1 and signal.size:  # one compiled pass
        return saturated_kernel(np.ascontiguousarray(signal), int(min_run))
    out = np.zeros(signal.size, dtype=bool)
    for extreme in (signal.max(), signal.min()):
        hit = signal == extreme
        if hit.sum() >= min_run:
            out |= hit
    return out


def find_run_regions(z: np.ndarray, s: np.ndarray, index: np.ndarray, kind: str, *,
                     saturated: np.ndarray, min_points: int = 5, baseline_fraction: float = 0.7,
                     compliance_fraction: float = 0.5, min_contrast: float = 10.0,
                     noise: float | None = None) -> RunRegions:
    """Find the contact and zero-force regions of one run.

    Parameters
    ----------
    z, s : ndarray
        Position [m] and deflection signal [any unit] of the whole curve.
    index : ndarray of int
        The run's samples in time order.
    kind : str
        ``"approach"`` or ``"retract"``.
    saturated : ndarray of bool
        Saturated samples of the whole curve.
    noise : float, optional
        Noise of the other run [signal unit]: the contrast test uses the smaller
        of the two (a cantilever ringing freely after pull-off makes the retract's
        free part noisy).

    Raises
    ------
    AnalysisError
        Too few samples, a flat signal, or no constant-compliance region.
    """
    if (z.dtype == np.float64 and s.dtype == np.float64 and z.ndim == 1 and s.ndim == 1
            and kind in ("approach", "retract") and _surface_force_like is _SURFACE_TEST):
        # one compiled call where the regions are found (the numpy path where a test replaced the shape test)
        status, split, contact, zero_force, compliance, sat, own = run_regions_kernel(
            np.ascontiguousarray(z), np.ascontiguousarray(s), np.ascontiguousarray(index, dtype=np.int64),
            np.ascontiguousarray(saturated, dtype=np.bool_), kind == "approach", int(min_points),
            float(baseline_fraction), float(compliance_fraction), float(min_contrast),
            math.nan if noise is None else float(noise), _onset_constants())
        if status == OK:
            return RunRegions(kind=kind, index=index, split=int(split), contact=contact, zero_force=zero_force,
                              compliance=compliance, saturated=sat, noise=float(own))
    return _find_run_regions(z, s, index, kind, saturated=saturated, min_points=min_points,
                             baseline_fraction=baseline_fraction, compliance_fraction=compliance_fraction,
                             min_contrast=min_contrast, noise=noise)


def _find_run_regions(z, s, index, kind, *, saturated, min_points, baseline_fraction, compliance_fraction,
                      min_contrast, noise) -> RunRegions:
    """:func:`find_run_regions` by numpy (its errors, and what the compiled kernel leaves to it)."""
    n = index.size
    if n < 2 * min_points + 2:
        raise AnalysisError(f"the {kind} run has {n} samples; at least {2 * min_points + 2} are needed")
    zr, sr, sat = z[index], s[index], saturated[index]
    if ptp(sr) == 0:
        raise AnalysisError(f"flat curve: the deflection signal of the {kind} run is constant")
    ok = ~sat
    if ok.sum() < 2 * min_points:
        raise AnalysisError(f"the {kind} run is saturated (the photodiode is clipped almost everywhere)")
    if ptp(sr[ok]) == 0:
        raise AnalysisError(f"flat curve: the deflection signal of the {kind} run is constant")
    pos = np.flatnonzero(ok)
    # approach: far side first in time; retract: contact first -> reverse so far side comes first
    order = pos if kind == "approach" else pos[::-1]
    k = two_line_split(zr[order], sr[order], min_points)
    if k < 0:
        raise AnalysisError(f"the {kind} run is too short to find a contact region")
    far, near = order[:k], order[k:]
    # contrast test: the contact line must rise well above the baseline noise
    own = float(mad_sigma(np.diff(sr[far])) / np.sqrt(2.0)) if far.size > 2 else 0.0
    sigma = own if noise is None or not np.isfinite(noise) else min(own, float(noise))
    span = ptp(sr[near]) if near.size else 0.0
    if not (span > min_contrast * max(sigma, 1e-300)) or near.size < min_points:
        raise AnalysisError(
            f"no contact region found on the {kind} run (the signal rises only {span:.3g} over a "
            f"noise of {sigma:.3g}); is the surface reached?")
    split = int(near.min() if kind == "approach" else far.min())
    contact = np.zeros(n, bool)
    contact[near] = True
    zero_force = np.zeros(n, bool)
    zfar = zr[far]
    z_lo, z_hi = zfar.min(), zfar.max()
    zero_force[far[zfar <= z_lo + baseline_fraction * (z_hi - z_lo)]] = True
    if zero_force.sum() < min_points:
        zero_force[far] = True
    compliance = np.zeros(n, bool)
    znear = zr[near]
    z_top = znear.max()
    keep = znear >= z_top - compliance_fraction * (z_top - znear.min())
    compliance[near[keep]] = True
    if compliance.sum() < min_points:
        compliance[near] = True
    if kind == "approach":  # a curved (repulsive) contact onset the two lines left on the free side
        sigma = own
        if not sigma > 0:  # a quiet signal on a coarse ADC: the quantisation's noise (step / sqrt 12)
            steps = np.abs(np.diff(sr[far]))
            sigma = float(steps[steps > 0].min() / np.sqrt(12.0)) if np.any(steps > 0) else 1e-300
        onset = _repulsive_onset(zr, sr, far, zero_force, split, sigma)
        if onset < split:
            contact[far[far >= onset]] = True
            zero_force[far[far >= onset]] = False
            split = onset
    return RunRegions(kind=kind, index=index, split=split, contact=contact, zero_force=zero_force,
                      compliance=compliance, saturated=sat, noise=own)


#: Samples before the two lines' split lying this many noise sigmas above the baseline line are in
#: contact already: a repulsive, curved contact onset (a stiff lever on a hard sample, issue 32: about
#: 200 sigma there), not a baseline bent by fringes or drift (a few sigma: the paper's Fig 7 runs).
ONSET_NSIGMA = 10.0
#: ... and only when that curved onset spans at most this many times the steep contact's own position
#: travel (the sapphire lever: 14 nm before 15 nm); a rise over much longer (the JPK calibration curve:
#: 0.93 um before 0.24 um) is left to the contact kind (a slow rise, a soft or long-range contact).
MAX_ONSET_RATIO = 2.0
#: ... and not when an attractive jump ends the rise: the signal falls by this many noise sigmas from
#: the rise's last samples to the split (a jump into contact: the tip was not touching during the rise,
#: which is a surface force: hydrodynamic drainage, a double layer; the liquid runs: 9-15 sigma).
ONSET_JUMP_NSIGMA = 5.0
#: ... and not when the rise grows like a surface force of the separation (:func:`_surface_force_like`):
#: its logarithmic slope, over the samples this many sigmas above the baseline (log noise < 0.2) ...
SURFACE_MIN_NSIGMA = 5.0
#: ... corresponds to a decay length in this range [m] on the rise's far half (double layer, hydration,
#: steric: eq 5's Debye lengths are 0.3-300 nm; drainage's 1/h over tens of nm) ...
SURFACE_DECAY_RANGE = (0.2e-9, 200e-9)
#: ... and keeps at least this fraction of it on the near half (an exponential: 1, within the noise; a
#: power of the separation such as drainage: above 1, less where the lever's deflection widens the gap;
#: a contact, a power of the indentation: it falls). Measured: the virtual liquid runs 0.66-1.22, the
#: sapphire lever's contact 0.46, an ideal Hertz onset from 5 to 100 sigma 0.42.
SURFACE_MIN_SLOPE_RATIO = 0.6


def _onset_constants() -> tuple:
    """The constants above, in the order the compiled kernel takes them (read at each call)."""
    lo, hi = SURFACE_DECAY_RANGE
    return (float(ONSET_NSIGMA), float(MAX_ONSET_RATIO), float(ONSET_JUMP_NSIGMA), float(SURFACE_MIN_NSIGMA),
            float(lo), float(hi), float(SURFACE_MIN_SLOPE_RATIO))


def _repulsive_onset(zr, sr, far, zero_force, split: int, sigma: float) -> int:
    """First sample of a repulsive contact onset before ``split`` on the approach (``split`` if none).

    The baseline is the robust line through the zero-force samples. When the last free samples before
    the split lie more than :data:`ONSET_NSIGMA` noise sigmas above it (a force that is already
    repulsive: no attractive jump ends the free branch), the contact begins where the signal last
    crossed the baseline before them: the onset of the curved region, not the start of its steep part
    (when it spans at most :data:`MAX_ONSET_RATIO` times the steep part's position travel).

    A repulsive rise is a contact only when its shape is one: a long-range repulsive *surface* force
    (in a liquid: hydrodynamic drainage, an electrical double layer, hydration, steric) also lifts the
    signal above the baseline before contact, and it stays out of the contact region (the liquid step
    fits it) when either

    * an attractive jump ends the rise (the signal falls by :data:`ONSET_JUMP_NSIGMA` sigmas into the
      split: the tip jumped into contact, so it was not touching before), or
    * the rise grows like a surface force of the separation: ``ln(rise)`` linear in the piezo
      position (an exponential, decay length in :data:`SURFACE_DECAY_RANGE`) or steepening towards
      the surface (drainage's ``1/h``), not flattening (:func:`_surface_force_like`).

    A contact's onset is a power of the indentation (Hertz: ``delta**1.5``), zero before a definite
    position and with a falling logarithmic slope: no exponential describes it (the sapphire lever).
    The curve's medium is not used: readers and virtual curves do not carry it (it is an analysis
    option of the liquid step), and the shape decides in air and in liquid alike.
    """
    base = far[zero_force[far]]
    if base.size < 3 or split < 1 or far.size < 3:
        return split
    x0 = float(zr[base].mean())
    a, b, *_ = robust_line_thin(zr[base] - x0, sr[base])
    if not (np.isfinite(a) and np.isfinite(b)):
        return split
    free = np.sort(far[far < split])
    res = sr[free] - (a + b * (zr[free] - x0))
    if free.size == 0 or free[-1] != split - 1 or not res[-1] > ONSET_NSIGMA * sigma:
        return split
    below = np.flatnonzero(res <= 0)
    if below.size == 0:
        return split
    onset = int(free[below[-1] + 1])
    steep = float(ptp(zr[split:])) if split < zr.size else 0.0
    if abs(float(zr[split] - zr[onset])) > MAX_ONSET_RATIO * steep:  # a slow rise, not a curved onset
        return split
    at_split = float(sr[split] - (a + b * (zr[split] - x0)))
    if float(res[-4:].max()) - at_split > ONSET_JUMP_NSIGMA * sigma:  # a jump into contact ends it
        return split
    width = abs(float(zr[split] - zr[onset]))
    window = np.abs(zr[free] - zr[split]) <= 2.0 * width
    if _surface_force_like(zr[free][window], res[window], float(zr[split]), sigma):
        return split
    return onset


def _surface_force_like(z: np.ndarray, rise: np.ndarray, z_split: float, sigma: float) -> bool:
    """The rise above the baseline grows like a surface force: its logarithmic slope does not fall.

    Over the samples of the rise more than :data:`SURFACE_MIN_NSIGMA` sigmas above the baseline, the
    slope of ``ln(rise)`` against the distance travelled towards the split is fitted on the far and on
    the near half: a surface force of the separation (exponential: constant, ``1/lambda`` with
    ``lambda`` in :data:`SURFACE_DECAY_RANGE`; a power of the separation such as drainage: growing)
    keeps the near slope at least :data:`SURFACE_MIN_SLOPE_RATIO` times the far one; a contact (a power
    of the indentation, Hertz ``delta**1.5``: slope ``1.5/delta``) has it fall.
    """
    if not sigma > 0:
        return False
    toward = np.sign(z_split - float(np.mean(z))) or 1.0
    x = (z - z_split) * toward          # <= 0, growing towards the split
    up = rise > SURFACE_MIN_NSIGMA * sigma
    x, y = x[up], np.log(rise[up])
    if x.size < 6 or ptp(x) == 0:
        return False
    mid = 0.5 * (x.min() + x.max())
    far, near = x <= mid, x > mid
    if far.sum() < 3 or near.sum() < 3 or ptp(x[far]) == 0 or ptp(x[near]) == 0:
        return False
    s_far = float(polyfit(x[far], y[far], 1)[0])
    s_near = float(polyfit(x[near], y[near], 1)[0])
    lo, hi = SURFACE_DECAY_RANGE
    return bool(1.0 / hi <= s_far <= 1.0 / lo and s_near >= SURFACE_MIN_SLOPE_RATIO * s_far)


#: The shape test the compiled kernel implements (the numpy path runs a replaced one).
_SURFACE_TEST = _surface_force_like


def _slope(z: np.ndarray, s: np.ndarray) -> float:
    if z.size < 3 or ptp(z) == 0:
        return math.nan
    return float(robust_line_thin(z - z.mean(), s)[1])


def contact_slopes(z: np.ndarray, s: np.ndarray, run: RunRegions) -> tuple[float, float]:
    """Robust slopes [signal unit/m] of a run's compliance region and of its zero-force region."""
    return _region_slope(z, s, run, run.compliance), _region_slope(z, s, run, run.zero_force)


def _region_slope(z: np.ndarray, s: np.ndarray, run: RunRegions, region: np.ndarray) -> float:
    """Robust slope of the unsaturated samples of one region of a run (a mask over its index)."""
    if z.dtype == np.float64 and s.dtype == np.float64 and z.ndim == 1 and s.ndim == 1:  # one compiled call
        return float(region_slope(np.ascontiguousarray(z), np.ascontiguousarray(s),
                                  np.ascontiguousarray(run.index, dtype=np.int64),
                                  np.ascontiguousarray(region, dtype=np.bool_),
                                  np.ascontiguousarray(run.saturated, dtype=np.bool_)))
    idx = run.index[region & ~run.saturated]
    return _slope(z[idx], s[idx])


def _without_compliance(run: RunRegions, note: str, reason: str) -> RunRegions:
    """The run with its contact reduced to the clipped samples next to the turning point.

    The unclipped rest is a free cantilever that has not settled: no baseline either.
    """
    n = run.index.size
    sat = run.saturated
    order = np.arange(n) if run.kind == "retract" else np.arange(n)[::-1]  # from the turning point
    stop = np.flatnonzero(~sat[order])
    m = int(stop[0]) if stop.size else n  # clipped samples contiguous with the turning point
    contact = np.zeros(n, bool)
    contact[order[:m]] = True
    split = m if run.kind == "retract" else n - m
    split = min(max(split, 0), n - 1)
    empty = np.zeros(n, bool)
    return dataclasses.replace(run, split=split, contact=contact, compliance=empty, zero_force=empty,
                               has_compliance=False, note=note, reason=reason)


def check_compliance(z: np.ndarray, s: np.ndarray, approach: RunRegions, retract: RunRegions, *,
                     flat_ratio: float = 0.05, max_slope_ratio: float = 2.0) -> tuple[RunRegions, RunRegions]:
    """Reject a contact region that is not a constant-compliance line.

    Only a run whose photodiode is clipped at its turning point (the last
    approach sample, the first retract sample) can hide its contact in the
    clip; the other keeps its region whatever its slopes.

    Parameters
    ----------
    z, s : ndarray
        Position [m] and deflection signal [unit] of the whole curve.
    flat_ratio : float
        The free part's slope must stay below this fraction of the contact
        slope [-] (drift and fringes give well under 1 %; a cantilever still
        relaxing after the pull-off, tens of per cent).
    max_slope_ratio : float
        The steeper run's contact slope may exceed the other's by at most this
        factor [-] (``inf`` to skip: a creeping piezo on the nominal channel
        changes the local gain by a factor of 2-4 between runs).

    Returns
    -------
    approach, retract : RunRegions
        Unchanged, or with ``has_compliance=False`` and a ``note``.

    Raises
    ------
    AnalysisError
        Neither run has a constant-compliance line.
    """
    runs = {"approach": approach, "retract": retract}
    slopes = {}
    # only a run clipped where it turns can hide its contact in the saturated samples
    clipped = {"approach": bool(approach.saturated[-1]), "retract": bool(retract.saturated[0])}
    for kind, run in runs.items():
        near = _region_slope(z, s, run, run.compliance)  # the free part's slope only where used:
        slopes[kind] = near
        if not clipped[kind]:
            continue
        far = _region_slope(z, s, run, run.zero_force)
        if math.isfinite(near) and math.isfinite(far) and abs(far) > flat_ratio * abs(near):
            runs[kind] = _without_compliance(run, (
                f"the {kind} run has no unclipped constant-compliance region: its contact part is only "
                f"{abs(near / far):.2g} x steeper than its free part (a free cantilever still relaxing, "
                "the contact hidden in the saturated samples)"), "unsettled")
    a, r = slopes["approach"], slopes["retract"]
    if runs["approach"].has_compliance and runs["retract"].has_compliance and math.isfinite(a * r) and a * r != 0:
        ratio = abs(a / r)
        kind, other = ("retract", "approach") if ratio > 1 else ("approach", "retract")
        if clipped[kind] and (max(ratio, 1 / ratio) > max_slope_ratio or a * r < 0):  # opposite signs: no line
            runs[kind] = _without_compliance(runs[kind], (
                f"the {kind} run has no unclipped constant-compliance region: its contact slope is "
                f"{max(ratio, 1 / ratio):.3g} x shallower than the {other}'s (friction changes it by a few "
                "per cent, eqs 18-19)"), "shallow")
    if not (runs["approach"].has_compliance or runs["retract"].has_compliance):
        raise AnalysisError("no constant-compliance region on either run: " + runs["approach"].note
                            + "; " + runs["retract"].note)
    return runs["approach"], runs["retract"]


#: A level step of the approach's free baseline (a jump of the deflection signal between two flat parts: a
#: photodiode or laser glitch, not a force) counts when its height is this many white-noise sigmas of the
#: baseline [-] ...
BASELINE_STEP_SIGMAS = 8.0
#: ... and this many times the spread of the same statistic along the baseline (slow wander, fringes) [-].
BASELINE_STEP_SPREAD = 10.0
#: Samples on each side of a candidate step whose levels (one common slope, two offsets) are compared [-] ...
BASELINE_STEP_WINDOW = 20
#: ... leaving this many samples between them for the jump itself [-].
BASELINE_STEP_GAP = 2
#: A baseline needs this many samples after its last step to be fitted there alone [-].
MIN_AFTER_STEP = 30
#: The jump itself: the medians of the 3 samples either side of the gap differ by at least this fraction of the
#: step [-] (a glitch jumps within a sample or two; a low-pass filtered signal that wanders, the AFM Workshop
#: 2018 export's, moves over 5-10 samples: its second differences, the noise sigma, are then tiny).
BASELINE_STEP_ABRUPT = 0.7
#: ... and the step is at least this fraction of the run's signal range [-] (a noise-free virtual curve's
#: baseline "steps" by its floating-point rounding, 1e-16 m, hundreds of its sigmas).
BASELINE_STEP_MIN_FRACTION = 1e-3


def baseline_steps(s: np.ndarray, floor: float = 0.0) -> list[tuple[int, float, float]]:
    """Level steps of a free baseline ``s`` (samples in time order): ``(i, height, sigma)`` per step, ``i`` the
    first sample of the jump (``s[i - 1]`` before it, ``s[i + BASELINE_STEP_GAP]`` after it), ``height`` the jump
    [signal unit] and ``sigma`` the baseline's white noise (:func:`~.glitches._noise`) [signal unit].

    At each boundary the :data:`BASELINE_STEP_WINDOW` samples before and after are fitted with one common slope
    and two offsets; the offsets' difference at the boundary is the step. It counts above
    :data:`BASELINE_STEP_SIGMAS` noise sigmas and :data:`BASELINE_STEP_SPREAD` times the statistic's robust
    spread along the baseline (drift, fringes and slow wander change it smoothly, by far less), and ``floor``
    [signal unit]; it must be abrupt (:data:`BASELINE_STEP_ABRUPT`). The largest first, then the next beyond
    ``2 w + g`` samples of those looked at (a step inside one window tilts the common slope: side lobes of the
    opposite sign there)."""
    from .glitches import _noise

    s = np.asarray(s, float)
    w, g = BASELINE_STEP_WINDOW, BASELINE_STEP_GAP
    n = s.size
    if n < 2 * w + g + 1:
        return []
    sigma = _noise(s)
    if not sigma > 0.0:
        return []
    x = np.arange(w, dtype=float) - (w - 1) / 2.0          # centred positions in a window
    sxx = float(np.sum(x * x))
    mean = np.convolve(s, np.full(w, 1.0 / w), "valid")    # mean[j]: s[j:j + w]
    sxy = np.convolve(s, x[::-1], "valid")                 # sum x s over s[j:j + w]
    i = np.arange(w, n - w - g + 1)                          # boundaries: left s[i - w:i], right s[i + g:i + g + w]
    left, right = i - w, i + g
    b = (sxy[left] + sxy[right]) / (2.0 * sxx)             # the common slope [unit/sample]
    d = (mean[right] - mean[left]) - b * (w + g)
    spread = float(mad_sigma(d))
    lim = max(BASELINE_STEP_SIGMAS * sigma, BASELINE_STEP_SPREAD * spread, floor)
    mag = np.abs(d)
    out = []
    while True:   # the largest first; a step inside a window tilts its slope: side lobes within 2 w + g, cleared
        k = int(np.argmax(mag))
        if not mag[k] > lim:
            break
        at = int(i[k])
        jump = float(np.median(s[at + g: at + g + 3]) - np.median(s[at - 3: at]))
        if jump * d[k] > 0 and abs(jump) >= BASELINE_STEP_ABRUPT * abs(d[k]):
            out.append((at, float(d[k]), float(sigma)))
        mag[max(0, k - 2 * w - g): k + 2 * w + g + 1] = 0.0
    return sorted(out)


def without_baseline_step(s: np.ndarray, run: RunRegions, unit: str) -> tuple[RunRegions, str | None]:
    """The approach run with its zero-force region cut to the samples after its free baseline's last level step
    (:func:`baseline_steps`), nearest the contact, and a warning; unchanged (None) without a step.

    A baseline with a step is not one line: a drift line fitted across it tilts to join the two levels and,
    carried on to the contact, puts the zero of force off by a fraction of the step (the PicoForce file
    ``kontrkulka00000.000``: a 0.06 V step 250 samples into a 634-sample baseline put the approach's zero
    0.12 V, 0.23 nN, low at the contact). With fewer than :data:`MIN_AFTER_STEP` samples after the step the
    region is kept and the warning says the zero is uncertain by the step's height."""
    pos = np.flatnonzero(run.zero_force)
    if pos.size < 2 * BASELINE_STEP_WINDOW + BASELINE_STEP_GAP + 1 or np.any(np.diff(pos) != 1):
        return run, None       # (a region with holes, saturated samples: not scanned)
    steps = baseline_steps(s[run.index[pos]], BASELINE_STEP_MIN_FRACTION * float(ptp(s[run.index])))
    if not steps:
        return run, None
    k, height, sigma = steps[-1]
    more = f" (the last of {len(steps)})" if len(steps) > 1 else ""
    what = (f"the approach's free baseline steps by {height:.3g} {unit} ({abs(height) / sigma:.0f} noise sigmas) at "
            f"sample {int(run.index[pos[k]])}{more}: a jump of the deflection signal off the surface (a glitch), "
            "not a force")
    after = pos[k + BASELINE_STEP_GAP:]
    if after.size < MIN_AFTER_STEP:
        return run, (f"{what}; too few baseline samples after it ({after.size}) for a line of their own: the zero "
                     f"of force is uncertain by the step, {abs(height):.3g} {unit}")
    zero_force = np.zeros_like(run.zero_force)
    zero_force[after] = True
    return dataclasses.replace(run, zero_force=zero_force, cut=int(after[0])), (
        f"{what}; the zero of force, the drift line and an indentation fit use the {after.size} baseline samples "
        f"after it (nearest the contact), the {pos.size - after.size} before it left out")
