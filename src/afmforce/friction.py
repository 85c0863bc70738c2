"""Friction laws for the lateral force on the tip (paper section 2.2-2.3).

Sign convention: ``Fy`` is the lateral force on the tip [N]. The quasi-static
laws of section 2.2 are written for steady sliding in constant compliance,
with ``direction = +1`` on the inward run (loading) and ``-1`` on the outward
run; the dynamic laws of section 2.3 act against the lateral velocity.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "constant_friction",
    "load_friction",
    "viscous_friction",
    "load_dependent_viscous_friction",
    "steady_sliding_friction",
]


def _out(x: np.ndarray):
    return x[()] if np.ndim(x) == 0 else x


def constant_friction(mu: float, direction: ArrayLike):
    """Constant friction ``Fy = +-mu`` (section 2.2.1; + inward, - outward) [N]."""
    return _out(mu * np.sign(np.asarray(direction, dtype=float)))


def load_friction(normal_force: ArrayLike, lam: float, direction: ArrayLike):
    """Friction proportional to load ``Fy = +-lambda Fz`` (section 2.2.2) [N]."""
    return _out(lam * np.sign(np.asarray(direction, float)) * np.asarray(normal_force, float))


def viscous_friction(lateral_velocity: ArrayLike, xi: float):
    """Viscous friction ``Fy = -xi dy2/dt`` (eq 28) [N].

    Parameters
    ----------
    lateral_velocity : array_like
        dy2/dt [m/s].
    xi : float
        Friction coefficient [kg/s].
    """
    return _out(-xi * np.asarray(lateral_velocity, dtype=float))


def load_dependent_viscous_friction(lateral_velocity: ArrayLike, normal_force: ArrayLike,
                                    xi: float, zeta: float):
    """Load-dependent viscous friction ``Fy = -(xi + zeta Fz^2) dy2/dt`` (after eq 28) [N].

    ``zeta`` is in [kg s^-1 N^-2].
    """
    fz = np.asarray(normal_force, dtype=float)
    return _out(-(xi + zeta * fz * fz) * np.asarray(lateral_velocity, dtype=float))


def steady_sliding_friction(xi: float, slide_ratio: float, velocity: ArrayLike):
    """Magnitude of viscous friction in steady sliding, ``xi |dy2/dz2| |dz/dt|`` [N].

    In constant compliance the tip follows the substrate (dz2/dt = dz/dt) and
    slides laterally at ``dy2/dt = (dy2/dz2) dz/dt``.
    """
    return _out(xi * abs(slide_ratio) * np.abs(np.asarray(velocity, dtype=float)))
