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


def sphere_contact_radius(delta: ArrayLike, radius: float) -> np.ndarray:
    """Contact radius a [m] of a rigid sphere (radius R [m]) at indentation ``delta`` [m] (Sneddon 1965):
    the root of ``delta = a/2 ln((R+a)/(R-a))``, by Newton's method from the Hertz value (converges
    from above: the function is increasing and convex in a)."""
    d = _depth(delta)
    r = float(radius)
    a = np.minimum(np.sqrt(r * d), r * (1 - 1e-12))
    for _ in range(60):
        lg = np.log((r + a) / (r - a))
        f = 0.5 * a * lg - d
        fp = 0.5 * lg + a * r / (r * r - a * a)
        step = np.where(a > 0, f / np.where(fp > 0, fp, 1.0), 0.0)
        a = np.clip(a - step, 0.0, r * (1 - 1e-15))
        if np.all(np.abs(step) <= 1e-13 * r):
            break
    return a


def sneddon_sphere(delta: ArrayLike, E: float, radius: float, nu: float = 0.5):
    """Rigid sphere of radius R, exact (Sneddon 1965, eqs 6.13 and 6.15).

    ``F = E/(2(1-nu^2)) [(a^2 + R^2) ln((R+a)/(R-a)) - 2 a R]`` with the contact
    radius ``a`` from ``delta = a/2 ln((R+a)/(R-a))`` (:func:`sphere_contact_radius`).
    Tends to :func:`hertz_paraboloid` for ``delta << R`` (nanite's ``sneddon_spher_approx`` is
    its power series).

    Returns
    -------
    numeric  force [N]
    """
    a = sphere_contact_radius(delta, radius)
    r = float(radius)
    lg = np.log((r + a) / (r - a))
    return _out(0.5 * E * _check_nu(nu) * ((a * a + r * r) * lg - 2 * a * r))


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
        r = geometry["radius"]
        a = sphere_contact_radius(d, r)
        lg = np.log((r + a) / (r - a))
        return 0.5 * c * ((a * a + r * r) * lg - 2 * a * r), 2.0 * c * a  # dF/d delta = 2 E* a
    pref = {"hertz_cone": 2.0 / math.pi, "bilodeau_pyramid3": BILODEAU_THREE_SIDED,
            "bilodeau_pyramid4": BILODEAU_FOUR_SIDED}.get(key)
    if pref is None:
        raise ParameterError(f"{key!r} is not an elastic law linear in E; choose from {', '.join(LINEAR_KEYS)}")
    k = pref * math.tan(geometry["half_angle"]) * c
    return k * d * d, 2 * k * d
