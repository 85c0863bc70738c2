"""Values with units on the command line (pint)."""

import math

import pytest

from afmforce.errors import UnitError
from afmforce.units import format_quantity, parse_quantity


@pytest.mark.parametrize("text, dim, expected", [
    ("0.13N/m", "stiffness", 0.13), ("200um", "length", 200e-6), ("-15deg", "angle", math.radians(-15)),
    ("5nN", "force", 5e-9), ("0.1kg/s", "damping", 0.1), ("10ug", "mass", 1e-8),
    ("0.1um/s", "velocity", 1e-7), ("5e-19J", "energy", 5e-19), ("0.35 nm", "length", 0.35e-9),
    ("1.5", "length", 1.5), ("-0.26", "angle", -0.26), ("200µm", "length", 200e-6), ("2kHz", "frequency", 2000),
    ("45nm/V", "sensitivity", 45e-9),
])
def test_parse(text, dim, expected):
    assert parse_quantity(text, dim) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("text, dim", [("5nN", "length"), ("5 blorps/s", "velocity"),
                                       ("abc", "length"), ("nan", "length"), ("", "length"), ("1m/", "length")])
def test_bad(text, dim):
    with pytest.raises(UnitError, match="expects"):
        parse_quantity(text, dim, "--x")


def test_format():
    assert format_quantity(1e-9, "m") == "1 nm"
    assert format_quantity(-3.1e-9, "N") == "-3.1 nN"
    assert format_quantity(0.13, "N/m") == "0.13 N/m"


def test_parse_typed_integer_quantity_and_plain():
    """The one parser of option texts shared by the CLI fields and analysis --option."""
    from afmforce.errors import ParameterError
    from afmforce.units import parse_typed

    assert parse_typed("3", "integer", "--n") == 3 and isinstance(parse_typed("3.0", "integer"), int)
    with pytest.raises(ParameterError, match="--n expects a whole number, got 3.5"):
        parse_typed("3.5", "integer", "--n")
    with pytest.raises(ParameterError, match="whole number"):
        parse_typed("three", "integer", "--n")
    assert parse_typed("200nm", "length", "--x") == pytest.approx(200e-9)


@pytest.mark.parametrize("text", ["1e400nm", "1e400", "1e308 km", "-1e400 um"])
def test_a_number_beyond_the_largest_float_says_why(text):
    """``1e400nm`` overflows to inf: before, the message was only "expects a length, got 1e400nm"
    (the same as for a wrong unit); it now says the number is not finite (audit)."""
    from afmforce.units import UnitError, parse_value

    with pytest.raises(UnitError, match=r"not a finite number: beyond the largest float"):
        parse_value(text, "length", "radius")
