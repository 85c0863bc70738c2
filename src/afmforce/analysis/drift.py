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

The retract's free part starts right after the pull-off, where a damped lever
is still returning to its rest position (an exponential of time constant
``~ xi / k``). That return is real motion, not drift: the retract baseline may
carry one more regressor, ``exp(-(t - t_first) / tau)`` with ``tau`` the best of
a grid from one sample to a fifth of the free part, rising from below (the
lever returns from the adhesive side; a baseline that bows the other way is not
this), kept under the same rule,
and again only the line is subtracted (the beam with xi = 0.01 kg/s at 1 um/s:
a false drift of 0.025 V/s without it, 0.38 nm at the compliance region).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import config as _numba_config
from numba import njit

from ._numeric import irls_bisquare, mad_sigma, polyfit, ptp, solve_small
from .regions import RunRegions
from ._units import unit as _u
from .options import DriftOptions as _D  # the default: declared once, in the step's record

__all__ = ["DriftResult", "fit_baseline", "remove_drift", "is_settling", "retract_line", "borrowed_line"]

#: Baselines longer than this are fitted on evenly thinned samples (the standard error of the
#: line grows as sqrt(n / MAX_POINTS), still far below the noise it is compared with).
MAX_POINTS = 4001


#: The retract line's model choice works on block means of at most about this many points.
SELECT_POINTS = 1000

