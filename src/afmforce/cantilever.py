"""Cantilever models: the simple spring and the inclined cantilever (Fig 2).

Spec sections 3-4; paper sections 2.1-2.2. Configurations are frozen
dataclasses validated on construction; derived quantities are properties.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._fields import qfield
from ._validate import finite, positive
from .errors import ParameterError

__all__ = ["SimpleSpring", "InclinedCantilever"]


@dataclass(frozen=True)
class SimpleSpring:
    """A mass on a spring (eq 1): the probe moves only vertically.

    Parameters
    ----------
    spring_constant : float
        k [N/m].
    mass : float
        Effective mass m [kg].
    """

    spring_constant: float = qfield("spring_constant")
    mass: float = qfield("mass")

    def __post_init__(self) -> None:
        object.__setattr__(self, "spring_constant", positive("spring_constant", self.spring_constant, "N/m"))
        object.__setattr__(self, "mass", positive("mass", self.mass, "kg"))

    @property
    def resonance_frequency(self) -> float:
        """``f = sqrt(k/m) / (2 pi)`` [Hz]."""
        return math.sqrt(self.spring_constant / self.mass) / (2.0 * math.pi)


@dataclass(frozen=True)
class InclinedCantilever:
    """Flexible beam at angle theta0, rigid base and rigid probe (Fig 2, eqs 7-12).

    Give either the intrinsic spring constant ``k0`` or the flexural rigidity
    ``B`` (``B = k0 L0^3 / 3``), not both.

    Parameters
    ----------
    L0 : float
        Length of the flexible beam [m].
    L1 : float
        Length of the rigid base [m] (> 0; the dynamics use L1 in qbeta).
    L2 : float
        Length of the rigid probe, at right angles to the base [m] (>= 0).
    theta0 : float
        Inclination of the beam to the horizontal [rad], |theta0| < pi/2;
        negative in the paper (-15 deg).
    k0 : float, optional
        Intrinsic spring constant of the beam, normal to it [N/m].
    B : float, optional
        Flexural rigidity [N m^2].
    """

    L0: float = qfield("L0")
    L1: float = qfield("L1")
    L2: float = qfield("L2")
    theta0: float = qfield("theta0")
    k0: float | None = qfield("k0", None)
    B: float | None = qfield("B", None)

    def __post_init__(self) -> None:
        set_ = lambda n, v: object.__setattr__(self, n, v)  # noqa: E731
        set_("L0", positive("L0", self.L0, "m"))
        set_("L1", positive("L1", self.L1, "m"))
        L2 = finite("L2", self.L2, "m")
        if L2 < 0:
            raise ParameterError(f"L2 must be zero or positive [m], got {self.L2!r}")
        set_("L2", L2)
        th = finite("theta0", self.theta0, "rad")
        if abs(th) >= math.pi / 2:
            raise ParameterError(
                f"|theta0| must be below 90 deg, got {math.degrees(th):.4g} deg; "
                "give the angle in radians or with a unit such as -15deg"
            )
        set_("theta0", th)
        if (self.k0 is None) == (self.B is None):
            raise ParameterError("give exactly one of k0 [N/m] or B (flexural rigidity) [N m^2]")
        if self.k0 is not None:
            k0 = positive("k0", self.k0, "N/m")
            set_("k0", k0)
            set_("B", k0 * self.L0**3 / 3.0)
        else:
            B = positive("B", self.B, "N m^2")
            set_("B", B)
            set_("k0", 3.0 * B / self.L0**3)

    # geometry (eq 10)
    @property
    def a(self) -> float:
        """Lever arm of Fz about the joint, ``a = L1 cos th0 + L2 sin th0`` [m]."""
        return self.L1 * math.cos(self.theta0) + self.L2 * math.sin(self.theta0)

    @property
    def b(self) -> float:
        """Lever arm of Fy about the joint, ``b = L1 sin th0 - L2 cos th0`` [m]."""
        return self.L1 * math.sin(self.theta0) - self.L2 * math.cos(self.theta0)

    @property
    def flexural_rigidity(self) -> float:
        """B [N m^2]."""
        return float(self.B)

    # linear maps (eqs 7-12)
    @property
    def force_to_load(self) -> np.ndarray:
        """P: (Fz, Fy) -> (F0, tau) (eqs 9, 10)."""
        c, s = math.cos(self.theta0), math.sin(self.theta0)
        return np.array([[c, s], [self.a, self.b]])

    @property
    def beam_compliance(self) -> np.ndarray:
        """G: (F0, tau) -> (x, theta) (eqs 7, 8) [m/N, 1/N ; 1/N, 1/(N m)]."""
        L0, B = self.L0, self.B
        return np.array([[2.0 / 3.0 * L0**3, L0**2], [L0**2, 2.0 * L0]]) / (2.0 * B)

    @property
    def beam_stiffness(self) -> np.ndarray:
        """K = G^-1: (x, theta) -> (F0, tau); elastic energy ``U = q.K.q / 2``."""
        L0, B = self.L0, self.B
        return B * np.array([[12.0 / L0**3, -6.0 / L0**2], [-6.0 / L0**2, 4.0 / L0]])

    @property
    def compliance_matrix(self) -> np.ndarray:
        """C: (Fz, Fy) -> (z2, y2) [m/N], ``C = P^T G P`` (eqs 7-12).

        Symmetric (Maxwell-Betti), because (z2, y2) = P^T (x, theta).
        """
        P = self.force_to_load
        return P.T @ self.beam_compliance @ P

    @property
    def angle_compliance(self) -> np.ndarray:
        """Row vector (d theta/dFz, d theta/dFy) [1/N] (eq 8 with eqs 9, 10)."""
        return (self.beam_compliance @ self.force_to_load)[1]

    # spring constants and calibration factor (eqs 13-15)
    @property
    def spring_constant(self) -> float:
        """Force-measuring spring constant ``k = dFz/dz2`` at Fy = 0 or const (eq 13) [N/m]."""
        return 1.0 / self.compliance_matrix[0, 0]

    @property
    def spring_constant_tilt_only(self) -> float:
        """``k0 / cos^2 theta0`` (eq 14, valid for L1, L2 << L0) [N/m]."""
        return self.k0 / math.cos(self.theta0) ** 2

    @property
    def calibration_factor(self) -> float:
        """``beta = dz2/dtheta`` at Fy = 0 or const (eq 15) [m/rad]."""
        return self.compliance_matrix[0, 0] / self.angle_compliance[0]

    @property
    def slide_ratio(self) -> float:
        """``dy2/dz2`` along the constant-compliance line without friction [-]."""
        C = self.compliance_matrix
        return C[1, 0] / C[0, 0]

    def tip_position(self, Fz, Fy=0.0):
        """Tip displacement (z2, y2) [m] under forces Fz, Fy [N] (eqs 11, 12)."""
        C = self.compliance_matrix
        Fz = np.asarray(Fz, float)
        Fy = np.asarray(Fy, float)
        z2 = C[0, 0] * Fz + C[0, 1] * Fy
        y2 = C[1, 0] * Fz + C[1, 1] * Fy
        return (z2[()] if z2.ndim == 0 else z2), (y2[()] if y2.ndim == 0 else y2)

    def angle(self, Fz, Fy=0.0):
        """Deflection angle theta [rad] under forces Fz, Fy [N] (eq 8)."""
        g = self.angle_compliance
        t = g[0] * np.asarray(Fz, float) + g[1] * np.asarray(Fy, float)
        return t[()] if np.ndim(t) == 0 else t
