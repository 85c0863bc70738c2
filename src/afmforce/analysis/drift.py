"""Thermal drift: a line in time fitted in the zero-force region, separately per run.

Paper section 3.1 (Fig 7): "A linear thermal drift correction has been applied
separately on the two runs, as measured in the zero-force regime." Subtracting
the line also sets the zero-force baseline to zero, so deflections and forces
afterwards are relative to the baseline.

When the approach starts close to the surface, the far part of the run still
feels the tail of the attraction, and a line fitted there is tilted by it
(by 10-15 % of A R for a 60 nm approach at R = 220 nm). The approach baseline
therefore may carry one more regressor, ``1 / (z_contact - z + h_tail)^2`` (the
shape of a van der Waals tail); it is kept only when it lowers the residual
sum of squares significantly, and only the line is subtracted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._numeric import mad_sigma
from .regions import RunRegions
from ._units import unit as _u
from .options import DriftOptions as _D  # the default: declared once, in the step's record

__all__ = ["DriftResult", "fit_baseline", "remove_drift", "is_settling"]

#: Baselines longer than this are fitted on evenly thinned samples (the standard error of the
#: line grows as sqrt(n / MAX_POINTS), still far below the noise it is compared with).
MAX_POINTS = 4001


@dataclass(frozen=True)
class DriftResult:
    """Baseline lines ``s = offset + slope (t - t_start)`` of each run (signal units ``unit``).

    Attributes
    ----------
    offset_approach, offset_retract : float
        Baseline at the start of the run [unit].
    slope_approach, slope_retract : float
        Drift rate [unit/s].
    noise : float
        Robust standard deviation of the approach baseline residuals [unit].
    retract_from_approach : bool
        The retract's free part was too short or too noisy; the approach line was used.
    unit : str
        ``"V"``, ``"m"`` or ``"N"``.
    retract_settling : bool
        The retract's free part is still relaxing after the pull-off (see :func:`is_settling`):
        not a drift line, so the approach line was used.
    """

    offset_approach: float = _u("{signal}")
    slope_approach: float = _u("{signal}/s")
    offset_retract: float = _u("{signal}")
    slope_retract: float = _u("{signal}/s")
    noise: float = _u("{signal}")
    retract_from_approach: bool
    unit: str
    retract_settling: bool = False


def _wls(X: np.ndarray, y: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Weighted least squares by the normal equations (the 1-3 columns here are scaled to
    order one); lstsq only if they are singular."""
    Xw = X * w[:, None]
    try:
        return np.linalg.solve(Xw.T @ X, Xw.T @ y)
    except np.linalg.LinAlgError:
        sw = np.sqrt(w)
        return np.linalg.lstsq(X * sw[:, None], y * sw, rcond=None)[0]


def _irls(X: np.ndarray, y: np.ndarray, n_iter: int = 6, tuning: float = 4.685):
    """Bisquare-weighted least squares: coefficients, robust residual scale, weighted SSR."""
    w = np.ones(y.size)
    coef = _wls(X, y, w)
    sigma = 0.0
    for _ in range(n_iter):
        r = y - X @ coef
        sigma = float(mad_sigma(r))
        if not sigma > 0:
            break
        u = r / (tuning * sigma)
        w = np.where(np.abs(u) < 1, (1 - u * u) ** 2, 0.0)
        coef = _wls(X, y, w)
    r = y - X @ coef
    return coef, sigma, float(np.sum(w * r * r))


def fit_baseline(t: np.ndarray, s: np.ndarray, order: int = 1,
                 tail: np.ndarray | None = None) -> tuple[float, float, float]:
    """Robust baseline of order 0 (offset) or 1 (line in time): ``(offset, slope, noise)``.

    ``offset`` is the value at ``t[0]``; ``noise`` the robust scale of the residuals.
    ``tail`` is an optional extra regressor (see the module docstring), kept only
    if it lowers the residual sum of squares by more than 25 noise variances.
    """
    if s.size > MAX_POINTS:  # a long baseline: evenly thinned (the line's error stays far below the noise)
        keep = np.linspace(0, s.size - 1, MAX_POINTS).astype(np.int64)
        t, s = t[keep], s[keep]
        tail = None if tail is None else tail[keep]
    tt = t - t[0]
    if order == 0 or np.ptp(tt) == 0:
        X = np.ones((s.size, 1))
    else:
        X = np.column_stack([np.ones_like(tt), tt / max(np.ptp(tt), 1e-300)])
    coef, sigma, ssr = _irls(X, s)
    if tail is not None and s.size > X.shape[1] + 5 and np.ptp(tail) > 0:
        Xt = np.column_stack([X, tail / np.max(np.abs(tail))])
        coef_t, sigma_t, ssr_t = _irls(Xt, s)
        if sigma > 0 and ssr - ssr_t > 25.0 * sigma**2:
            coef, sigma = coef_t, sigma_t
    slope = float(coef[1]) / max(np.ptp(tt), 1e-300) if X.shape[1] > 1 else 0.0
    return float(coef[0]), slope, float(sigma)


