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

The branches are exact (:func:`branch`, compiled in :mod:`._adhesive_kernels`): JKR's quartic and Maugis's
parametric equations inverted by Newton's method to rounding, not interpolated.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ParameterError

__all__ = ["jkr", "dmt", "maugis", "jkr_dimensionless", "maugis_dimensionless", "adhesive_force", "scales", "branch",
           "branch_end"]

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


def _kernels():
    from . import _adhesive_kernels

    return _adhesive_kernels


_NO_TABLE = (np.zeros(1), np.zeros(1))


def _tables(key: str, lam: float):
    return _maugis_table(float(lam)) if key == "maugis" else _NO_TABLE


_LAW = {"dmt": 0, "jkr": 1, "maugis": 2}  # the kernels' law codes (_adhesive_kernels.DMT, JKR, MAUGIS)


def _code(key: str) -> int:
    try:
        return _LAW[key]
    except KeyError:
        raise ParameterError(f"adhesive law {key!r} unknown; choose from jkr, dmt, maugis") from None


def jkr_dimensionless(D: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """JKR's stable branch: ``(A, P)`` at dimensionless indentation ``D`` (the root with
    dD/dA > 0 of ``D = A^2 - 2/3 sqrt(6 A)``, by Newton's method to rounding; D below the branch's
    minimum gives its end)."""
    A, P, _ = _kernels().branch_values(1, np.ascontiguousarray(np.ravel(D), dtype=float), 1.0, *_NO_TABLE)
    shape = np.shape(D)
    return A.reshape(shape), P.reshape(shape)


@functools.lru_cache(maxsize=1)
def _jkr_table(n: int = 6000) -> tuple[np.ndarray, np.ndarray]:
    """JKR's stable branch tabulated (D increasing, P) from its exact parametric form in s = sqrt(A)."""
    s_min = (_C / 4.0) ** (1.0 / 3.0)
    s = s_min + np.concatenate(([0.0], np.geomspace(1e-8, 1e4, n)))
    s3 = s ** 3
    return s ** 4 - _C * s, s3 * s3 - math.sqrt(6.0) * s3


@functools.lru_cache(maxsize=16)
def _maugis_table(lam: float, n: int = 6000) -> tuple[np.ndarray, np.ndarray]:
    """Maugis-Dugdale's stable branch for ``lambda`` on a grid of ln t (t = sqrt(m^2 - 1)), from its end
    (dD/dt = 0, refined by bisection) on: (ln t, y = sqrt(D - D_end)), y increasing (t decreasing)."""
    if not lam > 0:
        raise ParameterError(f"Maugis transition parameter lambda = {lam} must be > 0")
    k = _kernels()
    lt = np.linspace(math.log(1e-8), math.log(1e4), n)
    D = k.maugis_params(np.exp(lt), float(lam))[2]
    end = int(np.argmin(D))  # t beyond it: the unstable branch
    lo, hi = lt[max(end - 1, 0)], lt[min(end + 1, n - 1)]
    for _ in range(100):  # dD/dt = 0 by bisection
        mid = 0.5 * (lo + hi)
        if k.maugis_point(math.exp(mid), float(lam))[4] < 0:
            lo = mid
        else:
            hi = mid
    d_end = k.maugis_point(math.exp(lo), float(lam))[2]
    lt, D = np.concatenate(([lo], lt[:end][::-1])), np.concatenate(([d_end], D[:end][::-1]))
    keep = np.concatenate(([True], np.diff(D) > 0))
    lt, D = lt[keep], D[keep]
    return np.ascontiguousarray(lt), np.sqrt(np.maximum(D - d_end, 0.0))


def maugis_dimensionless(lam: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Maugis-Dugdale stable branch for ``lambda`` [-]: arrays ``(D, P, A)`` with D increasing.

    Parametrised by m = c/a (the cohesive zone's outer radius over the contact radius): the
    first Maugis equation is quadratic in A, so each m gives A, P and D explicitly.
    """
    lt, _ = _maugis_table(float(lam))
    A, P, D, _, _ = _kernels().maugis_params(np.exp(lt), float(lam))
    return D, P, A


def branch_end(key: str, lam: float = 1.0) -> tuple[float, float]:
    """(D, P) where the law's displacement-controlled branch ends (the pull-off at fixed position)."""
    if _code(key) == 0:
        return 0.0, -2.0
    if key == "jkr":
        s = (_C / 4.0) ** (1.0 / 3.0)
        return s ** 4 - _C * s, s ** 6 - math.sqrt(6.0) * s ** 3
    lt, _ = _maugis_table(float(lam))
    _, P, D, _, _ = _kernels().maugis_point(math.exp(lt[0]), float(lam))
    return float(D), float(P)


def branch(key: str, D: ArrayLike, lam: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """The law's stable branch at dimensionless indentation ``D`` (>= its end): ``(P, dP/dD)``.

    Exact: JKR's quartic and Maugis's parametric equations inverted by Newton's method to
    rounding (not interpolated); DMT in closed form.
    """
    Dv = np.ascontiguousarray(np.ravel(D), dtype=float)
    _, P, dP = _kernels().branch_values(_code(key), Dv, float(lam), *_tables(key, lam))
    return P.reshape(np.shape(D)), dP.reshape(np.shape(D))


def _law(key: str, delta: ArrayLike, E: float, w: float, radius: float, nu: float, lam: float, branch_: str):
    fs, ds = scales(E, w, radius, nu)
    delta = np.asarray(delta, dtype=float)
    D = delta / ds
    if branch_ == "approach":
        inside = delta > 0
    elif branch_ == "retract":
        inside = delta >= 0 if key == "dmt" else D >= branch_end(key, lam)[0]
    else:
        raise ParameterError(f"branch must be 'approach' or 'retract', got {branch_!r}")
    P = np.zeros_like(D)
    if np.any(inside):
        P[inside] = branch(key, D[inside], lam)[0]
    return _out(fs * P)


def jkr(delta: ArrayLike, E: float, w: float, radius: float, nu: float = 0.5, branch: str = "approach"):
    """JKR force [N] at indentation ``delta`` [m] (see the module docstring; the quartic of the
    parametric form solved to rounding)."""
    return _law("jkr", delta, E, w, radius, nu, 1.0, branch)


def dmt(delta: ArrayLike, E: float, w: float, radius: float, nu: float = 0.5, branch: str = "approach"):
    """DMT force [N]: Hertz minus 2 pi w R in contact (delta > 0; the retract branch also at delta = 0)."""
    return _law("dmt", delta, E, w, radius, nu, 1.0, branch)


def maugis(delta: ArrayLike, E: float, w: float, radius: float, nu: float = 0.5, lam: float = 1.0,
           branch: str = "approach"):
    """Maugis-Dugdale force [N] for the transition parameter ``lam`` (its parametric equations inverted
    to rounding)."""
    return _law("maugis", delta, E, w, radius, nu, lam, branch)


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
