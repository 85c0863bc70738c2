"""Elastic indentation laws: force against indentation for a rigid tip on an elastic sample.

Pure, vectorised functions of SI floats or arrays (a layer of its own at the level of the
laws: docs/architecture.md). ``delta`` is the indentation [m] (zero or negative: no
contact, no force), ``E`` the sample's Young's modulus [Pa], ``nu`` its Poisson ratio [-];
the tip is rigid, so the reduced modulus is ``E / (1 - nu^2)``. Every law is linear in
``E``: ``F = E * shape(delta)``, which the fit (:mod:`afmforce.contact.fit`) uses.

Each law has a record in :data:`afmforce.contact.registry.INDENTATION_MODELS` (key, name,
geometry parameters, validity, reference); the adhesive laws (JKR, DMT, Maugis-Dugdale) are
in :mod:`afmforce.contact.adhesive`.

>>> from afmforce.contact.models import hertz_paraboloid
>>> float(hertz_paraboloid(1e-6, 1e3, radius=5e-6, nu=0.5))   # 4/3 E/(1-nu^2) sqrt(R) d^1.5
3.975...e-09
"""

from __future__ import annotations

import math
import numpy as np
from numpy.typing import ArrayLike

from ..errors import ParameterError

__all__ = ["hertz_paraboloid", "sneddon_sphere", "sphere_contact_radius", "hertz_cone", "bilodeau_pyramid3",
           "bilodeau_pyramid4", "hertz_thin_layer", "dimitriadis_factor", "shape_and_slope", "LINEAR_KEYS"]

#: The laws linear in E (keys of :data:`afmforce.contact.registry.INDENTATION_MODELS`).
LINEAR_KEYS = ("hertz_paraboloid", "sneddon_sphere", "hertz_cone", "bilodeau_pyramid3", "bilodeau_pyramid4",
               "hertz_thin_layer")

#: Bilodeau (1992) prefactors of F = c tan(alpha) E/(1-nu^2) delta^2 (alpha: face angle).
BILODEAU_THREE_SIDED = 0.8887
BILODEAU_FOUR_SIDED = 0.7453


def _out(x: np.ndarray):
    return x[()] if np.ndim(x) == 0 else x


def _depth(delta: ArrayLike) -> np.ndarray:
    return np.maximum(np.asarray(delta, dtype=float), 0.0)


def _check_nu(nu: float) -> float:
    if not (-1.0 < nu <= 0.5):
        raise ParameterError(f"Poisson ratio nu = {nu} out of range: it must lie in (-1, 0.5]")
    return 1.0 / (1.0 - nu * nu)


def hertz_paraboloid(delta: ArrayLike, E: float, radius: float, nu: float = 0.5):
    """Hertz, paraboloidal tip of apex radius R (Hertz 1882; Sneddon 1965 eq 6.9).

    ``F = 4/3 E/(1-nu^2) sqrt(R) delta^(3/2)``

    Parameters
    ----------
    delta : array_like  indentation [m]
    E : float  Young's modulus [Pa]
    radius : float  tip radius R [m]
    nu : float  Poisson ratio [-]

    Returns
    -------
    numeric  force [N] (0 where delta <= 0)
    """
    d = _depth(delta)
    return _out(4.0 / 3.0 * E * _check_nu(nu) * math.sqrt(radius) * d ** 1.5)


#: Below this a/R the exact sphere's force is its power series (the closed form cancels: its bracket is
#: 8/3 (a/R)^3 R^2 out of terms of order 2 (a/R) R^2, 1e-8 relative lost at a = 1e-4 R).
_SPHERE_SERIES_BELOW = 0.5
#: sum_k 8k/(4k^2-1) x^(2k+1), k = 1..: the bracket (1+x^2) 2 atanh(x) - 2x; 30 terms: 0.5^60 ~ 1e-18
_SPHERE_SERIES = np.array([8.0 * k / (4.0 * k * k - 1.0) for k in range(1, 31)])


