"""Fit a surface force law of :mod:`afmforce.surface_laws` to a static force-separation curve.

Model: ``F(h) = eq 2 (A, z0; optional) + law(h; values) + c0`` on the geometry's Derjaguin
radius, fitted with ``scipy.optimize.least_squares`` for the law's ``free`` parameters (bounds:
their quantities' ranges; scales: the law's record) and an offset ``c0``. The separation must be
known (the zero of separation is not fitted: for an exponential law it trades against the
prefactor). Standard errors from the Jacobian at the optimum, ``cov = s^2 (J^T J)^-1``; a
parameter whose error is as large as its value is reported undetermined (NaN, named in ``note``).
Each other free parameter gets its 95 % profile-likelihood interval (``interval``: the chi-square,
the other parameters re-fitted, 3.84 above its minimum): open on a side (the profile stays below
up to the parameter's range end) or lower elsewhere (a local minimum), the parameter is
undetermined; an interval more than twice as wide as the standard error says on a side keeps the
value but no standard error. The Jacobian's error is local: a Debye length far beyond the data
range (the law then looks like a line the offset and the prefactor share) had a tight standard
error about a wrong value (2.6 +- 2.0 nm for a true 100 nm over 1-10 nm, the profile flat to
1 um); the note says how far the data allow.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np

from .. import forces
from .._fields import QUANTITIES
from ..errors import ParameterError
from ..surface_laws import law as _law

__all__ = ["LawFit", "fit_surface_law", "profile_interval", "PROFILE_THRESHOLD"]


@dataclass(frozen=True)
class LawFit:
    """Result of :func:`fit_surface_law`: the law, its parameters [SI] (free and fixed), the
    standard errors of the free ones (NaN: undetermined), the offset [N], the reduced chi-square
    (residual variance / noise variance, when ``sigma`` is given), the samples used and a note."""

    law: str
    values: dict
    stderr: dict
    offset: float
    redchi: float
    n: int
    note: str = field(default="")
    #: the 95 % profile-likelihood interval of each free parameter tested [SI]: (low, high), None
    #: for an end the data leave open
    interval: dict = field(default_factory=dict)


def _value(v):
    """A parameter's start value: a float, or None for one given by another (psi2, 1/kappa)."""
    return None if v is None else float(v)


#: Rise of the chi-square (in noise units) that closes a 95 % profile interval (chi-square, 1 dof).
PROFILE_THRESHOLD = 3.84


def profile_interval(res, i: int, model, f, unit: float, lo, hi, step: float,
                      noise_var: float) -> tuple[float | None, float | None, float | None]:
    """The 95 % profile-likelihood interval of parameter ``i`` (scaled units): ``(low, high, better)``.

    The other parameters are re-fitted at each value; an end is where the chi-square has risen by
    :data:`PROFILE_THRESHOLD` (in noise units). Found by walking out from the optimum ``t``
    standard errors away (``t = 1, 2, 4, ...``) up to the parameter's bound or a million times the
    larger of the value and the step, then bisecting the bracket (brentq). An end is ``None`` when the
    profile stays below the threshold up to the bound (open: the data allow any value there).
    ``better`` is a value where the fit is better by more than the threshold (the optimum was local;
    None otherwise).
    """
    from scipy.optimize import brentq, least_squares

    x_best = np.asarray(res.x, float)
    ssr0 = float(res.fun @ res.fun)
    others = [j for j in range(x_best.size) if j != i]
    step = step if math.isfinite(step) and step > 0 else 1.0
    reach = 1e6 * max(abs(float(x_best[i])), step)
    warm = {"y": x_best[others]}

    def rise(value: float) -> float:
        x = x_best.copy()
        x[i] = value
        if others:
            def resid(y):
                x[others] = y
                return (model(x) - f) / unit
            fit = least_squares(resid, np.clip(warm["y"], lo[others], hi[others]),
                                bounds=(lo[others], hi[others]), xtol=1e-10, ftol=1e-10, gtol=1e-10, max_nfev=200)
            warm["y"], r = fit.x, fit.fun
        else:
            r = (model(x) - f) / unit
        return (float(r @ r) - ssr0) / noise_var

    ends, better = [], None
    for d, bound in ((-1, lo[i]), (+1, hi[i])):
        warm["y"], t, inside, end = x_best[others], 1.0, float(x_best[i]), None
        while True:
            value = x_best[i] + d * step * t
            at_end = (value - bound) * d >= 0 or step * t >= reach
            if (value - bound) * d >= 0:
                value = float(bound)
            r = rise(value)
            if r < -PROFILE_THRESHOLD and better is None:
                better = value
            if r >= PROFILE_THRESHOLD:
                end = brentq(lambda v: rise(v) - PROFILE_THRESHOLD, inside, value, xtol=1e-6 * step, rtol=1e-6)
                break
            inside = value
            if at_end:
                break
            t *= 2.0
        ends.append(end)
    return ends[0], ends[1], better


