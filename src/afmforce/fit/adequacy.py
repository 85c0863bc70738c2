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

**The jump-in's neighbourhood** (:func:`jump_misfit`). A force the model lacks (a hydration
or double-layer repulsion, a wrong soft wall) bends the curve where the model has its
features: the last nanometres before the jump-in and the landing on contact, a few dozen of
a curve's hundreds of samples. Spread over the whole record its excess stays under the
global threshold, and a smooth excess is read as 1/f noise (:mod:`afmforce.fit.noise`) whose
whitening takes it out of the global chi-square (the ``paper`` virtual AFM with a hydration
force, P0 = 3e7 Pa, 1 nm: "adequate" at reduced chi-square 1.17 with 0.2 nm of 1/f noise
where the preset has none, xi = 0.066 [0.064, 0.068] kg/s for 0.1). The
:data:`JUMP_SAMPLES` fitted samples on either side of each curve's jump-in gap are therefore
tested on their own, with the same residuals (whitened where the fit models 1/f noise): their
chi-square against the chi-square quantile of their count at ``q`` Bonferroni-corrected for
the number of windows, inflated by the curve's noise-estimate spread as above.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import chi2 as chi2_dist

__all__ = ["ADEQUACY_QUANTILE", "ADVICE", "redchi_threshold", "adequacy", "residual_site",
           "undetermined_verdict", "worst_region", "JUMP_SAMPLES", "jump_misfit"]

#: Quantile of the chi-square distribution above which the model is rejected.
ADEQUACY_QUANTILE = 0.999
#: Relative variance of a second-difference estimate of sigma^2 times the sample count.
_SIGMA2_RELVAR = 140.0 / 36.0
#: Standard deviations of the noise estimate added to the threshold.
NOISE_SIGMAS = 3.0
#: Fitted samples on either side of a curve's jump-in gap tested on their own (:func:`jump_misfit`).
JUMP_SAMPLES = 20


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
    "the jump-in": "the misfit sits at the jump-in, where the model's surface force acts: a force "
                   "the model lacks (a double layer, hydration, a meniscus: the help of "
                   "afmforce simulate lists the laws) or a wrong fixed parameter of it (z0, the radius, the "
                   "lever); fit that law's parameters (`free`) or fix the right values",
}


def _jump_windows(c) -> dict[str, np.ndarray]:
    """Positions, among curve ``c``'s fitted samples, of the :data:`JUMP_SAMPLES` before its
    jump-in gap and the :data:`JUMP_SAMPLES` after it (on the approach)."""
    idx = np.flatnonzero(c.mask)
    end = c.retract_start if c.retract_start is not None else c.n
    before = np.flatnonzero(idx < c.jump_index)[-JUMP_SAMPLES:]
    after = np.flatnonzero((idx >= c.jump_index) & (idx < end))[:JUMP_SAMPLES]
    return {"before the jump-in": before, "on landing in contact": after}


def jump_misfit(curves, residuals, quantile: float = ADEQUACY_QUANTILE) -> list[dict]:
    """The windows next to the jump-ins whose chi-square exceeds its threshold (module docstring).

    ``residuals``: per curve, on its fitted samples, in noise units (whitened where 1/f noise is
    modelled). Returns ``[{"curve", "where", "n", "chi2", "threshold", "index"}, ...]`` for each
    window over its threshold (``index``: its positions among the curve's fitted samples);
    empty when none is.
    """
    wins = []
    for i, c in enumerate(curves):
        for where, pos in _jump_windows(c).items():
            if pos.size >= 5:
                wins.append((i, where, pos))
    out = []
    if not wins:
        return out
    q = 1.0 - (1.0 - quantile) / len(wins)       # Bonferroni over the windows
    for i, where, pos in wins:
        c, r = curves[i], np.asarray(residuals[i])
        nb = max(int(getattr(c, "noise_samples", 0)), 10)
        thr = float(chi2_dist.ppf(q, pos.size)) * (1.0 + NOISE_SIGMAS * math.sqrt(_SIGMA2_RELVAR / nb))
        x2 = float(np.sum(r[pos] ** 2))
        if x2 > thr:
            out.append({"curve": c.name, "where": where, "n": int(pos.size), "chi2": x2,
                        "threshold": thr, "index": pos})
    return out


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


