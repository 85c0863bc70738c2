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
   contact is fixed, and walks to the neighbouring gaps while the sum of squares falls
   (:func:`afmforce.contact._adhesive_kernels.adhesive_walk`; on the retract a free glide first),
3. reports the lowest sum of squares found, and the covariance ``s^2 (J^T J)^-1`` of all four
   (the Jacobian's contact-point column is the smooth slope of the law; the jump's own information
   about c is left out, so the intervals are, if anything, conservative): E and w +- t(0.975, n-4) se.
   Where w's interval reaches 0 (no adhesion measurable), the Hertz limit is tried as the optimum
   and w's upper end comes from the profile likelihood.

The retract branch (``branch="retract"``) ends at the law's pull-off (D_end < 0): the jump is there,
at ``c + D_end d_s``, and that position is the fitted parameter; c follows from it.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from ..errors import AnalysisError
from .adhesive import _code, _tables, branch_end
from .adhesive import branch as _branch

__all__ = ["AdhesiveFit", "fit_adhesive"]

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
    model : ndarray  the law's force at each sample at the optimum, baseline excluded [N]
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
    model: np.ndarray
    E_low: float = math.nan
    E_high: float = math.nan
    w_low: float = math.nan
    w_high: float = math.nan


class _Problem:
    """The law on one run, in the parameters x = (E, w, cj, b); cj is where the contact begins (the
    jump): c on the approach, c + D_end d_s on the retract (D_end < 0, the branch's end)."""

    def __init__(self, u, F, key, R, nu, lam, branch, width):
        from . import _adhesive_kernels as _kernels

        self.u, self.F, self.R, self.lam = u, F, R, float(lam)
        self.law = _code(key)
        self.tables = _tables(key, lam)
        self.kc = 4.0 / 3.0 / (1.0 - nu * nu)  # K / E
        self.d_end = 0.0 if (branch == "approach" or key == "dmt") else branch_end(key, lam)[0]
        self.width = float(width)
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
                                       self.d_end, self.lam, *self.tables, self.width, np.zeros((0, 0)),
                                       np.zeros(0))


