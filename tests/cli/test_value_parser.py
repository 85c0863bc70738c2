"""Issue 31 item 6: one value parser for every face.

Unicode minus signs read as minus; anything after the unit, and a unit without a
number, refused -- by :func:`afmforce.units.parse_value` and by every face that
uses it: the typed options, ``--option STEP.NAME=VALUE``, ``--meta KEY=VALUE``,
``--set``, sweep grids, instrument parameters and :func:`afmforce.units.parse_field`.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from afmforce.cli.main import main
from afmforce.errors import ParameterError, UnitError
from afmforce.units import MINUS_SIGNS, parse_field, parse_value

from test_cli_ranges import no_work, refused  # noqa: F401  (fixture)

CURVE = str(Path(__file__).parents[1] / "data" / "asylum-mfp3d_SiN-tip_air.ibw")


@pytest.mark.parametrize("minus", list(MINUS_SIGNS) + ["-"])
def test_every_minus_sign_reads_as_minus(minus):
    assert set(MINUS_SIGNS) == set("\u2212\u2010\u2011\u2012\u2013\ufe63\uff0d")
    assert parse_value(f"{minus}15deg", "angle") == pytest.approx(math.radians(-15), rel=1e-12)
    assert parse_value(f"{minus}15 deg", "angle") == pytest.approx(math.radians(-15), rel=1e-12)
    assert parse_value(f"{minus}2.5e{minus}3", "dimensionless") == pytest.approx(-2.5e-3, rel=1e-12)
    assert parse_value(f"{minus}3", "integer") == -3


@pytest.mark.parametrize("text, dimension, why", [
    ("5um/s=3", "velocity", "only a number and a unit"),
    ("10um/s,", "velocity", "only a number and a unit"),
    ("10um/s;", "velocity", "only a number and a unit"),
    ("5 um/s 3", "velocity", "only a number and a unit"),
    ("um/s", "velocity", "a unit without a number"),
    ("nm", "length", "a unit without a number"),
    ("nan", "length", "not a finite number"),
    ("inf", "dimensionless", "not a finite number"),
    ("5nm+3nm", "length", "only a number and a unit"),
    ("2*3", "dimensionless", "only a number and a unit"),
])
def test_trailing_text_and_bare_units_are_refused(text, dimension, why):
    with pytest.raises(UnitError, match=f"--x expects .* got {text.replace('+', '[+]').replace('*', '[*]')} \\({why}"):
        parse_value(text, dimension, "--x")


def test_a_long_garbage_text_is_refused_quickly():
    """No catastrophic backtracking in the unit grammar (a regex trap would take minutes)."""
    with pytest.raises(UnitError):
        parse_value("u" * 5000 + "=", "length", "--x")
    with pytest.raises(UnitError):
        parse_value("5 " + "m " * 2000 + ",", "length", "--x")


@pytest.mark.parametrize("text, dimension, si", [
    ("0.5 um/s", "velocity", 0.5e-6), ("1e-3 Pa s", "viscosity", 1e-3), ("1 kg/(s N^2)", "friction_per_force2", 1.0),
    ("2 N*m**2", "rigidity", 2.0), ("10 \u00b5m", "length", 10e-6), ("0.2V/s", "voltage_rate", 0.2),
    ("3.0", "integer", 3), ("1.5", "length", 1.5),
])
def test_valid_values_still_parse(text, dimension, si):
    assert parse_value(text, dimension) == pytest.approx(si, rel=1e-12)


def test_parse_field_checks_the_declared_range():
    assert parse_field("radius", "5nm") == pytest.approx(5e-9, rel=1e-12)
    with pytest.raises(ParameterError, match=r"^--radius \u22125nm is out of range: radius, the effective "
                                             r"radius R, must lie in \(0, 1 mm\]$"):
        parse_field("radius", "\u22125nm", "--radius")
    with pytest.raises(ParameterError, match=r"^radius = -5 nm is out of range"):
        parse_field("radius", -5e-9)


def _statics(capsys, theta0: str) -> dict:
    assert main(["statics", "--theta0", theta0, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_statics_theta0_unicode_minus_is_minus_15_deg(capsys):
    """The issue's case: ``statics --theta0 '−15deg'`` computed +15 deg."""
    minus = _statics(capsys, "\u221215deg")
    assert minus == _statics(capsys, "-15deg")
    plus = _statics(capsys, "15deg")
    # eq 15: the calibration factor depends on the sign of the inclination
    assert minus["calibration_factor"] != pytest.approx(plus["calibration_factor"], rel=1e-6)


@pytest.mark.parametrize("argv, fragment", [
    (["analyze", CURVE, "--radius", "\u22125nm"], "--radius \u22125nm is out of range: radius"),
    (["analyze", CURVE, "--radius", "\uff0d5nm"], "out of range: radius"),
    (["diagnose", "--velocity=5um/s=3"], "only a number and a unit"),
    (["diagnose", "--velocity", "um/s"], "a unit without a number"),
    (["diagnose", "--velocity", "10um/s,"], "only a number and a unit"),
    (["analyze", CURVE, "--option", "vdw.max_separation=20nm=3"], "only a number and a unit"),
    (["analyze", CURVE, "--meta", "sample_rate=kHz"], "a unit without a number"),
    (["analyze", CURVE, "--meta", "velocity=1um/s,"], "only a number and a unit"),
    (["sweep", "--grid", "velocity=1um/s,2um/s", "--set", "theta0=um"], "a unit without a number"),
    (["sweep", "--grid", "velocity=1um/s=2,2um/s"], "only a number and a unit"),
    (["sweep", "--grid", "theta0=\u221215deg,\u221295deg"], "--grid theta0 -95 deg is out of range"),
])
def test_every_face_uses_the_one_parser(capsys, tmp_path, monkeypatch, no_work, argv, fragment):  # noqa: F811
    monkeypatch.chdir(tmp_path)
    assert fragment in refused(capsys, argv)


def test_option_and_instrument_parameters_read_unicode_minus():
    from afmforce.analysis.options_text import parse_option
    from afmforce.instrument.config import parse_parameter

    assert parse_option("indentation.poisson=\u22120.3")[2] == pytest.approx(-0.3)
    key = next(k for k in _instrument_keys() if k[1] == "length")[0]
    assert parse_parameter(key, "\u22122nm") == pytest.approx(-2e-9, rel=1e-12)
    with pytest.raises(UnitError, match="only a number and a unit"):
        parse_parameter(key, "2nm,")


def _instrument_keys():
    from afmforce.instrument.config import PARAMETERS

    return [(k, p.dimension) for k, p in PARAMETERS.items()]


def test_a_dot_between_unit_names_is_a_product():
    """Issue 34's command line types ``--viscosity 0.05Pa.s``: a dot between two unit names is a
    product (Pa.s = Pa*s), while a dot followed by a digit after the unit is still refused."""
    from afmforce.errors import UnitError
    from afmforce.units import parse_value

    assert parse_value("0.05Pa.s", "viscosity") == parse_value("0.05Pa*s", "viscosity") == 0.05
    assert parse_value("2e-5 N.s/m", "damping") == pytest.approx(2e-5, rel=1e-15)
    for bad in ("5um/s.3", "5 um.", "0.05Pa..s"):
        with pytest.raises(UnitError):
            parse_value(bad, "velocity" if "um" in bad else "viscosity")