def _jump_site(c, w: dict, shift: float) -> str:
    z = (c.position[c.mask][w["index"]] - shift) * 1e9
    return (f"{w['curve']}: chi-square {w['chi2']:.3g} > {w['threshold']:.3g} over the {w['n']} "
            f"fitted samples {w['where']} (z - shift = {z.min():.3g} to {z.max():.3g} nm)")


def adequacy(prob, x, dof: int, chi2: float, curves, jump: bool = True) -> dict:
    """``{"redchi", "threshold", "adequate", "worst": [site, ...], "reason", "jump"}`` of the fit
    at ``x``: the global reduced chi-square against its threshold, and (``jump``) the jump-in's
    neighbourhood (:func:`jump_misfit`; ``"jump"``: the windows over their threshold). Noise-free
    curves (the noise taken as the solver's tolerance) are not held to the windows: their
    residual is the solver's error, largest where the model is stiff, at the jump-in."""
    thr = redchi_threshold(dof, curves)
    redchi = chi2 / max(dof, 1)
    rs = prob.curve_residuals(x)
    jump = jump_misfit(curves, rs) if jump else []
    out = {"redchi": redchi, "threshold": thr, "quantile": ADEQUACY_QUANTILE,
           "adequate": bool(redchi <= thr) and not jump, "worst": [],
           "jump": [{k: v for k, v in w.items() if k != "index"} for w in jump]}
    if out["adequate"]:
        out["reason"] = ""
        return out
    values, shifts = prob.unpack(x)
    if redchi <= thr:       # the global chi-square passes: the misfit sits at the jump-ins
        byname = {c.name: i for i, c in enumerate(curves)}
        jump.sort(key=lambda w: -w["chi2"] / w["threshold"])
        out["worst"] = [_jump_site(curves[byname[w["curve"]]], w, float(shifts[byname[w["curve"]]]))
                        for w in jump[:3]]
        out["advice"] = ADVICE["the jump-in"]
        out["reason"] = (f"the residuals next to the jump-in exceed the noise ({len(jump)} of the "
                         f"windows of {JUMP_SAMPLES} samples either side of it, at the "
                         f"{ADEQUACY_QUANTILE:.1%} quantile over all of them) although the reduced "
                         f"chi-square {redchi:.3g} passes its threshold {thr:.3g}")
        return out
    out["reason"] = (f"reduced chi-square {redchi:.3g} > {thr:.3g} (the {ADEQUACY_QUANTILE:.1%} "
                     "quantile, noise estimate's spread included)")
    per = []
    for i, (c, r) in enumerate(zip(curves, rs)):
        per.append((float(np.mean(r ** 2)), i, r))
    per.sort(key=lambda t: -t[0])
    bad = [p for p in per if p[0] > redchi_threshold(len(p[2]), [curves[p[1]]])][:3] or per[:1]
    out["worst"] = [residual_site(curves[i], r, float(shifts[i])) for _, i, r in bad]
    out["advice"] = ADVICE[worst_region(curves[bad[0][1]], bad[0][2])]
    return out


def undetermined_verdict(adq: dict) -> str:
    """The verdict when the model does not describe the data."""
    why = (adq["reason"] if adq.get("jump") and adq["redchi"] <= adq["threshold"]
           else f"reduced chi-square {adq['redchi']:.3g} > {adq['threshold']:.3g}")
    return (f"undetermined: the model does not describe the data ({why}); worst: " + "; ".join(adq["worst"])
            + (f"; {adq['advice']}" if adq.get("advice") else ""))