def fit_adhesive(u, F, key: str, radius: float, nu: float = 0.5, lam: float = 1.0, branch: str = "approach",
                 width: float = 0.0) -> AdhesiveFit:
    """Fit the adhesive law ``key`` (``jkr``, ``dmt``, ``maugis``) to one run (the module docstring).

    ``width``: the residuals weighted down linearly within ``width`` [m] of the contact point. Every
    sample given is fitted: a fit range is a fixed set of samples chosen before
    (:func:`afmforce.contact.fit.fit_indentation`'s ``max_indentation``); one measured from each tried
    contact point would let contact points early in the baseline win by fitting fewer samples.
    Raises AnalysisError when no contact point gives E > 0.
    """
    from ._kernels import scan_dmt
    from ._weights import t95 as _t95, weights as _weights

    def lowest(S):
        """The index of the lowest sum of squares of a DMT scan (AnalysisError where none is finite)."""
        i = int(np.argmin(S))
        if not math.isfinite(S[i]):
            raise AnalysisError(f"{key}: no contact point gives a positive modulus (the curve does not rise into "
                                "contact)")
        return i

    u = np.asarray(u, float)
    F = np.asarray(F, float)
    R = float(radius)
    us = np.unique(u)
    if us.size < 4:
        raise AnalysisError(f"{key}: the tip depth takes only {us.size} values: no contact to fit")
    mids = 0.5 * (us[:-1] + us[1:])  # one contact point between every two consecutive samples
    kh = 4.0 / 3.0 * math.sqrt(R) / (1.0 - nu * nu)
    # DMT at a point in every gap: every stride-th gap, then every gap near the best (on all samples:
    # thinned ones misplace the best on real curves whose jump is within the noise)
    stride = max(1, round(math.sqrt(mids.size / 4)))  # the fewest candidates: m/stride + 4 stride
    args = (kh, 2 * math.pi * R, float(width))
    cand = np.ascontiguousarray(mids[::stride])
    S0 = scan_dmt(u, F, cand, *args)[3]
    i = lowest(S0)
    if stride > 1:
        k = i * stride
        cand = np.ascontiguousarray(mids[max(k - 2 * stride, 0):k + 2 * stride + 1])
    E0, W0, B0, S0 = scan_dmt(u, F, cand, *args)
    i = lowest(S0)
    prob = _Problem(u, F, key, R, nu, lam, branch, width)
    w0 = float(W0[i]) * 2.0 / abs(_jump(key, float(lam))) if W0[i] > 0 else 0.0  # DMT's jump is -2 pi w R
    w_small = 1e-5 * max(float(np.abs(F).max()), 1e-30) / (math.pi * R)  # an adhesion far below the forces
    x0 = np.array([float(E0[i]), max(w0, w_small), float(cand[i]), float(B0[i])])
    if prob.d_end != 0.0:
        x0[2] = float(cand[i]) + prob.d_end * prob.scales(x0[0], x0[1])[1]
    gaps = _Gaps(prob, us, w_floor=1e-7 * w_small)  # no adhesion: the Hertz limit
    if prob.d_end != 0.0:  # a retract's neck: DMT's jump may lie tens of gaps from the law's
        x0 = gaps.glide(x0)
    best = gaps.walk(gaps.gap_of(x0[2]), x0)
    # a jump within a few noise levels leaves the sum of squares nearly flat over the gaps, with shallow
    # local minima a walk stops at (a retract's small neck on real curves): look further away
    P_jump = branch_end(key, lam)[1] if prob.d_end != 0.0 else _jump(key, float(lam))
    if abs(P_jump) * math.pi * best[1][1] * R < 10.0 * math.sqrt(best[2] / u.size):
        # DMT at every gap (closed form): a walk from each of its three best basins, then the sweep
        Ea, Wa, Ba, Sa = scan_dmt(u, F, np.ascontiguousarray(mids), *args)
        starts = []
        for j in np.argsort(Sa):
            if not math.isfinite(Sa[j]) or len(starts) == 3:
                break
            if all(abs(int(j) - k) > 5 for k in starts):
                starts.append(int(j))
        for j in starts:
            if j == best[0]:
                continue
            xs = np.array([Ea[j], max(float(Wa[j]) * 2.0 / abs(_jump(key, float(lam))), w_small), mids[j], Ba[j]])
            if prob.d_end != 0.0:
                xs[2] = mids[j] + prob.d_end * prob.scales(xs[0], xs[1])[1]
                xs = gaps.glide(xs)
            got = gaps.walk(gaps.gap_of(xs[2]), xs)
            if got[2] < best[2]:
                best = got
        best = gaps.sweep(best)
    x, S, JtJ = best[1:]
    q = _weights(u - prob.contact(x), width)
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
    if not w_low > 0:
        # w's interval reaches 0 (no adhesion measurable): the optimum may lie on that bound (the Hertz
        # limit), and the interval is [0, the profile likelihood's upper end]. E keeps the covariance's
        # interval: near w = 0 every law departs from Hertz linearly in w (JKR's sqrt(w) terms cancel), so
        # the linearisation holds, and it is that of w unconstrained (a profile over w >= 0 undercovers
        # E there: 91 of 100 seeds against 98)
        hertz = gaps.walk(best[0], x, w=gaps.w_floor)
        if hertz[2] < S:
            best = hertz
            x, S = best[1], best[2]
            q = _weights(u - prob.contact(x), width)
        w_low = 0.0
        w_high = gaps.profile(1, 1.0, best, S, s2, t * t, se[1])
    model = prob._k.adhesive_model(u, prob.law, x, prob.R, prob.kc, prob.d_end, prob.lam, *prob.tables)
    return AdhesiveFit(E=float(x[0]), w=float(x[1]), c=float(prob.contact(x)), b=float(x[3]), cov=cov,
                       ssr=float(S), n=n, weights=q, model=model, E_low=float(E_low), E_high=float(E_high),
                       w_low=float(w_low), w_high=float(w_high))


@functools.lru_cache(maxsize=32)
def _jump(key: str, lam: float) -> float:
    """The force at the start of contact on the approach [pi w R]: JKR -4/3, DMT -2."""
    return float(_branch(key, np.array([0.0]), lam)[0][0])


