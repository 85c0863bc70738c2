"""Adhesive sphere contacts: JKR, DMT and Maugis-Dugdale force against indentation.

Pure, vectorised functions in SI. A rigid sphere of radius R [m] on an elastic half
space (Young's modulus E [Pa], Poisson ratio nu [-]) with work of adhesion w [J/m^2];
``K = 4/3 E/(1 - nu^2)``. In the dimensionless variables of Maugis (1992) and Johnson &
Greenwood (1997)::

    A = a / (pi w R^2 / K)^(1/3),  P = F / (pi w R),  D = delta / (pi^2 w^2 R / K^2)^(1/3)

* JKR (Johnson, Kendall & Roberts 1971): ``P = A^3 - sqrt(6 A^3)``, ``D = A^2 - 2/3 sqrt(6 A)``;
  pull-off -3/2 pi w R under load control, -5/6 pi w R under displacement control.
* DMT (Derjaguin, Muller & Toporov 1975): ``P = A^3 - 2``, ``D = A^2`` (Hertz shifted by -2 pi w R).
* Maugis-Dugdale (Maugis 1992) with the transition parameter
  ``lambda = 2 sigma0 (R / (pi w K^2))^(1/3)``: DMT as lambda -> 0, JKR as lambda -> infinity.

``branch``: ``"approach"`` -- no force before contact (delta <= 0), the contact's stable
branch from delta = 0 on; ``"retract"`` -- the displacement-controlled branch down to its
smallest indentation (a neck: delta < 0), zero force past it.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ParameterError

__all__ = ["jkr", "dmt", "maugis", "jkr_dimensionless", "maugis_dimensionless", "adhesive_force", "scales"]

_C = 2.0 / 3.0 * math.sqrt(6.0)  # JKR: D = s^4 - _C s with s = sqrt(A)


def _out(x: np.ndarray):
    return x[()] if np.ndim(x) == 0 else x


def scales(E: float, w: float, radius: float, nu: float) -> tuple[float, float]:
    """(force scale pi w R [N], indentation scale (pi^2 w^2 R / K^2)^(1/3) [m])."""
    if not (-1.0 < nu <= 0.5):
        raise ParameterError(f"Poisson ratio nu = {nu} out of range: it must lie in (-1, 0.5]")
    k = 4.0 / 3.0 * E / (1.0 - nu * nu)
    w = max(w, 1e-12 * k * radius)  # w = 0: the Hertz limit (kept off zero, where the scales vanish)
    return math.pi * w * radius, (math.pi ** 2 * w * w * radius / (k * k)) ** (1.0 / 3.0)


def jkr_dimensionless(D: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """JKR's stable branch: ``(A, P)`` at dimensionless indentation ``D`` (the root with
    dD/dA > 0, by Newton's method from above; D below the branch's minimum gives its end)."""
    d = np.asarray(D, dtype=float)
    s_min = (_C / 4.0) ** (1.0 / 3.0)
    s = np.maximum(np.maximum(d, 0.0) ** 0.25 + _C ** (1.0 / 3.0), s_min)
    for _ in range(80):
        f = s ** 4 - _C * s - d
        slope = 4 * s ** 3 - _C
        step = np.where(slope > 0, f / np.where(slope > 0, slope, 1.0), 0.0)
        s = np.maximum(s - step, s_min)
        if np.all(np.abs(step) <= 1e-14 * s):
            break
    s3 = s ** 3
    return s * s, s3 * s3 - math.sqrt(6.0) * s3


@functools.lru_cache(maxsize=1)
def _jkr_table(n: int = 6000) -> tuple[np.ndarray, np.ndarray]:
    """JKR's stable branch tabulated (D increasing, P) from its exact parametric form in s = sqrt(A)."""
    s_min = (_C / 4.0) ** (1.0 / 3.0)
    s = s_min + np.concatenate(([0.0], np.geomspace(1e-8, 1e4, n)))
    s3 = s ** 3
    return s ** 4 - _C * s, s3 * s3 - math.sqrt(6.0) * s3


def _interp(D: np.ndarray, Dt: np.ndarray, Pt: np.ndarray) -> np.ndarray:
    """P on a tabulated branch (linear in D; Hertz's asymptote P ~ D^1.5 past the table)."""
    P = np.interp(D, Dt, Pt)
    big = D > Dt[-1]
    if np.any(big):
        P = np.where(big, Pt[-1] * (np.where(big, D, 1.0) / Dt[-1]) ** 1.5, P)
    return P


