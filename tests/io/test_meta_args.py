"""A metadata key given twice with different values is refused, not the last taken silently
(afmforce.io.parse_meta_args: ``--meta spring_constant=0.2 --meta spring_constant=0.3`` analysed with
0.3; ``--spring-constant 0.1 --meta spring_constant=0.2`` with 0.1; the web's ``meta`` the same)."""

from __future__ import annotations

import pytest

from afmforce.cli.main import main
from afmforce.errors import ParameterError
from afmforce.io import parse_meta_args


def test_a_key_given_twice_must_agree():
    with pytest.raises(ParameterError, match="spring_constant given twice with different values"):
        parse_meta_args(["spring_constant=0.2", "spring_constant=0.3"])
    # the same value twice, in other units, is one value
    assert parse_meta_args(["spring_constant=0.3", "spring_constant=300mN/m"]) == {"spring_constant": 0.3}


@pytest.mark.parametrize("argv", [["--spring-constant", "0.1", "--meta", "spring_constant=0.2"],
                                  ["--meta", "sensitivity=50nm/V", "--sensitivity", "40nm/V"],
                                  ["--meta", "spring_constant=0.2", "--meta", "spring_constant=0.3"]])
def test_cli_refuses_two_values_before_any_work(capsys, argv):
    code = main(["analyze", "--example", "asylum-air", *argv])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("error: ") and "different values" in err, err