def is_settling(t: np.ndarray, s: np.ndarray, nsigma: float = 5.0) -> bool:
    """True when a baseline is a relaxation, not a drift line: a parabola in time fits it
    better than the line by more than ``nsigma`` times the curvature's standard error, the
    curved part spans more than ``nsigma`` noise levels, and it decays (both halves slope the
    same way, the first at least twice as steeply).

    After the pull-off an overdamped (viscous) cantilever returns to zero over a time
    ``~ xi / k``; when the run ends within a few such times, its "free" part is an
    exponential tail. A line fitted there is the tail's slope, not the drift (in the
    paper preset's Fig 5 run, 1.14 V/s against a true drift of 0.098 V/s), and it tilts the
    whole retract. Drift over a fraction of a second is a line to well within the noise.
    """
    if t.size < 12 or np.ptp(t) == 0:
        return False
    if t.size > MAX_POINTS:
        keep = np.linspace(0, t.size - 1, MAX_POINTS).astype(np.int64)
        t, s = t[keep], s[keep]
    x = (t - t.mean()) / np.ptp(t)
    X = np.column_stack([np.ones_like(x), x, x * x - np.mean(x * x)])
    coef, sigma, _ = _irls(X, s)
    if not sigma > 0:
        return False
    r = s - X @ coef
    sigma = max(sigma, float(np.std(r)))
    cov = np.linalg.pinv(X.T @ X) * sigma**2
    c, se = float(coef[2]), float(np.sqrt(max(cov[2, 2], 0.0)))
    bow = abs(c) * float(np.ptp(X[:, 2]))  # signal change the curvature accounts for
    if not (abs(c) > nsigma * se and bow > nsigma * sigma):
        return False
    # a relaxation decays: both halves slope the same way, the first at least twice as steeply
    # (a bow of the baseline, e.g. optical, slopes the two ways and is not this)
    half = t.size // 2
    s1 = float(np.polyfit(t[:half], s[:half], 1)[0])
    s2 = float(np.polyfit(t[half:], s[half:], 1)[0])
    return s1 * s2 > 0 and abs(s1) > 2 * abs(s2)


def remove_drift(t: np.ndarray, s: np.ndarray, segment: np.ndarray, approach: RunRegions,
                 retract: RunRegions, unit: str, order: int = _D.order, min_points: int = 5,
                 max_noise_ratio: float = 5.0, z: np.ndarray | None = None, h_tail: float = 5e-9):
    """Subtract each run's baseline line; returns ``(corrected signal, DriftResult)``.

    Dwell samples (segment 2) get the approach line. The retract run uses the
    approach line instead of its own when its free part is too short, or more
    than ``max_noise_ratio`` times noisier than the approach's (a cantilever
    ringing freely after the pull-off: its line would be biased).
    """
    out = np.array(s, dtype=float, copy=True)
    ia = approach.index[approach.zero_force]
    tail = None
    if z is not None:
        z_c = z[approach.index[approach.split]]
        tail = 1.0 / (np.maximum(z_c - z[ia], 0.0) + h_tail) ** 2
    off_a, slope_a, noise = fit_baseline(t[ia], s[ia], order, tail)
    t0a = t[ia[0]]
    ir = retract.index[retract.zero_force]
    from_app = ir.size < min_points
    settling = False
    if not from_app:
        off_r, slope_r, noise_r = fit_baseline(t[ir], s[ir], order)
        t0r = t[ir[0]]
        from_app = noise > 0 and noise_r > max_noise_ratio * noise
        if not from_app and order == 1:
            settling = is_settling(t[ir], s[ir])
            from_app = settling
    if from_app:
        off_r, slope_r, t0r = off_a, slope_a, t0a
    not_ret = np.asarray(segment) != 1
    out[not_ret] -= off_a + slope_a * (t[not_ret] - t0a)
    ret = retract.index
    out[ret] -= off_r + slope_r * (t[ret] - t0r)
    # report offsets at the start of each run
    start_a, start_r = t[approach.index[0]], t[retract.index[0]]
    res = DriftResult(offset_approach=off_a + slope_a * (start_a - t0a), slope_approach=slope_a,
                      offset_retract=off_r + slope_r * (start_r - t0r), slope_retract=slope_r,
                      noise=noise, retract_from_approach=bool(from_app), unit=unit,
                      retract_settling=bool(settling))
    return out, res
