"""Thermal-noise calibration: a simple harmonic oscillator fitted to a deflection spectrum.

The first flexural mode of a lever in thermal equilibrium has the one-sided power spectral
density of a damped harmonic oscillator driven by white thermal force noise,

    P(f) = P_dc f0^4 / ((f^2 - f0^2)^2 + (f f0 / Q)^2),                                    (1)

whose area is ``<z^2> = pi P_dc f0 Q / 2``. The detector adds a white floor ``W`` and,
optionally, a ``B / f`` term. Equipartition gives the spring constant

    k = chi kB T / <z^2>                                                                     (2)

with ``chi`` the mode-shape and optical-lever correction: 0.817 for the first mode of an
end-loaded rectangular lever whose deflection is read by an optical lever calibrated with the
static InvOLS of a compliance line (Butt & Jaschke, Nanotechnology 6, 1 (1995); Hutter &
Bechhoefer's 0.817 for that case, Rev. Sci. Instrum. 64, 1868 (1993)); 1 for a true
displacement of a single-mode spring. A lever tilted by ``theta`` to the sample pushes
normal to the sample with ``k / cos^2 theta`` (Hutter, Langmuir 21, 2630 (2005)), reported
as ``spring_constant_normal`` when a tilt is given.

The fit is the maximum-likelihood (Whittle) fit of a spectrum of averaged periodograms: each
bin is ``P_model`` times a chi-square variable of ``2 N`` degrees of freedom over ``2 N``,
whatever N. Its gamma deviance ``2 [(P - M)/M - ln(P/M)]`` is summed by
:func:`scipy.optimize.least_squares` as squared deviance residuals, in the logarithms of the
parameters (well conditioned over decades); a least-squares fit of ``ln P`` would be biased by
``psi(N) - ln N`` (-0.58 for one periodogram: 44 % in k). The standard errors come from the
Fisher information ``N sum (d ln M / d theta)^2`` with N estimated from the scatter of
``P / M`` (so a spectrum of unknown averaging still gets honest intervals).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._fields import QUANTITIES
from ..constants import DEFAULT_TEMPERATURE  # declared once there (295 K): the tethers' WLC fits share it
from ..errors import AnalysisError, ParameterError

__all__ = ["BOLTZMANN", "DEFAULT_TEMPERATURE", "BUTT_JASCHKE", "sho_psd", "ThermalFit",
           "fit_thermal", "spring_constant_from_area"]

#: Boltzmann constant [J/K] (exact, SI 2019).
BOLTZMANN = 1.380649e-23
#: A bin this many times above the fitted model is an electrical line, not thermal noise (the
#: chance of a chi-square(2) bin reaching it is e^-20): masked and the fit redone.
SPIKE = 20.0
#: The resonance must lower the spectrum's deviance (times the averages: a likelihood ratio) against a
#: flat floor in the window by at least ``2 ln(bins in the spectrum) + RESONANCE_MARGIN``: the best
#: noise blip of a peak-free spectrum, found by the search over all its bins, reaches 4-10 (10 000 bins),
#: a lever's resonance hundreds to thousands. Below: no resonance above the noise (AnalysisError).
RESONANCE_MARGIN = 20.0
#: Butt & Jaschke's factor for the first mode of an end-loaded rectangular lever read by an
#: optical lever calibrated on a static compliance line: k = 0.817 kB T / <z*^2>.
BUTT_JASCHKE = 0.817


def sho_psd(f, f0: float, quality_factor: float, p_dc: float, white: float = 0.0,
            pink: float = 0.0):
    """Eq (1) plus background: ``P_dc f0^4 / ((f^2-f0^2)^2 + (f f0/Q)^2) + white + pink/f``.

    Parameters
    ----------
    f : array_like
        Frequencies [Hz] (> 0 where ``pink`` is non-zero).
    f0 : float
        Resonance frequency [Hz].
    quality_factor : float
        Quality factor Q [-].
    p_dc : float
        Resonant part at zero frequency [unit^2/Hz].
    white, pink : float
        White floor [unit^2/Hz] and 1/f coefficient [unit^2].

    Returns
    -------
    ndarray
        One-sided PSD [unit^2/Hz].
    """
    f = np.asarray(f, dtype=float)
    res = p_dc * f0**4 / ((f * f - f0 * f0) ** 2 + (f * f0 / quality_factor) ** 2)
    if pink:
        with np.errstate(divide="ignore"):
            res = res + pink / f
    return res + white


def spring_constant_from_area(mean_square: float, temperature: float = DEFAULT_TEMPERATURE,
                              correction: float = BUTT_JASCHKE) -> float:
    """Eq (2): ``k = correction kB T / <z^2>`` [N/m] for ``<z^2>`` [m^2]."""
    if not mean_square > 0:
        raise ParameterError(f"mean_square = {mean_square} must be positive")
    return correction * BOLTZMANN * temperature / mean_square


@dataclass(frozen=True)
class ThermalFit:
    """The first mode fitted to a thermal spectrum, and the spring constant by equipartition.

    Attributes
    ----------
    resonance_frequency, resonance_frequency_se : float  f0 and its standard error [Hz]
    quality_factor, quality_factor_se : float  Q [-] (both errors include the window's, as k's)
    mean_square : float  area of the resonance <z^2> [m^2]
    spring_constant, spring_constant_se : float  k by eq (2) and its standard error, the window's
        systematic part included [N/m]
    spring_constant_se_window : float  that systematic part: how much k moves with the window
        beyond the statistics of nested windows [N/m] (0 for a window given)
    spring_constant_normal : float  k / cos^2(tilt), normal to the sample [N/m] (= k, tilt 0)
    white, pink : float  background: white floor [m^2/Hz], 1/f coefficient [m^2]
    temperature : float  [K]
    correction : float  chi of eq (2) [-]
    tilt : float  lever tilt [rad]
    f_min, f_max : float  frequency window fitted [Hz]
    n_bins : int  bins fitted [-]
    masked : int  bins in the window masked as electrical lines (> SPIKE x the model) [-]
    averages : float  number of averaged periodograms, from the scatter of P/M [-]
    reduced_deviance : float  mean gamma deviance times the averages (about 1 for a good fit) [-]
    """

    resonance_frequency: float
    resonance_frequency_se: float
    quality_factor: float
    quality_factor_se: float
    mean_square: float
    spring_constant: float
    spring_constant_se: float
    spring_constant_normal: float
    white: float
    pink: float
    temperature: float
    correction: float
    tilt: float
    f_min: float
    f_max: float
    n_bins: int
    masked: int
    spring_constant_se_window: float
    averages: float
    reduced_deviance: float

    #: units of the fields, for JSON and tables
    UNITS = {"resonance_frequency": "Hz", "resonance_frequency_se": "Hz", "quality_factor": "",
             "quality_factor_se": "", "mean_square": "m^2", "spring_constant": "N/m",
             "spring_constant_se": "N/m", "spring_constant_normal": "N/m", "white": "m^2/Hz",
             "pink": "m^2", "temperature": "K", "correction": "", "tilt": "rad", "f_min": "Hz",
             "f_max": "Hz", "n_bins": "", "masked": "", "spring_constant_se_window": "N/m", "averages": "", "reduced_deviance": ""}

    def model(self, f):
        """The fitted PSD at ``f`` [m^2/Hz]."""
        p_dc = 2.0 * self.mean_square / (math.pi * self.resonance_frequency * self.quality_factor)
        return sho_psd(f, self.resonance_frequency, self.quality_factor, p_dc, self.white, self.pink)


def _smooth(p: np.ndarray, width: int) -> np.ndarray:
    width = max(1, min(width, p.size))
    kernel = np.ones(width) / width
    return np.convolve(p, kernel, mode="same")


def _guess(f: np.ndarray, p: np.ndarray, f_range) -> tuple[float, float]:
    """(f0, Q): the highest clear peak of the spectrum averaged in log-spaced bands (a 1/f rise
    at the low end is no peak), refined on the bins; Q from its half-power width."""
    from scipy.signal import find_peaks

    sel = (f >= f_range[0]) & (f <= f_range[1]) if f_range else np.ones(f.size, bool)
    sel &= f > 0
    if sel.sum() < 8:
        raise AnalysisError("the thermal spectrum has fewer than 8 bins in the frequency window")
    from scipy.ndimage import median_filter

    # a 3-bin running median removes one-bin electrical lines (a resonance spans more bins; the
    # fit masks wider lines in its window)
    fs, ps = f[sel], median_filter(p[sel], size=3, mode="nearest")
    edges = np.geomspace(fs[0], fs[-1] * (1 + 1e-12), min(300, fs.size // 2) + 1)
    band = np.clip(np.searchsorted(edges, fs, side="right") - 1, 0, edges.size - 2)
    counts = np.bincount(band, minlength=edges.size - 1)
    used = counts > 0
    level = np.bincount(band, weights=ps, minlength=edges.size - 1)[used] / counts[used]
    centre = np.sqrt(edges[:-1] * edges[1:])[used]
    log_level = np.log(level)
    peaks, props = find_peaks(log_level, prominence=0.0)   # an edge (a 1/f rise) is no peak
    if peaks.size == 0:
        raise AnalysisError("no resonance peak in the thermal spectrum; give the frequency window "
                            "(`frequency_min`/`frequency_max`)")
    # the highest of the peaks standing at least 2x above their surroundings (a noise blip on a
    # 1/f rise is not one); none such: the most prominent
    clear = props["prominences"] >= math.log(2.0)
    if clear.any():
        top = peaks[clear][int(np.argmax(log_level[peaks[clear]]))]
    else:
        top = peaks[int(np.argmax(props["prominences"]))]
    lo_f = centre[max(top - 1, 0)]
    hi_f = centre[min(top + 1, centre.size - 1)]
    near = (fs >= lo_f) & (fs <= hi_f)
    sm = _smooth(ps, 5)
    i = int(np.flatnonzero(near)[np.argmax(sm[near])]) if near.any() else int(np.argmin(abs(fs - centre[top])))
    f0, peak = fs[i], sm[i]
    floor = float(np.median(sm))
    half = floor + (peak - floor) / 2.0
    lo = i
    while lo > 0 and sm[lo] > half:
        lo -= 1
    hi = i
    while hi < sm.size - 1 and sm[hi] > half:
        hi += 1
    width = max(fs[hi] - fs[lo], 2.0 * (fs[1] - fs[0]))
    return float(f0), float(min(max(f0 / width, 0.5), 1e5))


def _window(f0: float, q: float, f: np.ndarray, scale: float = 1.0) -> tuple[float, float]:
    """Twelve line widths f0/Q each side (at most -85 % / +150 % of f0), times ``scale``."""
    below = min(0.85, 12.0 / q) * scale
    above = min(1.5, 12.0 / q) * scale
    return max(f0 * max(1.0 - below, 0.05), f[0]), min(f0 * (1.0 + above), f[-1])


def _fit_in(f, p, window, f0, q, pink):
    """The fit in ``window``, electrical lines masked: (theta, model, bins used, lines masked)."""
    sel = (f >= window[0]) & (f <= window[1])
    if sel.sum() < 8:
        raise AnalysisError(f"{int(sel.sum())} spectrum bins between {window[0]:.4g} and "
                            f"{window[1]:.4g} Hz; need 8 to fit a resonance")
    th, m = _fit(f[sel], p[sel], f0, q, pink)
    spikes = p[sel] > SPIKE * m          # lines (mains, electronics): masked, refitted
    masked = int(spikes.sum())
    if masked:
        sel[np.flatnonzero(sel)[spikes]] = False
        th, m = _fit(f[sel], p[sel], math.exp(th[0]), math.exp(th[1]), pink)
    if not window[0] < math.exp(th[0]) < window[1]:
        raise AnalysisError(f"the fitted resonance {math.exp(th[0]):.4g} Hz lies outside the window "
                            f"[{window[0]:.4g}, {window[1]:.4g}] Hz: no resonance found; "
                            "give the frequency window (`frequency_min`/`frequency_max`)")
    return th, m, sel, masked


def _covariance(fs, ps, th, m):
    """(covariance of theta, averages N from the scatter, mean deviance) of the Whittle fit."""
    ratio = ps / m
    spread = float(np.var(ratio - 1.0))
    averages = 1.0 / spread if spread > 0 else math.inf
    dev = float(np.mean(2.0 * (ratio - 1.0 - np.log(ratio))))
    # Fisher information of the Whittle likelihood: N J^T J, J = d ln M / d theta
    eps = 1e-6
    J = np.empty((fs.size, th.size))
    for j in range(th.size):
        t1, t2 = th.copy(), th.copy()
        t1[j] += eps
        t2[j] -= eps
        J[:, j] = (np.log(_model_at(fs, t1)) - np.log(_model_at(fs, t2))) / (2 * eps)
    # a background term the data do not see (its derivative vanishes) is dropped from the
    # information matrix instead of making it singular
    seen = np.linalg.norm(J, axis=0) > 1e-6 * np.sqrt(fs.size)
    cov = np.zeros((th.size, th.size))
    try:
        cov[np.ix_(seen, seen)] = np.linalg.inv(J[:, seen].T @ J[:, seen]) / averages
    except np.linalg.LinAlgError:
        cov[:] = np.nan
    return cov, averages, dev


def _lnk(th, cov) -> tuple[float, float]:
    """(ln of the area P_dc f0 Q, its variance): ln k = const - ln P_dc - ln f0 - ln Q."""
    g = np.zeros(th.size)
    g[:3] = 1.0
    return float(th[0] + th[1] + th[2]), float(g @ cov @ g)


def _fit(f, p, f0, q, pink: bool):
    p_dc = float(np.interp(f0, f, p)) / (q * q)
    white = max(float(np.median(p)) * 0.1, 1e-300)
    theta0 = [math.log(f0), math.log(q), math.log(max(p_dc, 1e-300)), math.log(white)]
    if pink:
        theta0.append(math.log(max(white * f[0], 1e-300)))

    def model(th):
        return sho_psd(f, math.exp(th[0]), math.exp(th[1]), math.exp(th[2]), math.exp(th[3]),
                       math.exp(th[4]) if pink else 0.0)

    def resid(th):
        m = model(th)
        r = p / m
        d = 2.0 * (r - 1.0 - np.log(r))
        return np.sign(r - 1.0) * np.sqrt(np.maximum(d, 0.0))

    from scipy.optimize import least_squares

    sol = least_squares(resid, np.asarray(theta0), method="trf", x_scale=1.0, max_nfev=2000)
    return sol.x, model(sol.x)


def fit_thermal(frequency, psd, *, temperature: float | None = None,
                correction: float = BUTT_JASCHKE, tilt: float = 0.0,
                f_range: tuple[float, float] | None = None, pink: bool = False,
                averages: int | None = None) -> ThermalFit:
    """Fit eq (1) with a white (and optionally 1/f) floor around the first mode; eq (2) for k.

    Parameters
    ----------
    frequency : array_like
        Bin frequencies [Hz], increasing.
    psd : array_like
        One-sided deflection PSD [m^2/Hz] (a spectrum in V^2/Hz times InvOLS^2).
    temperature : float, optional
        [K]; default :data:`DEFAULT_TEMPERATURE` (295 K).
    correction : float
        chi of eq (2) [-]; default :data:`BUTT_JASCHKE` (optical lever, static InvOLS).
    tilt : float
        Tilt of the lever to the sample [rad] (``spring_constant_normal = k / cos^2``).
    f_range : (float, float), optional
        Frequency window [Hz]; default: around the highest peak, twelve line widths (at most
        -85 % / +150 % of f0) each side, chosen from a first fit.
    pink : bool
        Fit a ``B/f`` term as well.
    averages : int, optional
        Periodograms averaged, as the file states them: the fit's scatter must not exceed what
        they allow by more than :data:`AVERAGES_SLACK` (and the statistics), else the oscillator
        does not describe the spectrum (:func:`_require_described`).

    Returns
    -------
    ThermalFit

    Raises
    ------
    AnalysisError
        Too few bins, no resonance in the window, or a fit that does not converge to a peak.
    """
    averages_in = averages
    f = np.asarray(frequency, dtype=float)
    p = np.asarray(psd, dtype=float)
    if f.shape != p.shape or f.ndim != 1:
        raise ParameterError("frequency and psd must be 1-D arrays of one length")
    ok = np.isfinite(f) & np.isfinite(p) & (f > 0) & (p > 0)
    f, p = f[ok], p[ok]
    T = DEFAULT_TEMPERATURE if temperature is None else float(temperature)
    for name, value in (("temperature", T), ("equipartition_correction", correction), ("lever_tilt", tilt)):
        if not math.isfinite(float(value)):
            raise ParameterError(f"{name} = {value!r} must be a finite number")
        QUANTITIES[name].check(float(value), name)      # the ranges declared once
    if f_range is not None:
        for name, value in zip(("frequency_min", "frequency_max"), f_range):
            QUANTITIES[name].check(float(value), name)
    f0, q = _guess(f, p, f_range)
    window = f_range if f_range else _window(f0, q, f)
    for _ in range(2 if not f_range else 1):
        th, m, sel, masked = _fit_in(f, p, window, f0, q, pink)
        f0, q = math.exp(th[0]), math.exp(th[1])
        if not f_range:
            window = _window(f0, q, f)
    fs, ps = f[sel], p[sel]
    cov, averages, dev = _covariance(fs, ps, th, m)
    _require_resonance(fs, ps, m, averages, f.size, pink, float(f[-1]))
    _require_described(averages, averages_stated=averages_in, n_bins=int(fs.size))
    ln_area, var_lnk = _lnk(th, cov)
    # the window's influence (a lever whose resonance is not exactly a harmonic oscillator, e.g.
    # in a liquid): refits in windows half and 1.5 times as wide; their differences beyond what
    # the statistics of nested windows explain (var_narrow - var_wide) count as a systematic error
    # (the same for ln f0 and ln Q)
    systematic = np.zeros(3)                            # ln f0, ln Q, ln area
    if not f_range:
        for scale in (0.5, 1.5):
            try:
                th_s, m_s, sel_s, _ = _fit_in(f, p, _window(f0, q, f, scale), f0, q, pink)
            except AnalysisError:
                continue
            cov_s = _covariance(f[sel_s], p[sel_s], th_s, m_s)[0]
            ln_s, var_s = _lnk(th_s, cov_s)
            d2 = np.array([(th_s[0] - th[0]) ** 2 - abs(cov_s[0, 0] - cov[0, 0]),
                           (th_s[1] - th[1]) ** 2 - abs(cov_s[1, 1] - cov[1, 1]),
                           (ln_s - ln_area) ** 2 - abs(var_s - var_lnk)])
            systematic = np.maximum(systematic, d2)
    area = math.pi * math.exp(ln_area) / 2.0
    k = spring_constant_from_area(area, T, correction)
    _require_possible_k(k, area, T, correction)
    window_se = k * math.sqrt(systematic[2])
    var_lnk += systematic[2]
    cov[0, 0] += systematic[0]
    cov[1, 1] += systematic[1]
    cos2 = math.cos(tilt) ** 2
    return ThermalFit(
        resonance_frequency=f0, resonance_frequency_se=f0 * math.sqrt(max(cov[0, 0], 0.0)),
        quality_factor=q, quality_factor_se=q * math.sqrt(max(cov[1, 1], 0.0)),
        mean_square=area, spring_constant=k, spring_constant_se=k * math.sqrt(max(var_lnk, 0.0)),
        spring_constant_normal=k / cos2, white=math.exp(th[3]),
        pink=math.exp(th[4]) if pink else 0.0, temperature=T, correction=float(correction),
        tilt=float(tilt), f_min=float(fs[0]), f_max=float(fs[-1]), n_bins=int(fs.size), masked=masked,
        spring_constant_se_window=window_se,
        averages=float(averages), reduced_deviance=dev * averages)


#: The scatter of a spectrum about its fit may exceed what its stated averages allow by this factor
#: before it is a misfit: Welch's overlapped Hann segments are ~5-10 % less independent than their count.
AVERAGES_SLACK = 1.2


def _require_described(averages_fit: float, *, averages_stated: int | None, n_bins: int) -> None:
    """Raise AnalysisError when the spectrum scatters about its fit far more than its stated averages
    allow: the oscillator does not describe it (a clipped or distorted peak, a second mode or lines in
    the window), and its area, hence k, is not the lever's.

    The fit reads the averages from the scatter of ``P / M`` (``averages_fit``); a misfit inflates the
    scatter and would be taken for fewer averages. With the file's count ``averages_stated`` the
    ratio ``stated / fitted`` of a described spectrum is 1 within the relative spread of a variance
    over ``n_bins`` bins (``sqrt((2 + 6/N) / n_bins)``, the kurtosis of a chi-square(2N)/2N bin being
    3 + 6/N); above ``AVERAGES_SLACK`` and 4 such spreads it is refused. A peak clipped at 1/250 of its height (virtual 0.2 mN/m lever, 64 averages stated) read
    43 averages and gave k = 2.66 +- 0.05 mN/m, 12x the truth, as a result.
    """
    if not averages_stated or not (averages_fit > 0) or not math.isfinite(averages_fit):
        return
    ratio = averages_stated / averages_fit
    spread = math.sqrt((2.0 + 6.0 / averages_stated) / max(n_bins, 1))   # gamma(N)'s kurtosis 3 + 6/N
    if ratio > AVERAGES_SLACK and ratio - 1.0 > 4.0 * spread:
        raise AnalysisError(
            f"the spectrum scatters about the fitted oscillator as {averages_fit:.3g} averaged periodograms "
            f"would, but the file states {averages_stated} ({ratio:.2f}x the variance): the oscillator does "
            "not describe it (a clipped or distorted peak, a second mode or electrical lines in the window), "
            "so its area is not the lever's and no k is given -- look at the spectrum (`plot`) and record it "
            "again, or fit a clean window (`frequency_min`/`frequency_max`)")


def _require_possible_k(k: float, area: float, temperature: float, correction: float) -> None:
    """Raise AnalysisError when the spring constant ``k`` [N/m] lies outside the range any lever can
    have (``QUANTITIES["spring_constant"]``, declared once: 0.1 mN/m .. 1000 N/m).

    Equipartition turns the peak's area ``<z^2>`` [m^2] into k, so a spectrum whose unit or InvOLS is
    wrong gives a k off by the square of the error: a spectrum in V^2/Hz read as m^2/Hz (an InvOLS of
    ~50 nm/V missing) gave 1.6e-11 N/m, one scaled by 1e-8 gave 1.6e7 N/m, both printed as results
    with a 2 % error. Such a number is not a spring constant; the message says what to check.
    """
    spec = QUANTITIES["spring_constant"]
    if spec.contains(k):
        return
    lo, hi = (math.sqrt(correction * BOLTZMANN * temperature / kk) for kk in (spec.hi, spec.lo))
    raise AnalysisError(
        f"the thermal peak's area <z^2> = {area:.3g} m^2 (rms {math.sqrt(area):.3g} m) gives k = {k:.3g} N/m, "
        f"outside the range any lever has ({spec.range_text()}: a thermal rms of {lo:.2g} to {hi:.2g} m): "
        "not a spring constant; the spectrum's unit or InvOLS is wrong (a spectrum in V^2/Hz read as "
        "m^2/Hz, an InvOLS off by a unit prefix) -- check the file's unit (`psd_unit`) and InvOLS (`sensitivity`)")


def _require_resonance(fs, ps, m, averages: float, n_all: int, pink: bool, f_top: float) -> None:
    """Raise AnalysisError unless the fitted resonance stands above the noise floor.

    The likelihood ratio of the fit against the floor alone (white, or white + 1/f) in the window,
    ``N [D(floor) - D(fit)]`` with D the summed gamma deviance and N the averages, must exceed
    ``2 ln(n_all) + RESONANCE_MARGIN`` (the search looked at every bin of the spectrum). A peak
    buried in the detector noise or above the spectrum's highest frequency (Nyquist) gives a blip
    of noise a "resonance" with any k: no spring constant, and the reason instead.
    """
    def deviance(model):
        r = ps / model
        return float(np.sum(2.0 * (r - 1.0 - np.log(r))))

    floor = np.full(ps.shape, float(np.mean(ps)))   # the maximum-likelihood constant
    if pink:
        from scipy.optimize import least_squares

        def resid(th):
            r = ps / (math.exp(th[0]) + math.exp(th[1]) / fs)
            return np.sign(r - 1.0) * np.sqrt(np.maximum(2.0 * (r - 1.0 - np.log(r)), 0.0))

        x0 = np.log([max(float(np.median(ps)) * 0.5, 1e-300), max(float(np.median(ps * fs)) * 0.5, 1e-300)])
        th = least_squares(resid, x0, method="trf").x
        alt = math.exp(th[0]) + math.exp(th[1]) / fs
        if deviance(alt) < deviance(floor):
            floor = alt
    n = averages if math.isfinite(averages) else 1.0
    lr = n * (deviance(floor) - deviance(m))
    need = 2.0 * math.log(max(n_all, 2)) + RESONANCE_MARGIN
    if not lr >= need:
        raise AnalysisError(
            f"no resonance stands above the noise in the thermal spectrum (the best candidate, "
            f"{fs[int(np.argmax(m))]:.4g} Hz, improves the likelihood over a flat floor by {lr:.3g}, "
            f"{need:.3g} needed): the lever's peak is buried in the detector noise or lies above the "
            f"spectrum's highest frequency ({f_top:.4g} Hz); the spring constant is not "
            "determined -- record a spectrum that shows the resonance (a higher sampling rate, more "
            "averages), or give the frequency window (`frequency_min`/`frequency_max`) around it")


def _model_at(f, th):
    return sho_psd(f, math.exp(th[0]), math.exp(th[1]), math.exp(th[2]), math.exp(th[3]),
                   math.exp(th[4]) if th.size > 4 else 0.0)