#: numba does not compile (``NUMBA_DISABLE_JIT``: the first run after an install): the numpy code,
#: without loops run as Python.
_COLD = bool(_numba_config.DISABLE_JIT)


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
        The approach line was used for the retract: its free part was too short or too noisy, or
        it continues the approach line (see :func:`continues_approach`).
    unit : str
        ``"V"``, ``"m"`` or ``"N"``.
    retract_settling : bool
        The retract's free part is still relaxing after the pull-off (see :func:`is_settling`):
        not a drift line, so the approach line was used.
    retract_line : str
        Which retract line was used: ``"approach"`` (the approach line continued), ``"continuous"``
        (from the approach line's end, own slope) or ``"separate"`` (own offset and slope), see
        :func:`retract_line`; on a retract too noisy for a line of its own, ``"offset"``,
        ``"approach slope"`` or ``"position tilt"`` (its own offset; see :func:`borrowed_line`).
    tilt_retract : float
        Baseline slope per unit position subtracted on the retract [unit/m] (``"position tilt"``
        only; 0 otherwise): the baseline there is ``offset_retract + slope_retract (t - t_r) +
        tilt_retract (z - z_r)`` from the retract's first free sample.
    baseline_climb : float
        The fraction of the approach signal's rise after its free part that the approach's drift line takes
        away, when over the drift step's limit (its warning, ``MAX_BASELINE_CLIMB``) [-]; NaN otherwise. The
        indentation step then also fits without the drift slope and widens the modulus's interval.
    """

    offset_approach: float = _u("{signal}")
    slope_approach: float = _u("{signal}/s")
    offset_retract: float = _u("{signal}")
    slope_retract: float = _u("{signal}/s")
    noise: float = _u("{signal}")
    retract_from_approach: bool
    unit: str
    retract_settling: bool = False
    retract_line: str = "separate"
    tilt_retract: float = _u("{signal}/m", 0.0)
    baseline_climb: float = _u("", math.nan)


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
    """Bisquare-weighted least squares: coefficients, robust residual scale, weighted SSR.

    Stops early once an iteration moves the fit by less than 1e-4 of the residual scale
    (the columns here are scaled to order one, so ``sum |delta coef|`` bounds the move).
    Compiled (:func:`~._numeric.irls_bisquare`: the same iterations in loops, ~10x faster than
    the numpy calls; sums in another order, so the results differ in the last bits); the numpy
    version below when a normal-equation system is singular.
    """
    X = np.ascontiguousarray(X, dtype=float)
    y = np.ascontiguousarray(y, dtype=float)
    coef, sigma, ssr, ok = (_irls_seq if _COLD else irls_bisquare)(X, y, n_iter, tuning)
    if ok:
        return coef, float(sigma), float(ssr)
    return _irls_numpy(X, y, n_iter, tuning)


def _sum(v: np.ndarray) -> float:
    """The sum of ``v`` from the first element on, in order (a compiled loop's sum)."""
    return float(np.add.accumulate(v)[-1]) if v.size else 0.0


def _irls_seq(X: np.ndarray, y: np.ndarray, n_iter: int = 6, tuning: float = 4.685):
    """:func:`~._numeric.irls_bisquare` in numpy calls, its numbers bit for bit (its sums in order by
    ``np.add.accumulate``, the same products): what :func:`_irls` runs when numba does not compile
    (the first run after an install), where the kernel's loops would run as Python."""
    n, p = X.shape

    def wls(w):
        keep = w != 0.0
        Xk, yk = X[keep], y[keep]
        xw = Xk * w[keep][:, None]
        A = np.array([[_sum(xw[:, j] * Xk[:, k]) for k in range(p)] for j in range(p)])
        b = np.array([_sum(xw[:, j] * yk) for j in range(p)])
        out = solve_small(A, b)
        return out, not math.isnan(out[0])

    def resid(coef):
        fit = 0.0 + X[:, 0] * coef[0]
        for j in range(1, p):
            fit = fit + X[:, j] * coef[j]
        return y - fit

    w = np.ones(n)
    coef, ok = wls(w)
    if not ok:
        return coef, 0.0, 0.0, False
    sigma = 0.0
    for _ in range(n_iter):
        r = resid(coef)
        sigma = mad_sigma(r)
        if not sigma > 0:
            break
        u = r / (tuning * sigma)
        w = np.where(np.abs(u) < 1.0, (1.0 - u * u) ** 2, 0.0)
        new, ok = wls(w)
        if not ok:
            return coef, sigma, 0.0, False
        moved = 0.0
        for j in range(p):
            moved += abs(new[j] - coef[j])
        coef = new
        if moved < 1e-4 * sigma:
            break
    e = resid(coef)
    return coef, sigma, _sum(w * e * e), True


def _irls_numpy(X: np.ndarray, y: np.ndarray, n_iter: int = 6, tuning: float = 4.685):
    """:func:`_irls` in numpy calls, with lstsq for a singular system."""
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
        new = _wls(X, y, w)
        moved = float(np.sum(np.abs(new - coef)))
        coef = new
        if moved < 1e-4 * sigma:
            break
    r = y - X @ coef
    return coef, sigma, float(np.sum(w * r * r))


def _transient(t: np.ndarray, min_points: int = 12, n_tau: int = 16) -> np.ndarray:
    """Candidate settling regressors ``exp(-(t - t[0]) / tau)`` as columns (n, K), tau from one
    sample to a fifth of the span; (n, 0) when the baseline is too short."""
    span = float(t[-1] - t[0]) if t.size else 0.0
    if t.size < min_points or not span > 0:
        return np.empty((t.size, 0))
    dt = span / (t.size - 1)
    taus = np.geomspace(dt, span / 5.0, n_tau)
    return np.exp(-np.divide.outer(t - t[0], taus))


@njit(cache=True)
def _family_costs(X, y, E, cap):
    """The capped residual sums of :func:`_family`'s candidates ``[X, E_k]`` in compiled loops (the
    same normal equations, sums in another order; infinite where the settling term's coefficient
    is not negative): ``(costs, ok)``; ``ok`` False when a system is singular."""
    n, p = X.shape
    K = E.shape[1]
    q = p + 1
    G = np.zeros((p, p))  # X^T X, X^T y, X^T E, E^T y, diag(E^T E)
    gy = np.zeros(p)
    xe = np.zeros((p, K))
    ey = np.zeros(K)
    ee = np.zeros(K)
    for i in range(n):
        for j in range(p):
            gy[j] += X[i, j] * y[i]
            for l in range(p):
                G[j, l] += X[i, j] * X[i, l]
            for k in range(K):
                xe[j, k] += X[i, j] * E[i, k]
        for k in range(K):
            ey[k] += E[i, k] * y[i]
            ee[k] += E[i, k] * E[i, k]
    costs = np.full(K, np.inf)
    M = np.empty((q, q))
    rhs = np.empty(q)
    for k in range(K):
        for j in range(p):
            for l in range(p):
                M[j, l] = G[j, l]
            M[j, p] = xe[j, k]
            M[p, j] = xe[j, k]
            rhs[j] = gy[j]
        M[p, p] = ee[k]
        rhs[p] = ey[k]
        c = solve_small(M, rhs)
        if math.isnan(c[0]):
            return costs, False
        if not c[p] < 0:
            continue
        cost = 0.0
        for i in range(n):
            r = y[i] - E[i, k] * c[p]
            for j in range(p):
                r -= X[i, j] * c[j]
            cost += min(r * r, cap)
        costs[k] = cost
    return costs, True


def _family(X: np.ndarray, y: np.ndarray, E: np.ndarray, cap: float) -> tuple[float, np.ndarray, int]:
    """Least squares of ``y`` on ``X`` (n, p; p may be 0) and on ``[X, E_k]`` for every column of
    ``E`` at once (the settling candidates; kept only with a negative coefficient: rising from below).

    Returns the smallest capped residual sum (squares capped at ``cap``, so a spike costs the same
    in every model), the coefficients of ``X`` there, and the column of ``E`` used (-1: none).
    Plain least squares on normal equations: 16 candidates cost one matrix product, not 16 robust fits.
    The candidates' sums are compiled (:func:`_family_costs`); the numpy solve below runs only when
    a candidate wins with coefficients to give (they are then those of these numpy calls, bit for bit:
    the retract's line reaches every sample).
    """
    p = X.shape[1]
    if p:
        c0 = _wls(X, y, np.ones(y.size))
        r0 = y - X @ c0
    else:
        c0, r0 = np.empty(0), y
    best, coef, used = float(np.sum(np.minimum(r0 * r0, cap))), c0, -1
    K = E.shape[1]
    if K == 0 or y.size <= p + 2:
        return best, coef, used
    costs, ok = (None, False) if _COLD else _family_costs(  # uncompiled: the numpy sums below decide
        np.ascontiguousarray(X, dtype=float), np.ascontiguousarray(y, dtype=float),
        np.ascontiguousarray(E, dtype=float), float(cap))
    if ok:
        k = int(np.argmin(costs))
        if not costs[k] < best:
            return best, coef, used
        if p == 0:  # no coefficients to give: the winner's sum is all
            return float(costs[k]), c0, k
    M = np.empty((K, p + 1, p + 1))
    rhs = np.empty((K, p + 1))
    M[:, :p, :p] = X.T @ X
    xe = X.T @ E  # (p, K)
    M[:, :p, p] = xe.T
    M[:, p, :p] = xe.T
    M[:, p, p] = np.einsum("ij,ij->j", E, E)
    rhs[:, :p] = X.T @ y
    rhs[:, p] = E.T @ y
    try:
        C = np.linalg.solve(M, rhs[..., None])[..., 0]  # (K, p + 1)
    except np.linalg.LinAlgError:
        return best, coef, used
    R = y[:, None] - X @ C[:, :p].T - E * C[:, p]
    costs = np.sum(np.minimum(R * R, cap), axis=0)
    costs[~(C[:, p] < 0)] = np.inf
    k = int(np.argmin(costs))
    if costs[k] < best:
        best, coef, used = float(costs[k]), C[k, :p], k
    return best, coef, used


def fit_baseline(t: np.ndarray, s: np.ndarray, order: int = 1,
                 tail: np.ndarray | None = None, transient: bool = False) -> tuple[float, float, float]:
    """Robust baseline of order 0 (offset) or 1 (line in time): ``(offset, slope, noise)``.

    ``offset`` is the value at ``t[0]``; ``noise`` the robust scale of the residuals.
    ``tail`` is an optional extra regressor (see the module docstring), kept only
    if it lowers the residual sum of squares by more than 25 noise variances.
    ``transient`` tries a decaying exponential from the first sample (a lever
    settling after the pull-off) under the same rule.
    """
    if s.size > MAX_POINTS:  # a long baseline: evenly thinned (the line's error stays far below the noise)
        keep = np.linspace(0, s.size - 1, MAX_POINTS).astype(np.int64)
        t, s = t[keep], s[keep]
        tail = None if tail is None else tail[keep]
    tt = t - t[0]
    if order == 0 or ptp(tt) == 0:
        X = np.ones((s.size, 1))
    else:
        X = np.column_stack([np.ones_like(tt), tt / max(ptp(tt), 1e-300)])
    coef, sigma, ssr = _irls(X, s)
    extra = [(tail, False)] if tail is not None else []
    if transient and X.shape[1] > 1 and sigma > 0:  # the best settling candidate, then one robust fit
        E = _transient(t)
        _, _, k = _family(X, s, E, (4.685 * sigma) ** 2)
        if k >= 0:
            extra.append((E[:, k], True))
    best = None
    for col, settles in extra:
        if s.size > X.shape[1] + 5 and ptp(col) > 0:
            Xt = np.column_stack([X, col / np.max(np.abs(col))])
            coef_t, sigma_t, ssr_t = _irls(Xt, s)
            if settles and not coef_t[-1] < 0:  # a lever settling after a pull-off rises from below
                continue
            if sigma > 0 and ssr - ssr_t > 25.0 * sigma**2 and (best is None or ssr_t < best[2]):
                best = (coef_t, sigma_t, ssr_t)
    if best is not None:
        coef, sigma = best[0], best[1]
    slope = float(coef[1]) / max(ptp(tt), 1e-300) if X.shape[1] > 1 else 0.0
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
    if t.size < 12 or ptp(t) == 0:
        return False
    if t.size > MAX_POINTS:
        keep = np.linspace(0, t.size - 1, MAX_POINTS).astype(np.int64)
        t, s = t[keep], s[keep]
    x = (t - t.mean()) / ptp(t)
    X = np.column_stack([np.ones_like(x), x, x * x - np.mean(x * x)])
    coef, sigma, _ = _irls(X, s)
    if not sigma > 0:
        return False
    r = s - X @ coef
    sigma = max(sigma, float(np.std(r)))
    cov = np.linalg.pinv(X.T @ X) * sigma**2
    c, se = float(coef[2]), float(np.sqrt(max(cov[2, 2], 0.0)))
    bow = abs(c) * float(ptp(X[:, 2]))  # signal change the curvature accounts for
    if not (abs(c) > nsigma * se and bow > nsigma * sigma):
        return False
    # a relaxation decays: both halves slope the same way, the first at least twice as steeply
    # (a bow of the baseline, e.g. optical, slopes the two ways and is not this)
    half = t.size // 2
    s1 = float(polyfit(t[:half], s[:half], 1)[0])
    s2 = float(polyfit(t[half:], s[half:], 1)[0])
    return s1 * s2 > 0 and abs(s1) > 2 * abs(s2)


def retract_line(t: np.ndarray, s: np.ndarray, off_a: float, slope_a: float, t0a: float, t_turn: float,
                 noise: float, threshold: float = 25.0, gap: bool = False) -> tuple[str, float, float]:
    """The retract's drift line, the simplest the data allow: ``(model, offset at t_turn, slope)``.

    Models, each kept only when it lowers the residual sum of squares of the retract's free part
    by more than ``threshold`` noise variances over the previous one (the rule the tail and
    settling regressors are kept by), each with an optional settling transient:

    * ``"approach"``: the approach line continued (drift is continuous in time);
    * ``"continuous"``: starts where the approach line ends (at ``t_turn``, the first retract
      sample) with its own slope (a drift rate that changes at the turn; also what a baseline
      that depends on the position, e.g. optical crosstalk, looks like in time);
    * ``"separate"``: its own offset and slope (the paper's recipe, section 3.1).

    The retract's free part is often short (80 ms against 200 ms of approach baseline on the
    xi = 0.01 kg/s beam run) and its line is extrapolated back over the whole contact, so its
    own offset and slope carry the larger error there. ``gap``: a dwell lies between the runs, so
    ``"continuous"`` (anchored at the approach line's value after the dwell) is not tried.
    """
    at_turn = off_a + slope_a * (t_turn - t0a)
    if not noise > 0 or t.size < 12:
        return "separate", math.nan, math.nan
    m = t.size // SELECT_POINTS
    if m > 1:  # block means: the same evidence in fewer points (the noise of a mean is noise / sqrt(m))
        k = t.size // m
        t, s = t[: k * m].reshape(k, m).mean(1), s[: k * m].reshape(k, m).mean(1)
        noise = noise / math.sqrt(m)
    E = _transient(t)
    cap = (4.685 * noise) ** 2
    y0 = s - (off_a + slope_a * (t - t0a))
    ssr0, _, _ = _family(np.empty((t.size, 0)), y0, E, cap)
    scale = max(float(t[-1] - t_turn), 1e-300)
    y1 = s - at_turn
    ssr1, c1, _ = _family(((t - t_turn) / scale)[:, None], y1, E, cap)
    X2 = np.column_stack([np.ones_like(t), (t - t_turn) / scale])
    ssr2, c2, _ = _family(X2, y1, E, cap)
    lim = threshold * noise**2
    if ssr0 - min(ssr1, ssr2) <= lim:
        return "approach", at_turn, slope_a
    if ssr1 - ssr2 <= lim and not gap:
        return "continuous", at_turn, float(c1[0]) / scale
    return "separate", at_turn + float(c2[0]), float(c2[1]) / scale


def borrowed_line(t: np.ndarray, s: np.ndarray, z: np.ndarray | None, off_a: float, slope_a: float, t0a: float,
                  tilt: float, noise: float, threshold: float = 25.0) -> tuple[str, float, float, float]:
    """The retract's baseline when its free part is too noisy for a line of its own (a ringing or
    unbinding retract): ``(model, offset at t[0], slope in time, tilt in position)``.

    The baseline ``offset + slope (t - t[0]) + tilt (z - z[0])`` is the simplest of:

    * ``"approach"``: the approach line continued in time (drift is continuous);
    * ``"offset"``: its own robust offset only;
    * ``"approach slope"``: its own offset, the approach's drift rate;
    * ``"position tilt"``: its own offset, the approach baseline's tilt per unit position
      (``tilt``: optical crosstalk, virtual deflection: what makes a long baseline slope, and
      what follows the position, not the time, on the way back);

    a one-parameter model replaces the continued line only when it lowers the residuals of the free
    part by more than ``threshold`` noise variances (squares capped at 4.7 noise levels: spikes and
    unbinding events count the same in every model). A dwell between the runs (a stress-relaxation or
    a pause) makes the continued line an extrapolation over the dwell: the data decide.
    """
    cap = (4.685 * noise) ** 2 if noise > 0 else np.inf
    tt = t - t[0]
    cont = s - (off_a + slope_a * (t - t0a))
    best = ("approach", off_a + slope_a * (t[0] - t0a), slope_a, 0.0)
    ssr0 = float(np.sum(np.minimum(cont * cont, cap)))
    cands = [("offset", np.zeros_like(s), 0.0, 0.0), ("approach slope", slope_a * tt, slope_a, 0.0)]
    if z is not None and math.isfinite(tilt):
        cands.append(("position tilt", tilt * (z - z[0]), 0.0, tilt))
    ssr_best = ssr0
    for name, shape, slope, tl in cands:
        y = s - shape
        coef, _, _ = _irls(np.ones((y.size, 1)), y)
        r = y - coef[0]
        ssr = float(np.sum(np.minimum(r * r, cap)))
        if ssr0 - ssr > threshold * noise**2 and ssr < ssr_best:
            ssr_best, best = ssr, (name, float(coef[0]), slope, tl)
    return best


def _remove_drift_numpy(t: np.ndarray, s: np.ndarray, segment: np.ndarray, approach: RunRegions,
                        retract: RunRegions, unit: str, order: int = _D.order, min_points: int = 5,
                        max_noise_ratio: float = 5.0, z: np.ndarray | None = None, h_tail: float = 5e-9):
    """:func:`remove_drift` in numpy calls and the compiled fits of :mod:`._numeric` (the code the
    kernels of :mod:`._drift_kernel` reproduce; what runs when they are not compiled): the same
    arguments, the same ``(corrected signal, DriftResult)``, the method described there.
    """
    out = np.array(s, dtype=float, copy=True)
    ia = approach.index[approach.zero_force]
    tail = None
    zpos = z
    if z is not None:
        z_c = z[approach.index[approach.split]]
        tail = 1.0 / (np.maximum(z_c - z[ia], 0.0) + h_tail) ** 2
    off_a, slope_a, noise = fit_baseline(t[ia], s[ia], order, tail)
    t0a = t[ia[0]]
    ir = retract.index[retract.zero_force]
    settling = False
    line = "approach"  # too short a free part, or too noisy (ringing): the approach line
    off_r, slope_r, t0r, tilt_r, z0r = off_a, slope_a, t0a, 0.0, 0.0
    gap = bool(retract.index[0] - approach.index[-1] > 1)  # a dwell (or anything) between the runs
    if ir.size >= min_points:
        off, slope, noise_r = fit_baseline(t[ir], s[ir], order, transient=order != 1)  # order 1: retract_line
        if noise > 0 and noise_r > max_noise_ratio * noise:
            tilt = math.nan
            if zpos is not None and ia.size > 2 and ptp(t[ia]) > 0:
                v = float(np.polyfit(t[ia] - t0a, zpos[ia], 1)[0])  # numpy: the tilt reaches every retract sample
                tilt = slope_a / v if v != 0 else math.nan
            line, off, slope, tl = borrowed_line(t[ir], s[ir], None if zpos is None else zpos[ir], off_a, slope_a,
                                                 t0a, tilt, noise_r)
            if line != "approach":
                off_r, slope_r, t0r, tilt_r = off, slope, t[ir[0]], tl
                z0r = float(zpos[ir[0]]) if zpos is not None else 0.0
        elif order != 1:
            line, off_r, slope_r, t0r = "separate", off, slope, t[ir[0]]
        else:
            settling = is_settling(t[ir], s[ir])
            if not settling:
                t_turn = t[retract.index[0]]
                line, off, slope = retract_line(t[ir], s[ir], off_a, slope_a, t0a, t_turn, noise, gap=gap)
                if math.isfinite(off):
                    off_r, slope_r, t0r = off, slope, t_turn
                else:
                    line = "approach"
    from_app = line == "approach"
    base = np.full(s.size, np.nan)
    app = approach.index
    base[app] = off_a + slope_a * (t[app] - t0a)
    ret = retract.index
    base[ret] = off_r + slope_r * (t[ret] - t0r) + (tilt_r * (z[ret] - z0r) if tilt_r else 0.0)
    other = np.isnan(base)
    if other.any():  # dwell, pauses: between the runs' baselines in time, held outside them
        known = np.flatnonzero(~other)
        order_t = known[np.argsort(t[known], kind="stable")]
        base[other] = np.interp(t[other], t[order_t], base[order_t])
    out -= base
    # report offsets at the start of each run
    start_a, start_r = t[approach.index[0]], t[retract.index[0]]
    res = DriftResult(offset_approach=off_a + slope_a * (start_a - t0a), slope_approach=slope_a,
                      offset_retract=float(base[ret[0]]), slope_retract=slope_r,
                      noise=noise, retract_from_approach=bool(from_app), unit=unit,
                      retract_settling=bool(settling), retract_line=line, tilt_retract=float(tilt_r))
    return out, res


def _tau(start: float, stop: float, num: int, k: int) -> float:
    """``np.geomspace(start, stop, num)[k]`` for ``0 < start, stop`` (the same number: its
    ``np.linspace`` element ``k * step + log10(start)`` and ``np.power``, on scalars)."""
    if k == 0:
        return start
    if k == num - 1:
        return stop
    lo = np.log10(np.float64(start))
    step = float(np.log10(np.float64(stop)) - lo) / (num - 1)
    if step == 0:  # linspace's denormal branch (never for a settling grid)
        y = np.linspace(lo, np.log10(np.float64(stop)), num)
        return float(np.power(10.0, y)[k])
    return float(np.power(10.0, float(k) * step + float(lo)))


def family_coef(X: np.ndarray, y: np.ndarray, t: np.ndarray, k: int) -> np.ndarray:
    """The coefficients of ``X`` that :func:`_family` gives when its settling column ``k`` of
    ``_transient(t)`` wins (-1: none wins), bit for bit, in fewer numpy calls: the winner's system
    alone, from a matrix that holds only its column (BLAS gives each column's sums from that column
    alone; einsum's column sums are the sums in order, ``np.add.accumulate``'s:
    ``tests/analysis/test_drift_kernel.py`` checks it against :func:`_family`)."""
    if k < 0:
        return _wls(X, y, np.ones(y.size))
    p = X.shape[1]
    span = float(t[-1] - t[0])
    e = np.exp(-((t - t[0]) / _tau(span / (t.size - 1), span / 5.0, 16, k)))
    E = np.zeros((t.size, 16))
    E[:, k] = e
    M = np.empty((1, p + 1, p + 1))
    rhs = np.empty((1, p + 1))
    M[0, :p, :p] = X.T @ X
    xe = (X.T @ E)[:, k]
    M[0, :p, p] = xe
    M[0, p, :p] = xe
    M[0, p, p] = _sum(e * e)
    rhs[0, :p] = X.T @ y
    rhs[0, p] = (E.T @ y)[k]
    return np.linalg.solve(M, rhs[..., None])[0, :p, 0]


def remove_drift(t: np.ndarray, s: np.ndarray, segment: np.ndarray, approach: RunRegions,
                 retract: RunRegions, unit: str, order: int = _D.order, min_points: int = 5,
                 max_noise_ratio: float = 5.0, z: np.ndarray | None = None, h_tail: float = 5e-9):
    """Subtract each run's baseline line; returns ``(corrected signal, DriftResult)``.

    The runs are found by their segment type, wherever they lie in the record. Samples of other
    segments (a dwell, a pause before the approach) get the baseline interpolated in time between
    the runs' (held at the nearest run's value outside them). The retract run uses its own line;
    when its free part is too short, or more than ``max_noise_ratio`` times noisier than the
    approach's (a cantilever ringing freely after the pull-off, unbinding events: its line would be
    biased), it uses the simplest of the approach line and its own offset (:func:`borrowed_line`).
    A dwell between the runs rules out the "continuous" retract line (the approach line's end is
    then an extrapolation over the dwell).

    Compiled (:mod:`._drift_kernel`: the fits and choices in one call, the numbers of the numpy
    code bit for bit); :func:`_remove_drift_numpy` when numba does not compile (the first run
    after an install) or in the rare cases the kernel leaves to it.
    """
    args = (t, s, segment, approach, retract, unit, order, min_points, max_noise_ratio, z, h_tail)
    if _K is None:
        return _remove_drift_numpy(*args)
    tf = np.ascontiguousarray(t, dtype=float)
    sf = np.ascontiguousarray(s, dtype=float)
    zf = _EMPTY if z is None else np.ascontiguousarray(z, dtype=float)
    a_idx, r_idx = approach.index, retract.index
    (status, off_a, slope_a, noise, t0a, line, settling, off_r, slope_r, t0r, tilt_r, z0r, p,
     k) = _K.decide(tf, sf, a_idx, approach.zero_force, int(approach.split), r_idx, retract.zero_force, zf,
                    z is not None, int(order), int(min_points), float(max_noise_ratio), float(h_tail))
    if status != 0:
        return _remove_drift_numpy(*args)
    if p:  # the retract line's coefficients (retract_line's family p): numpy's sums and solve, bit for bit
        ir = retract.index[retract.zero_force]
        tr, sr = t[ir], s[ir]
        m = tr.size // SELECT_POINTS
        if m > 1:
            nb = tr.size // m
            tr, sr = tr[: nb * m].reshape(nb, m).mean(1), sr[: nb * m].reshape(nb, m).mean(1)
        t_turn = t[retract.index[0]]
        at_turn = off_a + slope_a * (t_turn - t0a)
        scale = max(float(tr[-1] - t_turn), 1e-300)
        y1 = sr - at_turn
        X = np.empty((tr.size, p))  # np.column_stack([np.ones_like(tr), u]) for p = 2, u[:, None] for 1
        X[:, p - 1] = (tr - t_turn) / scale
        if p == 2:
            X[:, 0] = 1.0
        c = family_coef(X, y1, tr, k)
        if p == 1:
            off_r, slope_r = at_turn, float(c[0]) / scale
        else:
            off_r, slope_r = at_turn + float(c[0]), float(c[1]) / scale
        t0r = t_turn
    out, base, ok = _K.apply(tf, sf, zf, a_idx, r_idx, off_a, slope_a, t0a, off_r, slope_r, t0r, tilt_r, z0r)
    if not ok:  # samples outside the runs, the runs' not in time order: numpy's stable sort
        return _remove_drift_numpy(*args)
    ret0 = retract.index[0]
    res = DriftResult(offset_approach=off_a + slope_a * (t[approach.index[0]] - t0a), slope_approach=slope_a,
                      offset_retract=float(base[ret0]), slope_retract=slope_r,
                      noise=noise, retract_from_approach=line == 0, unit=unit,
                      retract_settling=bool(settling), retract_line=_K.LINES[line], tilt_retract=float(tilt_r))
    return out, res


_EMPTY = np.empty(0)
if _COLD:  # the first run after an install: the numpy code (no loops run as Python)
    _K = None
else:
    from . import _drift_kernel as _K
