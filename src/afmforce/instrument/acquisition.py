"""Acquisition: sampling the analog signals at the sample rate, ADC quantisation.

The instrument samples its analog signals at ``t_k = t_0 + k / f_s`` (point
sampling: the signals are interpolated linearly between the trajectory's
samples, which must be at least as dense as ``f_s``; no anti-alias filter,
as in a plain ADC). Without a sample rate the trajectory's own time grid is
kept unchanged. The deflection ADC is bipolar with ``2^bits`` codes over
``[-range, +range)``: ``v -> lsb * clip(round(v / lsb), -2^(bits-1), 2^(bits-1) - 1)``,
``lsb = 2 range / 2^bits``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._fields import meta as _meta
from .._validate import positive
from ..errors import ParameterError

__all__ = ["Acquisition", "trajectory_sample_rate"]

#: Relative tolerance when comparing sample rates.
RATE_TOLERANCE = 1e-6


def trajectory_sample_rate(time) -> float:
    """Sample rate of a time grid: ``1 / median(diff(t))`` [Hz]."""
    t = np.asarray(time, float)
    if t.size < 2:
        raise ParameterError("a trajectory needs at least two samples")
    return float(1.0 / np.median(np.diff(t)))


@dataclass(frozen=True)
class Acquisition:
    """Sampling and digitisation of the deflection signal.

    Parameters
    ----------
    sample_rate : float or None
        f_s [Hz]; ``None`` keeps the trajectory's time grid.
    adc_bits : int or None
        Resolution of the deflection ADC [bits] (``None``: no quantisation).
    adc_range : float
        The ADC spans ``[-adc_range, +adc_range)`` [V]; values outside clip.
    """

    sample_rate: float | None = field(default=None,
          metadata=_meta("frequency", "Hz", "sample rate (unset: the trajectory's)"))
    adc_bits: int | None = field(default=None,
          metadata=_meta("integer", "", "deflection ADC resolution in bits (unset: none)"))
    adc_range: float = field(default=10.0, metadata=_meta("voltage", "V", "ADC input range +-adc_range"))

    def __post_init__(self) -> None:
        if self.sample_rate is not None:
            object.__setattr__(self, "sample_rate", positive("acquisition sample_rate", self.sample_rate, "Hz"))
        if self.adc_bits is not None:
            b = self.adc_bits
            if isinstance(b, bool) or not float(b).is_integer() or not 1 <= int(b) <= 32:
                raise ParameterError(f"acquisition adc_bits must be a whole number from 1 to 32, got {b!r}")
            object.__setattr__(self, "adc_bits", int(b))
        object.__setattr__(self, "adc_range", positive("acquisition adc_range", self.adc_range, "V"))

    @property
    def lsb(self) -> float | None:
        """ADC step [V] (``None`` without an ADC)."""
        return None if self.adc_bits is None else 2.0 * self.adc_range / 2.0**self.adc_bits

    def sample_times(self, time) -> np.ndarray | None:
        """Sample times ``t_0 + k / f_s`` within the trajectory, or ``None`` (keep its grid).

        Raises
        ------
        ParameterError
            If ``f_s`` exceeds the trajectory's own sample rate.
        """
        if self.sample_rate is None:
            return None
        t = np.asarray(time, float)
        native = trajectory_sample_rate(t)
        if self.sample_rate > native * (1.0 + RATE_TOLERANCE):
            raise ParameterError(
                f"instrument sample rate {self.sample_rate:.6g} Hz is above the trajectory's "
                f"{native:.6g} Hz: simulate at a sample rate of at least {self.sample_rate:.6g} Hz "
                "or lower the instrument's sample rate")
        n = int(np.floor((t[-1] - t[0]) * self.sample_rate * (1.0 + 1e-12))) + 1
        if n < 2:
            raise ParameterError(
                f"instrument sample rate {self.sample_rate:.6g} Hz gives fewer than two samples "
                f"over the trajectory's {t[-1] - t[0]:.6g} s")
        return t[0] + np.arange(n) / self.sample_rate

    def quantise(self, signal) -> np.ndarray:
        """Clip to the ADC range and round to its step [V]."""
        v = np.asarray(signal, float)
        if self.adc_bits is None:
            return v
        lsb = self.lsb
        half = 2 ** (self.adc_bits - 1)
        return lsb * np.clip(np.round(v / lsb), -half, half - 1)


def resample(time, values, sample_times) -> np.ndarray:
    """Linear interpolation of ``values`` at ``sample_times`` (identity without them)."""
    v = np.asarray(values, float)
    if sample_times is None:
        return v.copy()
    return np.interp(sample_times, np.asarray(time, float), v)


def resample_segment(time, segment, sample_times) -> np.ndarray:
    """Segment of the trajectory interval each sample time falls in (int8)."""
    seg = np.asarray(segment)
    if sample_times is None:
        return seg.astype(np.int8, copy=True)
    idx = np.searchsorted(np.asarray(time, float), sample_times, side="right") - 1
    return seg[np.clip(idx, 0, seg.size - 1)].astype(np.int8)