def _sphere_atanh(delta: np.ndarray, radius: float) -> np.ndarray:
    """y = atanh(a/R) [-] of a rigid sphere at indentation ``delta`` [m]: the root of ``y tanh(y) = delta/R``
    (Sneddon's ``delta = a/2 ln((R+a)/(R-a))`` with a = R tanh(y)), which stays finite and well conditioned
    as a -> R (deep indentations, delta >> R: y -> delta/R), unlike a itself. Newton's method, safeguarded by
    the bracket max(t, sqrt(t)) < y <= (t + sqrt(t^2 + 4t))/2 (t = delta/R; tanh y >= y/(1+y))."""
    t = np.asarray(delta, dtype=float) / float(radius)
    lo = np.maximum(t, np.sqrt(t))
    hi = 0.5 * (t + np.sqrt(t * t + 4.0 * t))
    y = 0.5 * (lo + hi)
    for _ in range(100):
        th = np.tanh(y)
        h = y * th - t
        hp = th + y * (1.0 - th * th)
        lo = np.where(h < 0, y, lo)
        hi = np.where(h > 0, y, hi)
        ok = hp > 0
        new = y - np.where(ok, h / np.where(ok, hp, 1.0), 0.0)
        bad = ~((new > lo) & (new < hi))
        new = np.where(bad, 0.5 * (lo + hi), new)
        done = np.abs(new - y) <= 1e-15 * np.maximum(y, 1e-300)
        y = new
        if np.all(done | (t <= 0)):
            break
    return np.where(t > 0, y, 0.0)


def sphere_contact_radius(delta: ArrayLike, radius: float) -> np.ndarray:
    """Contact radius a [m] of a rigid sphere (radius R [m]) at indentation ``delta`` [m] (Sneddon 1965):
    the root of ``delta = a/2 ln((R+a)/(R-a))``, as ``R tanh(y)`` with y from :func:`_sphere_atanh` (relative
    error ~1e-15 at any depth; a -> R as delta >> R)."""
    return float(radius) * np.tanh(_sphere_atanh(_depth(delta), radius))


def _sphere_bracket(y: np.ndarray) -> np.ndarray:
    """``(1 + x^2) 2y - 2x`` with x = tanh(y) [-]: Sneddon's ``[(a^2 + R^2) ln((R+a)/(R-a)) - 2aR] / R^2``,
    by its power series in x where the closed form cancels (x < 0.5), else closed (ln((R+a)/(R-a)) = 2y)."""
    x = np.tanh(y)
    x2 = x * x
    ser = np.zeros_like(x)
    for c in _SPHERE_SERIES[::-1]:
        ser = ser * x2 + c
    return np.where(x < _SPHERE_SERIES_BELOW, ser * x2 * x, (1.0 + x2) * 2.0 * y - 2.0 * x)


def sneddon_sphere(delta: ArrayLike, E: float, radius: float, nu: float = 0.5):
    """Rigid sphere of radius R, exact (Sneddon 1965, eqs 6.13 and 6.15).

    ``F = E/(2(1-nu^2)) [(a^2 + R^2) ln((R+a)/(R-a)) - 2 a R]`` with the contact
    radius ``a`` from ``delta = a/2 ln((R+a)/(R-a))`` (:func:`sphere_contact_radius`); evaluated in
    y = atanh(a/R), by the bracket's power series for a < R/2 (no cancellation at shallow depths) and
    accurate at any depth (delta >> R: F -> E/(1-nu^2) R (2 delta - R)). Tends to :func:`hertz_paraboloid`
    for ``delta << R`` (nanite's ``sneddon_spher_approx`` is its power series).

    Returns
    -------
    numeric  force [N]
    """
    r = float(radius)
    y = _sphere_atanh(_depth(delta), r)
    return _out(0.5 * E * _check_nu(nu) * r * r * _sphere_bracket(y))


def hertz_cone(delta: ArrayLike, E: float, half_angle: float, nu: float = 0.5):
    """Rigid cone of half-angle alpha (Love 1939; Sneddon 1965 eq 6.4).

    ``F = 2 tan(alpha)/pi E/(1-nu^2) delta^2``, alpha [rad].
    """
    d = _depth(delta)
    return _out(2.0 * math.tan(half_angle) / math.pi * E * _check_nu(nu) * d * d)


def bilodeau_pyramid3(delta: ArrayLike, E: float, half_angle: float, nu: float = 0.5):
    """Three-sided pyramid, face angle alpha [rad] (Bilodeau 1992): ``F = 0.8887 tan(alpha) E/(1-nu^2) delta^2``."""
    d = _depth(delta)
    return _out(BILODEAU_THREE_SIDED * math.tan(half_angle) * E * _check_nu(nu) * d * d)


def bilodeau_pyramid4(delta: ArrayLike, E: float, half_angle: float, nu: float = 0.5):
    """Four-sided pyramid, face angle alpha [rad] (Bilodeau 1992): ``F = 0.7453 tan(alpha) E/(1-nu^2) delta^2``."""
    d = _depth(delta)
    return _out(BILODEAU_FOUR_SIDED * math.tan(half_angle) * E * _check_nu(nu) * d * d)


