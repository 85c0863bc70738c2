"""Thermal drift and noise of the deflection signal.

Drift (spec section 6): the paper corrects "a linear thermal drift ...
separately on the two runs, as measured in the zero force regime". We model
a continuous signal drift, linear in time within each run with an
independent slope per run (a run is a block of equal ``segment``): drawn
from a normal distribution of rms ``rate_rms``, or given explicitly.

Noise: white (independent normal samples, rms ``white``) and optionally
1/f ("pink", power spectral density proportional to 1/f from the record's
lowest frequency up, rms ``pink``), both at the acquisition's sample rate
and seeded through :class:`numpy.random.Generator`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._fields import meta as _meta
from .._validate import finite, non_negative
from ..errors import ParameterError
from .detector import run_bounds

__all__ = ["Drift", "Noise", "pink_noise"]


@dataclass(frozen=True)
class Drift:
    """Linear drift of the deflection signal, independent on each run.

    Parameters
    ----------
    rate_rms : float
        rms of the random slope of each run [V/s] (signal unit per second).
    rates : tuple of float
        Explicit slopes of the runs, in order [V/s]; used cyclically and
        instead of random ones when given.
    """

    rate_rms: float = field(default=0.0,
          metadata=_meta("voltage_rate", "V/s", "rms of the random drift slope per run"))
    rates: tuple[float, ...] = field(default=(),
          metadata=_meta("voltage_rate", "V/s", "explicit drift slopes per run"))

    def __post_init__(self) -> None:
        object.__setattr__(self, "rate_rms", non_negative("drift rate_rms", self.rate_rms, "V/s"))
        rates = tuple(finite("drift rates", r, "V/s") for r in np.atleast_1d(np.asarray(self.rates, float)))
        object.__setattr__(self, "rates", rates)

    @property
    def is_zero(self) -> bool:
        """True when the drift is identically zero."""
        if self.rates:
            return not any(self.rates)
        return self.rate_rms == 0.0

    def signal(self, time, segment, rng: np.random.Generator | None) -> tuple[np.ndarray, list[float]]:
        """Drift [V] at the sample times, starting at 0, and the slope of each run [V/s]."""
        t = np.asarray(time, float)
        bounds = run_bounds(segment, t.size)
        if self.rates:
            slopes = [self.rates[i % len(self.rates)] for i in range(len(bounds))]
        elif self.rate_rms > 0.0:
            if rng is None:
                raise ParameterError("a random drift needs a random generator")
            slopes = [float(s) for s in rng.normal(0.0, self.rate_rms, len(bounds))]
        else:
            return np.zeros(t.size), [0.0] * len(bounds)
        out = np.empty(t.size)
        level = 0.0
        for (a, b), slope in zip(bounds, slopes):
            t_start = t[max(a - 1, 0)]
            out[a:b] = level + slope * (t[a:b] - t_start)
            level = float(out[b - 1])
        return out, slopes


@dataclass(frozen=True)
class Noise:
    """Noise of the deflection signal.

    Parameters
    ----------
    white : float
        rms of white noise [V].
    pink : float
        rms of 1/f noise [V].
    """

    white: float = field(default=0.0, metadata=_meta("voltage", "V", "white noise rms"))
    pink: float = field(default=0.0, metadata=_meta("voltage", "V", "1/f noise rms"))

    def __post_init__(self) -> None:
        object.__setattr__(self, "white", non_negative("noise white", self.white, "V"))
        object.__setattr__(self, "pink", non_negative("noise pink", self.pink, "V"))

    @property
    def is_zero(self) -> bool:
        """True without noise."""
        return self.white == 0.0 and self.pink == 0.0

    def sample(self, n: int, rng: np.random.Generator | None) -> np.ndarray:
        """``n`` samples of noise [V]."""
        if self.is_zero:
            return np.zeros(n)
        if rng is None:
            raise ParameterError("noise needs a random generator")
        out = rng.normal(0.0, self.white, n) if self.white > 0 else np.zeros(n)
        if self.pink > 0:
            out = out + pink_noise(n, self.pink, rng)
        return out


def pink_noise(n: int, rms: float, rng: np.random.Generator) -> np.ndarray:
    """1/f noise of the given rms: white noise shaped by ``f^(-1/2)`` in amplitude.

    The mean is removed (no power at f = 0); the record's lowest frequency
    ``1/(n dt)`` is the low cut-off.
    """
    if n < 4:
        return rng.normal(0.0, rms, n)
    spec = np.fft.rfft(rng.normal(0.0, 1.0, n))
    k = np.arange(spec.size, dtype=float)
    spec[0] = 0.0
    spec[1:] /= np.sqrt(k[1:])
    x = np.fft.irfft(spec, n)
    std = float(np.std(x))
    return x * (rms / std) if std > 0 and math.isfinite(std) else np.zeros(n)
