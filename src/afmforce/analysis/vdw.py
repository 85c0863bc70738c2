"""van der Waals fit of the approach before the jump into contact (eq 2).

Model: ``F(h) = -(A R / 12 h^2) (1 - z0^6 / (4 h^6)) + c0 + c1 (h - h_ref)``,
fitted with ``scipy.optimize.least_squares`` for ``A R`` (or ``A`` when R is
given), a baseline (``"none"``, ``"offset"`` c0, or ``"line"`` c0 + c1 h) and
optionally a shift of the zero of separation ``h -> h + dh``. The baseline
terms absorb what the drift step leaves behind: a drift line fitted where the
attraction's tail has not quite vanished is a line in time, hence in h, and
would otherwise bias A R (by 10-15 % for a 60 nm baseline at R = 220 nm).
Standard errors come from the Jacobian at the optimum,
``cov = s^2 (J^T J)^-1`` with ``s^2`` the residual variance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import forces
from ..errors import ParameterError
from ._units import unit as _u
from .options import VdwOptions as _O  # the defaults: declared once, in the step's record

__all__ = ["VdwFit", "fit_vdw", "BASELINES"]

#: Baseline models of the fit and their number of parameters.
BASELINES = {"none": 0, "offset": 1, "line": 2}


@dataclass(frozen=True)
class VdwFit:
    """Result of the van der Waals fit.

    Attributes
    ----------
    status : str  ``"ok"`` or why no fit was made
    hamaker_radius : float  A R [J m]
    hamaker_radius_se : float  standard error [J m]
    hamaker : float  A when R is given [J] (NaN otherwise)
    hamaker_se : float  [J]
    radius : float  R used [m] (NaN if fitted as A R)
    baseline : str  baseline model
    force_offset : float  c0 at the middle of the range [N]
    force_slope : float  c1 [N/m]
    separation_offset : float  fitted dh (0 unless asked) [m]
    separation_offset_se : float  [m]
    n_points : int  [-]
    separation_min, separation_max : float  fitted range [m]
    rms_residual : float  [N]
    static_jump_in_separation : float  from the fitted A R and k [m]
    reliable : bool  False when the fit failed or the dynamic diagnosis flags the run
    """

    status: str
    hamaker_radius: float = _u("J m")
    hamaker_radius_se: float = _u("J m")
    hamaker: float = _u("J")
    hamaker_se: float = _u("J")
    radius: float = _u("m")
    baseline: str
    force_offset: float = _u("N")
    force_slope: float = _u("N/m")
    separation_offset: float = _u("m")
    separation_offset_se: float = _u("m")
    n_points: int = _u("")
    separation_min: float = _u("m")
    separation_max: float = _u("m")
    rms_residual: float = _u("N")
    static_jump_in_separation: float = _u("m")
    reliable: bool = True


def _failed(status: str, baseline: str, n: int = 0, radius: float = math.nan) -> VdwFit:
    nan = math.nan
    return VdwFit(status, nan, nan, nan, nan, radius, baseline, nan, nan, nan, nan, n, nan, nan, nan, nan, False)


def _shape(h: np.ndarray, z0: float) -> np.ndarray:
    """``F / (A R)`` of eq 2 [1/m^2]."""
    return -(1.0 / (12.0 * h * h)) * (1.0 - 0.25 * (z0 / h) ** 6)


def fit_vdw(separation: np.ndarray, force: np.ndarray, *, spring_constant: float,
            radius: float | None = None, z0: float = _O.z0, max_separation: float = _O.max_separation,
            min_separation: float = 0.0, baseline: str = _O.baseline,
            fit_separation_offset: bool = _O.fit_separation_offset,
            min_points: int = 8) -> VdwFit:
    """Fit eq 2 to approach points (separation [m], force [N]) before the jump.

    Parameters
    ----------
    separation, force : ndarray
        Pre-jump approach samples.
    spring_constant : float
        k [N/m], for the static jump-in separation of the fitted law.
    radius : float, optional
        R [m]: report A = (A R) / R as well.
    max_separation, min_separation : float
        Fitted separation range [m].
    baseline : str
        ``"none"``, ``"offset"`` or ``"line"`` (see module docstring).
    fit_separation_offset : bool
        Also fit a shift of the zero of separation, ``h -> h + dh`` [m].
    """
    if baseline not in BASELINES:
        raise ParameterError(f"vdw baseline must be one of {', '.join(BASELINES)}, got {baseline!r}")
    r_used = math.nan if radius is None else float(radius)
    h = np.asarray(separation, float)
    f = np.asarray(force, float)
    keep = np.isfinite(h) & np.isfinite(f) & (h > max(min_separation, 0.5 * z0)) & (h <= max_separation)
    h, f = h[keep], f[keep]
    nb = BASELINES[baseline]
    n_par = 1 + nb + int(fit_separation_offset)
    if h.size < max(min_points, n_par + 3):
        return _failed(f"too few points ({h.size}) between the jump and {max_separation * 1e9:.3g} nm",
                       baseline, h.size, r_used)
    h_ref, h_span = 0.5 * (h.max() + h.min()), max(0.5 * float(np.ptp(h)), 1e-12)
    f_scale = max(float(np.max(np.abs(f))), 1e-300)
    sh0 = _shape(h, z0)
    ar_scale = f_scale / max(float(np.max(np.abs(sh0))), 1e-300)
    # columns scaled to order one: AR*shape, c0, c1*(h-h_ref)
    cols = [sh0 * ar_scale / f_scale, np.ones_like(h), (h - h_ref) / h_span][: 1 + nb]
    lin, *_ = np.linalg.lstsq(np.column_stack(cols), f / f_scale, rcond=None)
    p0 = np.concatenate([lin, [0.0]]) if fit_separation_offset else lin

    def model(q):
        hh = h + (q[-1] * 1e-9 if fit_separation_offset else 0.0)
        m = q[0] * ar_scale / f_scale * _shape(np.maximum(hh, 0.1 * z0), z0)
        if nb >= 1:
            m = m + q[1]
        if nb >= 2:
            m = m + q[2] * (h - h_ref) / h_span
        return m

    from scipy.optimize import least_squares  # here: its import costs 0.25 s of every command
    sol = least_squares(lambda q: model(q) - f / f_scale, p0, method="lm")
    q = sol.x
    r = (model(q) - f / f_scale) * f_scale
    s2 = float(r @ r) / max(h.size - n_par, 1)
    J = sol.jac * f_scale
    try:
        se = np.sqrt(np.clip(np.diag(np.linalg.inv(J.T @ J)) * s2, 0, None))
    except np.linalg.LinAlgError:
        se = np.full(n_par, math.nan)
    ar, ar_se = float(q[0] * ar_scale), float(se[0] * ar_scale)
    c0 = float(q[1] * f_scale) if nb >= 1 else 0.0
    c1 = float(q[2] * f_scale / h_span) if nb >= 2 else 0.0
    dh, dh_se = (float(q[-1] * 1e-9), float(se[-1] * 1e-9)) if fit_separation_offset else (0.0, 0.0)
    a, a_se = (ar / r_used, ar_se / r_used) if math.isfinite(r_used) else (math.nan, math.nan)
    h_jump = math.nan
    if ar > 0 and math.isfinite(spring_constant) and spring_constant > 0:
        # eq 2's gradient equals k: forces.static_jump_in_separation with A R as the "Hamaker" and R = 1
        h_jump = float(forces.static_jump_in_separation(spring_constant, 1.0, hamaker=ar, z0=z0))
    ok = ar > 0 and math.isfinite(ar_se)
    status = "ok" if ok else "no attraction found (A R <= 0)"
    return VdwFit(status, ar, ar_se, a, a_se, r_used, baseline, c0, c1, dh, dh_se, int(h.size), float(h.min()),
                  float(h.max()), float(math.sqrt(float(r @ r) / h.size)), h_jump, ok)
