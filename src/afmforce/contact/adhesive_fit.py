"""The adhesive fit (JKR, DMT, Maugis-Dugdale): E, w, the contact point and the baseline together.

Model, on one run of tip depth u [m] and force F [N]::

    F(u) = pi w R P((u - c) / d_s) + b     in contact,    b  before it

with the law's stable branch P(D) (:func:`afmforce.contact.adhesive.branch`, exact), the scales
``pi w R`` and ``d_s = (pi^2 w^2 R / K^2)^(1/3)``, ``K = 4/3 E/(1 - nu^2)``. The force jumps where
contact begins (to -4/3 pi w R for JKR on the approach, -2 pi w R for DMT), so the sum of squares
is discontinuous in the contact point at every sample and smooth between two consecutive
samples. The fit therefore

1. scans DMT in closed form (linear in E, w and b for a given contact point) at a point between
   every two consecutive samples (a compiled kernel; long runs: every k-th, then all near the best),
2. fits all four parameters (E, w, the contact point c, b) by a bounded Levenberg-Marquardt with
   the analytic Jacobian, c confined to the gap between two samples where the set of points in
   contact is fixed, and walks to the neighbouring gaps while the sum of squares falls,
3. reports the lowest sum of squares found, and the covariance ``s^2 (J^T J)^-1`` of all four
   (the Jacobian's contact-point column is the smooth slope of the law; the jump's own information
   about c is left out, so the intervals are, if anything, conservative).

The retract branch (``branch="retract"``) ends at the law's pull-off (D_end < 0): the jump is there,
at ``c + D_end d_s``, and that position is the fitted parameter; c follows from it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import AnalysisError
from .adhesive import _code, _tables, branch_end
from .adhesive import branch as _branch

__all__ = ["AdhesiveFit", "fit_adhesive"]

_NAMES = ("E", "w", "c", "b")


@dataclass(frozen=True)
class AdhesiveFit:
    """The optimum of one adhesive fit (SI).

    Attributes
    ----------
    E, w, c, b : float  Young's modulus [Pa], work of adhesion [J/m^2], contact point (tip depth) [m],
        baseline [N]
    cov : ndarray  4 x 4 covariance of (E, w, c, b) [SI products]
    ssr : float  weighted sum of squares at the optimum [N^2]
    n : int  points with a non-zero weight [-]
    weights : ndarray  the residuals' weights at the optimum [-]
    E_low, E_high : float  95 % interval of E [Pa] (the covariance's; the lower end at least 0)
    w_low, w_high : float  95 % interval of w [J/m^2]; when it reaches 0, [0, the profile likelihood's upper
        end] (NaN: open, the data do not bound w)
    """

    E: float
    w: float
    c: float
    b: float
    cov: np.ndarray
    ssr: float
    n: int
    weights: np.ndarray
    E_low: float = math.nan
    E_high: float = math.nan
    w_low: float = math.nan
    w_high: float = math.nan


class _Problem:
    """The law on one run, in the parameters x = (E, w, cj, b); cj is where the contact begins (the
    jump): c on the approach, c + D_end d_s on the retract (D_end < 0, the branch's end)."""

    def __init__(self, u, F, key, R, nu, lam, branch, width, max_ind):
        from . import _kernels

        self.u, self.F, self.R, self.lam = u, F, R, float(lam)
        self.law = _code(key)
        self.tables = _tables(key, lam)
        self.kc = 4.0 / 3.0 / (1.0 - nu * nu)  # K / E
        self.d_end = 0.0 if (branch == "approach" or key == "dmt") else branch_end(key, lam)[0]
        self.width, self.max_ind = float(width), float(max_ind)
        self._k = _kernels

    def scales(self, E, w):
        K = self.kc * E
        return math.pi * w * self.R, (math.pi ** 2 * w * w * self.R / (K * K)) ** (1.0 / 3.0)

    def contact(self, x) -> float:
        """The contact point c [m] of the parameters x."""
        return x[2] - self.d_end * self.scales(x[0], x[1])[1]

    def ssr(self, x) -> float:
        """The weighted sum of squares at x [N^2]."""
        return self._k.adhesive_normal(self.u, self.F, self.law, np.asarray(x, float), self.R, self.kc,
                                       self.d_end, self.lam, *self.tables, self.width, self.max_ind,
                                       np.zeros((0, 0)), np.zeros(0))

    def lm(self, x0, lo, hi, max_iter: int = 200):
        """Bounded Levenberg-Marquardt from x0: (x, sum of squares, J^T J)."""
        x, S, A, _ = self._k.adhesive_lm(self.u, self.F, self.law, np.asarray(x0, float), lo, hi, self.R,
                                          self.kc, self.d_end, self.lam, *self.tables, self.width,
                                          self.max_ind, max_iter)
        return x, S, A


def fit_adhesive(u, F, key: str, radius: float, nu: float = 0.5, lam: float = 1.0, branch: str = "approach",
                 width: float = 0.0, max_ind: float = math.inf) -> AdhesiveFit:
    """Fit the adhesive law ``key`` (``jkr``, ``dmt``, ``maugis``) to one run (the module docstring).

    ``width``, ``max_ind``: the residuals weighted down linearly within ``width`` [m] of the contact
    point and dropped beyond the indentation ``max_ind`` [m] (:func:`afmforce.contact.fit.fit_indentation`).
    Raises AnalysisError when no contact point gives E > 0.
    """
    from ._kernels import scan_dmt
    from .fit import _t95, _weights

    def weights(d):
        return _weights(d, width, max_ind)

    u = np.asarray(u, float)
    F = np.asarray(F, float)
    R = float(radius)
    us = np.unique(u)
    if us.size < 4:
        raise AnalysisError(f"{key}: the tip depth takes only {us.size} values: no contact to fit")
    mids = 0.5 * (us[:-1] + us[1:])  # one contact point between every two consecutive samples
    kh = 4.0 / 3.0 * math.sqrt(R) / (1.0 - nu * nu)
    stride = max(1, mids.size // 400)
    cand = np.ascontiguousarray(mids[::stride])
    E0, W0, B0, S0 = scan_dmt(u, F, cand, kh, 2 * math.pi * R, float(width), float(max_ind))
    i = int(np.argmin(S0))
    if not math.isfinite(S0[i]):
        raise AnalysisError(f"{key}: no contact point gives a positive modulus (the curve does not rise into "
                            "contact)")
    if stride > 1:
        k = i * stride
        cand = np.ascontiguousarray(mids[max(k - 2 * stride, 0):k + 2 * stride + 1])
        E0, W0, B0, S0 = scan_dmt(u, F, cand, kh, 2 * math.pi * R, float(width), float(max_ind))
        i = int(np.argmin(S0))
    prob = _Problem(u, F, key, R, nu, lam, branch, width, max_ind)
    P0 = float(_branch(key, np.array([0.0]), lam)[0][0])  # the jump at contact [pi w R]
    w0 = float(W0[i]) * 2.0 / abs(P0) if W0[i] > 0 else 0.0
    w_small = 1e-5 * max(float(np.std(F)), 1e-30) / (math.pi * R)  # an adhesion far below the noise
    x0 = np.array([float(E0[i]), max(w0, w_small), float(cand[i]), float(B0[i])])
    if prob.d_end != 0.0:
        x0[2] = float(cand[i]) + prob.d_end * prob.scales(x0[0], x0[1])[1]
    gaps = _Gaps(prob, us, w_floor=1e-9 * x0[1])
    best = gaps.walk(gaps.gap_of(x0[2]), x0)
    x, S, JtJ = best[1:]
    q = weights(u - prob.contact(x))
    n = int((q > 0).sum())
    dof = n - 4
    s2 = S / max(dof, 1)
    try:
        cov = _covariance(JtJ, s2)
    except np.linalg.LinAlgError:
        cov = np.full((4, 4), np.nan)
    # c = cj - D_end d_s(E, w): its gradient in (E, w, cj, b)
    if prob.d_end != 0.0:
        ds = prob.scales(x[0], x[1])[1]
        grad = np.array([prob.d_end * ds * 2.0 / (3.0 * x[0]), -prob.d_end * ds * 2.0 / (3.0 * x[1]), 1.0, 0.0])
        T = np.eye(4)
        T[2] = grad
        cov = T @ cov @ T.T
    t = _t95(dof)
    se = np.sqrt(np.clip(np.diag(cov), 0, None))
    E_low, E_high = max(x[0] - t * se[0], 0.0), x[0] + t * se[0]  # E > 0: the bound ends the interval
    w_low, w_high = x[1] - t * se[1], x[1] + t * se[1]
    if not w_low > 0:  # the interval reaches w = 0, where the law's Jacobian fails (JKR: F ~ sqrt(w)): profile
        w_low = 0.0
        w_high = gaps.profile_w(best, S, s2, t * t, se[1])
    return AdhesiveFit(E=float(x[0]), w=float(x[1]), c=float(prob.contact(x)), b=float(x[3]), cov=cov,
                       ssr=float(S), n=n, weights=q, E_low=float(E_low), E_high=float(E_high),
                       w_low=float(w_low), w_high=float(w_high))


class _Gaps:
    """The search over the gaps between consecutive samples (the contact set fixed within one)."""

    def __init__(self, prob: _Problem, us: np.ndarray, w_floor: float):
        self.prob, self.us, self.w_floor = prob, us, w_floor

    def gap_of(self, cj: float) -> int:
        return int(np.clip(np.searchsorted(self.us, cj, side="right") - 1, 0, self.us.size - 2))

    def fit(self, k: int, start: np.ndarray, w_fixed: float | None = None):
        """LM with the jump confined to gap k (and w held at ``w_fixed``): (k, x, ssr, J^T J)."""
        us = self.us
        gap = us[k + 1] - us[k]
        lo_c, hi_c = us[k] + 1e-9 * gap, us[k + 1] - 1e-9 * gap
        lo = np.array([1e-12 * start[0], self.w_floor, lo_c, -np.inf])
        hi = np.array([np.inf, np.inf, hi_c, np.inf])
        s = start.copy()
        if w_fixed is not None:
            lo[1] = hi[1] = s[1] = w_fixed
        s[2] = min(max(s[2], lo_c), hi_c)
        return (k, *self.prob.lm(s, lo, hi))

    def walk(self, k0: int, x0: np.ndarray, w_fixed: float | None = None):
        """From gap k0, to the neighbouring gaps while the sum of squares falls (two gaps' look-ahead)."""
        best = self.fit(k0, x0, w_fixed)
        tried = {k0}
        for direction in (-1, 1):
            k, x_from, misses = best[0], best[1], 0
            while misses < 2:
                k += direction
                if k < 0 or k > self.us.size - 2 or k in tried:
                    break
                got = self.fit(k, x_from, w_fixed)
                tried.add(k)
                if got[2] < best[2]:
                    best, misses, x_from = got, 0, got[1]
                else:
                    misses += 1
        return best

    def profile_w(self, best, S_min: float, s2: float, thr: float, w_se: float) -> float:
        """The upper end of w's interval by profile likelihood: the w above the optimum where the sum of
        squares, re-minimised over (E, c, b), exceeds its minimum by thr s^2. NaN (open) if it stays
        below out to 13 steps (the data do not bound w)."""
        x = best[1]
        step = w_se if math.isfinite(w_se) and w_se > 0 else max(x[1], 1e-12)
        prev_v, prev_d, cur = x[1], 0.0, best
        for m in (1.0, 2.0, 3.0, 4.5, 6.5, 9.0, 13.0):
            v = x[1] + m * step
            cur = self.walk(cur[0], cur[1], w_fixed=v)
            d = max((cur[2] - S_min) / s2, 0.0)
            if d >= thr:  # the signed root sqrt(d) is ~linear in w: interpolate it
                a, b = math.sqrt(prev_d), math.sqrt(d)
                return prev_v + (v - prev_v) * (math.sqrt(thr) - a) / max(b - a, 1e-300)
            prev_v, prev_d = v, d
        return math.nan


def _covariance(A: np.ndarray, s2: float) -> np.ndarray:
    """s^2 A^-1 (A = J^T J), inverted with the columns scaled."""
    n = np.sqrt(np.diag(A))
    n[n == 0] = 1.0
    return np.linalg.inv(A / np.outer(n, n)) / np.outer(n, n) * s2
