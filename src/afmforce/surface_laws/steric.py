"""Steric repulsion of polymer brushes (Alexander-de Gennes), exponential approximation.

Alexander, J. Phys. (Paris) 38, 983 (1977); de Gennes, Adv. Colloid Interface Sci. 27, 189
(1987): pressure between brushes of thickness L0 and anchor spacing s,
``P = kT/s^3 [(2 L0/D)^(9/4) - (D/2 L0)^(3/4)]``. For a sphere of radius R on a brush-bearing
flat, Butt, Kappl, Mueller & Raiteri, Langmuir 15, 2559 (1999) (also the review of Butt, Cappella &
Kappl, Surf. Sci. Rep. 59, 1 (2005), section on steric forces) approximate the Derjaguin-integrated pressure by::

    F(h) = 50 kT R_eff L0 Gamma^(3/2) exp(-2 pi h / L0),   Gamma = 1/s^2,

valid for 0.2 < h/L0 < 0.9; ``dF/dh = -(2 pi / L0) F``. R_eff is the geometry's Derjaguin
radius (the sphere's R on a flat).
"""

from __future__ import annotations

import math

import numpy as np

from ..forces import KB
from ..constants import DEFAULT_TEMPERATURE  # the one room temperature (295 K)
from ._record import LawParameter, SurfaceLaw


def brush_force(h, radius_eff: float, brush_length: float, brush_spacing: float,
                temperature: float = DEFAULT_TEMPERATURE):
    """Alexander-de Gennes brush force ``50 kT R L0 s^-3 exp(-2 pi h/L0)`` [N] (repulsive).

    Parameters
    ----------
    h : array_like
        Separation [m].
    radius_eff : float
        Derjaguin radius R_eff [m] (the sphere's radius on a flat).
    brush_length : float
        Brush thickness L0 [m].
    brush_spacing : float
        Mean distance s between grafting points [m] (grafting density Gamma = 1/s^2).
    temperature : float
        T [K].
    """
    h = np.asarray(h, dtype=float)
    gamma32 = brush_spacing ** -3.0
    return 50.0 * KB * temperature * radius_eff * brush_length * gamma32 * np.exp(
        -2.0 * math.pi * h / brush_length)


def _force(h, r_eff, v):
    f = brush_force(h, r_eff, v["brush_length"], v["brush_spacing"], v["temperature"])
    return f, -(2.0 * math.pi / v["brush_length"]) * f


def _pack(r_eff, v):
    L0 = v["brush_length"]
    return (50.0 * KB * v["temperature"] * r_eff * L0 * v["brush_spacing"] ** -3.0,
            2.0 * math.pi / L0)


def _kernel(h, p, o):
    f = p[o] * math.exp(-h * p[o + 1])
    return f, -p[o + 1] * f


LAW = SurfaceLaw(
    name="steric",
    title="polymer brushes, Alexander-de Gennes (exponential form of Butt et al. 1999)",
    parameters=(LawParameter("brush_length", 0.0, fit=(1e-8, 0.01, 1e-11)),
                LawParameter("brush_spacing", 5e-9, fit=(5e-9, 0.01, 1e-12)),
                LawParameter("temperature", DEFAULT_TEMPERATURE)),
    force=_force,
    active=lambda v: v["brush_length"] > 0.0,
    pack=_pack,
    kernel=_kernel,
    n_slots=2,
    reach=lambda v: 6.0 * v["brush_length"],
    reference="Alexander, J. Phys. (Paris) 38, 983 (1977); de Gennes, Adv. Colloid Interface "
              "Sci. 27, 189 (1987); Butt, Kappl, Mueller & Raiteri, Langmuir 15, 2559 (1999)",
    validity="0.2 < h/L0 < 0.9 (the exponential fit of the Derjaguin-integrated AdG pressure); "
             "s < L0 (a brush, not mushrooms); R_eff >> L0",
    example={"brush_length": 10e-9, "brush_spacing": 3e-9},
)