def _dimitriadis_coefficients(nu: float, bonded: bool) -> tuple[float, ...]:
    if bonded:
        a0 = -(1.2876 - 1.4678 * nu + 1.3442 * nu * nu) / (1 - nu)
        b0 = (0.6387 - 1.0277 * nu + 1.5164 * nu * nu) / (1 - nu)
    else:
        a0 = -0.347 * (3 - 2 * nu) / (1 - nu)
        b0 = 0.056 * (5 - 2 * nu) / (1 - nu)
    pi = math.pi
    return (-2 * a0 / pi, 4 * a0 * a0 / pi ** 2, -8 / pi ** 3 * (a0 ** 3 + 4 * pi ** 2 / 15 * b0),
            16 * a0 / pi ** 4 * (a0 ** 3 + 3 * pi ** 2 / 5 * b0))


def dimitriadis_factor(delta: ArrayLike, radius: float, thickness: float, nu: float = 0.5,
                       bonded: bool = True) -> np.ndarray:
    """Finite-thickness factor of the Hertz sphere on a layer of thickness h (Dimitriadis et al. 2002, eqs 12-13).

    ``1 + c1 chi + c2 chi^2 + c3 chi^3 + c4 chi^4`` with ``chi = sqrt(R delta)/h``; for a layer
    bonded to the substrate and nu = 0.5: 1.133 chi + 1.283 chi^2 + 0.769 chi^3 - 0.0975 chi^4
    (eq 11's sign; eq 12 prints +0.0975, docs/contact.md).
    """
    _check_nu(nu)
    c1, c2, c3, c4 = _dimitriadis_coefficients(nu, bonded)
    chi = np.sqrt(radius * _depth(delta)) / thickness
    return 1 + chi * (c1 + chi * (c2 + chi * (c3 + chi * c4)))


def hertz_thin_layer(delta: ArrayLike, E: float, radius: float, thickness: float, nu: float = 0.5,
                     bonded: bool = True):
    """Hertz sphere on an elastic layer of thickness h on a rigid substrate (Dimitriadis et al. 2002).

    ``F = hertz_paraboloid(delta) * dimitriadis_factor(delta)``; ``bonded``: the layer adheres to the
    substrate (else it slides). Valid while chi = sqrt(R delta)/h stays below about 1.
    """
    return _out(np.asarray(hertz_paraboloid(delta, E, radius, nu))
                * dimitriadis_factor(delta, radius, thickness, nu, bonded))


# --- shape functions for the fit: F = E * shape(delta), with d shape / d delta --------------------

def shape_and_slope(key: str, delta: np.ndarray, geometry: dict, nu: float) -> tuple[np.ndarray, np.ndarray]:
    """``(F/E, d(F/E)/d delta)`` of the elastic law ``key`` at ``delta`` [m] (0 where delta <= 0).

    ``geometry``: ``radius`` [m], ``half_angle`` [rad], ``thickness`` [m], ``bonded``.
    """
    d = _depth(delta)
    c = _check_nu(nu)
    if key in ("hertz_paraboloid", "hertz_thin_layer"):
        k = 4.0 / 3.0 * c * math.sqrt(geometry["radius"])
        sq = np.sqrt(d)
        f, fp = k * d * sq, 1.5 * k * sq
        if key == "hertz_thin_layer":
            c1, c2, c3, c4 = _dimitriadis_coefficients(nu, geometry.get("bonded", True))
            s = math.sqrt(geometry["radius"]) / geometry["thickness"]
            chi = s * sq
            g = 1 + chi * (c1 + chi * (c2 + chi * (c3 + chi * c4)))
            dg_dchi = c1 + chi * (2 * c2 + chi * (3 * c3 + chi * 4 * c4))
            # d chi / d delta = s / (2 sqrt(delta)); times f = k delta^1.5 -> k s delta / 2
            fp = fp * g + 0.5 * k * s * d * dg_dchi
            f = f * g
        return f, fp
    if key == "sneddon_sphere":
        r = float(geometry["radius"])
        y = _sphere_atanh(d, r)
        return 0.5 * c * r * r * _sphere_bracket(y), 2.0 * c * r * np.tanh(y)  # dF/d delta = 2 E* a
    pref = {"hertz_cone": 2.0 / math.pi, "bilodeau_pyramid3": BILODEAU_THREE_SIDED,
            "bilodeau_pyramid4": BILODEAU_FOUR_SIDED}.get(key)
    if pref is None:
        raise ParameterError(f"{key!r} is not an elastic law linear in E; choose from {', '.join(LINEAR_KEYS)}")
    k = pref * math.tan(geometry["half_angle"]) * c
    return k * d * d, 2 * k * d
