"""Values with units for the command line and configuration files.

The library itself works in SI floats. Users type ``200nm``, ``0.1um/s``,
``-15deg`` or plain SI numbers; :func:`parse_value` (every face: the command
line's typed options, ``--option``, ``--meta``, ``--set``, sweep grids, the web
forms) turns them into SI floats of the expected dimension, and
:func:`parse_field` also checks a quantity of :data:`afmforce._fields.QUANTITIES`
against its valid range.

The grammar is strict: a number (any Unicode minus sign reads as ``-``),
then optionally one unit expression (unit names, ``/``, ``*``, ``^``/``**``
exponents, parentheses) and nothing else: ``5um/s=3``, ``10um/s,`` and a unit
without a number (``um/s``) are refused, never read as another value.
"""

from __future__ import annotations

import functools
import math
import re

from .errors import ParameterError, UnitError

__all__ = ["DIMENSIONS", "MINUS_SIGNS", "parse_value", "parse_field", "parse_quantity", "parse_typed",
           "normalize_number_text", "format_quantity", "unit_registry"]

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
    "temperature": ("K", "a temperature (K, or degC)"),
    "density": ("kg/m**3", "a density"),
    "voltage_rate": ("V/s", "a signal drift rate (e.g. 0.2V/s)"),
    "pressure": ("Pa", "a pressure"),
    "dimensionless": ("", "a plain number"),
}

_NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")
#: A number followed by the rest of the text (the unit expression, checked by :data:`_UNIT`).
_LEADING_NUMBER = re.compile(r"^([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*(.*)$", re.S)
#: One unit name with an optional exponent (``m``, ``um``, ``s^-1``, ``m**2``, ``m2`` is not one).
_UNIT_NAME = r"[A-Za-z\u00b0\u03a9\u2126%_]++(?:\s*(?:\^|\*\*)\s*[+-]?\d+(?:\.\d+)?)?"
#: A unit expression: names joined by ``/``, ``*``, ``·`` or spaces, with parentheses.
_UNIT = re.compile(r"^(?:" + _UNIT_NAME + r"|[()/*\u00b7\s]|(?<=[A-Za-z])\.(?=[A-Za-z]))++$")
#: A dot between two unit names is a product (``Pa.s``, ``N.s/m``), as engineers write it.
_DOT_PRODUCT = re.compile(r"(?<=[A-Za-z])\.(?=[A-Za-z])")

#: Characters read as a minus sign: U+2212 minus, U+2010 hyphen, U+2011 non-breaking hyphen,
#: U+2012 figure dash, U+2013 en dash, U+FE63 small hyphen-minus, U+FF0D fullwidth hyphen-minus
#: (a value pasted from a paper or a word processor).
MINUS_SIGNS = "\u2212\u2010\u2011\u2012\u2013\ufe63\uff0d"
_TO_ASCII = str.maketrans({**{c: "-" for c in MINUS_SIGNS}, "\u00b5": "u", "\u03bc": "u", "\uff0b": "+",
                           "\u00a0": " ", "\u202f": " "})


def normalize_number_text(text: str) -> str:
    """``text`` with every minus sign of :data:`MINUS_SIGNS` as ``-``, ``µ``/``μ`` as ``u``
    and non-breaking spaces as spaces, stripped."""
    return str(text).translate(_TO_ASCII).strip()


@functools.lru_cache(maxsize=1)
def unit_registry():
    """The one pint registry of afmforce (built once; ``micron`` defined)."""
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
    if isinstance(text, bool):
        raise UnitError(f"{name} expects {word}, got {text!r}")
    if isinstance(text, (int, float)):
        value = float(text)
    else:
        s = normalize_number_text(text)
        if _NUMBER.match(s):
            value = float(s)
        else:
            match = _LEADING_NUMBER.match(s)
            if match is None and not s:     # "" or "  ": said as empty, never "got  (not a number)"
                raise UnitError(f"{name} expects {word}, got an empty value; give one (e.g. "
                                f"{_EXAMPLE.get(dimension, '1.5')})")
            if match is None:
                why = ("not a finite number" if s.lower().lstrip("+-") in ("nan", "inf", "infinity")
                       else "a unit without a number" if s and _UNIT.match(s) else "not a number")
                raise UnitError(f"{name} expects {word}, got {text} ({why}; e.g. "
                                f"{_EXAMPLE.get(dimension, '1.5')})")
            if not _UNIT.match(match.group(2)) or not re.search(r"[A-Za-z\u00b0\u03a9\u2126%]", match.group(2)):
                raise UnitError(f"{name} expects {word}, got {text} (only a number and a unit; "
                                f"e.g. {_EXAMPLE.get(dimension, '1.5')})")
            if _DOT_PRODUCT.search(match.group(2)):
                s = match.group(1) + " " + _DOT_PRODUCT.sub("*", match.group(2))
            value = _parse_with_pint(s, si, word, name, text)
    if not math.isfinite(value):    # 1e400nm: a number beyond the largest float (1.8e308), read as inf
        raise UnitError(f"{name} expects {word}, got {text} (not a finite number: beyond the largest float, "
                        f"1.8e308; e.g. {_EXAMPLE.get(dimension, '1.5')})")
    return value


