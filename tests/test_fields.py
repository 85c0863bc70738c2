"""A value that is no number, given to a library entry point, is a ParameterError naming the quantity
(afmforce._fields.FieldSpec.check, afmforce._validate): before, ``diagnose(radius=[1e-7])`` and
``SimulationConfig(velocity=[1e-6])`` raised a bare TypeError, ``velocity="1um/s"`` a bare ValueError,
and ``afmforce diagnose --radius=--`` (argparse hands ``[]`` over) 'unexpected TypeError ... a bug'."""

from __future__ import annotations

import pytest

from afmforce.cli.main import main
from afmforce.diagnostics import diagnose
from afmforce.dynamics import SimulationConfig
from afmforce.errors import ParameterError

NOT_NUMBERS = [[1e-7], [], 1j, "1um/s", "abc", {"v": 1}]


@pytest.mark.parametrize("value", NOT_NUMBERS, ids=repr)
def test_library_entry_points_name_the_quantity(value):
    with pytest.raises(ParameterError, match=r"^radius expects a number \[m\]"):
        diagnose(spring_constant=0.2, mass=1e-8, radius=value, velocity=1e-5)
    with pytest.raises(ParameterError, match=r"^velocity expects a number \[m/s\]"):
        SimulationConfig(velocity=value)


def test_a_number_as_text_still_counts_and_is_range_checked():
    assert SimulationConfig(velocity="1e-6").velocity == 1e-6
    with pytest.raises(ParameterError, match="out of range"):
        SimulationConfig(velocity="-5")


def test_cli_value_that_argparse_turns_into_a_list(capsys):
    code = main(["diagnose", "--spring-constant", "0.21N/m", "--mass", "10ug", "--radius=--"])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("error: radius expects a number") and "unexpected" not in err, err
