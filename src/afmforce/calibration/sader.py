"""The Sader method: a lever's spring constant from its plan view, resonance and quality factor.

* **Rectangular levers** (Sader, Chon & Mulvaney, Rev. Sci. Instrum. 70, 3967 (1999), eq 2):

      k = 0.1906 rho_f b^2 L Q_f Gamma_i(Re) w_f^2,      Re = rho_f w_f b^2 / (4 eta),       (1)

  with ``w_f = 2 pi f_f`` the fundamental resonance in the fluid [rad/s], ``Q_f`` its quality
  factor, ``b`` the width, ``L`` the length and ``Gamma_i`` the imaginary part of the
  hydrodynamic function of a rectangular beam (:func:`hydrodynamic_function`).
* **Hydrodynamic function** (Sader, J. Appl. Phys. 84, 64 (1998)): the exact function of a
  circular cylinder, eq 18,

      Gamma_circ = 1 + 4 i K1(-i sqrt(i Re)) / (sqrt(i Re) K0(-i sqrt(i Re))),              (2)

  (scipy's modified Bessel functions of complex argument), times the correction
  ``Omega(tau)``, ``tau = log10 Re``, of eq 21 (rational fits, accurate to 0.1 % for
  ``1e-6 <= Re <= 1e4``).
* **General method** (Sader et al., Rev. Sci. Instrum. 83, 103705 (2012)): for levers of any
  plan view, ``Gamma_i ~ Re^-a`` locally, so that

      k = A rho^(1-a) eta^a Q_f f_f^(2-a),                                                   (3)

  with the constant ``A`` calibrated once on a reference lever of the same type whose k is
  known (:func:`general_constant`) and ``a`` the local slope of ``-ln Gamma_i`` in ``ln Re``
  (:func:`hydrodynamic_exponent`).

The medium presets (:data:`FLUIDS`), at 25 C: water 997.05 kg/m^3 and 0.890 mPa s, air 1.184
kg/m^3 and 18.49 uPa s (CRC Handbook).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._fields import QUANTITIES
from ..constants import SADER_FLUIDS
from ..errors import AnalysisError, ParameterError

__all__ = ["FLUIDS", "fluid", "reynolds_number", "gamma_circular", "omega_rectangular",
           "hydrodynamic_function", "hydrodynamic_exponent", "SaderResult", "sader_rectangular",
           "GeneralConstant", "general_constant", "sader_general"]

#: medium -> (density [kg/m^3], viscosity [Pa s]) of the Sader method's preset media: declared in
#: :data:`afmforce.constants.SADER_FLUIDS` (a module the command line reads without numpy).
FLUIDS: dict[str, tuple[float, float]] = SADER_FLUIDS


def fluid(medium: str | None, density: float | None = None,
          viscosity: float | None = None) -> tuple[float, float]:
    """(density [kg/m^3], viscosity [Pa s]) of a preset medium, each overridable."""
    if medium is None:
        if density is None or viscosity is None:
            raise ParameterError("give the medium (air, water) or both its density and viscosity")
        return _checked("density", density), _viscous(_checked("viscosity", viscosity))
    key = medium.lower()
    if key not in FLUIDS:
        raise ParameterError(f"medium {medium!r}: the Sader presets are {', '.join(FLUIDS)}; "
                             "give the density and viscosity of another fluid")
    rho, eta = FLUIDS[key]
    return (rho if density is None else _checked("density", density)), \
        (eta if viscosity is None else _viscous(_checked("viscosity", viscosity)))


def reynolds_number(frequency, width: float, density: float, viscosity: float):
    """``Re = rho (2 pi f) b^2 / (4 eta)`` [-] (Sader 1998, below eq 8)."""
    return density * 2.0 * math.pi * np.asarray(frequency, float) * width**2 / (4.0 * viscosity)


def gamma_circular(re):
    """Eq (2): the hydrodynamic function of a circular cylinder (Sader 1998, eq 18) [-]."""
    from scipy.special import kve   # exponentially scaled: the ratio K1/K0 without underflow

    re = np.asarray(re, dtype=float)
    s = np.sqrt(1j * re)
    return 1.0 + 4j * kve(1, -1j * s) / (s * kve(0, -1j * s))


_OR_NUM = (0.91324, -0.48274, 0.46842, -0.12886, 0.044055, -0.0035117, 0.00069085)
_OR_DEN = (1.0, -0.56964, 0.48690, -0.13444, 0.045155, -0.0035862, 0.00069085)
_OI_NUM = (-0.024134, -0.029256, 0.016294, -0.00010961, 0.000064577, -0.000044510)
_OI_DEN = (1.0, -0.59702, 0.55182, -0.18357, 0.079156, -0.014369, 0.0028361)


def _poly(c, t):
    return sum(a * t**n for n, a in enumerate(c))


def omega_rectangular(re):
    """The correction Omega(Re) of a rectangular beam (Sader 1998, eq 21) [-], complex."""
    t = np.log10(np.asarray(re, dtype=float))
    return _poly(_OR_NUM, t) / _poly(_OR_DEN, t) + 1j * _poly(_OI_NUM, t) / _poly(_OI_DEN, t)


def hydrodynamic_function(re):
    """Gamma of a rectangular beam, ``Omega(Re) Gamma_circ(Re)`` [-] (Sader 1998, eq 20)."""
    re = np.asarray(re, dtype=float)
    if np.any(re <= 0):
        raise ParameterError("the Reynolds number must be positive")
    return omega_rectangular(re) * gamma_circular(re)


def hydrodynamic_exponent(re: float) -> float:
    """``a = -d ln Gamma_i / d ln Re`` of the rectangular beam at ``re`` [-] (eq 3)."""
    h = 1e-4
    gi = lambda x: float(np.imag(hydrodynamic_function(x)))  # noqa: E731
    return -(math.log(gi(re * math.exp(h))) - math.log(gi(re * math.exp(-h)))) / (2 * h)


@dataclass(frozen=True)
class SaderResult:
    """A Sader calibration.

    Attributes
    ----------
    spring_constant : float  k [N/m]
    reynolds_number : float  Re at the resonance [-] (NaN for the general method without width)
    gamma_real, gamma_imag : float  the hydrodynamic function there [-]
    density, viscosity : float  of the medium [kg/m^3], [Pa s]
    method : str  ``"rectangular"`` or ``"general"``
    """

    spring_constant: float
    reynolds_number: float
    gamma_real: float
    gamma_imag: float
    density: float
    viscosity: float
    method: str

    UNITS = {"spring_constant": "N/m", "reynolds_number": "", "gamma_real": "", "gamma_imag": "",
             "density": "kg/m^3", "viscosity": "Pa s", "method": ""}


def _checked(name: str, value) -> float:
    """``value`` as a float within the range :data:`afmforce._fields.QUANTITIES` declares for ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ParameterError(f"{name} = {value!r} must be a finite number")
    return float(QUANTITIES[name].check(float(value), name))