@functools.lru_cache(maxsize=16)
def maugis_dimensionless(lam: float, n: int = 6000) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Maugis-Dugdale stable branch for ``lambda`` [-]: arrays ``(D, P, A)`` with D increasing.

    Parametrised by m = c/a (the cohesive zone's outer radius over the contact radius): the
    first Maugis equation is quadratic in A, so each m gives A, P and D explicitly.
    """
    if not lam > 0:
        raise ParameterError(f"Maugis transition parameter lambda = {lam} must be > 0")
    t = np.geomspace(1e-8, 1e4, n)  # t = sqrt(m^2 - 1)
    m = np.sqrt(1 + t * t)
    at = np.arctan(t)
    a1 = t + (m * m - 2) * at
    a1 = np.where(t < 1e-3, 4.0 / 3.0 * t ** 3 - 0.4 * t ** 5, a1)  # series: cancellation at small t
    a2 = t * at - m + 1
    a2 = np.where(t < 1e-3, 0.5 * t * t - 5.0 / 24.0 * t ** 4, a2)
    qa, qb = lam * a1 / 2, 4 * lam * lam * a2 / 3
    A = 2.0 / (qb + np.sqrt(qb * qb + 4 * qa))  # positive root of qa A^2 + qb A - 1 = 0
    P = A ** 3 - lam * A * A * (t + m * m * at)
    D = A * A - 4.0 / 3.0 * lam * A * t
    order = np.argsort(A)
    A, P, D = A[order], P[order], D[order]
    start = int(np.argmin(D))  # the stable (displacement-controlled) branch: D increasing with A
    A, P, D = A[start:], P[start:], D[start:]
    keep = np.concatenate(([True], np.diff(D) > 0))
    return D[keep], P[keep], A[keep]


def _branch(delta: np.ndarray, D: np.ndarray, P: np.ndarray, d_min: float, branch: str) -> np.ndarray:
    if branch == "approach":
        return np.where(delta > 0, P, 0.0)
    if branch == "retract":
        return np.where(D >= d_min, P, 0.0)
    raise ParameterError(f"branch must be 'approach' or 'retract', got {branch!r}")


def jkr(delta: ArrayLike, E: float, w: float, radius: float, nu: float = 0.5, branch: str = "approach"):
    """JKR force [N] at indentation ``delta`` [m] (see the module docstring; interpolated on the branch
    tabulated from its exact parametric form, within 1e-4 of :func:`jkr_dimensionless`)."""
    fs, ds = scales(E, w, radius, nu)
    delta = np.asarray(delta, dtype=float)
    D = delta / ds
    Dt, Pt = _jkr_table()
    return _out(fs * _branch(delta, D, _interp(D, Dt, Pt), float(Dt[0]), branch))


def dmt(delta: ArrayLike, E: float, w: float, radius: float, nu: float = 0.5, branch: str = "approach"):
    """DMT force [N]: Hertz minus 2 pi w R in contact (delta > 0; the retract branch also at delta = 0)."""
    fs, ds = scales(E, w, radius, nu)
    delta = np.asarray(delta, dtype=float)
    D = np.maximum(delta / ds, 0.0)
    P = D ** 1.5 - 2.0
    if branch == "retract":
        return _out(fs * np.where(delta >= 0, P, 0.0))
    return _out(fs * _branch(delta, D, P, 0.0, branch))


def maugis(delta: ArrayLike, E: float, w: float, radius: float, nu: float = 0.5, lam: float = 1.0,
           branch: str = "approach"):
    """Maugis-Dugdale force [N] for the transition parameter ``lam`` (interpolated on its branch)."""
    fs, ds = scales(E, w, radius, nu)
    Dt, Pt, _ = maugis_dimensionless(float(lam))
    delta = np.asarray(delta, dtype=float)
    D = delta / ds
    return _out(fs * _branch(delta, D, _interp(D, Dt, Pt), float(Dt[0]), branch))


def adhesive_force(key: str, delta: ArrayLike, E: float, w: float, radius: float, nu: float = 0.5,
                   lam: float = 1.0, branch: str = "approach"):
    """The adhesive law ``key`` (``jkr``, ``dmt``, ``maugis``) [N]."""
    if key == "jkr":
        return jkr(delta, E, w, radius, nu, branch)
    if key == "dmt":
        return dmt(delta, E, w, radius, nu, branch)
    if key == "maugis":
        return maugis(delta, E, w, radius, nu, lam, branch)
    raise ParameterError(f"adhesive law {key!r} unknown; choose from jkr, dmt, maugis")
