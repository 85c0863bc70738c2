"""Is a measurement dynamic? Inertia diagnostics of section 2.1 (eqs 3, 4).

Small pure functions plus :func:`diagnose`, which bundles them for one probe
and one driving speed into a :class:`Diagnosis` with units on every field.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import ArrayLike

from ._fields import check
from ._validate import positive
from .constants import HAMAKER, Z0
from .forces import (
    max_attraction_force,
    pull_off_force_dmt,
    pull_off_force_jkr,
    static_jump_in_separation,
    surface_energy,
    vdw_force_gradient,
)

__all__ = ["resonance_frequency", "inertia_parameter", "inertial_lag", "Diagnosis", "diagnose"]


def _out(x):
    x = np.asarray(x, dtype=float)
    return x[()] if x.ndim == 0 else x


def resonance_frequency(spring_constant: ArrayLike, mass: ArrayLike):
    """``f = sqrt(k/m) / (2 pi)`` [Hz] (section 2.1)."""
    return _out(np.sqrt(np.asarray(spring_constant, float) / np.asarray(mass, float)) / (2 * math.pi))


def inertia_parameter(velocity: ArrayLike, force_gradient: ArrayLike, resonance_frequency: ArrayLike,
                      spring_constant: ArrayLike, resolution: ArrayLike):
    """Inertia parameter ``R = |v| |Fs'| / (4 f k dx)`` [-] (eq 3).

    Inertia is measurable when R > 1.

    Parameters
    ----------
    velocity : array_like
        Driving speed dz/dt [m/s].
    force_gradient : array_like
        Surface-force gradient Fs'(h) where inertia matters [N/m].
    resonance_frequency : array_like
        f [Hz].
    spring_constant : array_like
        k [N/m].
    resolution : array_like
        Deflection resolution dx [m].
    """
    v = np.abs(np.asarray(velocity, float))
    g = np.abs(np.asarray(force_gradient, float))
    return _out(v * g / (4.0 * np.asarray(resonance_frequency, float)
                         * np.asarray(spring_constant, float) * np.asarray(resolution, float)))


def inertial_lag(velocity: ArrayLike, resonance_frequency: ArrayLike):
    """Inertial lag at jump-in ``dx = |v| / (4 f)`` [m] (eq 4).

    An order-of-magnitude estimate: simulated lags are 1.5-3.6 times smaller
    (spec section 7).
    """
    return _out(np.abs(np.asarray(velocity, float)) / (4.0 * np.asarray(resonance_frequency, float)))


@dataclass(frozen=True)
class Diagnosis:
    """Dynamic diagnosis of a probe at one driving speed (all SI).

    Attributes
    ----------
    resonance_frequency : float  [Hz]
    force_gradient : float  |Fs'(h)| at ``separation`` [N/m]
    inertia_parameter : float  eq 3 [-]
    inertial_lag : float  eq 4 [m]
    static_jump_in_separation : float  largest h with Fs'(h) = k [m]
    surface_energy : float  A/(16 pi z0^2) [J/m^2]
    pull_off_force_jkr : float  -3 pi gamma R / 4 [N]
    pull_off_force_dmt : float  -pi gamma R [N]
    max_attraction_force : float  Fs(z0) = -A R /(16 z0^2) [N]
    inertia_measurable : bool  R > 1
    verdict : str  plain words
    """

    resonance_frequency: float
    force_gradient: float
    inertia_parameter: float
    inertial_lag: float
    static_jump_in_separation: float
    surface_energy: float
    pull_off_force_jkr: float
    pull_off_force_dmt: float
    max_attraction_force: float
    inertia_measurable: bool
    verdict: str

    UNITS = {
        "resonance_frequency": "Hz", "force_gradient": "N/m", "inertia_parameter": "",
        "inertial_lag": "m", "static_jump_in_separation": "m", "surface_energy": "J/m^2",
        "pull_off_force_jkr": "N", "pull_off_force_dmt": "N", "max_attraction_force": "N",
    }

    def to_dict(self) -> dict:
        """JSON-ready dict with SI values."""
        d = asdict(self)
        d["units"] = dict(self.UNITS)
        return d


def diagnose(*, spring_constant: float, mass: float, radius: float, velocity: float,
             resolution: float = 0.5e-9, separation: float = 5e-9, hamaker: float = HAMAKER,
             z0: float = Z0) -> Diagnosis:
    """Inertia diagnosis of section 2.1 for one probe and speed.

    Parameters
    ----------
    spring_constant : float
        k [N/m].
    mass : float
        Effective mass [kg].
    radius : float
        The paper's R = 2 R_eff [m] (eq 2; :func:`afmforce.forces.vdw_force`).
    velocity : float
        Driving speed [m/s].
    resolution : float
        Deflection resolution dx [m] (default 0.5 nm, as in the paper).
    separation : float
        Separation where the force gradient is evaluated [m] (default 5 nm, as in the paper).
    hamaker, z0 : float
        Surface-force parameters [J], [m].
    """
    for name, value in (("spring_constant", spring_constant), ("mass", mass), ("radius", radius),
                        ("velocity", abs(velocity)), ("resolution", resolution), ("separation", separation),
                        ("hamaker", hamaker), ("z0", z0)):
        check(name, value)          # the declared valid range (afmforce._fields.QUANTITIES)
    k = positive("spring_constant", spring_constant, "N/m")
    m = positive("mass", mass, "kg")
    R = positive("radius", radius, "m")
    v = positive("velocity", abs(velocity), "m/s")
    dx = positive("resolution", resolution, "m")
    h = positive("separation", separation, "m")
    positive("hamaker", hamaker, "J")
    positive("z0", z0, "m")
    f = float(resonance_frequency(k, m))
    grad = abs(float(vdw_force_gradient(h, R, hamaker, z0)))
    ip = float(inertia_parameter(v, grad, f, k, dx))
    lag = float(inertial_lag(v, f))
    gamma = float(surface_energy(hamaker, z0))
    if ip > 1:
        verdict = (f"inertia is measurable (R = {ip:.2g} > 1): the deflection lags the static curve by "
                   f"about {lag * 1e9:.2g} nm near jump-in; slow down or use a stiffer/lighter probe")
    else:
        verdict = (f"inertia is below the resolution (R = {ip:.2g} < 1): a static analysis is adequate "
                   "at this speed")
    return Diagnosis(
        resonance_frequency=f,
        force_gradient=grad,
        inertia_parameter=ip,
        inertial_lag=lag,
        static_jump_in_separation=float(static_jump_in_separation(k, R, hamaker, z0)),
        surface_energy=gamma,
        pull_off_force_jkr=float(pull_off_force_jkr(gamma, R)),
        pull_off_force_dmt=float(pull_off_force_dmt(gamma, R)),
        max_attraction_force=float(max_attraction_force(R, hamaker, z0)),
        inertia_measurable=ip > 1,
        verdict=verdict,
    )