def fit_surface_law(separation, force, law: str, *, radius: float, free: Sequence[str],
                    fixed: Mapping[str, float] | None = None, geometry: str = "sphere-flat",
                    hamaker: float = 0.0, z0: float = 0.35e-9, sigma: float | None = None,
                    offset: bool = True) -> LawFit:
    """Fit ``law``'s ``free`` parameters (start: ``fixed`` or the defaults) to ``force(separation)``.

    Parameters
    ----------
    separation, force : array_like
        h [m] and the static force F [N] (negative: attractive).
    law : str
        A key of :data:`afmforce.surface_laws.LAWS` (eq 2 ``van_der_waals`` and ``double_layer``
        included; the double layer's form from ``fixed["double_layer"]``, default its record's
        example, constant potential).
    radius : float
        Probe radius R [m]; R_eff follows ``geometry``.
    free : sequence of str
        Parameters of the law to fit; the others from ``fixed`` or the record's defaults.
    hamaker, z0 : float
        Eq 2 added to the law (A [J]; 0: none) with its soft wall [m].
    sigma : float, optional
        Force noise [N] (for ``redchi``).
    offset : bool
        Fit a constant force offset c0 [N] with the law (False: c0 = 0; a law linear in h, such
        as the meniscus, cannot be told from an offset).
    """
    rec = _law(law)
    names = rec.parameter_names
    unknown = [n for n in free if n not in names]
    if unknown or not free:
        raise ParameterError(f"free must name parameters of the {law} law ({', '.join(names)}), "
                             f"got {list(free)}")
    h, f = np.asarray(separation, float), np.asarray(force, float)
    ok = np.isfinite(h) & np.isfinite(f) & (h > 0)
    h, f = h[ok], f[ok]
    if h.size < len(free) + 2:
        raise ParameterError(f"fit_surface_law: {h.size} samples for {len(free) + 1} parameters")
    start = {p.name: _value((fixed or {}).get(p.name, p.default)) for p in rec.parameters}
    if rec.switch is not None:          # the law's form (the double layer's boundary condition)
        start[rec.switch.name] = (fixed or {}).get(rec.switch.name, rec.example[rec.switch.name])
    r_eff = float(forces.effective_radius(radius, geometry))
    base = (np.asarray(forces.vdw_force(h, 2.0 * r_eff, hamaker, z0)) if hamaker > 0
            else np.zeros_like(h))
    params = {p.name: p for p in rec.parameters}
    k = len(free)
    spec = [QUANTITIES[n] for n in free]
    scale = np.array([params[n].fit[0] if params[n].fit else (abs(start[n]) or 1.0) for n in free]
                     + ([max(float(np.std(f)), 1e-15)] if offset else []))
    lo = np.array([-np.inf if s.lo is None else s.lo for s in spec] + [-np.inf] * offset) / scale
    hi = np.array([np.inf if s.hi is None else s.hi * (1 - 1e-9 * s.hi_open) for s in spec]
                  + [np.inf] * offset) / scale

    def model(x):
        v = {**start, **{n: xi for n, xi in zip(free, x[:k] * scale[:k])}}
        return base + rec.force(h, r_eff, v)[0] + (x[k] * scale[k] if offset else 0.0)

    x0 = np.clip(np.array([start[n] for n in free] + [0.0] * offset) / scale, lo, hi)
    unit = sigma or float(np.std(f)) or 1.0       # residuals in units of the noise: tolerances apply
    from scipy.optimize import least_squares  # here: its import costs 0.25 s of every command
    res = least_squares(lambda x: (model(x) - f) / unit, x0, bounds=(lo, hi),
                        xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=2000)
    dof = max(h.size - len(x0), 1)
    s2 = float(res.fun @ res.fun) / dof                       # [noise units^2]
    se = np.sqrt(np.clip(np.diag(np.linalg.pinv(res.jac.T @ res.jac)) * s2, 0.0, None)) * scale
    # a parameter moving the model by less than the noise over its whole scale is not seen
    seen = np.linalg.norm(res.jac, axis=0) > math.sqrt(s2) * 1e-3
    values = {**start, **{n: float(x) for n, x in zip(free, res.x[:k] * scale[:k])}}
    stderr, interval, bad, why = {}, {}, [], []
    noise_var = max(s2, 1.0) if sigma else s2          # chi-square units of the profile [noise units^2]
    for i, n in enumerate(free):
        stderr[n] = float(se[i])
        if not (seen[i] and se[i] < abs(values[n]) and math.isfinite(se[i])):
            bad.append(n)
            values[n], stderr[n] = math.nan, math.nan
            continue
        low, high, better = profile_interval(res, i, model, f, unit, lo, hi, se[i] / scale[i], noise_var)
        low, high = (None if e is None else float(e * scale[i]) for e in (low, high))
        interval[n] = (low, high)
        shown = f"[{'-' if low is None else f'{low:.3g}'}, {'-' if high is None else f'{high:.3g}'}]"
        if better is not None:
            why.append(f"{n}: a better fit lies at {better * scale[i]:.3g} (the fit's {values[n]:.3g} is a local "
                       "minimum)")
        elif low is None or high is None:
            why.append(f"{n}: its profile (the others re-fitted) stays within {PROFILE_THRESHOLD} of the minimum "
                       f"up to the range's end: 95 % interval {shown}, open")
        elif max(values[n] - low, high - values[n]) > 2 * 1.96 * se[i]:
            why.append(f"{n} = {values[n]:.3g}: its 95 % profile interval {shown} is far wider than the standard "
                       f"error {se[i]:.2g} says (no standard error given)")
            stderr[n] = math.nan
            continue
        else:
            continue
        bad.append(n)
        values[n], stderr[n] = math.nan, math.nan
    note = f"undetermined by these data: {', '.join(bad)}" if bad else ""
    if why:
        note += "; " + "; ".join(why)
    redchi = s2 if sigma else math.nan
    c0 = float(res.x[k] * scale[k]) if offset else 0.0
    return LawFit(law, values, stderr, c0, redchi, int(h.size), note, interval)
