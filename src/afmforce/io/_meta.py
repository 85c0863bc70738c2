"""Metadata table shared by the readers: each key with its label, SI unit and validator.

Readers put SI values under these keys in :attr:`afmforce.raw.RawCurve.metadata`;
unknown vendor keys are kept as they are. ``meta_override`` (from the user, e.g.
``--spring-constant``) is validated against this table and wins over values read
from the file.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, Mapping

import numpy as np

from ..errors import FileFormatError, ParameterError
from ..raw import RawCurve

__all__ = ["MetaField", "METADATA", "check_meta_override", "finalize_curve"]


def _positive(value: Any) -> float:
    v = float(value)
    if not math.isfinite(v) or v <= 0:
        raise ValueError("must be a positive finite number")
    return v


def _finite(value: Any) -> float:
    v = float(value)
    if not math.isfinite(v):
        raise ValueError("must be a finite number")
    return v


def _text(value: Any) -> str:
    return str(value)


@dataclass(frozen=True)
class MetaField:
    """One metadata key: what it is, its SI unit and how to validate it."""

    label: str
    unit: str
    validate: Callable[[Any], Any]


#: The metadata keys afmforce understands (SI values).
METADATA: dict[str, MetaField] = {
    "spring_constant": MetaField("Spring constant", "N/m", _positive),
    "sensitivity": MetaField("Deflection sensitivity (InvOLS)", "m/V", _positive),
    "velocity": MetaField("Approach speed", "m/s", _positive),
    "retract_velocity": MetaField("Retract speed", "m/s", _positive),
    "sample_rate": MetaField("Sample rate", "Hz", _positive),
    "resonance_frequency": MetaField("Resonance frequency", "Hz", _positive),
    "theta0": MetaField("Cantilever inclination", "rad", _finite),
    "radius": MetaField("Probe radius", "m", _positive),
    "instrument": MetaField("Instrument", "", _text),
    "format": MetaField("File format", "", _text),
    "source_file": MetaField("Source file", "", _text),
    "reader": MetaField("afmforce reader identifier", "", _text),
}

#: Vendor (afmformats) key -> afmforce key.
AFMFORMATS_KEYS = {
    "spring constant": "spring_constant",
    "sensitivity": "sensitivity",
    "speed approach": "velocity",
    "speed retract": "retract_velocity",
    "rate approach": "sample_rate",
    "instrument": "instrument",
}


def check_meta_override(meta_override: Mapping[str, Any] | None) -> dict[str, Any]:
    """Validate a user's ``meta_override`` against :data:`METADATA`.

    Accepts afmforce keys (``spring_constant``) and afmformats keys
    (``"spring constant"``); unknown keys raise :class:`ParameterError`.
    """
    out: dict[str, Any] = {}
    for key, value in (meta_override or {}).items():
        if value is None:
            continue
        name = AFMFORMATS_KEYS.get(key, key)
        if name not in METADATA:
            raise ParameterError(
                f"unknown metadata key {key!r}; known keys: {', '.join(sorted(METADATA))}")
        field = METADATA[name]
        try:
            out[name] = field.validate(value)
        except (TypeError, ValueError) as exc:
            raise ParameterError(f"metadata {name} [{field.unit}] {exc}, got {value!r}") from None
    return out


def finalize_curve(curve: RawCurve, path: str) -> RawCurve:
    """Check that a freshly read curve is usable: finite columns, monotonic time.

    Raises
    ------
    FileFormatError
        Non-finite values in a column, or no sample on the approach run.
    """
    cols = {"time": curve.time, "piezo_nominal": curve.piezo_nominal,
            "deflection_signal": curve.deflection_signal}
    if curve.piezo_measured is not None:
        cols["piezo_measured"] = curve.piezo_measured
    for name, col in cols.items():
        arr = np.asarray(col, dtype=float)
        bad = ~np.isfinite(arr)
        if bad.any():
            raise FileFormatError(
                f"{path}: column {name} has {int(bad.sum())} non-finite values (first at sample "
                f"{int(np.argmax(bad))}); the file is damaged or padded: remove those rows")
    if not np.any(curve.approach):
        raise FileFormatError(f"{path}: no approach (extend) segment found")
    return curve
