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
from scipy.optimize import least_squares
from scipy.signal import lombscargle

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
    """

    found: bool
    period: float
    amplitude: float
    phase: float
    scale: float
    a2: float
    a3: float
    z_mid: float
    half_range: float
    nonlinearity: float
    explained: float
    cycles: float
    residual: float
    baseline_offset: float = 0.0
    baseline_slope: float = 0.0
    baseline_origin: float = 0.0
    baseline_variable: str = "position"


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
    loop_width: float
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
    poly = xc + fr.a2 * xc**2 + fr.a3 * xc**3
    slope = 1.0 + 2 * fr.a2 * xc + 3 * fr.a3 * xc**2
    return fr.z_mid + fr.scale * fr.half_range * (poly + slope * (x - xc))


def fringe_signal(z: np.ndarray, fr: FringeRun) -> np.ndarray:
    """The fitted fringe term ``I0 cos(2 pi u / P + phase)`` [signal unit]."""
    return fr.amplitude * np.cos(2 * math.pi * position_map(z, fr) / fr.period + fr.phase)


def fringe_baseline(t: np.ndarray, z: np.ndarray, fr: FringeRun) -> np.ndarray:
    """The baseline line fitted with the fringes, ``e0 + e1 (t - t_mid)`` (or in position) [signal unit]."""
    v = np.asarray(t if fr.baseline_variable == "time" else z, float)
    return fr.baseline_offset + fr.baseline_slope * (v - fr.baseline_origin)


def _design(z, zm, L, P, c1, a2, a3, xt=None):
    x = (z - zm) / L
    u = zm + c1 * L * (x + a2 * x**2 + a3 * x**3)
    th = 2 * math.pi * u / P
    return np.column_stack([np.cos(th), np.sin(th), np.ones_like(x), x if xt is None else xt]), x, u


def _initial_period(z: np.ndarray, r: np.ndarray, max_points: int = 4000) -> float:
    """Strongest period of a Lomb-Scargle periodogram (on at most ``max_points`` samples, evenly thinned)."""
    span = float(np.ptp(z))
    step = float(np.median(np.abs(np.diff(np.sort(z))))) or span / z.size
    if z.size > max_points:  # a starting value only: thin the samples, the search grid stays the same
        keep = np.linspace(0, z.size - 1, max_points).astype(np.int64)
        z, r = z[keep], r[keep]
    p_min, p_max = max(4 * step, span / 400), span / 1.5
    periods = np.geomspace(p_min, p_max, 800)
    zz = z - z.mean()
    rr = r - r.mean()
    power = lombscargle(zz, rr, 2 * math.pi / periods)
    return float(periods[int(np.argmax(power))])


def fit_fringes(z: np.ndarray, r: np.ndarray, *, period: float | None = None, order: int | str = "auto",
                min_explained: float = 0.3, min_cycles: float = 1.0, t: np.ndarray | None = None) -> FringeRun:
    """Fit the fringe model to the baseline residual ``r`` against position ``z``.

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
    t : ndarray, optional
        Sample times [s]: the baseline line is fitted in time instead of position.
    """
    z = np.asarray(z, float)
    r = np.asarray(r, float)
    p0 = None if period or z.size < 16 or np.var(r) == 0 else _initial_period(z, r)
    if order == "auto":
        fits = [_fit_order(z, r, period, o, min_explained, min_cycles, t, p0) for o in (1, 2, 3)]
        n = max(np.asarray(z).size, 1)
        bic = [n * math.log(max(f.residual, 1e-300) ** 2) + (o + 3) * math.log(n) if math.isfinite(f.residual)
               else math.inf for o, f in zip((1, 2, 3), fits)]
        return fits[int(np.argmin(bic))]
    return _fit_order(z, r, period, int(order), min_explained, min_cycles, t, p0)


def _fit_order(z, r, period, order, min_explained, min_cycles, t=None, p_start=None) -> FringeRun:
    """:func:`fit_fringes` for one map order."""
    z = np.asarray(z, float)
    r = np.asarray(r, float)
    nan = math.nan
    if z.size < 16:
        return FringeRun(False, nan, 0.0, 0.0, 1.0, 0.0, 0.0, nan, 1.0, 0.0, 0.0, 0.0, nan)
    zm = 0.5 * (z.max() + z.min())
    L = 0.5 * float(np.ptp(z)) or 1.0
    xt = None
    if t is not None:
        t = np.asarray(t, float)
        tm, tL = 0.5 * (t.max() + t.min()), 0.5 * float(np.ptp(t)) or 1.0
        xt = (t - tm) / tL
    var0 = float(np.var(r))
    if z.size < 16 or var0 == 0:
        return FringeRun(False, nan, 0.0, 0.0, 1.0, 0.0, 0.0, zm, L, 0.0, 0.0, 0.0, nan)
    P0 = float(period) if period else (p_start if p_start else _initial_period(z, r))
    n_map = max(0, min(order, 3) - 1)

    def unpack(q):
        if period:
            c1, P, rest = q[0], float(period), q[1:]
        else:
            c1, P, rest = 1.0, P0 * math.exp(q[0]), q[1:]
        a2 = rest[0] if n_map >= 1 else 0.0
        a3 = rest[1] if n_map >= 2 else 0.0
        return P, c1, a2, a3

    def resid(q):
        X, _, _ = _design(z, zm, L, *unpack(q), xt)
        coef, *_ = np.linalg.lstsq(X, r, rcond=None)
        return X @ coef - r

    q0 = np.zeros(1 + n_map)
    q0[0] = 1.0 if period else 0.0
    best = None
    for a3_start in (0.0,) if n_map < 2 else (0.0, 0.05, -0.05):
        q = q0.copy()
        if n_map >= 2:
            q[2] = a3_start
        sol = least_squares(resid, q, method="trf", x_scale=1.0)
        if best is None or sol.cost < best.cost:
            best = sol
    P, c1, a2, a3 = unpack(best.x)
    X, x, u = _design(z, zm, L, P, c1, a2, a3, xt)
    coef, *_ = np.linalg.lstsq(X, r, rcond=None)
    res = X @ coef - r
    amp = float(math.hypot(coef[0], coef[1]))
    phase = float(math.atan2(-coef[1], coef[0]))
    lin = np.polyval(np.polyfit(z, u, 1), z)
    nonlin = float(np.max(np.abs(u - lin)) / max(np.ptp(u), 1e-300))
    explained = 1.0 - float(np.var(res)) / var0
    cycles = float(np.ptp(u) / P)
    found = explained >= min_explained and cycles >= min_cycles
    if xt is None:
        base = (float(coef[2]), float(coef[3]) / L, float(zm), "position")
    else:
        base = (float(coef[2]), float(coef[3]) / tL, float(tm), "time")
    return FringeRun(bool(found), float(P), amp, phase, float(c1), float(a2), float(a3), float(zm), float(L),
                     nonlin, float(explained), cycles, float(np.sqrt(np.mean(res**2))), *base)


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
