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

from .constants import ETA_AIR, HAMAKER, STANDARD_TEMPERATURE, Z0
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
        The paper's R [m]: R = 2 R_eff (R_eff the Derjaguin effective radius), the radius of
        each of two equal spheres; 2a for a sphere of radius a on a flat.
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
        The paper's R [m]: R = 2 R_eff (R_eff the Derjaguin effective radius); 2a for a sphere
        of radius a on a flat.
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
    """The paper's R (= 2 R_eff) from a measured jump-out (pull-off) distance [m].

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
    # In u = (z0/h)^3 = z0^3 x the cubic is u^3 - u + q = 0 with q = c z0^3: written so, no power of
    # z0 over- or underflows (1/z0^6 overflowed a float for z0 below ~1e-26 m: OverflowError). Three
    # real roots iff 4(-1)^3 + 27 q^2 < 0, i.e. q < 2/sqrt(27); the largest h is the smallest positive u.
    c = 6.0 * k / (hamaker * r)
    q = c * z0**3
    disc = 27.0 * q**2 - 4.0
    m = 2.0 / math.sqrt(3.0)                              # 2 sqrt(-P/3) with P = -1
    arg = np.clip(-1.5 * math.sqrt(3.0) * q, -1.0, 1.0)   # 3Q/(P m) with Q = q
    phi = np.arccos(arg) / 3.0
    roots = np.stack([m * np.cos(phi - 2.0 * math.pi * j / 3.0) for j in range(3)])
    # one negative root and two positive (sum 0, product -q < 0). The small positive one is a
    # difference of numbers of order 1 (its relative error 1e-16/q: 1e-12 at the paper's values,
    # all of it for a hard wall); from the product of the roots (Vieta) it is exact to rounding.
    with np.errstate(divide="ignore", invalid="ignore"):
        u = -q / (roots.max(axis=0) * roots.min(axis=0))
        h = np.where(disc < 0, z0 * u ** (-1.0 / 3.0), np.nan)
    return _out(h)


# --- liquids (issue 25): geometry, double layer, drainage with slip, lever drag ----------------
#: Vacuum permittivity [F/m] (CODATA 2018).
EPS0 = 8.8541878128e-12
#: Boltzmann constant [J/K], elementary charge [C], Avogadro constant [1/mol] (SI 2019, exact).
KB, E_CHARGE, N_A = 1.380649e-23, 1.602176634e-19, 6.02214076e23

#: Geometries of the two interacting surfaces -> the factor R_eff / R (Derjaguin).
#: ``sphere-sphere`` (the paper): two spheres of radius R, R_eff = R/2, so eq 2 reads
#: ``-A R / (12 h^2)`` and drainage ``-6 pi eta R^2 h' / (4 h)``; ``sphere-flat`` (a colloid
#: probe on a flat): R_eff = R, ``-A R / (6 h^2)`` and ``-6 pi eta R^2 h' / h``.
GEOMETRIES = {"sphere-sphere": 0.5, "sphere-flat": 1.0}
#: Double-layer laws (planar energy per area W(h), Derjaguin force ``2 pi R_eff W``).
DOUBLE_LAYERS = {
    "none": "no double-layer force",
    "weak_overlap": "linear superposition, low potentials: W = 2 eps eps0 kappa psi1 psi2 exp(-kappa h)",
    "constant_potential": "Hogg-Healy-Fuerstenau, constant surface potential",
    "constant_charge": "Hogg-Healy-Fuerstenau form at constant charge (linearised PB)",
}

#: The double-layer laws that exert a force (every one but ``none``): what a fit can choose.
DOUBLE_LAYER_LAWS = tuple(law for law in DOUBLE_LAYERS if law != "none")

__all__ += ["EPS0", "GEOMETRIES", "DOUBLE_LAYERS", "DOUBLE_LAYER_LAWS", "effective_radius", "paper_radius",
            "debye_length", "double_layer_energy", "double_layer_force",
            "double_layer_force_gradient", "slip_factor", "slip_factor_over_h",
            "slip_drainage_force", "lever_drag_force"]


def effective_radius(radius: ArrayLike, geometry: str = "sphere-sphere"):
    """Derjaguin effective radius R_eff [m]: R/2 for two spheres of radius R, R for sphere-flat."""
    try:
        g = GEOMETRIES[geometry]
    except KeyError:
        raise ParameterError(f"geometry must be one of {sorted(GEOMETRIES)}, got {geometry!r}") from None
    return _out(g * np.asarray(radius, dtype=float))


def paper_radius(radius: ArrayLike, geometry: str = "sphere-sphere"):
    """The radius to give the paper's sphere-sphere formulas (eq 2, drainage, statics) [m].

    Every law of the paper is written with R = 2 R_eff; a sphere of radius R on a flat
    (R_eff = R) is the paper's law with 2R.
    """
    return _out(2.0 * np.asarray(effective_radius(radius, geometry)))


def debye_length(ionic_strength: ArrayLike, permittivity: float = 78.5, temperature: float = STANDARD_TEMPERATURE):
    """Debye length ``1/kappa = sqrt(eps eps0 kB T / (2 NA e^2 I))`` [m].

    Parameters
    ----------
    ionic_strength : array_like
        I = 1/2 sum c_i z_i^2 [mol/L] (for a z:z salt at concentration c: z^2 c).
    permittivity : float
        Relative permittivity of the medium (water at 25 C: 78.5).
    temperature : float
        [K].

    Water at 25 C: 0.304 nm / sqrt(I [mol/L]) (9.6 nm at 1 mM NaCl).
    """
    i = np.asarray(ionic_strength, dtype=float) * 1e3   # mol/m^3
    if np.any(i <= 0):
        raise ParameterError("ionic_strength [mol/L] must be positive")
    return _out(np.sqrt(permittivity * EPS0 * KB * temperature / (2.0 * N_A * E_CHARGE**2 * i)))


def _dl_terms(h, kappa, law):
    """(csch-like, coth-1-like) terms of W and their h-derivatives' companions (stable forms)."""
    x = kappa * np.asarray(h, dtype=float)
    e1 = np.exp(-x)
    if law == "weak_overlap":
        return x, 2.0 * e1, np.zeros_like(e1), 2.0 * e1, np.zeros_like(e1)
    q = -np.expm1(-2.0 * x)                  # 1 - e^-2x
    csch = 2.0 * e1 / q
    cothm1 = 2.0 * e1 * e1 / q               # coth x - 1
    return x, csch, cothm1, csch * (cothm1 + 1.0), csch * csch


