"""Hydration (exponential) repulsion: ``P(h) = P0 exp(-h/lambda)`` between planes.

Israelachvili, *Intermolecular and Surface Forces*, 3rd ed. (Academic Press, 2011), section
15.6 (hydration forces, ``P = P0 exp(-D/lambda0)``, lambda0 ~ 0.2-1.1 nm); LeNeveu, Rand &
Parsegian, Nature 259, 601 (1976). Energy per area ``W = P0 lambda exp(-h/lambda)``; the
Derjaguin force on the geometry's effective radius::

    F(h) = 2 pi R_eff P0 lambda exp(-h/lambda),   dF/dh = -F / lambda
"""

from __future__ import annotations

import math

import numpy as np

from ._record import LawParameter, SurfaceLaw


def hydration_force(h, radius_eff: float, hydration_pressure: float, hydration_length: float):
    """Hydration force ``2 pi R_eff P0 lambda exp(-h/lambda)`` [N] (repulsive, positive).

    Parameters
    ----------
    h : array_like
        Separation [m].
    radius_eff : float
        Derjaguin radius R_eff [m] (R for a sphere on a flat, R/2 for two spheres of radius R).
    hydration_pressure : float
        P0 [Pa], the pressure between planes in contact.
    hydration_length : float
        Decay length lambda [m].
    """
    h = np.asarray(h, dtype=float)
    return 2.0 * math.pi * radius_eff * hydration_pressure * hydration_length * np.exp(
        -h / hydration_length)


def _force(h, r_eff, v):
    f = hydration_force(h, r_eff, v["hydration_pressure"], v["hydration_length"])
    return f, -f / v["hydration_length"]


def _pack(r_eff, v):
    lam = v["hydration_length"]
    return (2.0 * math.pi * r_eff * v["hydration_pressure"] * lam, 1.0 / lam)


def _kernel(h, p, o):
    f = p[o] * math.exp(-h * p[o + 1])
    return f, -p[o + 1] * f


LAW = SurfaceLaw(
    name="hydration",
    title="hydration / exponential repulsion, P = P0 exp(-h/lambda) (Derjaguin)",
    parameters=(LawParameter("hydration_pressure", 0.0, fit=(1e8, 0.02, 1e4)),
                LawParameter("hydration_length", 0.3e-9, fit=(3e-10, 0.01, 1e-13))),
    force=_force,
    active=lambda v: v["hydration_pressure"] > 0.0,
    pack=_pack,
    kernel=_kernel,
    n_slots=2,
    reach=lambda v: 40.0 * v["hydration_length"],
    reference="Israelachvili, Intermolecular and Surface Forces, 3rd ed. (2011), section 15.6; "
              "LeNeveu, Rand & Parsegian, Nature 259, 601 (1976)",
    validity="h > ~1 nm between smooth hydrophilic surfaces (oscillatory at molecular separations); "
             "Derjaguin: R_eff >> lambda",
    example={"hydration_pressure": 3e7, "hydration_length": 0.5e-9},
)
