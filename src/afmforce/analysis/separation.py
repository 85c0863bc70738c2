"""Zero of separation and deflection-to-force conversion (paper section 3.2).

* Separation ``h = z2 - z`` (spec section 1) up to a constant: the constant is
  chosen so that the constant-compliance line lies at ``h = contact_separation``
  where it crosses zero deflection (zero load; the line's slope is one in
  deflection against position unless the position channel or the calibration
  is off, and the contact point is where the separation matters)
  (the paper uses ``z0 = 0.35 nm``, consistent with the van der Waals law; 0 is
  the common alternative).
* The position axis is also given relative to the contact: ``position = 0``
  where the compliance line crosses zero deflection (so pull-off lies near
  ``-|F|/k``, Fig 5).
* Force ``F = k d``; when the user gives the inclination ``theta0`` the
  intrinsic spring constant ``k0`` is corrected with eq 14 (``k0 / cos^2 theta0``)
  or, with the beam geometry (L0, L1, L2), with eq 13 via
  :class:`~afmforce.cantilever.InclinedCantilever`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..cantilever import InclinedCantilever
from ..errors import AnalysisError, ParameterError
from ._numeric import robust_line
from .regions import RunRegions
from ._units import unit as _u
from .options import ZeroOptions as _Z  # the default: declared once, in the step's record

__all__ = ["ZeroResult", "zero_of_separation", "ForceConversion", "effective_spring_constant"]


@dataclass(frozen=True)
class ZeroResult:
    """Where the zero of separation was put.

    Attributes
    ----------
    contact_separation : float
        Separation assigned to the constant-compliance line [m].
    contact_position : float
        Position z of the compliance line at zero deflection (the origin of
        ``position``) [m].
    run : str
        Run whose compliance line defines it.
    scatter : float
        Robust spread of ``d - z`` along that line [m].
    """

    contact_separation: float = _u("m")
    contact_position: float = _u("m")
    run: str
    scatter: float = _u("m")


def zero_of_separation(z: np.ndarray, d: np.ndarray, run: RunRegions,
                       contact_separation: float = _Z.contact_separation):
    """Separation and position arrays, and the :class:`ZeroResult`.

    Parameters
    ----------
    z : ndarray
        Position [m] (inward run already shifted, if it was).
    d : ndarray
        Deflection relative to the baseline [m].
    run : RunRegions
        The run whose compliance region fixes the constant.
    contact_separation : float
        h assigned to the compliance line [m].
    """
    if not np.isfinite(contact_separation) or contact_separation < 0:
        raise ParameterError(f"contact separation must be >= 0 [m], got {contact_separation!r}")
    idx = run.index[run.compliance & ~run.saturated]
    if idx.size < 3:
        raise AnalysisError(f"the {run.kind} run has no constant-compliance region to put the zero of separation on")
    u = d[idx] - z[idx]
    c0 = float(np.median(u))
    zm = float(z[idx].mean())
    a, b, *_ = robust_line(z[idx] - zm, d[idx])
    if np.isfinite(b) and b > 0:  # anchor at zero load: d - z at the line's zero deflection
        c0 = float(-(zm - a / b))  # (equal to the median of d - z when the slope is one)
    scatter = float(1.4826 * np.median(np.abs(u - np.median(u))))
    separation = d - z - c0 + contact_separation
    contact_position = -c0  # where d = 0 on the line d = z + c0
    position = z - contact_position
    return separation, position, ZeroResult(contact_separation=float(contact_separation),
                                            contact_position=contact_position, run=run.kind,
                                            scatter=scatter)


@dataclass(frozen=True)
class ForceConversion:
    """Spring constant used to turn deflection into force.

    Attributes
    ----------
    spring_constant : float
        Force-measuring spring constant k used [N/m] (NaN: no force computed).
    spring_constant_given : float
        The value given (user or file) [N/m].
    tilt_factor : float
        ``k / k_given`` [-] (1 without tilt correction; ``1/cos^2 theta0`` by eq 14).
    theta0 : float
        Inclination used [rad] (NaN if none).
    method : str
        ``"given"``, ``"eq 14"``, ``"eq 13"``, ``"compliance slope"`` or ``"none"``.
    """

    spring_constant: float = _u("N/m")
    spring_constant_given: float = _u("N/m")
    tilt_factor: float = _u("")
    theta0: float = _u("rad")
    method: str


def effective_spring_constant(spring_constant: float | None, *, theta0: float | None = None,
                              L0: float | None = None, L1: float | None = None,
                              L2: float | None = None, from_slope: float = math.nan) -> ForceConversion:
    """The force-measuring spring constant from what the user knows.

    Parameters
    ----------
    spring_constant : float or None
        k [N/m]; with ``theta0`` it is the *intrinsic* constant k0 (resonance or
        Sader method), which eqs 13/14 correct for the tilt.
    theta0 : float, optional
        Inclination of the cantilever [rad] (negative in the paper, -15 deg).
    L0, L1, L2 : float, optional
        Beam, base and probe lengths [m]; all three select eq 13, otherwise eq 14.
    from_slope : float
        Fallback k from the compliance slope of a force signal [N/m].
    """
    if spring_constant is None or not math.isfinite(float(spring_constant)):
        if math.isfinite(from_slope) and from_slope > 0:
            return ForceConversion(from_slope, math.nan, 1.0, math.nan, "compliance slope")
        return ForceConversion(math.nan, math.nan, math.nan, math.nan, "none")
    k = float(spring_constant)
    if k <= 0:
        raise ParameterError(f"spring constant must be positive [N/m], got {spring_constant!r}")
    if theta0 is None:
        return ForceConversion(k, k, 1.0, math.nan, "given")
    if None not in (L0, L1, L2):
        lever = InclinedCantilever(L0=L0, L1=L1, L2=L2, theta0=theta0, k0=k)
        k_eff = lever.spring_constant
        method = "eq 13"
    else:
        if abs(theta0) >= math.pi / 2:
            raise ParameterError(f"|theta0| must be below 90 deg, got {math.degrees(theta0):.4g} deg")
        k_eff = k / math.cos(theta0) ** 2
        method = "eq 14"
    return ForceConversion(float(k_eff), k, float(k_eff / k), float(theta0), method)