def _dl_params(surface_potential, surface_potential_2, debye_length, permittivity):
    """(psi1 [V], psi2 [V] (psi1 when not given), kappa [1/m], eps eps0 kappa / 2 [F/m^2])."""
    p1 = float(surface_potential)
    p2 = p1 if surface_potential_2 is None else float(surface_potential_2)
    kappa = 1.0 / debye_length
    return p1, p2, kappa, 0.5 * permittivity * EPS0 * kappa


def _dl_check(law: str) -> None:
    if law not in DOUBLE_LAYERS:
        raise ParameterError(f"double_layer must be one of {sorted(DOUBLE_LAYERS)}, got {law!r}")


def double_layer_energy(h: ArrayLike, surface_potential: float, debye_length: float,
                        surface_potential_2: float | None = None, permittivity: float = 78.5,
                        law: str = "constant_potential"):
    """Double-layer interaction energy per area of two planes W(h) [J/m^2] (linearised PB).

    ``c = eps eps0 kappa / 2``, ``S = psi1^2 + psi2^2``:

    * ``weak_overlap``: ``W = 2 eps eps0 kappa psi1 psi2 exp(-kappa h)``;
    * ``constant_potential`` (Hogg, Healy & Fuerstenau 1966): ``W = c [2 psi1 psi2 csch(kappa h)
      - S (coth(kappa h) - 1)]``;
    * ``constant_charge`` (psi at infinite separation): ``W = c [2 psi1 psi2 csch(kappa h)
      + S (coth(kappa h) - 1)]``.

    Both HHF forms tend to the weak-overlap one for kappa h >> 1.
    """
    _dl_check(law)
    if law == "none":
        return _out(np.zeros_like(np.asarray(h, dtype=float)))
    p1, p2, kappa, c = _dl_params(surface_potential, surface_potential_2, debye_length, permittivity)
    _, cs, cm, _, _ = _dl_terms(h, kappa, law)
    sign = -1.0 if law == "constant_potential" else 1.0
    return _out(c * (2.0 * p1 * p2 * cs + sign * (p1 * p1 + p2 * p2) * cm))


def double_layer_force(h: ArrayLike, radius: float, surface_potential: float, debye_length: float,
                       surface_potential_2: float | None = None, permittivity: float = 78.5,
                       law: str = "constant_potential", geometry: str = "sphere-sphere"):
    """Derjaguin double-layer force ``F = 2 pi R_eff W(h)`` [N] (positive: repulsive).

    ``radius`` is the probe radius R [m]; ``R_eff`` follows ``geometry``
    (:func:`effective_radius`). W: :func:`double_layer_energy`.
    """
    w = double_layer_energy(h, surface_potential, debye_length, surface_potential_2, permittivity, law)
    return _out(2.0 * math.pi * effective_radius(radius, geometry) * np.asarray(w))