class _Gaps:
    """The search over the gaps between consecutive samples (the contact set fixed within one)."""

    def __init__(self, prob: _Problem, us: np.ndarray, w_floor: float):
        self.prob, self.us, self.w_floor = prob, us, w_floor

    def gap_of(self, cj: float) -> int:
        return min(max(int(np.searchsorted(self.us, cj, side="right")) - 1, 0), self.us.size - 2)

    def glide(self, x0: np.ndarray) -> np.ndarray:
        """LM with the jump free over the whole run (the sum of squares jumps where a sample changes side,
        which the smooth Jacobian ignores): a start some gaps away -- DMT's on a retract's neck -- reaches
        the right gap's neighbourhood in a few steps instead of gap by gap."""
        p = self.prob
        lo = np.array([1e-12 * x0[0], self.w_floor, self.us[0], -np.inf])
        hi = np.array([np.inf, np.inf, self.us[-1], np.inf])
        x, S, _, _ = p._k.adhesive_lm(p.u, p.F, p.law, np.asarray(x0, float), lo, hi, p.R, p.kc, p.d_end, p.lam,
                                      *p.tables, p.width, 100)
        return x if S < p.ssr(x0) else np.asarray(x0, float)

    def walk(self, k0: int, x0: np.ndarray, E: float = math.nan, w: float = math.nan):
        """The jump confined to the gap k0 between two samples, then to the neighbouring gaps while the sum
        of squares falls (_adhesive_kernels.adhesive_walk); E, w held where given: (gap, x, ssr, J^T J) of the best."""
        p = self.prob
        k, x, S, A = p._k.adhesive_walk(p.u, p.F, p.law, self.us, int(k0), np.asarray(x0, float), self.w_floor,
                                        np.array([E, w]), p.R, p.kc, p.d_end, p.lam, *p.tables, p.width, 200)
        return int(k), x, float(S), A

    def sweep(self, best, rounds: int = 3):
        """Gaps 2, 3, 5, ... 233 away from the best on each side, each probed from the best (a short LM);
        from the first better one a walk, and again from there, until none is better (at most
        ``rounds`` times)."""
        p = self.prob
        fixed = np.array([math.nan, math.nan])
        for _ in range(rounds):
            k0 = best[0]
            for off in (2, 3, 5, 8, 13, 21, 34, 55, 89, 144, 233):
                better = None
                for k in (k0 - off, k0 + off):
                    if 0 <= k < self.us.size - 1:
                        x, S, _ = p._k.gap_fit(p.u, p.F, p.law, self.us, k, best[1], self.w_floor, fixed, p.R, p.kc,
                                               p.d_end, p.lam, *p.tables, p.width, 8)
                        if S < best[2] and (better is None or S < better[1]):
                            better = (k, S, x)
                if better is not None:
                    break
            if better is None:
                return best
            got = self.walk(better[0], better[2])
            if got[2] < best[2]:
                best = got
        return best

    def profile(self, j: int, sign: float, best, S_min: float, s2: float, thr: float, step: float,
                lower: float = -math.inf) -> float:
        """One end of parameter j's (0: E, 1: w) interval by profile likelihood: where the sum of squares,
        re-minimised over the others, exceeds its minimum by thr s^2, on the side ``sign``. ``lower``: the
        parameter's physical bound, the end if the profile reaches it below the threshold; NaN (open) if the
        profile stays below out to 13 steps (the data do not bound it)."""
        x = best[1]
        step = step if math.isfinite(step) and step > 0 else 0.2 * abs(x[j])
        prev_v, prev_d, cur = x[j], 0.0, best
        for m in (1.0, 2.0, 3.0, 4.5, 6.5, 9.0, 13.0):
            v = x[j] + sign * m * step
            if v <= lower:
                return lower
            fix = [math.nan, math.nan]
            fix[j] = v
            cur = self.walk(cur[0], cur[1], *fix)
            d = max((cur[2] - S_min) / s2, 0.0)
            if d >= thr:  # the signed root sqrt(d) is ~linear in the parameter: interpolate it
                a, b = math.sqrt(prev_d), math.sqrt(d)
                return prev_v + (v - prev_v) * (math.sqrt(thr) - a) / max(b - a, 1e-300)
            prev_v, prev_d = v, d
        return math.nan


def _covariance(A: np.ndarray, s2: float) -> np.ndarray:
    """s^2 A^-1 (A = J^T J), inverted with the columns scaled."""
    n = np.sqrt(np.diag(A))
    n[n == 0] = 1.0
    return np.linalg.inv(A / np.outer(n, n)) / np.outer(n, n) * s2
