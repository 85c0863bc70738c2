"""The conversion of a deflection signal into deflection and force, written once.

A curve's ``deflection_signal`` is in volts (the photodiode), metres or newtons
(:data:`afmforce.io.curve.DEFLECTION_UNITS`). Its deflection is the signal times the InvOLS
(``sensitivity`` [m/V]) for volts, the signal itself for metres and the signal over the spring
constant for newtons; its force is the deflection times the spring constant (Hooke). Every user of
the conversion (``RawCurve.deflection_factor`` / ``force_factor``, the calibration step's
metadata factor, the pipeline's adhesion-only path, the indentation fast path) calls
:func:`signal_factor`, so the rule and its "unknown" (None, 0 or missing: NaN) live here only.
"""

from __future__ import annotations

import math
from typing import Any

__all__ = ["signal_factor", "known"]


def known(value: Any) -> float:
    """A calibration value as a float; NaN when it is unknown (None, 0 or missing)."""
    return float(value) if value else math.nan


def signal_factor(unit: str, sensitivity: Any, spring_constant: Any, to: str = "deflection") -> float:
    """Deflection [m] or force [N] per unit of a deflection signal in ``unit``.

    Parameters
    ----------
    unit : {"V", "m", "N"}
        Unit of the signal.
    sensitivity : float or None
        InvOLS [m/V] (used for volts only).
    spring_constant : float or None
        k [N/m] (used for newtons to deflection, and for volts and metres to force).
    to : {"deflection", "force"}
        What the factor converts to.

    Returns
    -------
    float
        ``to="deflection"``: the sensitivity [m/V] for volts, 1 for metres, 1/k [m/N] for newtons;
        ``to="force"``: k x sensitivity [N/V] for volts, k [N/m] for metres, 1 for newtons. NaN when
        a value the unit needs is unknown (None, 0 or NaN) or the unit is not one of V, m, N.
    """
    if to == "deflection":
        if unit == "V":
            return known(sensitivity)
        if unit == "m":
            return 1.0
        return 1.0 / float(spring_constant) if spring_constant and unit == "N" else math.nan
    if to == "force":
        if unit == "N":
            return 1.0
        if unit == "m":
            return known(spring_constant)
        return known(spring_constant) * known(sensitivity) if unit == "V" else math.nan
    raise ValueError(f"signal_factor converts to 'deflection' or 'force', not {to!r}")
