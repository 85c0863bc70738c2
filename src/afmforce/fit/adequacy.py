"""Does the best model describe the data? The reduced chi-square against its threshold.

A verdict on friction compares two models; it means nothing when neither
describes the curves. The fit therefore tests its best model first: with
Gaussian noise of known rms, ``chi2`` follows the chi-square distribution with
``dof`` degrees of freedom, so ``chi2 / dof`` exceeds ``chi2_dof^-1(q) / dof``
(``q = 0.999``: 1.12 for 1400 degrees of freedom) only once in a thousand fits.
The noise rms is not known but estimated per curve from ``n_b`` baseline samples
(second differences, :func:`afmforce.fit.data._noise_sigma`): the relative
standard deviation of that estimate of sigma^2 is ``sqrt(140 / 36 / n_b) = 1.97 /
sqrt(n_b)`` (the second differences of white noise are correlated at lags 1 and 2).
The joint chi-square scales with ``1 / sigma_i^2`` curve by curve, so it is uncertain
by ``s = sqrt(sum_i (n_i / N)^2 3.89 / n_b,i)``; the threshold is inflated by
three of those: ``chi2_dof^-1(q) / dof * (1 + 3 s)``. Above it the model does not
describe the data: no verdict (``friction_detected = None``), and the worst curves
are named with where their residuals sit.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import chi2 as chi2_dist

__all__ = ["ADEQUACY_QUANTILE", "ADVICE", "redchi_threshold", "adequacy", "residual_site",
           "undetermined_verdict", "worst_region"]

#: Quantile of the chi-square distribution above which the model is rejected.
ADEQUACY_QUANTILE = 0.999
#: Relative variance of a second-difference estimate of sigma^2 times the sample count.
_SIGMA2_RELVAR = 140.0 / 36.0
#: Standard deviations of the noise estimate added to the threshold.
NOISE_SIGMAS = 3.0


def _noise_spread(curves) -> float:
    n = np.array([int(c.mask.sum()) for c in curves], float)
    nb = np.array([max(int(getattr(c, "noise_samples", 0)), 10) for c in curves], float)
    w = n / n.sum()
    return float(math.sqrt(np.sum(w ** 2 * _SIGMA2_RELVAR / nb)))


def redchi_threshold(dof: int, curves, quantile: float = ADEQUACY_QUANTILE) -> float:
    """Largest reduced chi-square a model that describes the data reaches (module docstring)."""
    dof = max(int(dof), 1)
    return float(chi2_dist.ppf(quantile, dof) / dof) * (1.0 + NOISE_SIGMAS * _noise_spread(curves))


def _regions(c) -> dict[str, np.ndarray]:
    idx = np.arange(c.n)
    end = c.retract_start if c.retract_start is not None else c.n
    out = {"the free approach": idx < c.jump_index,
           "contact": (idx >= c.jump_index) & (idx < end)}
    if c.retract_start is not None:
        out["the retract's contact line"] = idx >= end
    return {k: v[c.mask] for k, v in out.items()}


#: What to check when the misfit sits in a region: the artefacts that put it there.
ADVICE = {
    "the free approach": "the misfit is in the free approach: fringes of another period "
                         "(`fringe_period`) or shape, a drift that is not linear, or noise the fit "
                         "does not model; check the baseline with `afmforce analyze` (drift, fringes)",
    "contact": "the misfit is in contact: a soft or rough contact, a stepped or backlashing "
               "position sensor, or a wrong calibration; check the compliance line with "
               "`afmforce analyze` (compliance, kind)",
    "the retract's contact line": "the misfit is on the retract's contact line: backlash or creep "
                                  "at the turn; fit the approaches alone (without `retract`)",
}


def worst_region(c, r: np.ndarray) -> str:
    """The region of curve ``c`` (a key of :data:`ADVICE`) with the largest excess chi-square."""
    best, excess = None, -math.inf
    for name, sel in _regions(c).items():
        if sel.any():
            e = float(np.sum(r[sel] ** 2) - sel.sum())
            if e > excess:
                best, excess = name, e
    return best


def residual_site(c, r: np.ndarray, shift: float) -> str:
    """Where the residuals ``r`` (noise units, on the mask) of curve ``c`` concentrate.

    The region (free approach, contact, retract) with the largest excess chi-square
    and the range of ``z - shift`` [nm] holding the middle 80 % of its chi-square.
    """
    z = (c.position[c.mask] - shift) * 1e9
    best = worst_region(c, r)
    sel = _regions(c)[best]
    zs, r2 = z[sel], r[sel] ** 2
    order = np.argsort(zs)
    cum = np.cumsum(r2[order]) / max(np.sum(r2), 1e-300)
    lo = zs[order][int(np.searchsorted(cum, 0.1))]
    hi = zs[order][min(int(np.searchsorted(cum, 0.9)), len(zs) - 1)]
    share = float(np.sum(r2) / max(float(np.sum(r ** 2)), 1e-300))
    return (f"{c.name}: reduced chi-square {float(np.mean(r ** 2)):.3g}, residuals concentrated "
            f"in {best}, z - shift = {lo:.3g} to {hi:.3g} nm ({share:.0%} of its chi-square)")


def adequacy(prob, x, dof: int, chi2: float, curves) -> dict:
    """``{"redchi", "threshold", "adequate", "worst": [site, ...]}`` of the fit at ``x``."""
    thr = redchi_threshold(dof, curves)
    redchi = chi2 / max(dof, 1)
    out = {"redchi": redchi, "threshold": thr, "quantile": ADEQUACY_QUANTILE,
           "adequate": bool(redchi <= thr), "worst": []}
    if out["adequate"]:
        return out
    values, shifts = prob.unpack(x)
    per = []
    for i, (c, r) in enumerate(zip(curves, prob.curve_residuals(x))):
        per.append((float(np.mean(r ** 2)), i, r))
    per.sort(key=lambda t: -t[0])
    bad = [p for p in per if p[0] > redchi_threshold(len(p[2]), [curves[p[1]]])][:3] or per[:1]
    out["worst"] = [residual_site(curves[i], r, float(shifts[i])) for _, i, r in bad]
    out["advice"] = ADVICE[worst_region(curves[bad[0][1]], bad[0][2])]
    return out


def undetermined_verdict(adq: dict) -> str:
    """The verdict when the model does not describe the data."""
    return (f"undetermined: the model does not describe the data (reduced chi-square "
            f"{adq['redchi']:.3g} > {adq['threshold']:.3g}); worst: " + "; ".join(adq["worst"])
            + (f"; {adq['advice']}" if adq.get("advice") else ""))
