"""Capillary meniscus of water in humid air (Laplace pressure, Kelvin radius).

A water meniscus in equilibrium with vapour at relative humidity RH has the Kelvin radius
``r_K = gamma V_m / (R_g T |ln RH|)`` (0.54 nm / |ln RH| for water at room temperature).
Between a sphere (contact angle theta1) and a flat (theta2) the meniscus spans the gap where it
is ``r_K (cos theta1 + cos theta2)`` wide; the Laplace pressure ``gamma / r_K`` on the wetted
area ``pi x^2 = 2 pi R_eff (d_c - h)`` gives (r_K << R_eff; Butt & Kappl, Adv. Colloid
Interface Sci. 146, 48 (2009), "Normal capillary forces", sphere and plane; Israelachvili,
*Intermolecular and Surface Forces*, 3rd ed. (2011), section 17.8)::

    F(h) = -2 pi R_eff gamma (cos theta1 + cos theta2) (1 - h / d_c)   for h < d_c,
    d_c  = r_K (cos theta1 + cos theta2),                              F = 0 beyond,

``-4 pi R gamma cos theta`` at contact for equal angles on a flat. The meniscus is taken in
equilibrium at every separation (no hysteresis: it forms and ruptures at d_c). Water's molar
volume is fixed (18.07 cm^3/mol at 25 C); ``surface_tension`` and ``temperature`` are
parameters.
"""

from __future__ import annotations

import math

import numpy as np

from ..constants import DEFAULT_TEMPERATURE  # the one room temperature (295 K)
from ._record import LawParameter, SurfaceLaw

#: Molar volume of liquid water at 25 C [m^3/mol]; the molar gas constant [J/(mol K)] (exact).
V_WATER, R_GAS = 18.07e-6, 8.314462618


def kelvin_radius(relative_humidity, surface_tension: float = 0.072, temperature: float = DEFAULT_TEMPERATURE):
    """Kelvin radius ``r_K = gamma V_m / (R_g T |ln RH|)`` of a water meniscus [m]."""
    rh = np.asarray(relative_humidity, dtype=float)
    return surface_tension * V_WATER / (R_GAS * temperature * np.abs(np.log(rh)))


def capillary_force(h, radius_eff: float, relative_humidity: float, surface_tension: float = 0.072,
                    contact_angle: float = 0.0, contact_angle_2: float = 0.0,
                    temperature: float = DEFAULT_TEMPERATURE):
    """Capillary force of an equilibrium water meniscus, sphere-flat (Derjaguin radius) [N].

    Negative (attractive) below ``d_c = r_K (cos theta1 + cos theta2)``, zero beyond.

    Parameters
    ----------
    h : array_like
        Separation [m].
    radius_eff : float
        R_eff [m] (the sphere's radius on a flat).
    relative_humidity : float
        RH in (0, 1).
    surface_tension : float
        gamma [N/m] (water 0.072).
    contact_angle, contact_angle_2 : float
        theta1 (sphere), theta2 (flat) [rad].
    temperature : float
        T [K].
    """
    h = np.asarray(h, dtype=float)
    c = math.cos(contact_angle) + math.cos(contact_angle_2)
    dc = float(kelvin_radius(relative_humidity, surface_tension, temperature)) * c
    f0 = 2.0 * math.pi * radius_eff * surface_tension * c
    return np.where(h < dc, -f0 * (1.0 - h / dc), 0.0)


def _values(v):
    c = math.cos(v["contact_angle"]) + math.cos(v["contact_angle_2"])
    dc = float(kelvin_radius(v["relative_humidity"], v["surface_tension"], v["temperature"])) * c
    return c, dc


def _force(h, r_eff, v):
    f = capillary_force(h, r_eff, v["relative_humidity"], v["surface_tension"], v["contact_angle"],
                        v["contact_angle_2"], v["temperature"])
    c, dc = _values(v)
    slope = 2.0 * math.pi * r_eff * v["surface_tension"] * c / dc
    return f, np.where(np.asarray(h) < dc, slope, 0.0)


def _pack(r_eff, v):
    c, dc = _values(v)
    return (2.0 * math.pi * r_eff * v["surface_tension"] * c, dc)


def _kernel(h, p, o):
    dc = p[o + 1]
    if h < dc:
        return -p[o] * (1.0 - h / dc), p[o] / dc
    return 0.0, 0.0


def _active(v):
    rh = v["relative_humidity"]
    return 0.0 < rh < 1.0 and math.cos(v["contact_angle"]) + math.cos(v["contact_angle_2"]) > 0.0


LAW = SurfaceLaw(
    name="capillary",
    title="water meniscus in humid air: Laplace pressure at the Kelvin radius (sphere-flat)",
    parameters=(LawParameter("relative_humidity", 0.0, fit=(0.3, 0.01, 1e-4)),
                LawParameter("surface_tension", 0.072),
                LawParameter("contact_angle", 0.0, fit=(0.5, 0.01, 1e-4)),
                LawParameter("contact_angle_2", 0.0),
                LawParameter("temperature", DEFAULT_TEMPERATURE)),
    force=_force,
    active=_active,
    pack=_pack,
    kernel=_kernel,
    n_slots=2,
    reach=lambda v: 2.0 * _values(v)[1] if _active(v) else 0.0,
    reference="Butt & Kappl, Adv. Colloid Interface Sci. 146, 48 (2009); Israelachvili, "
              "Intermolecular and Surface Forces, 3rd ed. (2011), section 17.8",
    validity="r_K << R_eff (a thin meniscus); the meniscus in equilibrium with the vapour at every "
             "separation (no volume conservation, no hysteresis); cos theta1 + cos theta2 > 0",
    example={"relative_humidity": 0.4, "contact_angle": 0.35, "contact_angle_2": 0.2},
)
