"""Fit a surface force law of :mod:`afmforce.surface_laws` to a static force-separation curve.

Model: ``F(h) = eq 2 (A, z0; optional) + law(h; values) + c0`` on the geometry's Derjaguin
radius, fitted with ``scipy.optimize.least_squares`` for the law's ``free`` parameters (bounds:
their quantities' ranges; scales: the law's record) and an offset ``c0``. The separation must be
known (the zero of separation is not fitted: for an exponential law it trades against the
prefactor). Standard errors from the Jacobian at the optimum, ``cov = s^2 (J^T J)^-1``; a
parameter whose error is as large as its value is reported undetermined (NaN, named in ``note``).
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

__all__ = ["LawFit", "fit_surface_law"]


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


def _value(v):
    """A parameter's start value: a float, or None for one given by another (psi2, 1/kappa)."""
    return None if v is None else float(v)


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
    stderr, bad = {}, []
    for i, n in enumerate(free):
        stderr[n] = float(se[i])
        if not seen[i] or not (se[i] < abs(values[n])) or not math.isfinite(se[i]):
            bad.append(n)
            values[n], stderr[n] = math.nan, math.nan
    note = f"undetermined by these data: {', '.join(bad)}" if bad else ""
    redchi = s2 if sigma else math.nan
    c0 = float(res.x[k] * scale[k]) if offset else 0.0
    return LawFit(law, values, stderr, c0, redchi, int(h.size), note)