def double_layer_force_gradient(h: ArrayLike, radius: float, surface_potential: float,
                                debye_length: float, surface_potential_2: float | None = None,
                                permittivity: float = 78.5, law: str = "constant_potential",
                                geometry: str = "sphere-sphere"):
    """dF/dh of :func:`double_layer_force` [N/m] (closed form).

    ``dW/dh = c kappa [-2 psi1 psi2 csch coth -/+ S csch^2]`` (HHF; - for constant
    potential's ``-S(coth - 1)`` term differentiated: ``+S csch^2``), ``-kappa W`` (weak overlap).
    """
    _dl_check(law)
    if law == "none":
        return _out(np.zeros_like(np.asarray(h, dtype=float)))
    p1, p2, kappa, c = _dl_params(surface_potential, surface_potential_2, debye_length, permittivity)
    _, cs, _, cscoth, cs2 = _dl_terms(h, kappa, law)
    sign = 1.0 if law == "constant_potential" else -1.0
    dw = c * kappa * (-2.0 * p1 * p2 * cscoth + sign * (p1 * p1 + p2 * p2) * cs2)
    return _out(2.0 * math.pi * effective_radius(radius, geometry) * dw)


def slip_factor(h: ArrayLike, slip_length: float):
    """Vinogradova's slip correction f*(h) of the drainage force (Langmuir 11, 2213 (1995)).

    ``f* = (h / 3b) [(1 + h / 6b) ln(1 + 6b / h) - 1]`` for equal slip length b on both
    surfaces; f* -> 1 as b -> 0 (series ``1 - u/3 + u^2/6 - ...``, u = 6b/h, below u = 1e-3)
    and ``f* ~ (h/3b) ln(6b/h)`` for h << b. Dimensionless.
    """
    return _out(np.asarray(slip_factor_over_h(h, slip_length)) * np.asarray(h, dtype=float))


def slip_factor_over_h(h: ArrayLike, slip_length: float):
    """``f*(h) / h`` [1/m] (what the drainage force multiplies; finite as h -> 0 for b > 0)."""
    h = np.asarray(h, dtype=float)
    b = float(slip_length)
    if b < 0:
        raise ParameterError("slip_length [m] must be non-negative")
    if b == 0.0:
        return _out(1.0 / h)
    u = 6.0 * b / h
    small = u < 1e-3
    us = np.where(small, u, 0.0)
    series = (1.0 - us / 3.0 + us * us / 6.0 - us**3 / 10.0) / h
    ul = np.where(small, 1.0, u)
    exact = ((1.0 + 1.0 / ul) * np.log1p(ul) - 1.0) / (3.0 * b)
    return _out(np.where(small, series, exact))


def slip_drainage_force(h: ArrayLike, h_dot: ArrayLike, radius: float, viscosity: float,
                        slip_length: float = 0.0, geometry: str = "sphere-sphere"):
    """Reynolds-Taylor drainage with slip ``-6 pi eta R_eff^2 h' f*(h) / h`` [N].

    ``sphere-sphere`` with b = 0 is the paper's :func:`drainage_force`; ``sphere-flat`` is
    the colloid probe on a flat (Vinogradova 1995).
    """
    r = float(effective_radius(radius, geometry))
    h_dot = np.asarray(h_dot, dtype=float)
    return _out(-6.0 * math.pi * viscosity * r * r * h_dot * np.asarray(slip_factor_over_h(h, slip_length)))


def lever_drag_force(h: ArrayLike, h_dot: ArrayLike, lever_drag: float, lever_height: float = 0.0):
    """Viscous drag on the lever body ``-c g(h) h'`` [N] (Vinogradova et al. 2001, 2003).

    ``c`` = ``lever_drag`` [N s/m] acts on the relative velocity of lever and substrate
    (h' [m/s]). ``lever_height`` H [m] (the lever's height above the substrate at contact)
    gives the distance dependence of a plate near a wall, ``g = H / (h + H)`` (c is then the
    drag at contact); H = 0: constant drag, ``g = 1`` (the far-field "virtual deflection").
    """
    h = np.asarray(h, dtype=float)
    g = np.ones_like(h) if lever_height <= 0 else lever_height / (h + lever_height)
    return _out(-lever_drag * g * np.asarray(h_dot, dtype=float))
