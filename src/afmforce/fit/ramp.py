"""The drive of a measured run for the fit: its time axis, speed, sample rate and position channel.

The model is driven at constant speed in true position; these read what it needs off a
file: the speed and sample rate from the metadata or, where the file lacks them, off the
ramp itself (:func:`_ramp`); the position channel as the analysis chooses it, with the
robust line through a measured (sensor) channel (:func:`_position`); seconds where the
file stores the sample index (:func:`_timed`).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import AnalysisError, FileFormatError, MissingMetadataError
from ..io.curve import RawCurve

__all__: list[str] = []


def _meta_value(curve: RawCurve, key: str, override, name: str, unit: str) -> float:
    value = override if override is not None else (curve.metadata or {}).get(key)
    if value is None:
        kw = {"velocity": "velocities", "sample_rate": "sample_rates"}[key]
        raise MissingMetadataError(f"{name}: no {key} [{unit}] in the file; give it (`{kw}` V1,V2,.. "
                                   f"or `meta_override` {key}=VALUE)", keys=(key,))
    value = float(value)
    if not math.isfinite(value) or value <= 0:
        raise FileFormatError(f"{name}: {key} must be positive, got {value!r} {unit}")
    return value


def _ramp(curve: RawCurve, idx: np.ndarray) -> dict:
    """Speed [m/s] and sample rate [Hz] read off the approach itself, where the file lacks them.

    The sample rate is 1 / the median time step when the steps agree within 1 %; the speed
    is the slope of the nominal position in time when a straight line describes the ramp
    (its middle 80 %) within 5 % of its travel, with that deviation in
    ``ramp_deviation``. Otherwise None (the user must give them).
    """
    t = np.asarray(curve.time, float)[idx]
    z = np.asarray(curve.piezo_nominal, float)[idx]
    out = {"velocity": None, "sample_rate": None}
    dt = np.diff(t)
    if dt.size < 10 or not np.all(np.isfinite(dt)) or not np.all(np.isfinite(z)):
        return out
    med = float(np.median(dt))
    if med > 0 and np.percentile(np.abs(dt / med - 1.0), 95) < 0.01:
        out["sample_rate"] = 1.0 / med
    n = t.size
    mid = slice(n // 10, n - n // 10)            # closed-loop ramps bend at their ends
    slope, icpt = np.polyfit(t[mid], z[mid], 1)
    travel = abs(z[-1] - z[0])
    dev = float(np.max(np.abs(z[mid] - (icpt + slope * t[mid])))) if travel > 0 else math.inf
    if slope > 0 and dev < 0.05 * travel:
        out["velocity"] = float(slope)
        out["ramp_deviation"] = dev / travel
    return out


def drive_line(t: np.ndarray, zm: np.ndarray) -> tuple[float, float, int]:
    """Robust line ``a + b (t - t[0])`` [m], [m/s] through a run's measured positions, its
    dead zone (:func:`afmforce.analysis.dynamic.dead_zone`, the analysis's rule too) left out; returns
    ``(a, b, dead_zone_samples)``. Every zone is left out here, also one that tilts the speed by under
    :data:`~afmforce.analysis.dynamic.DEAD_ZONE_MIN_BIAS` (which the analysis's speed keeps): the model is
    driven along this line, so its position matters, not only its slope (the ``paper`` preset's intervals at
    seed 2 missed the true A R with those zones kept)."""
    from ..analysis import robust_line_thin   # here: registering `fit` loads no analysis (numba)
    from ..analysis.dynamic import dead_zone

    t = np.asarray(t, float)
    zm = np.asarray(zm, float)
    k = dead_zone(zm)
    a, b, *_ = robust_line_thin(t[k:] - t[0], zm[k:])
    return float(a), float(b), k


def _position(curve: RawCurve, idx: np.ndarray, name: str) -> tuple[np.ndarray, dict]:
    """The approach's piezo position [m] and how it was chosen.

    The channel is chosen as the analysis chooses it (:func:`afmforce.analysis.state.prepare`,
    ``channel="auto"``): the measured (sensor) position when the file has one, else the
    nominal (commanded) one. The nominal position of a piezo without closed-loop control is
    not the true one (hysteresis, creep: a 10 % nonlinearity shifts the zero of position by
    nanometres and bends the ramp); the model is driven at constant speed in true position,
    so with a measured channel the fit takes the robust line through the measured positions
    in time (sensor steps and noise removed) and its slope as the speed
    (:func:`afmforce.analysis.dynamic.run_velocity`).
    """
    from ..analysis.dynamic import run_velocity
    from ..analysis.state import prepare

    try:
        channel = prepare(curve).channel
    except AnalysisError:      # e.g. an approach-only file: the analysis needs both runs
        channel = curve.position_channel()
    if channel != "measured":
        return np.asarray(curve.piezo_nominal, float)[idx], {"channel": "nominal"}
    t = np.asarray(curve.time, float)[idx]
    zm = np.asarray(curve.piezo_measured, float)[idx]
    a, b, k0 = drive_line(t, zm)
    v = abs(b) if k0 else run_velocity(t, zm)
    n = t.size
    mid = slice(max(n // 10, k0), n - n // 10)      # as _ramp: the middle 80 % of the run
    dev = float(np.max(np.abs(zm[mid] - (a + b * (t[mid] - t[0])))))
    travel = float(abs(zm[-1] - zm[0]))
    steps = np.abs(np.diff(zm))
    step = float(np.median(steps[steps > 0])) if np.any(steps > 0) else 0.0   # sensor digits
    if not dev < 0.05 * travel + step:    # not a constant speed: the model cannot follow it
        return zm, {"channel": "measured", "bent": (
            f"{name}: the measured position deviates from a straight line in time by "
            f"{dev / max(travel, 1e-300):.1%} of the travel; the model drives at constant speed")}
    return zm, {"channel": "measured", "velocity": v, "deviation": dev,
                "line": lambda tt: a + b * np.asarray(tt, float)}


def _timed(curve: RawCurve, name: str, sample_rate: float | None) -> RawCurve:
    """``curve`` with its time in seconds when the file stores only the sample index
    (``time_is_sample_index``, e.g. AFM Workshop CSV): index / sample rate, the rate given
    or in the file's metadata; without one the speed read off the ramp would be in metres
    per sample, so the user is asked."""
    import dataclasses

    meta = curve.metadata or {}
    if not meta.get("time_is_sample_index"):
        return curve
    fs = sample_rate if sample_rate is not None else meta.get("sample_rate")
    if not fs:
        raise MissingMetadataError(
            f"{name}: the file stores no time (its time column is the sample index), so neither the "
            "driving speed nor the sample rate can be read off the ramp; give the sample rate "
            "(`sample_rates` F1,F2,.. or `meta_override` sample_rate=VALUE) and, if the file lacks it, "
            "the speed (`velocities`)", keys=("sample_rate",))
    t = np.asarray(curve.time, float) / float(fs)
    return dataclasses.replace(curve, time=t, metadata={**meta, "time_is_sample_index": False,
                                                        "sample_rate": float(fs)})