def _viscous(eta: float) -> float:
    """The medium's viscosity [Pa s], which the method needs positive: its hydrodynamic function is
    the lever's viscous load (0 gave Re = inf and numpy's divide-by-zero warning before the refusal)."""
    if eta <= 0.0:
        raise ParameterError("`viscosity` 0: the Sader method weighs the lever by the viscous load of its "
                             "medium, so it needs a viscous one; give the fluid's viscosity (air 1.8e-5 Pa s)")
    return eta


#: The shortest lever (length over width) eq (1) describes: Sader, Chon & Mulvaney (1999) take the
#: hydrodynamic function of an infinitely long beam, accurate for L/b > 3.
MIN_ASPECT = 3.0

#: The Reynolds numbers where the rectangular correction Omega (Sader 1998, eq 21) is accurate (0.1 %).
REYNOLDS_RANGE = (1e-6, 1e4)

#: The lowest quality factor the Sader method takes: eqs (1) and (3) assume a weakly damped
#: resonance (Q_f >> 1, Sader, Chon & Mulvaney 1999); below 1 the lever is overdamped.
MIN_QUALITY = 1.0


def _plausible(k: float, method: str) -> float:
    """``k`` [N/m], or :class:`AnalysisError` when no AFM lever has it (the declared range of
    ``spring_constant``): a resonance, quality factor, size or medium that belong to no lever."""
    spec = QUANTITIES["spring_constant"]
    if not spec.contains(k):
        raise AnalysisError(f"the {method} Sader method gives spring_constant = {k:.4g} N/m, outside any AFM "
                            f"lever's ({spec.range_text()}): check the resonance_frequency, quality_factor, "
                            "the lever's size and the medium")
    return k


def _damped(q: float) -> float:
    if q < MIN_QUALITY:
        raise ParameterError(f"quality_factor = {q:g} < {MIN_QUALITY:g}: the Sader method assumes a weakly damped "
                             "resonance (Q >> 1); an overdamped lever has none: calibrate it by its thermal "
                             "spectrum")
    return q


