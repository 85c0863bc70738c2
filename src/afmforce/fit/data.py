"""Curves prepared for the dynamic fit: approach samples, noise, mask, static guesses.

A measured curve enters the fit as its inward (approach) run: time since the
start of the run, piezo position, calibrated apparent deflection [m].
From the data alone (no model) we estimate the noise, find the jump-in and the
contact, and take the static first guesses of the per-curve nuisance
parameters: the baseline offset and drift (zero-force region), and the zero of
position (constant-compliance line: in contact the deflection follows z).

Shared with the analysis (:mod:`afmforce.analysis`), so that a fix serves both:
the choice of the position channel (:func:`afmforce.analysis.state.prepare`:
the measured one when the file has it), the speed of a run
(:func:`afmforce.analysis.dynamic.run_velocity`), the robust line through a
stepped sensor channel and the robust drift baseline
(:func:`afmforce.analysis.drift.fit_baseline`), and through
:mod:`afmforce.fit.preprocess` the analysis steps ``contact`` ... ``kind``: the
calibration (the file's; the compliance slope where the file has none, where asked, or
where the file's is impossible on a hard contact), the contact kind (a soft contact is refused), the jump-in, the
contact onset and the compliance line of the rigid-contact test. Still the fit's
own: the noise (second differences, whose spread the adequacy test of
:mod:`afmforce.fit.adequacy` is built on, and the 1/f part in
:mod:`afmforce.fit.noise`) and the mask built from the jump-in and the contact.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from ..errors import AnalysisError, FileFormatError, ParameterError
from ..io.curve import RawCurve
from .ramp import _meta_value, _position, _ramp, _timed

__all__ = ["FitCurve", "prepare_curves", "check_consistent"]

#: Spring constants or sensitivities of the curves may differ by this fraction at most.
CALIBRATION_TOLERANCE = 0.02


@dataclass
class FitCurve:
    """One approach run ready for fitting (SI units).

    Attributes
    ----------
    name : str
        Label (file name).
    time : ndarray
        Time since the first approach sample [s].
    position : ndarray
        Nominal piezo position z [m] (unknown zero).
    deflection : ndarray
        Calibrated apparent deflection [m] (unknown baseline offset).
    velocity, sample_rate : float
        Driving speed [m/s] and sample rate [Hz].
    sigma : float
        Noise rms estimated from the zero-force region [m].
    jump_index : int
        Index of the first sample after the jump-in (largest drop).
    mask : ndarray of bool
        Samples used by the fit: all but the jump-in and the landing transient, and
        the last one (an averaging detector's window may straddle the turn).
    guess : dict
        Static guesses: ``shift`` (nominal position of the true z = 0) [m],
        ``offset`` [m], ``drift`` [m/s], ``min_deflection`` [m] (before the jump,
        baseline removed).
    metadata : dict
        The curve's metadata, with ``calibration`` (how the analysis steps calibrated it:
        :meth:`afmforce.fit.preprocess.AnalysisInputs.as_metadata`) and ``preparation_notes``.
    retract_start : int or None
        Index of the first retract sample when the retract run is fitted too
        (None: approach only).
    turn_time, turn_position : float
        Time [s] and nominal position [m] of the turn (intersection of the
        approach and retract drive lines); NaN for an approach only.
    retract_velocity : float
        Retract speed [m/s] (NaN for an approach only).
    noise_samples : int
        Samples the noise estimate ``sigma`` rests on (its relative uncertainty
        in sigma^2 is about ``2 / sqrt(noise_samples)``; see docs/fit.md).
    """

    name: str
    time: np.ndarray
    position: np.ndarray
    deflection: np.ndarray
    velocity: float
    sample_rate: float
    sigma: float
    jump_index: int
    mask: np.ndarray
    guess: dict = field(default_factory=dict)
    metadata: dict = field(default_factory=dict)
    retract_start: int | None = None
    turn_time: float = math.nan
    turn_position: float = math.nan
    retract_velocity: float = math.nan
    noise_samples: int = 0
    #: rms of the 1/f noise [m] (0: white noise only; see afmforce.fit.noise)
    pink: float = 0.0
    #: whitening filter of the noise on the fitted samples (afmforce.fit.noise.ARWhitener;
    #: None: white noise of rms ``sigma``)
    whitener: object | None = None

    @property
    def n(self) -> int:
        return len(self.time)


def _noise_sigma(y: np.ndarray) -> float:
    """White-noise rms from second differences (var = 6 sigma^2), outliers beyond 4 MADs dropped."""
    d = np.diff(y, 2)
    mad = 1.4826 * np.median(np.abs(d - np.median(d)))
    d = d[np.abs(d - np.median(d)) < 4 * mad] if mad > 0 else d
    return float(np.std(d) / math.sqrt(6.0))


#: Longest window left out after the jump-in [s] (the old fixed default).
JUMP_WINDOW_MAX = 2e-3


def landing_samples(z: np.ndarray, y: np.ndarray, m0: int, sigma: float, fs: float) -> int:
    """Samples after ``m0`` (the jump-in or contact) until the deflection has landed on the
    contact line (issue 34: the jump window chosen from the data).

    The contact line is the straight line through the deflection against the position on
    the second half of the contact samples; the landing ends where the deviation from it
    stays within 4 noise rms for 10 samples. At most :data:`JUMP_WINDOW_MAX`; that long when
    the contact is too short to tell (fewer than 20 samples) or never settles.
    """
    cap = int(math.ceil(JUMP_WINDOW_MAX * fs))
    n = len(y)
    if n - m0 < 20:
        return cap
    late = slice(m0 + (n - m0) // 2, n)
    a, b = np.polyfit(z[late], y[late], 1)
    ok = np.abs(y[m0:] - (a * z[m0:] + b)) < 4.0 * sigma
    run = 10
    if ok.size < run:
        return cap
    settled = np.convolve(ok.astype(float), np.ones(run), "valid") >= run   # 10 in a row
    first = np.flatnonzero(settled)
    return int(min(first[0], cap)) if first.size else cap


#: A second difference before the jump-in larger than this many of its noise (``sqrt(6)`` noise rms)
#: belongs to the jump (:func:`rise_samples`) [-].
RISE_NSIGMA = 4.0
#: At most this many samples before the jump-in are taken to its rise (:func:`rise_samples`).
RISE_MAX = 20
#: The noise :func:`rise_samples` assumes at least [m]: the model's default absolute tolerance
#: (``SimulationConfig.atol``); noise-free curves (the plan's, ``afmforce.fit.plan``) bend by more.
RISE_SIGMA_FLOOR = 1e-12


def rise_samples(y: np.ndarray, first: int, sigma: float) -> int:
    """Samples before ``first`` (the first one left out at the jump-in) that belong to the
    jump's rise: walking back, each whose second difference ``y[k] - 2 y[k-1] + y[k-2]`` exceeds
    :data:`RISE_NSIGMA` of its noise (at most :data:`RISE_MAX`): where the deflection bends within
    a sample, what a sample is (the state at its time or the mean over its interval, which differ
    by about the second difference / 24) and the jump's timing matter.

    The analysis's jump-in index can sit a few samples past the jump's start (on the slow
    ``liquid`` virtual AFM at 0.5 um/s, 10 kHz: three, a sample 1.9 nm above its neighbour
    fitted; its point and averaged values 0.44 nm, 13 noise rms, apart): that one sample fixed A
    to 0.4 % and moved it 2-8 %. The smooth attraction before it (steps larger than the noise on
    a quiet detector, bends within it) stays in the fit.
    """
    lim = RISE_NSIGMA * math.sqrt(6.0) * max(sigma, RISE_SIGMA_FLOOR)
    k = int(first)
    while k - 3 >= 0 and first - k < RISE_MAX and abs(y[k - 1] - 2 * y[k - 2] + y[k - 3]) > lim:
        k -= 1
    return first - k


def prepare_curve(curve: RawCurve, name: str = "curve", *, velocity: float | None = None,
                  sample_rate: float | None = None, jump_window: float | None = None,
                  retract: bool = False, soft: str = "refuse",
                  calibration: str = "auto") -> FitCurve:
    """Prepare the approach run of ``curve`` (see the module docstring).

    ``jump_window``: samples this long after the jump-in [s] are left out; None (default):
    until the deflection has landed on the contact line (:func:`landing_samples`).
    ``soft``: what to do with a curve the analysis classifies as a soft contact
    (:func:`prepare_curves`); ``calibration``: the analysis's ``calibration.source`` (``auto``: the file's sensitivity
    where it has one, as ``afmforce analyze``; ``fit``: the compliance slope; ``metadata``, or
    ``file``: the file's always).

    With ``retract=True`` the retract run that follows it is appended
    (:func:`_append_retract`): its contact part is fitted, the pull-off and the
    free part after it are left out.

    Raises
    ------
    FileFormatError
        Speed or sample rate missing (:class:`~afmforce.errors.MissingMetadataError`; also a
        time axis that is the sample index without a sample rate), NaN or infinite samples.
    AnalysisError
        Too few approach samples, no contact, a soft contact or one the deflection does not
        follow with slope ~1 (:func:`afmforce.fit.preprocess.analysis_inputs`).
    """
    app = np.asarray(curve.segment) == 0
    idx = np.flatnonzero(app)
    if idx.size < 30:
        raise AnalysisError(f"{name}: only {idx.size} approach samples; the fit needs >= 30")
    idx = idx[: np.flatnonzero(np.diff(idx) != 1)[0] + 1] if np.any(np.diff(idx) != 1) else idx
    from .preprocess import analysis_inputs

    ana = analysis_inputs(curve, name, idx, soft, calibration)  # calibration, kind, jump, contact
    curve = _timed(curve, name, sample_rate)      # (a soft contact is refused before a missing time)
    scale = ana.factor
    ramp = _ramp(curve, idx)
    z, channel_note = _position(curve, idx, name)
    v_meas = channel_note.get("velocity") if velocity is None else None
    if v_meas is not None and not (math.isfinite(v_meas) and v_meas > 0):
        v_meas = None
    from_ramp = (velocity is None and v_meas is None and not (curve.metadata or {}).get("velocity")
                 and ramp["velocity"])
    v = _meta_value(curve, "velocity", velocity if velocity is not None else v_meas if v_meas
                    else (ramp["velocity"] if from_ramp else None), name, "m/s")
    v_file = (curve.metadata or {}).get("velocity")
    if v_meas and v_file and abs(v_meas / float(v_file) - 1.0) > 0.02:
        channel_note["speed_note"] = (
            f"{name}: the measured position moves at {v_meas * 1e6:.4g} um/s, the file says "
            f"{float(v_file) * 1e6:.4g} um/s (piezo gain or nonlinearity); the fit uses the measured "
            "speed (give `velocities` to override)")
    fs = _meta_value(curve, "sample_rate", sample_rate if sample_rate is not None else
                     (None if (curve.metadata or {}).get("sample_rate") else ramp["sample_rate"]),
                     name, "Hz")
    t = np.asarray(curve.time, float)[idx]
    y = np.asarray(curve.deflection_signal, float)[idx] * scale
    t = t - t[0]
    n = len(t)
    if not (np.all(np.isfinite(y)) and np.all(np.isfinite(z))):
        raise FileFormatError(f"{name}: the approach contains NaN or infinite values")
    if channel_note.get("line") is not None:   # the measured channel: the true drive line
        z = channel_note.pop("line")(t)
    # contact, jump-in and the rigid-contact test from the analysis's compliance line
    a, a_se = ana.slope, ana.slope_se
    if 0.5 < a + 3 * a_se and a - 3 * a_se < 2.0:
        a = min(max(a, 0.51), 1.99)   # noisy (e.g. a 0.3 nm-noise detector over a few nm): ~1
    if not 0.5 < a < 2.0:
        raise AnalysisError(
            f"{name}: in contact the deflection follows the position with slope {a:.3g}, not ~1 "
            f"(calibrated: {ana.source}): a deformable sample or a wrong deflection calibration; "
            "the dynamic model assumes rigid surfaces (eq 2), so this curve cannot be fitted as it "
            "is: give the right calibration (`sensitivity`, or `calibration` fit to take the compliance "
            f"slope's on a rigid contact) or analyse it with `afmforce analyze {name}`")
    i_c, j = min(ana.contact, n - 1), min(max(ana.jump, 1), n - 1)
    n_noise = max(12, int(0.8 * j))
    sigma = max(_noise_sigma(y[:n_noise]), 1e-15)
    win = (landing_samples(z, y, max(j, i_c), sigma, fs) if jump_window is None
           else int(math.ceil(jump_window * fs)))
    mask = np.ones(n, bool)
    lo = max(j - 2, 0)
    lo -= rise_samples(y, lo, sigma)     # the jump's rise before the analysis's jump-in
    mask[lo: min(max(j, i_c) + win + 2, n)] = False
    # the last approach sample: an averaging detector's window may straddle the turn,
    # which the model (turned one sample later) cannot know
    mask[-1] = False
    if mask.sum() < 20:
        raise AnalysisError(f"{name}: only {int(mask.sum())} samples left outside the jump-in "
                            "window; record a longer approach or a higher sample rate")
    base = slice(0, max(10, int(0.6 * j)))
    # the analysis's robust baseline (drift step): a line in time, spikes down-weighted
    from ..analysis.drift import fit_baseline   # lazily: registering `afmforce fit` loads no numba

    offset, drift, _ = fit_baseline(t[base], y[base], order=1)
    ybl = y - offset - drift * t
    post = slice(min(max(j, i_c) + win + 2, n - 3), n)
    shift = float(np.median(z[post] - ybl[post]))
    fc = FitCurve(name=name, time=t, position=z, deflection=y, velocity=v, sample_rate=fs,
                  sigma=sigma, jump_index=j, mask=mask, noise_samples=min(n_noise, n) - 2,
                  guess={"shift": shift, "offset": float(offset), "drift": float(drift),
                         "min_deflection": float(np.min(ybl[max(j - 3, 0):j]))},
                  metadata=dict(curve.metadata or {}))
    fc.metadata["position_channel"] = channel_note["channel"]
    fc.metadata["calibration"] = {**ana.as_metadata(), "jump_window": win / fs}
    if ana.notes:
        fc.metadata["preparation_notes"] = list(ana.notes)
    if channel_note.get("bent"):
        fc.metadata["velocity_from_ramp"] = channel_note["bent"]
    fc.metadata["record_samples"] = int(np.asarray(curve.time).size)
    if channel_note.get("speed_note"):
        fc.metadata["velocity_from_ramp"] = channel_note["speed_note"]
    elif v_meas and velocity is None and not v_file:
        fc.metadata["velocity_from_ramp"] = (
            f"{name}: no velocity in the file; {v * 1e6:.4g} um/s read off the approach ramp of "
            "the measured position; give `velocities` to override")
    if from_ramp:
        fc.metadata["velocity_from_ramp"] = (
            f"{name}: no velocity in the file; {v * 1e6:.4g} um/s read off the approach ramp "
            f"(positions deviate from a straight line by up to {ramp['ramp_deviation']:.1%} of the "
            "travel; the model drives at constant speed); give `velocities` to override")
    return _append_retract(fc, curve, idx, scale, jump_window) if retract else fc


def _append_retract(fc: FitCurve, curve: RawCurve, idx: np.ndarray, scale: float,
                    jump_window: float) -> FitCurve:
    """Append the retract run that directly follows the approach samples ``idx``.

    The turn is where the two drive lines (nominal position vs time) meet; the
    model is then driven through the same turn. Fitted: the retract in contact
    down to half the adhesive deflection before the pull-off (the largest rise
    of the deflection on the retract, if it exceeds 8 noise rms); the pull-off
    and the free retract after it are left out (``mask``).
    """
    seg = np.asarray(curve.segment)
    nxt = int(idx[-1]) + 1
    if nxt >= seg.size or seg[nxt] != 1:
        raise AnalysisError(
            f"{fc.name}: no retract run directly after the approach (a dwell or pause in "
            "between, or an approach-only file); fit the approach only (no `retract`)")
    ridx = np.arange(nxt, seg.size)
    stop = np.flatnonzero(seg[ridx] != 1)
    ridx = ridx[: stop[0]] if stop.size else ridx
    if ridx.size < 30:
        raise AnalysisError(f"{fc.name}: only {ridx.size} retract samples; the fit needs >= 30")
    t0 = float(np.asarray(curve.time, float)[idx[0]])
    tr = np.asarray(curve.time, float)[ridx] - t0
    if fc.metadata.get("position_channel") == "measured":   # the same channel as the approach
        from .ramp import drive_line

        zm = np.asarray(curve.piezo_measured, float)[ridx]
        a, b, _ = drive_line(tr, zm)   # the backlash's dead zone after the turn left out
        zr = a + b * (tr - tr[0])
    else:
        zr = np.asarray(curve.piezo_nominal, float)[ridx]
    yr = np.asarray(curve.deflection_signal, float)[ridx] * scale
    if not (np.all(np.isfinite(yr)) and np.all(np.isfinite(zr)) and np.all(np.diff(tr) > 0)):
        raise FileFormatError(f"{fc.name}: the retract contains NaN/infinite values or "
                              "non-increasing times")
    va, za = np.polyfit(fc.time, fc.position, 1)
    vr, zb = np.polyfit(tr, zr, 1)
    if not (va > 0 and vr < 0):
        raise AnalysisError(f"{fc.name}: the nominal position does not rise on the approach "
                            "and fall on the retract; cannot place the turn")
    t_turn = (zb - za) / (va - vr)
    gap = tr[0] - fc.time[-1]
    if gap > 1.5 / fc.sample_rate or not (
            fc.time[-1] - 1.0 / fc.sample_rate <= t_turn <= tr[0] + 1.0 / fc.sample_rate):
        raise AnalysisError(f"{fc.name}: {gap:.4g} s between the last approach and the first "
                            f"retract sample (drive lines meet at t = {t_turn:.4g} s); a pause "
                            "at the turn is not supported (fit the approach only)")
    # keep the outward compliance line down to half the adhesive deflection before the
    # pull-off; leave out the rest: where the model pulls off moves discontinuously with
    # the parameters (like the jump-in), so samples near it would steer the fit by timing
    mask_r = np.ones(ridx.size, bool)
    yb = yr - (fc.guess["offset"] + fc.guess["drift"] * tr)
    dy = np.diff(yr)
    k = int(np.argmax(dy)) + 1
    if dy[k - 1] > 8.0 * fc.sigma:
        floor = float(np.min(yb[:k]))
        below = np.flatnonzero(yb[:k] < 0.5 * floor) if floor < -8.0 * fc.sigma else np.array([], int)
        cut = int(below[0]) if below.size else max(k - 2, 0)
        mask_r[cut:] = False
    mask = fc.mask.copy()
    mask[-1] = True             # the model is driven through the same turn
    n_app = fc.n
    return FitCurve(
        name=fc.name, time=np.concatenate([fc.time, tr]),
        position=np.concatenate([fc.position, zr]),
        deflection=np.concatenate([fc.deflection, yr]), velocity=fc.velocity,
        sample_rate=fc.sample_rate, sigma=fc.sigma, jump_index=fc.jump_index,
        mask=np.concatenate([mask, mask_r]), guess=fc.guess, metadata=fc.metadata,
        retract_start=n_app, turn_time=float(t_turn), turn_position=float(za + va * t_turn),
        retract_velocity=float(-vr), noise_samples=fc.noise_samples)


def check_consistent(curves: Sequence[RawCurve], names: Sequence[str]) -> None:
    """Refuse curves whose calibrations disagree (spring constant, sensitivity).

    Raises
    ------
    ParameterError
        Two curves differ by more than :data:`CALIBRATION_TOLERANCE`.
    """
    for key, unit in (("spring_constant", "N/m"), ("sensitivity", "m/V")):
        vals = [(nm, float(c.metadata[key])) for c, nm in zip(curves, names)
                if (c.metadata or {}).get(key) is not None]
        if len(vals) < 2:
            continue
        ref_name, ref = vals[0]
        for nm, v in vals[1:]:
            if abs(v / ref - 1.0) > CALIBRATION_TOLERANCE:
                raise ParameterError(
                    f"inconsistent calibrations: {key} is {ref:.4g} {unit} in {ref_name} but "
                    f"{v:.4g} {unit} in {nm}; a joint fit needs one probe and one calibration "
                    "(recalibrate, or fit the curves separately)")


def prepare_curves(curves: Sequence[RawCurve | FitCurve], names: Sequence[str] | None = None,
                   *, velocities: Sequence[float] | None = None,
                   sample_rates: Sequence[float] | None = None,
                   jump_window: float | None = None, retract: bool = False,
                   soft: str = "refuse", calibration: str = "auto") -> list[FitCurve]:
    """Prepare several curves (see :func:`prepare_curve`) and check their calibrations.

    ``soft``: ``refuse`` a curve the analysis classifies as a soft contact, or ``warn`` (in a
    liquid, drainage and double-layer forces bend the approach like an indentation: the
    model describes that, and its adequacy test judges the rest). ``calibration``: ``auto`` or
    ``file`` (:func:`prepare_curve`).
    """
    if len(curves) == 0:
        raise ParameterError("give at least one curve")
    names = list(names) if names is not None else [f"curve {i + 1}" for i in range(len(curves))]
    raws = [c for c in curves if isinstance(c, RawCurve)]
    check_consistent(raws, [nm for c, nm in zip(curves, names) if isinstance(c, RawCurve)])
    out = []
    for i, (c, nm) in enumerate(zip(curves, names)):
        if isinstance(c, FitCurve):
            out.append(c)
            continue
        out.append(prepare_curve(c, nm, velocity=None if velocities is None else velocities[i],
                                 sample_rate=None if sample_rates is None else sample_rates[i],
                                 jump_window=jump_window, retract=retract, soft=soft,
                                 calibration=calibration))
    _refuse_duplicates(out)
    return out


def _refuse_duplicates(curves: Sequence[FitCurve]) -> None:
    """Raise ParameterError when two curves hold the same samples (one measurement given twice:
    a file named twice, an upload listed twice). The joint fit counts every curve as independent
    data, so a copy shrinks every standard error by sqrt(2) with no new information."""
    import hashlib

    seen: dict[bytes, str] = {}
    for c in curves:
        h = hashlib.blake2b(digest_size=16)
        for a in (c.time, c.position, c.deflection):
            h.update(np.ascontiguousarray(a, dtype=float).tobytes())
        key = h.digest()
        if key in seen:
            raise ParameterError(f"curves {seen[key]} and {c.name} hold the same samples: one measurement "
                                 "given twice would count as two and make every interval too tight; "
                                 "give each curve once")
        seen[key] = c.name