#: An example value of each dimension, for the messages.
_EXAMPLE = {"length": "200nm", "force": "5nN", "stiffness": "0.1N/m", "angle": "-15deg", "mass": "10ug",
            "velocity": "0.5um/s", "energy": "1e-19J", "damping": "0.002kg/s", "frequency": "10kHz",
            "time": "5ms", "viscosity": "1mPa*s", "voltage": "-50mV", "sensitivity": "50nm/V",
            "concentration": "1mM"}


def parse_value(text: str | float | int, dimension: str, name: str = "value") -> float | int:
    """Parse what a user typed for a value of ``dimension`` -- the one parser of every face.

    Parameters
    ----------
    text : str or float
        ``"200nm"``, ``"−15 deg"`` (any minus of :data:`MINUS_SIGNS`), ``"3"``,
        or a number (taken as SI).
    dimension : str
        ``"integer"`` (a whole number), a key of :data:`DIMENSIONS` (a value with
        optional units -> SI), or anything else: a plain number.
    name : str
        What the value is, for the message (``"--velocity"``, ``"radius"``).

    Returns
    -------
    float or int
        The value in SI units (an int for ``"integer"``).

    Raises
    ------
    UnitError
        Unknown unit, wrong dimension, a unit without a number, text after
        the unit, or not a finite number.
    ParameterError
        ``"integer"`` and not a whole number.
    """
    if dimension == "integer":
        plain = normalize_number_text(text) if isinstance(text, str) else text
        try:
            number = float(plain)
        except (TypeError, ValueError):
            raise ParameterError(f"{name} expects a whole number, got {text}") from None
        if isinstance(text, bool) or not number.is_integer():
            raise ParameterError(f"{name} expects a whole number, got {text}")
        return int(number)
    if dimension in DIMENSIONS:
        return parse_quantity(text, dimension, name)
    return parse_quantity(text, "dimensionless", name)


def parse_field(name: str, text: str | float | int, where: str | None = None) -> float | int:
    """Parse ``text`` as the quantity ``name`` of :data:`afmforce._fields.QUANTITIES` and check
    its valid range: the command line's flags, ``--set``, sweep grids and the web forms.

    Parameters
    ----------
    name : str
        Key of ``QUANTITIES`` (``"radius"``).
    text : str or float
        What the user typed (``"-5nm"``) or an SI number.
    where : str or None
        How the user typed it (``"--radius"``), to prefix the message; default the name.

    Raises
    ------
    UnitError, ParameterError
        Not a value of the quantity's dimension, or out of its range (the message
        of :meth:`afmforce._fields.FieldSpec.check`: the name, its meaning and the range).
    """
    from ._fields import QUANTITIES

    spec = QUANTITIES[name]
    value = parse_value(text, spec.dimension, where or name)
    return spec.check(value, name, where, typed=str(text).strip() if isinstance(text, str) else None)


def parse_typed(text: str, dimension: str, name: str = "value") -> float | int:
    """The same as :func:`parse_value` (kept for its callers)."""
    return parse_value(text, dimension, name)


def _parse_with_pint(s: str, si: str, word: str, name: str, original) -> float:
    import pint

    ureg = unit_registry()
    try:
        m = re.match(r"^([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*(.+)$", s)
        # an offset unit (25 degC) needs the number apart from its unit
        q = ureg.Quantity(float(m.group(1)), m.group(2)) if m and si == "K" else ureg.Quantity(s)
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
