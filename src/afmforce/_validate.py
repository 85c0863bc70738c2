"""Small validators shared by the configuration dataclasses."""

from __future__ import annotations

import math

from .errors import ParameterError


def positive(name: str, value: float, unit: str = "") -> float:
    """Return ``value`` as float or raise :class:`ParameterError` if not > 0."""
    v = _float(name, value, unit)
    if not math.isfinite(v) or v <= 0.0:
        raise ParameterError(f"{name} must be a positive finite number{_u(unit)}, got {value!r}")
    return v


def non_negative(name: str, value: float, unit: str = "") -> float:
    """Return ``value`` as float or raise :class:`ParameterError` if not >= 0."""
    v = _float(name, value, unit)
    if not math.isfinite(v) or v < 0.0:
        raise ParameterError(f"{name} must be zero or positive{_u(unit)}, got {value!r}")
    return v


def finite(name: str, value: float, unit: str = "") -> float:
    """Return ``value`` as float or raise :class:`ParameterError` if not finite."""
    v = _float(name, value, unit)
    if not math.isfinite(v):
        raise ParameterError(f"{name} must be a finite number{_u(unit)}, got {value!r}")
    return v


def _float(name: str, value, unit: str) -> float:
    """``float(value)``, or :class:`ParameterError` naming ``name`` for a value that is no number."""
    try:
        return float(value)
    except (TypeError, ValueError):
        hint = " (a text with units: read it with afmforce.units.parse_value)" if isinstance(value, str) else ""
        raise ParameterError(f"{name} expects a number{_u(unit)}, got {value!r}{hint}") from None


def _u(unit: str) -> str:
    return f" [{unit}]" if unit else ""