def sader_rectangular(length: float, width: float, resonance_frequency: float,
                      quality_factor: float, medium: str | None = "air", *,
                      density: float | None = None, viscosity: float | None = None) -> SaderResult:
    """Eq (1): the spring constant of a rectangular lever [N/m].

    Parameters
    ----------
    length, width : float  L and b of the lever [m]
    resonance_frequency : float  f_f of the fundamental mode in the fluid [Hz]
    quality_factor : float  Q_f there [-]
    medium : str  ``"air"`` or ``"water"`` (:data:`FLUIDS`); density, viscosity override it

    Raises
    ------
    ParameterError
        A value out of its range, or a lever shorter than :data:`MIN_ASPECT` widths.
    """
    L = _checked("lever_length", length)
    b = _checked("lever_width", width)
    f = _checked("resonance_frequency", resonance_frequency)
    q = _checked("quality_factor", quality_factor)
    if L < MIN_ASPECT * b:
        raise ParameterError(
            f"lever_length / lever_width = {L / b:.3g}: the rectangular Sader method (eq 1, the "
            f"hydrodynamics of an infinitely long beam) holds for a long lever, L/b > {MIN_ASPECT:g}; "
            "this lever is not one: calibrate it by its thermal spectrum or by the general method "
            "with a reference lever of its type")
    _damped(q)
    rho, eta = fluid(medium, density, viscosity)
    re = float(reynolds_number(f, b, rho, eta))
    lo, hi = REYNOLDS_RANGE
    if not lo <= re <= hi:
        raise ParameterError(f"the Reynolds number of this lever, rho w b^2 / (4 eta) = {re:.3g}, lies outside "
                             f"{lo:g}..{hi:g}, where the rectangular hydrodynamic function holds (Sader 1998, "
                             "eq 21): check the resonance_frequency, the lever_width and the medium")
    g = complex(hydrodynamic_function(re))
    w = 2.0 * math.pi * f
    k = 0.1906 * rho * b * b * L * q * g.imag * w * w
    return SaderResult(_plausible(k, "rectangular"), re, g.real, g.imag, rho, eta, "rectangular")


@dataclass(frozen=True)
class GeneralConstant:
    """The constant of eq (3) for one type of lever.

    Attributes
    ----------
    constant : float  A [SI: k / (rho^(1-a) eta^a Q f^(2-a))]
    exponent : float  a [-]
    """

    constant: float
    exponent: float


def general_constant(spring_constant: float, resonance_frequency: float, quality_factor: float,
                     medium: str | None = "air", *, exponent: float | None = None,
                     width: float | None = None, density: float | None = None,
                     viscosity: float | None = None) -> GeneralConstant:
    """A of eq (3) from a reference lever of known k [N/m], f [Hz] and Q [-].

    The exponent ``a`` is given, or the local slope of the rectangular beam's ``Gamma_i`` at
    the reference's Reynolds number (which needs the lever's ``width`` [m]).
    """
    k = _checked("reference_spring_constant", spring_constant)
    f = _checked("reference_frequency", resonance_frequency)
    q = _checked("reference_quality_factor", quality_factor)
    rho, eta = fluid(medium, density, viscosity)
    if exponent is None:
        if width is None:
            raise ParameterError("the general Sader method needs the exponent a or the lever width "
                                 "to compute it")
        exponent = hydrodynamic_exponent(float(reynolds_number(f, _checked("lever_width", width), rho, eta)))
    a = _checked("sader_exponent", exponent)
    return GeneralConstant(k / (rho ** (1 - a) * eta**a * q * f ** (2 - a)), a)


def sader_general(resonance_frequency: float, quality_factor: float, constant: GeneralConstant,
                  medium: str | None = "air", *, density: float | None = None,
                  viscosity: float | None = None) -> SaderResult:
    """Eq (3): k [N/m] of a lever of the reference's type from its f [Hz] and Q [-]."""
    f = _checked("resonance_frequency", resonance_frequency)
    q = _damped(_checked("quality_factor", quality_factor))
    rho, eta = fluid(medium, density, viscosity)
    a = constant.exponent
    k = constant.constant * rho ** (1 - a) * eta**a * q * f ** (2 - a)
    return SaderResult(_plausible(k, "general"), math.nan, math.nan, math.nan, rho, eta, "general")
