"""Surface-force laws (paper section 2.1, spec section 2).

Pure, vectorised functions of SI floats or arrays. Scalars in give numpy
float64 scalars out; arrays in give arrays of the broadcast shape out.

Sign convention: a negative force is attractive (it pulls the probe towards
the substrate); ``h`` is the separation between the surfaces [m].
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from .constants import ETA_AIR, HAMAKER, Z0
from .errors import ParameterError

__all__ = [
    "vdw_force",
    "vdw_force_gradient",
    "drainage_force",
    "zero_force_separation",
    "max_attraction_separation",
    "max_attraction_force",
    "surface_energy",
    "pull_off_force_jkr",
    "pull_off_force_dmt",
    "radius_from_jump_out",
    "energy_per_area",
    "static_jump_in_separation",
]


def _out(x: np.ndarray):
    """Return a numpy scalar for 0-d results, the array otherwise."""
    return x[()] if np.ndim(x) == 0 else x


def vdw_force(h: ArrayLike, radius: float, hamaker: float = HAMAKER, z0: float = Z0):
    """van der Waals force with soft-wall repulsion, sphere geometry (eq 2).

    ``Fs(h) = -(A R / (12 h^2)) (1 - z0^6 / (4 h^6))``

    Parameters
    ----------
    h : array_like
        Separation [m], > 0.
    radius : float
        Effective radius of curvature R [m].
    hamaker : float
        Hamaker constant A [J].
    z0 : float
        Soft-wall length [m]; the force is most attractive at ``h = z0``.

    Returns
    -------
    numeric
        Force [N]; negative is attractive.
    """
    h = np.asarray(h, dtype=float)
    r6 = (z0 / h) ** 6
    return _out(-(hamaker * radius / (12.0 * h * h)) * (1.0 - 0.25 * r6))


def vdw_force_gradient(h: ArrayLike, radius: float, hamaker: float = HAMAKER, z0: float = Z0):
    """Derivative of :func:`vdw_force` with respect to separation (eq 2).

    ``Fs'(h) = (A R / 6) (h^-3 - z0^6 h^-9)``  [N/m]
    """
    h = np.asarray(h, dtype=float)
    return _out((hamaker * radius / 6.0) * (h**-3 - z0**6 * h**-9))


def drainage_force(h: ArrayLike, h_dot: ArrayLike, radius: float, viscosity: float = ETA_AIR):
    """Hydrodynamic drainage force between sphere and plane (after eq 1).

    ``Fd(h, dh/dt) = -6 pi eta R^2 (dh/dt) / (4 h)``

    Parameters
    ----------
    h : array_like
        Separation [m].
    h_dot : array_like
        Rate of change of separation [m/s]; negative on approach.
    radius : float
        Effective radius R [m].
    viscosity : float
        Fluid viscosity eta [Pa s] (air: 1.8e-5).

    Returns
    -------
    numeric
        Force [N]; it opposes the relative motion (repulsive on approach).
    """
    h = np.asarray(h, dtype=float)
    h_dot = np.asarray(h_dot, dtype=float)
    return _out(-6.0 * math.pi * viscosity * radius**2 * h_dot / (4.0 * h))


def zero_force_separation(z0: float = Z0) -> float:
    """Separation of zero force, ``h0 = z0 / 2^(1/3)`` [m] (below eq 2)."""
    return z0 / 2.0 ** (1.0 / 3.0)


def max_attraction_separation(z0: float = Z0) -> float:
    """Separation of strongest attraction, ``h = z0`` [m]."""
    return float(z0)


def max_attraction_force(radius: ArrayLike, hamaker: float = HAMAKER, z0: float = Z0):
    """Strongest attraction ``Fs(z0) = -A R / (16 z0^2)`` [N]."""
    return _out(-hamaker * np.asarray(radius, dtype=float) / (16.0 * z0**2))


def surface_energy(hamaker: ArrayLike = HAMAKER, z0: float = Z0):
    """Surface energy ``gamma = A / (16 pi z0^2)`` [J/m^2] (section 2.1)."""
    return _out(np.asarray(hamaker, dtype=float) / (16.0 * math.pi * z0**2))


def pull_off_force_jkr(surface_energy: ArrayLike, radius: ArrayLike):
    """JKR pull-off force in the paper's convention, ``-3 pi gamma R / 4`` [N].

    The paper (section 2.1, ref 26) defines gamma through ``A/(16 pi z0^2)``,
    for which the rigid (DMT-like) maximum attraction is ``-pi gamma R``;
    JKR is 3/4 of that.
    """
    g = np.asarray(surface_energy, dtype=float)
    return _out(-0.75 * math.pi * g * np.asarray(radius, dtype=float))


def pull_off_force_dmt(surface_energy: ArrayLike, radius: ArrayLike):
    """DMT (rigid) pull-off force in the paper's convention, ``-pi gamma R`` [N].

    Equal to the maximum attraction of eq 2, ``-A R / (16 z0^2)``.
    """
    g = np.asarray(surface_energy, dtype=float)
    return _out(-math.pi * g * np.asarray(radius, dtype=float))


def radius_from_jump_out(spring_constant: ArrayLike, jump_out: ArrayLike, surface_energy: float):
    """Effective radius from a measured jump-out (pull-off) distance [m].

    JKR: ``k d_out = 3 pi gamma R / 4``, so ``R = 4 k d_out / (3 pi gamma)``
    (section 2.1: 200 nm with k = 0.21 N/m gives R = 220 nm).

    Parameters
    ----------
    spring_constant : array_like
        Force-measuring spring constant k [N/m].
    jump_out : array_like
        Deflection at pull-off, as a positive distance [m].
    surface_energy : float
        gamma [J/m^2].
    """
    k = np.asarray(spring_constant, dtype=float)
    d = np.abs(np.asarray(jump_out, dtype=float))
    return _out(4.0 * k * d / (3.0 * math.pi * surface_energy))


def energy_per_area(force: ArrayLike, radius: float):
    """Force to interaction energy per unit area of planes, ``F / (pi R)`` [J/m^2].

    The paper's Derjaguin convention (Fig 9), consistent with ``Fs(z0) = -pi gamma R``.
    """
    return _out(np.asarray(force, dtype=float) / (math.pi * radius))


def static_jump_in_separation(
    spring_constant: ArrayLike, radius: ArrayLike, hamaker: float = HAMAKER, z0: float = Z0
):
    """Static jump-in separation: the largest h with ``Fs'(h) = k`` [m].

    With ``x = h^-3`` the condition is the cubic ``z0^6 x^3 - x + 6k/(AR) = 0``;
    its smallest positive root gives the largest h. If the spring is stiffer than
    the steepest attractive gradient, ``max Fs' = (AR/6) (2/3) 3^(-1/2) z0^-3``,
    there is no mechanical instability and the result is NaN.

    Parameters
    ----------
    spring_constant : array_like
        k [N/m], > 0.
    radius : array_like
        R [m], > 0.
    """
    k, r = np.broadcast_arrays(np.asarray(spring_constant, float), np.asarray(radius, float))
    if np.any(k <= 0) or np.any(r <= 0):
        raise ParameterError("spring_constant [N/m] and radius [m] must be positive")
    c = 6.0 * k / (hamaker * r)  # cubic: z0^6 x^3 - x + c = 0
    p = z0**6
    # Depressed cubic x^3 + P x + Q = 0 with P = -1/p, Q = c/p. Three real roots
    # iff 4P^3 + 27Q^2 < 0; the smallest positive is the trigonometric root k=1.
    P = -1.0 / p
    Q = c / p
    disc = 4.0 * P**3 + 27.0 * Q**2
    m = 2.0 * np.sqrt(-P / 3.0)
    arg = np.clip(3.0 * Q / (P * m), -1.0, 1.0)
    phi = np.arccos(arg) / 3.0
    # roots: m cos(phi - 2 pi j / 3); the smallest positive one is j = 2... pick min positive
    roots = np.stack([m * np.cos(phi - 2.0 * math.pi * j / 3.0) for j in range(3)])
    roots = np.where(roots > 0, roots, np.inf)
    x = roots.min(axis=0)
    h = np.where(disc < 0, x ** (-1.0 / 3.0), np.nan)
    return _out(h)
