"""Post-contact oscillations: frequency, and temporal versus spatial origin (section 3.2).

The paper saw oscillations after contact at 640 Hz (1.36 um/s) and 670 Hz
(2.0 um/s): the same *temporal* frequency at different speeds points to the
instrument or stick-slip, not to surface corrugation (which would keep the same
*spatial* frequency). Here the residual of each run's constant-compliance line
(less a cubic trend: a curved contact is no oscillation) is searched for a
spectral peak: the Lomb-Scargle periodogram (for evenly sampled data the
classical periodogram, computed by FFT) normalised by the local noise level
(the running median of the power over its neighbourhood divided by ln 2, so
coloured noise is not taken for a line). The normalised power ``z`` of noise is
exponential, so the false-alarm probability of the highest of ``M`` independent
frequencies is ``1 - (1 - exp(-z))^M``; a peak counts when it is below
``false_alarm`` (1e-3) and lies below ``max_nyquist_fraction`` (0.8) of the
Nyquist frequency (near Nyquist, aliasing and the anti-alias filter make
lines). An oscillation is reported only when *both* runs show such a peak.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from . import _oscillation_kernel as _K
from ._numeric import polyfit
from ._units import unit as _u
from .options import OscillationOptions as _Osc  # the defaults: declared once, in the step's record

__all__ = ["OscillationPeak", "OscillationResult", "find_peak", "oscillation_origin", "false_alarm_probability",
           "both_runs"]


@dataclass(frozen=True)
class OscillationPeak:
    """Strongest spectral line of a run's post-contact residual.

    Attributes
    ----------
    run : str
    found : bool  significant peak
    frequency : float  [Hz]
    spatial_frequency : float  frequency / speed [1/m]
    wavelength : float  speed / frequency [m]
    amplitude : float  [m]
    significance : float  peak power / median power [-]
    threshold : float  the significance needed [-]
    velocity : float  run speed [m/s]
    false_alarm : float  probability that noise makes a peak this high [-]
    nyquist : float  Nyquist frequency of the run [Hz] (NaN without a time base)
    """

    run: str
    found: bool
    frequency: float = _u("Hz")
    spatial_frequency: float = _u("1/m")
    wavelength: float = _u("m")
    amplitude: float = _u("m")
    significance: float = _u("")
    threshold: float = _u("")
    velocity: float = _u("m/s")
    false_alarm: float = _u("", math.nan)
    nyquist: float = _u("Hz", math.nan)


@dataclass(frozen=True)
class OscillationResult:
    """Peaks of both runs and the verdict on their origin.

    Attributes
    ----------
    approach, retract : OscillationPeak
    origin : str  ``"temporal"``, ``"spatial"``, ``"undetermined"`` or ``"none"``
    verdict : str  plain words
    """

    approach: OscillationPeak
    retract: OscillationPeak
    origin: str
    verdict: str


def _no_peak(run: str, velocity: float, significance: float = 0.0, threshold: float = math.nan,
             false_alarm: float = math.nan, nyquist: float = math.nan, frequency: float = math.nan) -> OscillationPeak:
    nan = math.nan
    return OscillationPeak(run, False, frequency, nan, nan, nan, significance, threshold, velocity, false_alarm,
                           nyquist)


def false_alarm_probability(z: float, m: int) -> float:
    """``1 - (1 - exp(-z))^m``: chance that the highest of ``m`` noise powers exceeds ``z`` [-]."""
    return float(-np.expm1(m * np.log1p(-math.exp(-z)))) if z > 0 else 1.0


def find_peak(t: np.ndarray, r: np.ndarray, velocity: float, run: str, *, min_cycles: float = _Osc.min_cycles,
              false_alarm: float = _Osc.false_alarm, min_points: int = 32, max_nyquist_fraction: float = 0.8) -> OscillationPeak:
    """Strongest line in the periodogram of ``r`` sampled at times ``t`` [s].

    Parameters
    ----------
    r : ndarray
        Residual deflection [m] (compliance line removed), time order.
    velocity : float
        Speed of the run [m/s] for the spatial frequency.
    min_cycles : float
        Lowest frequency considered: ``min_cycles`` periods in the record [-].
    """
    n = r.size
    if not np.all(np.isfinite(t)):
        return _no_peak(run, velocity)
    if n < min_points:  # a time base, too few samples in contact: say so (the Nyquist frequency), not "no time base"
        step = float(np.median(np.diff(t))) if n > 1 else math.nan
        return _no_peak(run, velocity, nyquist=0.5 / step if step > 0 else math.nan)
    if _compiled() and np.isfinite(r).all():
        t = np.ascontiguousarray(t, dtype=float)
        w, w_sum = _hann(n)
        dt, xw, ok = _K.detrend(t, np.ascontiguousarray(r, dtype=float), w)
        if not dt > 0:
            return _no_peak(run, velocity)
        if ok:
            spec = np.abs(np.fft.rfft(xw)) ** 2
            k0, count, k, sig = _K.band_peak(spec, n, float(dt), float(min_cycles), float(max_nyquist_fraction))
            nyq = 0.5 / dt
            if count < 16:
                return _no_peak(run, velocity, nyquist=nyq)
            p = spec[k0:k0 + count]
            df = float((k0 + 1) * (1.0 / (n * dt)) - k0 * (1.0 / (n * dt)))  # f[1] - f[0] of rfftfreq's grid
            return _line(run, velocity, p, float(sig), int(k), (k0 + k) * (1.0 / (n * dt)), df, count,
                         false_alarm, nyq, w_sum)
    return _find_peak_numpy(t, r, velocity, run, min_cycles=min_cycles, false_alarm=false_alarm,
                            max_nyquist_fraction=max_nyquist_fraction)


def _compiled() -> bool:
    """The kernels are compiled (not the first, uncompiled run: ``NUMBA_DISABLE_JIT``), where the
    numpy version, the same numbers, is the faster."""
    from numba.core import config

    return not config.DISABLE_JIT


_HANN: dict[int, tuple[np.ndarray, float]] = {}


def _hann(n: int) -> tuple[np.ndarray, float]:
    """``np.hanning(n)`` and its sum (cached per length: a map's runs share a few)."""
    hit = _HANN.get(n)
    if hit is None:
        if len(_HANN) > 256:
            _HANN.clear()
        w = np.hanning(n)
        hit = _HANN[n] = (w, float(w.sum()))
    return hit


def _line(run, velocity, p, sig, k, fk, df, count, false_alarm, nyq, w_sum) -> OscillationPeak:
    """The peak at band index ``k`` (normalised power ``sig``, frequency ``fk``) judged and refined."""
    threshold = math.log2(count / false_alarm)
    fap = false_alarm_probability(sig * math.log(2.0), int(count))
    if not fap < false_alarm:
        return _no_peak(run, velocity, sig, threshold, fap, nyq, float(fk))
    if 0 < k < p.size - 1:  # parabolic refinement on log power
        y0, y1, y2 = np.log(p[k - 1:k + 2])
        den = y0 - 2 * y1 + y2
        if den < 0:
            fk = fk + 0.5 * (y0 - y2) / den * df
    amp = 2.0 * math.sqrt(p[k]) / w_sum
    v = abs(velocity)
    sf = fk / v if v > 0 else math.nan
    return OscillationPeak(run, True, float(fk), float(sf), float(1.0 / sf) if sf > 0 else math.nan,
                           float(amp), sig, float(threshold), float(velocity), fap, nyq)


def _find_peak_numpy(t, r, velocity, run, *, min_cycles, false_alarm, max_nyquist_fraction) -> OscillationPeak:
    """:func:`find_peak` in numpy and scipy calls (the uncompiled run, and samples that are not finite)."""
    n = r.size
    dt = float(np.median(np.diff(t)))
    if not dt > 0:
        return _no_peak(run, velocity)
    tt = (t - t[0]) / max(t[-1] - t[0], dt)
    x = r - np.polyval(polyfit(tt, r, 3), tt)  # a curved (nonlinear) contact is not an oscillation
    w = np.hanning(n)  # leakage of what the cubic trend left would raise the noise floor
    spec = np.abs(np.fft.rfft(x * w)) ** 2
    freq = np.fft.rfftfreq(n, dt)
    nyq = 0.5 / dt
    band = (freq >= min_cycles / (n * dt)) & (freq <= max_nyquist_fraction * nyq)
    if band.sum() < 16:
        return _no_peak(run, velocity, nyquist=nyq)
    p = spec[band]
    f = freq[band]
    width = max(9, 2 * (p.size // 20) + 1)
    from scipy.ndimage import median_filter  # here: its import costs 0.25 s of every command
    local = median_filter(p, size=width, mode="nearest")  # coloured noise: compare with the neighbourhood
    ratio = p / np.where(local > 0, local, np.inf)
    k = int(np.argmax(ratio))
    return _line(run, velocity, p, float(ratio[k]), k, f[k], f[1] - f[0], int(band.sum()), false_alarm, nyq,
                 w.sum())


def oscillation_origin(frequencies: Sequence[float], velocities: Sequence[float], *,
                       tolerance: float = 0.15) -> tuple[str, str]:
    """Temporal or spatial? Compare peaks found at different speeds.

    Parameters
    ----------
    frequencies : sequence of float
        Temporal frequencies of significant peaks [Hz].
    velocities : sequence of float
        Speeds at which they were seen [m/s].
    tolerance : float
        Relative spread below which values count as equal [-].

    Returns
    -------
    origin : str
        ``"temporal"`` (same Hz at different speeds: stick-slip or instrument),
        ``"spatial"`` (same wavelength: surface corrugation), ``"undetermined"``
        or ``"none"``.
    verdict : str
    """
    pairs = [(f, abs(v)) for f, v in zip(frequencies, velocities)
             if math.isfinite(f) and math.isfinite(v) and v != 0]
    if not pairs:
        return "none", "no post-contact oscillation found"
    fs = np.array([p[0] for p in pairs])
    vs = np.array([p[1] for p in pairs])
    if len(pairs) < 2 or vs.max() / vs.min() < 1.0 + 2 * tolerance:
        return "undetermined", (f"oscillation at {np.mean(fs):.4g} Hz; a second speed is needed to "
                                "tell a temporal from a spatial origin")
    t_spread = fs.max() / fs.min() - 1.0
    lam = vs / fs
    s_spread = lam.max() / lam.min() - 1.0
    if t_spread <= tolerance < s_spread:
        return "temporal", (f"same temporal frequency ({np.mean(fs):.4g} Hz) at speeds {vs.min():.3g}-"
                            f"{vs.max():.3g} m/s: stick-slip or an instrument resonance, not the surface")
    if s_spread <= tolerance < t_spread:
        return "spatial", (f"same wavelength ({np.mean(lam) * 1e9:.4g} nm) at different speeds: "
                           "a spatial feature (surface corrugation)")
    return "undetermined", "frequencies and wavelengths both vary: origin undetermined"


def both_runs(approach: OscillationPeak, retract: OscillationPeak, *, tolerance: float = 0.15) -> tuple[str, str, float]:
    """Verdict on one curve: an oscillation needs a significant peak in both runs at one frequency.

    Returns
    -------
    origin : str  ``"temporal"``, ``"spatial"``, ``"undetermined"`` or ``"none"``
    verdict : str  with the numbers (frequencies, false-alarm probabilities)
    frequency : float  [Hz] (NaN unless an oscillation is confirmed)
    """
    def words(p: OscillationPeak) -> str:
        if math.isnan(p.nyquist):
            return f"{p.run}: no time base"
        f = f"{p.frequency:.4g} Hz" if math.isfinite(p.frequency) else "no peak"
        fap = f"false alarm {p.false_alarm:.2g}" if math.isfinite(p.false_alarm) else "too few samples"
        return f"{p.run}: {f}, {fap} (Nyquist {p.nyquist:.4g} Hz)"

    evidence = "; ".join(words(p) for p in (approach, retract))
    if math.isnan(approach.nyquist) and math.isnan(retract.nyquist):
        return "none", "oscillation not assessed: no time base", math.nan
    if not (approach.found and retract.found):
        return "none", f"no post-contact oscillation (needs a peak with false alarm < 1e-3 in both runs: {evidence})", \
            math.nan
    fa, fr = approach.frequency, retract.frequency
    if abs(fa - fr) <= tolerance * 0.5 * (fa + fr):
        origin, verdict = oscillation_origin([fa, fr], [approach.velocity, retract.velocity], tolerance=tolerance)
        return origin, f"{verdict} ({evidence})", 0.5 * (fa + fr)
    la, lr = approach.wavelength, retract.wavelength
    if math.isfinite(la * lr) and abs(la - lr) <= tolerance * 0.5 * (la + lr):
        return "spatial", (f"same wavelength ({0.5 * (la + lr) * 1e9:.4g} nm) in both runs at different speeds: a "
                           f"spatial feature ({evidence})"), math.nan
    return "none", f"peaks in both runs at unrelated frequencies: not one oscillation ({evidence})", math.nan
