"""Optical lever and split photodiode: signal, offset, interference fringes, saturation.

Optical lever (spec section 6): the photodiode signal is proportional to the
cantilever angle theta. With the calibration factor beta (eq 15) the
constant-compliance slope reads ``beta theta`` [m] (the apparent deflection,
eq 29), so ``signal = beta theta / s + offset`` with ``s`` the sensitivity
[m/V] (the "InvOLS" of instrument software, here the true one).

Interference (paper section 3.1): part of the laser light is reflected by the
substrate and interferes with the beam reflected by the cantilever. Two
reflecting planes a distance ``d`` apart, light of wavelength ``lambda``
arriving at the angle ``alpha`` to their normal: the substrate beam travels
the extra path ``2 d cos(alpha)`` (as in a thin air film), a phase
``4 pi d cos(alpha) / lambda``. The photodiode therefore sees
``I0 cos(d / Delta + phi)`` with

    ``Delta = lambda / (4 pi cos(alpha))``,   fringe period ``2 pi Delta = lambda / (2 cos alpha)``,

335 nm for a 670 nm laser diode at normal incidence. ``d`` changes like the
tip-substrate separation ``h = z2 - z`` (the laser spot sits near the tip),
so the fringes run with the piezo position in the zero-force regime and stop
in contact -- the paper's absolute scale of displacement.

Saturation: the amplifier clips the signal to ``[-V_sat, +V_sat]`` (the
paper's Fig 7 saturates at the top of constant compliance and at the bottom
of the pull-off).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._fields import meta as _meta
from .._validate import finite, non_negative, positive
from ..errors import ParameterError

__all__ = ["Photodiode", "fringe_length"]


def fringe_length(wavelength: float, incidence_angle: float = 0.0) -> float:
    """``Delta = lambda / (4 pi cos alpha)`` [m]; the fringe period is ``2 pi Delta``."""
    return wavelength / (4.0 * math.pi * math.cos(incidence_angle))


@dataclass(frozen=True)
class Photodiode:
    """Optical lever detector (see the module docstring).

    Parameters
    ----------
    sensitivity : float or None
        s [m/V]: apparent deflection per volt. ``None``: the instrument
        reports the calibrated deflection in metres, and every other
        amplitude must then be zero.
    offset : float
        Signal at zero deflection [V].
    saturation : float or None
        |signal| limit of the amplifier [V] (``None``: none).
    interference_amplitude : float
        I0 [V] (0: no fringes).
    wavelength : float
        Laser wavelength lambda [m].
    incidence_angle : float
        alpha, angle of the light to the substrate normal [rad].
    interference_phase : float
        phi [rad].
    nonlinearity_length : float or None
        L [m] of a quadratic response (issue 25; Attard 2012, "non-linear compliance"):
        ``signal = (d + d^2 / L) / s + offset`` for the apparent deflection d; the constant
        compliance then reads curved. None: linear. L may be negative.
    """

    sensitivity: float | None = field(default=None,
          metadata=_meta("sensitivity", "m/V", "optical lever sensitivity (InvOLS); unset: report metres"))
    offset: float = field(default=0.0, metadata=_meta("voltage", "V", "signal at zero deflection"))
    saturation: float | None = field(default=None,
          metadata=_meta("voltage", "V", "amplifier limit: the signal is clipped to +-saturation"))
    interference_amplitude: float = field(default=0.0, metadata=_meta("voltage", "V", "fringe amplitude I0"))
    wavelength: float = field(default=670e-9, metadata=_meta("length", "m", "laser wavelength"))
    incidence_angle: float = field(default=0.0,
          metadata=_meta("angle", "rad", "angle of the light to the substrate normal"))
    interference_phase: float = field(default=0.0, metadata=_meta("angle", "rad", "fringe phase phi"))
    nonlinearity_length: float | None = field(default=None, metadata=_meta(
        "length", "m", "quadratic photodiode response: signal (d + d^2/L)/s; unset: linear"))

    def __post_init__(self) -> None:
        set_ = lambda n, v: object.__setattr__(self, n, v)  # noqa: E731
        if self.sensitivity is not None:
            set_("sensitivity", positive("photodiode sensitivity", self.sensitivity, "m/V"))
        set_("offset", finite("photodiode offset", self.offset, "V"))
        if self.saturation is not None:
            set_("saturation", positive("photodiode saturation", self.saturation, "V"))
        set_("interference_amplitude",
             non_negative("photodiode interference_amplitude", self.interference_amplitude, "V"))
        set_("wavelength", positive("photodiode wavelength", self.wavelength, "m"))
        alpha = finite("photodiode incidence_angle", self.incidence_angle, "rad")
        if abs(alpha) >= math.pi / 2:
            raise ParameterError(f"photodiode incidence_angle must be below 90 deg, got {math.degrees(alpha):.4g} deg")
        set_("incidence_angle", alpha)
        set_("interference_phase", finite("photodiode interference_phase", self.interference_phase, "rad"))
        if self.nonlinearity_length is not None:
            L = finite("photodiode nonlinearity_length", self.nonlinearity_length, "m")
            if L == 0.0:
                raise ParameterError("photodiode nonlinearity_length must be non-zero (unset: linear)")
            set_("nonlinearity_length", L)
        if self.sensitivity is None and (self.offset or self.saturation is not None or self.interference_amplitude):
            raise ParameterError("photodiode offset, saturation and interference are in volts: "
                                 "give the photodiode sensitivity [m/V] too")

    @property
    def unit(self) -> str:
        """Unit of the signal: ``"V"``, or ``"m"`` without a sensitivity."""
        return "m" if self.sensitivity is None else "V"

    @property
    def fringe_length(self) -> float:
        """Delta [m]."""
        return fringe_length(self.wavelength, self.incidence_angle)

    @property
    def fringe_period(self) -> float:
        """2 pi Delta = lambda / (2 cos alpha) [m]: fringe spacing in separation."""
        return 2.0 * math.pi * self.fringe_length

    def optical(self, apparent_deflection) -> np.ndarray:
        """``beta theta / s + offset`` [V] (or the deflection itself [m] without s)."""
        d = np.asarray(apparent_deflection, float)
        if self.nonlinearity_length is not None:
            d = d + d * d / self.nonlinearity_length
        if self.sensitivity is None:
            return d.copy()
        out = d / self.sensitivity
        return out + self.offset if self.offset else out

    def interference(self, separation) -> np.ndarray:
        """``I0 cos(h / Delta + phi)`` [V]."""
        h = np.asarray(separation, float)
        return self.interference_amplitude * np.cos(h / self.fringe_length + self.interference_phase)

    def saturate(self, signal) -> np.ndarray:
        """Clip to ``[-V_sat, V_sat]`` [V]."""
        v = np.asarray(signal, float)
        if self.saturation is None:
            return v
        return np.clip(v, -self.saturation, self.saturation)
