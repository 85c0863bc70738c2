"""Interferometric calibration from the fringes of the zero-force baseline (section 3.1).

Light reflected by the substrate interferes with the beam from the cantilever
and adds ``I0 cos(z_true / Delta)`` to the photodiode signal while the surfaces
are apart (spec section 6). The fringes are uniform in the *true* substrate
position, so their phase measured against the recorded position ``z`` gives
the map ``z -> z_true`` of a nonlinear piezo (Fig 7A).

Model, per run, on the zero-force samples: with ``x = (z - z_mid) / L``,

``u(z) = z_mid + c1 L (x + a2 x^2 + a3 x^3)``,
``r = p cos(2 pi u / P) + q sin(2 pi u / P) + e0 + e1 x``

(or ``e0 + e1 (t - t_mid)`` when the sample times are given: the baseline
left by the drift step is a line in time, and over many fringes the drift line
fitted alone is pulled by the fringes) fitted by variable projection (the linear p, q, e0, e1 solved inside
``scipy.optimize.least_squares`` on the nonlinear ones). If the fringe period
``P = 2 pi Delta`` is known, ``c1`` is fitted (the map gets the absolute scale);
otherwise ``c1 = 1`` and ``P`` is fitted (the map corrects the nonlinearity
only). The constant phase is unknown modulo one period, so the loop width
between runs is known modulo ``P``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ._fringe_kernel import _INTERPRETED, _prepare, _thin_indices, finish_stats, fit_orders, variance
from ._numeric import lstsq_qr, polyfit, ptp
from ._units import unit as _u
from .options import FringesOptions as _Fr  # the defaults: declared once, in the step's record

__all__ = ["FringeRun", "FringeResult", "fit_fringes", "position_map", "fringe_signal", "fringe_baseline",
           "loop_width"]


@dataclass(frozen=True)
class FringeRun:
    """Fringe fit of one run.

    Attributes
    ----------
    found : bool  fringes detected (explain at least ``min_explained`` of the variance)
    period : float  fringe period P in true position [m]
    amplitude : float  I0 [signal unit]
    phase : float  phase of the fringes at u = 0 [rad]
    scale : float  c1 [-]
    a2, a3 : float  map coefficients [-]
    z_mid, half_range : float  normalisation of x [m]
    nonlinearity : float  max deviation of the map from a line / range [-]
    explained : float  fraction of the baseline variance the fit explains [-]
    cycles : float  fringes in the fitted range [-]
    residual : float  rms residual [signal unit]
    baseline_offset : float  e0 [signal unit]
    baseline_slope : float  e1 [signal unit per s, or per m with ``baseline_variable="position"``]
    baseline_origin : float  t_mid [s] or z_mid [m]
    baseline_variable : str  ``"time"`` or ``"position"``
    converged : bool  the nonlinear fit converged within :data:`MAX_NFEV` evaluations (clean fringes
        take under ten; a fit that wanders is not evidence of fringes: ``found`` is then False)
    """

    found: bool
    period: float = _u("m")
    amplitude: float = _u("{signal}")
    phase: float = _u("rad")
    scale: float = _u("")
    a2: float = _u("")
    a3: float = _u("")
    z_mid: float = _u("m")
    half_range: float = _u("m")
    nonlinearity: float = _u("")
    explained: float = _u("")
    cycles: float = _u("")
    residual: float = _u("{signal}")
    baseline_offset: float = _u("{signal}", 0.0)
    baseline_slope: float = _u("{signal}/s or {signal}/m (baseline_variable)", 0.0)
    baseline_origin: float = _u("s or m (baseline_variable)", 0.0)
    baseline_variable: str = "position"
    converged: bool = True


@dataclass(frozen=True)
class FringeResult:
    """Fringe calibration of both runs.

    Attributes
    ----------
    approach, retract : FringeRun
    loop_width : float  largest gap between the runs' true-position maps, modulo P [m]
    applied : bool  positions were remapped to the fringes' scale
    verdict : str
    """

    approach: FringeRun
    retract: FringeRun
    loop_width: float = _u("m")
    applied: bool
    verdict: str


def position_map(z: np.ndarray, fr: FringeRun) -> np.ndarray:
    """True position ``u(z)`` of the fitted map [m] (up to a constant).

    The polynomial is used up to a quarter of the fitted range beyond its ends
    (|x| <= 1.5, enough to reach the contact region), and continues along its
    tangent farther out, so a cubic is never extrapolated far.
    """
    x = (np.asarray(z, float) - fr.z_mid) / fr.half_range
    xc = np.clip(x, -1.5, 1.5)
    poly = xc + fr.a2 * xc**2 + fr.a3 * _cube(xc, fr.a3)
    slope = 1.0 + 2 * fr.a2 * xc + 3 * fr.a3 * xc**2
    return fr.z_mid + fr.scale * fr.half_range * (poly + slope * (x - xc))


def fringe_signal(z: np.ndarray, fr: FringeRun) -> np.ndarray:
    """The fitted fringe term ``I0 cos(2 pi u / P + phase)`` [signal unit]."""
    return fr.amplitude * np.cos(2 * math.pi * position_map(z, fr) / fr.period + fr.phase)


def fringe_baseline(t: np.ndarray, z: np.ndarray, fr: FringeRun) -> np.ndarray:
    """The baseline line fitted with the fringes, ``e0 + e1 (t - t_mid)`` (or in position) [signal unit]."""
    v = np.asarray(t if fr.baseline_variable == "time" else z, float)
    return fr.baseline_offset + fr.baseline_slope * (v - fr.baseline_origin)


def _cube(x: np.ndarray, a3: float) -> np.ndarray:
    """``x**3`` where it is multiplied by ``a3``; ``x`` itself when ``a3`` is zero: ``a3 * x`` is then
    ``a3 * x**3`` (the same signed zero, NaN where x is NaN or infinite) wherever ``x**3`` does not
    overflow (``|x|`` < 5e102; the callers' ``x`` lie within 1.5 of the fitted range's middle, in its
    half-ranges). ``x**3`` goes through ``pow`` (~0.15 us a sample, ~50x ``x * x``): most maps are
    of order 1 or 2 (a3 = 0)."""
    return x if a3 == 0.0 else x**3


def _design(z, zm, L, P, c1, a2, a3, xt=None):
    x = (z - zm) / L  # within [-1, 1]: zm and L are the middle and half of z's own range
    u = zm + c1 * L * (x + a2 * x**2 + a3 * _cube(x, a3))
    th = 2 * math.pi * u / P
    return np.column_stack([np.cos(th), np.sin(th), np.ones_like(x), x if xt is None else xt]), x, u


#: At most this many samples enter the nonlinear fit (evenly thinned; the final linear solve and the
#: reported residual and explained variance use every sample).
FIT_POINTS = 4000
#: Samples per fringe period kept when thinning for the nonlinear fit, and at least this many in all.
POINTS_PER_PERIOD = 12
MIN_FIT_POINTS = 200
#: Evaluations allowed to one start of the nonlinear fit (fringes converge in 3-17 in the tests; a smooth
#: bow fitted as 1-2 "periods" with a strongly bent map wanders for a hundred).
MAX_NFEV = 20
#: Number of uniform position bins of the FFT periodogram.
BINS = 2048
#: The nonlinear fit evaluates cos and sin by the vectorised ``_fringe_kernel.sincos`` (an ulp from libm's,
#: ~6x faster) when its starting period fits at least this many times in the range [-]; its result is kept
#: only where the fit is well posed (every order converged over at least one period: then within ~1e-13 of
#: libm's fit), else it is fitted again with libm (a fit that wanders amplifies an ulp into percent). On the
#: 8 soft real files (issue 35) a start of 1.5-2.4 periods wandered on 5 of 6 runs, one of 8.6-302 on none of 3.
FAST_CYCLES = 3.0


def _periodogram(z: np.ndarray, r: np.ndarray) -> tuple[float, float]:
    """Strongest period and the fraction of the variance of ``r`` near it, from an FFT periodogram.

    The samples are averaged into :data:`BINS` uniform bins of ``z`` (empty bins
    interpolated), a line is removed, and the binned series is Fourier
    transformed (zero-padded 8x for the peak's position). The search range is the
    one of the former Lomb-Scargle grid: periods from ``max(4 dz, span/400)`` to
    ``span/1.5``. The fraction is the variance (Parseval, unpadded transform) in
    the band of frequencies within 20 % (at least one cycle over the span) of the peak, divided by the variance of the
    raw ``r``: a chirped fringe (nonlinear piezo) spreads its power over that band,
    noise averaged in the bins adds little. Cost O(BINS log BINS), whatever the
    number of samples.

    Returns
    -------
    period : float  [m]
    fraction : float  [-]
    """
    span = float(ptp(z))
    var = float(np.var(r))
    if not span > 0 or not var > 0:
        return math.nan, 0.0
    step = float(np.median(np.abs(np.diff(np.sort(z))))) or span / z.size
    nb = int(min(BINS, max(64, z.size)))
    width = span / nb
    k = np.minimum(((z - z.min()) / width).astype(np.int64), nb - 1)
    counts = np.bincount(k, minlength=nb)
    sums = np.bincount(k, weights=r - r.mean(), minlength=nb)
    full = counts > 0
    centres = np.arange(nb, dtype=float)
    y = np.interp(centres, centres[full], sums[full] / counts[full])
    y = y - np.polyval(polyfit(centres, y, 1), centres)
    p_min, p_max = max(4 * step, span / 400, 2.5 * width), span / 1.5
    pad = 8 * nb
    spec = np.abs(np.fft.rfft(y, pad)) ** 2
    periods = pad * width / np.maximum(np.arange(spec.size), 1e-300)
    inside = (periods >= p_min) & (periods <= p_max)
    if not inside.any():
        return math.nan, 0.0
    peak = float(periods[inside][int(np.argmax(spec[inside]))])
    coarse = np.abs(np.fft.rfft(y)) ** 2
    cycles = np.arange(coarse.size, dtype=float)  # cycles over the binned span
    k_peak = nb * width / peak
    band = (np.abs(cycles - k_peak) <= max(0.2 * k_peak, 1.0)) & (cycles > 0)
    band_var = 2.0 * float(np.sum(coarse[band])) / nb**2
    return peak, min(band_var / var, 1.0)


@njit(cache=True)
def _binned(z, r, nb):
    """:func:`_periodogram`'s series: ``r`` (less its mean) averaged in ``nb`` uniform bins of ``z``,
    empty bins interpolated (held beyond the ends), a line removed; and the median sample step."""
    n = z.size
    zmin = z.min()
    span = z.max() - zmin
    width = span / nb
    mean = r.mean()
    counts = np.zeros(nb)
    sums = np.zeros(nb)
    for i in range(n):
        k = min(int((z[i] - zmin) / width), nb - 1)
        counts[k] += 1.0
        sums[k] += r[i] - mean
    y = np.empty(nb)
    last = -1
    for i in range(nb):
        if counts[i] > 0:
            y[i] = sums[i] / counts[i]
            if last < 0:
                for j in range(i):
                    y[j] = y[i]
            elif i - last > 1:
                slope = (y[i] - y[last]) / (i - last)
                for j in range(last + 1, i):
                    y[j] = slope * (j - last) + y[last]
            last = i
    for j in range(last + 1, nb):
        y[j] = y[last]
    cm = 0.5 * (nb - 1)  # the least-squares line over the bin index, removed
    sxx = 0.0
    sxy = 0.0
    ym = y.mean()
    for i in range(nb):
        sxx += (i - cm) * (i - cm)
        sxy += (i - cm) * (y[i] - ym)
    b = sxy / sxx
    for i in range(nb):
        y[i] -= ym + b * (i - cm)
    zs = np.sort(z)
    d = np.empty(n - 1)
    for i in range(n - 1):
        d[i] = abs(zs[i + 1] - zs[i])
    return y, np.median(d)


@njit(cache=True)
def _peak_and_band(spec, coarse, pad, width, p_min, p_max, nb):
    """:func:`_periodogram`'s peak period in the search range (NaN: none) and the band's variance."""
    best = -1.0
    peak = math.nan
    for k in range(spec.size):
        period = pad * width / max(k, 1e-300)
        if period >= p_min and period <= p_max and spec[k] > best:
            best = spec[k]
            peak = period
    if math.isnan(peak):
        return peak, 0.0
    k_peak = nb * width / peak
    half = max(0.2 * k_peak, 1.0)
    band = 0.0
    for c in range(1, coarse.size):
        if abs(c - k_peak) <= half:
            band += coarse[c]
    return peak, 2.0 * band / nb**2


def _periodogram_fast(z: np.ndarray, r: np.ndarray, var: float | None = None) -> tuple[float, float]:
    """:func:`_periodogram` with the binning and the search compiled (equal to rounding; used where
    the fit's result is reported, not subtracted from the curve); ``var``: ``np.var(r)`` if known."""
    span = float(ptp(z))
    var = float(np.var(r)) if var is None else var
    if not span > 0 or not var > 0:
        return math.nan, 0.0
    nb = int(min(BINS, max(64, z.size)))
    y, step = _binned(np.ascontiguousarray(z, dtype=float), np.ascontiguousarray(r, dtype=float), nb)
    step = float(step) or span / z.size
    width = span / nb
    p_min, p_max = max(4 * step, span / 400, 2.5 * width), span / 1.5
    pad = 8 * nb
    spec = _padded_power(y)
    coarse = np.ascontiguousarray(spec[::8])  # the unpadded transform's bins: every 8th of the padded one
    peak, band_var = _peak_and_band(spec, coarse, float(pad), width, p_min, p_max, nb)
    return float(peak), min(float(band_var) / var, 1.0) if math.isfinite(peak) else 0.0


#: :func:`_padded_power` takes the chirp-z route when the number of bins has a prime factor above this
#: (pocketfft's own route for such a length, 8x padded, costs 0.4-1.8 ms; the chirp-z 0.1-0.2 ms).
CHIRP_PRIME = 100
_CHIRPS: dict[int, tuple] = {}


def _largest_prime_factor(n: int) -> int:
    f, big = 2, 1
    while f * f <= n:
        while n % f == 0:
            big, n = f, n // f
        f += 1
    return max(big, n)


def _chirp(nb: int) -> tuple:
    """The chirps and the transformed filter of :func:`_padded_power` for ``nb`` samples (cached)."""
    hit = _CHIRPS.get(nb)
    if hit is not None:
        return hit
    from scipy.fft import next_fast_len as _next_fast_len  # here: the import costs the cold start nothing
    N, K = 8 * nb, 4 * nb + 1
    size = _next_fast_len(nb + K - 1)
    j = np.arange(max(nb, K), dtype=np.int64)
    c = np.exp(-1j * (np.pi * ((j * j) % (2 * N)) / N))  # exp(-i pi j^2 / N), the phase reduced exactly
    b = np.zeros(size, complex)
    b[:K] = np.conj(c[:K])
    b[size - nb + 1:] = np.conj(c[1:nb])[::-1]
    out = (c[:nb].copy(), np.fft.fft(b), c[:K].copy(), size)
    if len(_CHIRPS) > 64:
        _CHIRPS.clear()
    _CHIRPS[nb] = out
    return out


def _padded_power(y: np.ndarray) -> np.ndarray:
    """``|rfft(y, 8 y.size)|^2``: pocketfft where the length factors well, else Bluestein's chirp-z
    (``nk = (n^2 + k^2 - (k - n)^2) / 2``: one convolution by FFTs of a fast length); the two agree to
    ~1e-15 of the largest bin (tested against a direct DFT)."""
    nb = y.size
    if _largest_prime_factor(nb) <= CHIRP_PRIME:
        return np.abs(np.fft.rfft(y, 8 * nb)) ** 2
    cn, B, ck, size = _chirp(nb)
    X = np.fft.ifft(np.fft.fft(y * cn, size) * B)[:ck.size] * ck
    return X.real ** 2 + X.imag ** 2


def _initial_period(z: np.ndarray, r: np.ndarray) -> float:
    """Strongest period of the baseline residual (see :func:`_periodogram`) [m]."""
    return _periodogram(z, r)[0]


def _not_found(z: np.ndarray, r: np.ndarray, explained: float, period: float) -> FringeRun:
    zm = 0.5 * (z.max() + z.min())
    L = 0.5 * float(ptp(z)) or 1.0
    return FringeRun(False, period, 0.0, 0.0, 1.0, 0.0, 0.0, float(zm), float(L), 0.0, float(explained),
                     float(ptp(z) / period) if period > 0 else 0.0, float(np.std(r)))


def fit_fringes(z: np.ndarray, r: np.ndarray, *, period: float | None = _Fr.period, order: int | str = _Fr.order,
                min_explained: float = 0.3, min_cycles: float = 1.0, t: np.ndarray | None = None) -> FringeRun:
    """Fit the fringe model to the baseline residual ``r`` against position ``z``.

    Search first, fit only what can pass: an FFT periodogram of the binned
    residual (:func:`_periodogram`) gives the starting period and the fraction of
    the variance near it. When that fraction is under a third of
    ``min_explained`` (and no period is given), no fringe model can explain
    ``min_explained`` of it (a chirp's power stays within the band), and the run
    is reported not found without the nonlinear fit. Otherwise the nonlinear
    parameters are fitted on at most :data:`FIT_POINTS` evenly thinned samples
    (at least :data:`POINTS_PER_PERIOD` per period), and the linear ones, the
    residual and the explained variance on every sample.

    Parameters
    ----------
    z : ndarray
        Recorded position on the zero-force samples [m].
    r : ndarray
        Baseline residual of the deflection signal there [signal unit].
    period : float, optional
        Known fringe period ``2 pi Delta`` [m] (gives the absolute scale).
    order : int or "auto"
        Polynomial order of the map (1, 2 or 3); ``"auto"`` takes the order
        with the lowest Bayesian information criterion ``n ln(SSR/n) + p ln n``.
    min_explained, min_cycles : float
        A run has fringes when the fit explains at least ``min_explained`` of
        the variance over at least ``min_cycles`` periods [-].
    t : ndarray, optional
        Sample times [s]: the baseline line is fitted in time instead of position.
    """
    z = np.asarray(z, float)
    r = np.asarray(r, float)
    t = None if t is None else np.asarray(t, float)
    p0 = None
    var_r = variance(r) if z.size >= 16 else None  # computed once: the search, the fit, the verdict (np.var's number)
    if not (period or z.size < 16 or var_r == 0):
        p0, fraction = _periodogram_fast(z, r, var_r)  # compiled: the same starting period (a grid value)
        if not math.isfinite(p0) or fraction < min_explained / 3:
            return _not_found(z, r, fraction, p0 if math.isfinite(p0) else math.nan)
    keep = None
    per = float(period) if period else p0
    if per and z.size > 16:
        m = int(min(FIT_POINTS, max(MIN_FIT_POINTS, POINTS_PER_PERIOD * ptp(z) / per)))
        if z.size > m:
            keep = _thin_indices(z.size, m)  # np.unique(np.linspace(0, n - 1, m).round().astype(np.int64))
    zs, rs, ts = (z, r, t) if keep is None else (z[keep], r[keep], None if t is None else t[keep])
    best = _fit_map(zs, rs, ts, period, order, p0, var_r if keep is None else None)
    if not math.isfinite(best.period):
        return best
    return _finish(z, r, t, best.period, best.scale, best.a2, best.a3, min_explained, min_cycles,
                   converged=best.converged, var_r=var_r)


def _fit_map(z, r, t, period, order, p_start, var0=None) -> FringeRun:
    """:func:`fit_fringes`'s nonlinear fit on the samples given: the map of the best order (``"auto"``:
    1, 2, 3 by the Bayesian information criterion) and its residual; amplitude, line and verdict are
    left to :func:`_finish`. The orders and their starts run in one compiled call
    (:func:`._fringe_kernel.fit_orders`): each order starts from the lower order's map; the cubic from
    a3 = 0, and from a3 = +-0.05 only when the first start does not improve on the lower order's cost
    (a sign of a local minimum)."""
    nan = math.nan
    if z.size < 16:
        return FringeRun(False, nan, 0.0, 0.0, 1.0, 0.0, 0.0, nan, 1.0, 0.0, 0.0, 0.0, nan)
    prep = _prepare(z, r, t, var0)
    zm, L, var0 = prep.zm, prep.L, prep.var0
    P0 = float(period) if period else p_start
    if var0 == 0 or not (P0 and math.isfinite(P0)):
        return FringeRun(False, nan, 0.0, 0.0, 1.0, 0.0, 0.0, zm, L, 0.0, 0.0, 0.0, nan)
    o_first, o_last = (1, 3) if order == "auto" else (int(order), int(order))
    args = (o_first, o_last, bool(period), float(P0), float(period) if period else 0.0, prep.x, prep.x2, prep.x3,
            float(zm), float(L), prep.Q0, prep.r_perp, MAX_NFEV, 1e-6, 1e-7)
    # cos and sin vectorised (issue 35) where the fit is likely well posed; not as Python (the first run's
    # NUMBA_DISABLE_JIT: the loop's dozen operations a sample cost more there than math.cos and math.sin)
    fast = 2.0 * L >= FAST_CYCLES * P0 and not _INTERPRETED
    P, c1, a2, a3, converged, rms, posed = fit_orders(*args, fast)
    if fast and not posed:  # a wandering fit amplifies rounding: libm's cos and sin, the numbers as before
        P, c1, a2, a3, converged, rms, _ = fit_orders(*args, False)
    return FringeRun(False, float(P), 0.0, 0.0, float(c1), float(a2), float(a3), float(zm), float(L), 0.0,
                     1.0 - rms**2 / var0, float(ptp(z)) / P if P > 0 else 0.0, rms, converged=bool(converged))


def _finish(z, r, t, P, c1, a2, a3, min_explained, min_cycles, converged=True, lapack=False,
            var_r=None, _design_of=None, lin_coef=None) -> FringeRun:
    """The linear coefficients, residual and verdict of a map (P, c1, a2, a3) on every sample.

    The linear solve is the compiled :func:`~._numeric.lstsq_qr` (equal to rounding) where the map is
    well posed (converged, at least one period in the range); LAPACK's, the solver these numbers were
    first computed with, with ``lapack``, where the map is ill-posed (cos and sin then nearly the
    baseline's line: rounding moves the amplitude by percent, the JPK stress-relaxation curve) and
    where fringes are found (they are subtracted from every sample: the same bits).
    """
    if _design_of is None:
        z_hi, z_lo = z.max(), z.min()
        zm = 0.5 * (z_hi + z_lo)
        L = 0.5 * float(z_hi - z_lo) or 1.0
        xt = tm = tL = None
        if t is not None:
            t_hi, t_lo = t.max(), t.min()
            tm, tL = 0.5 * (t_hi + t_lo), 0.5 * float(t_hi - t_lo) or 1.0
            xt = (t - tm) / tL
        X, x, u = _design(z, zm, L, P, c1, a2, a3, xt)
        u_range = ptp(u)
    else:  # the LAPACK pass of the same map: the same design matrix
        zm, L, xt, tm, tL, X, x, u, u_range = _design_of
    lapack = lapack or not (converged and float(u_range / P) >= 1.0)
    coef, ok = (None, False) if lapack else lstsq_qr(X, np.ascontiguousarray(r, dtype=float), 1e-5)
    if not ok:  # ill-conditioned (a period far beyond the range): LAPACK's truncated solution
        coef, *_ = np.linalg.lstsq(X, r, rcond=None)
    res = X @ coef - r
    amp = float(math.hypot(coef[0], coef[1]))
    phase = float(math.atan2(-coef[1], coef[0]))
    # a linear map (a2 = a3 = 0) leaves rounding noise here: np.polyfit's, kept bit for bit; a curved one
    # a nonlinearity far above rounding, which the compiled fit gives to ~1e-13 of it
    curved = abs(a2) + abs(a3) > 1e-3  # (u does not depend on the linear solve: LAPACK or not alike)
    if lin_coef is None:
        lin_coef = polyfit(z, u, 1) if curved else _np_line(z, u)
    # numpy's max |u - polyval|, var(res) and sqrt(mean(res^2)), bit for bit, in one compiled call
    dev, var_res, rms = finish_stats(res, u, z, float(lin_coef[0]), float(lin_coef[1]))
    nonlin = float(dev / max(u_range, 1e-300))
    explained = 1.0 - float(var_res) / (float(np.var(r)) if var_r is None else var_r)
    cycles = float(u_range / P)
    found = converged and explained >= min_explained and cycles >= min_cycles and monotonic_map(c1, a2, a3)
    if found and ok:
        return _finish(z, r, t, P, c1, a2, a3, min_explained, min_cycles, converged, lapack=True, var_r=var_r,
                       _design_of=(zm, L, xt, tm, tL, X, x, u, u_range), lin_coef=lin_coef)
    if xt is None:
        base = (float(coef[2]), float(coef[3]) / L, float(zm), "position")
    else:
        base = (float(coef[2]), float(coef[3]) / tL, float(tm), "time")
    return FringeRun(bool(found), float(P), amp, phase, float(c1), float(a2), float(a3), float(zm), float(L),
                     nonlin, float(explained), cycles, float(rms), *base, converged=converged)


def _np_line(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``np.polyfit(x, y, 1)`` for 1-D float64 ``x``, ``y`` of equal length > 0, bit for bit: its steps (the
    Vandermonde columns scaled by their norms, LAPACK's least squares at numpy's ``rcond``, the scale
    divided out, RankWarning on a rank below 2) without its argument checks and ``lstsq``'s wrappers
    (~30 us of the ~80 of a 1,300-sample call; the fringe fit's linear maps, issue 35)."""
    from numpy.linalg import _umath_linalg

    n = x.size
    lhs = np.empty((n, 2))
    lhs[:, 0] = x
    lhs[:, 1] = 1.0
    scale = np.sqrt((lhs * lhs).sum(axis=0))
    lhs /= scale
    with np.errstate(call=_lstsq_failed, invalid="call", over="ignore", divide="ignore", under="ignore"):
        c, _, rank, _ = _umath_linalg.lstsq(lhs, y[:, None], n * np.finfo(float).eps, signature="ddd->ddid")
    if rank != 2:
        import warnings

        warnings.warn("Polyfit may be poorly conditioned", np.exceptions.RankWarning, stacklevel=2)
    return c[:, 0] / scale


def _lstsq_failed(err, flag):
    raise np.linalg.LinAlgError("SVD did not converge in Linear Least Squares")


def monotonic_map(c1: float, a2: float, a3: float, reach: float = 1.5) -> bool:
    """Does the map ``u(x) = c1 (x + a2 x^2 + a3 x^3)`` increase over ``|x| <= reach`` (as far as
    :func:`position_map` uses the polynomial)? A piezo moves one way while its drive does: a map
    that turns back (``du/dx <= 0`` somewhere) is no position, whatever it explains of a baseline
    (a fit of a slow wobble over barely one period), and is not taken for fringes."""
    if not c1 > 0:
        return False
    grid = _MAP_GRIDS.get(reach)
    if grid is None:
        x = np.linspace(-reach, reach, 301)
        x2 = x**2
        x.flags.writeable = x2.flags.writeable = False
        grid = _MAP_GRIDS[reach] = (x, x2)
    x, x2 = grid
    return bool(np.all(1.0 + 2.0 * a2 * x + 3.0 * a3 * x2 > 0))


_MAP_GRIDS: dict[float, tuple[np.ndarray, np.ndarray]] = {}


def loop_width(fa: FringeRun, fr: FringeRun, z: np.ndarray) -> float:
    """Largest gap between the two runs' true-position maps over ``z``, modulo P [m]."""
    if not (fa.found and fr.found):
        return math.nan
    P = 0.5 * (fa.period + fr.period)
    pa = position_map(z, fa) + fa.phase * fa.period / (2 * math.pi)
    pr = position_map(z, fr) + fr.phase * fr.period / (2 * math.pi)
    gap = pa - pr
    mean = float(np.mean(gap))
    gap = gap - P * round(mean / P)
    return float(np.max(np.abs(gap)))
