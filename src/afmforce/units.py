"""Values with units for the command line and configuration files.

The library itself works in SI floats. Users type ``200nm``, ``0.1um/s``,
``-15deg`` or plain SI numbers; :func:`parse_quantity` turns them into SI
floats of the expected dimension using pint.
"""

from __future__ import annotations

import functools
import math
import re

from .errors import ParameterError, UnitError

__all__ = ["DIMENSIONS", "parse_quantity", "parse_typed", "format_quantity"]

#: Expected dimension name -> (SI unit understood by pint, human word).
DIMENSIONS: dict[str, tuple[str, str]] = {
    "length": ("m", "a length"),
    "force": ("N", "a force"),
    "stiffness": ("N/m", "a spring constant (force per length)"),
    "angle": ("rad", "an angle"),
    "mass": ("kg", "a mass"),
    "velocity": ("m/s", "a speed"),
    "energy": ("J", "an energy"),
    "damping": ("kg/s", "a friction coefficient (kg/s)"),
    "frequency": ("Hz", "a frequency"),
    "time": ("s", "a time"),
    "viscosity": ("Pa*s", "a viscosity"),
    "voltage": ("V", "a voltage"),
    "sensitivity": ("m/V", "a sensitivity (length per volt)"),
    "rigidity": ("N*m**2", "a flexural rigidity"),
    "friction_per_force2": ("kg/s/N**2", "a coefficient in kg/(s N^2)"),
    "surface_energy": ("J/m**2", "an energy per area"),
    "concentration": ("mol/m**3", "a concentration (1 mM = 1 mol/m^3)"),
    "pressure": ("Pa", "a pressure"),
    "temperature": ("K", "a temperature in kelvin"),
    "dimensionless": ("", "a plain number"),
}

_NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")


@functools.lru_cache(maxsize=1)
def _registry():
    import pint

    ureg = pint.UnitRegistry()
    ureg.define("micron = micrometer")
    return ureg


def parse_quantity(text: str | float | int, dimension: str, name: str = "value") -> float:
    """Parse a value with optional units into an SI float.

    Parameters
    ----------
    text : str or float
        ``"200nm"``, ``"0.1 um/s"``, ``"-15deg"``, ``"5e-19J"`` or a plain number
        (taken as SI: metres, newtons, radians, ...).
    dimension : str
        One of :data:`DIMENSIONS`.
    name : str
        What the value is, for the error message (e.g. ``"--L0"``).

    Returns
    -------
    float
        The value in SI units.

    Raises
    ------
    UnitError
        Unknown unit, wrong dimension, or not a finite number.
    """
    if dimension not in DIMENSIONS:
        raise ValueError(f"unknown dimension {dimension!r}")
    si, word = DIMENSIONS[dimension]
    if isinstance(text, (int, float)):
        value = float(text)
    else:
        s = str(text).strip().replace("µ", "u").replace("μ", "u")
        if _NUMBER.match(s):
            value = float(s)
        else:
            value = _parse_with_pint(s, si, word, name, text)
    if not math.isfinite(value):
        raise UnitError(f"{name} expects {word}, got {text}")
    return value



def parse_typed(text: str, dimension: str, name: str = "value") -> float | int:
    """Parse the text of an option of ``dimension``: ``"integer"`` (a whole number, e.g.
    ``"3"`` or ``"3.0"``), a key of :data:`DIMENSIONS` (a value with optional units -> SI,
    :func:`parse_quantity`), else a plain float. Raises ParameterError/UnitError naming ``name``."""
    if dimension == "integer":
        try:
            number = float(text)
        except ValueError:
            raise ParameterError(f"{name} expects a whole number, got {text}") from None
        if not number.is_integer():
            raise ParameterError(f"{name} expects a whole number, got {text}")
        return int(number)
    if dimension in DIMENSIONS:
        return parse_quantity(text, dimension, name)
    return float(text)


def _parse_with_pint(s: str, si: str, word: str, name: str, original) -> float:
    import pint

    ureg = _registry()
    try:
        q = ureg.Quantity(s)
    except (pint.errors.UndefinedUnitError, pint.errors.DefinitionSyntaxError, AttributeError,
            TypeError, ValueError, SyntaxError, KeyError, AssertionError) as exc:
        raise UnitError(f"{name} expects {word}, got {original} (unknown unit)") from exc
    except Exception as exc:  # pint's parser may raise other errors on garbage
        raise UnitError(f"{name} expects {word}, got {original} (cannot parse)") from exc
    try:
        if si == "":
            return float(q.to("dimensionless").magnitude)
        return float(q.to(si).magnitude)
    except pint.errors.DimensionalityError as exc:
        raise UnitError(f"{name} expects {word}, got {original}") from exc
    except Exception as exc:
        raise UnitError(f"{name} expects {word}, got {original}") from exc


_PRETTY = {
    "length": [(1e-3, "mm"), (1e-6, "um"), (1e-9, "nm")],
    "force": [(1e-3, "mN"), (1e-6, "uN"), (1e-9, "nN"), (1e-12, "pN")],
}


def format_quantity(value: float, unit: str, digits: int = 5) -> str:
    """Format an SI value with its unit, e.g. ``format_quantity(1e-9, 'm') -> '1 nm'``.

    Lengths and forces are scaled to the nearest engineering prefix; other
    units are printed as given.
    """
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "nan"
    dim = {"m": "length", "N": "force"}.get(unit)
    if dim and value != 0:
        for scale, name in _PRETTY[dim]:
            if abs(value) >= scale * 0.9999:
                return f"{value / scale:.{digits}g} {name}"
        scale, name = _PRETTY[dim][-1]
        return f"{value / scale:.{digits}g} {name}"
    return f"{value:.{digits}g} {unit}".rstrip()
