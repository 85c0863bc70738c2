"""Issue 31 item 4: the command line's vocabulary stays in cli/.

Library messages name a quantity the user can give by its key in backquotes
(`` `spring_constant` ``, :data:`afmforce.errors.QUANTITY_KEY`); errors carry the keys
(``exc.keys``); the command line renders each as its flag (``--spring-constant``), the
web as its field. A scan keeps the analysis and contact packages free of CLI flags.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import numpy as np
import pytest

from afmforce.cli.main import main
from afmforce.errors import AnalysisError, MissingMetadataError, ParameterError, render_keys

from test_cli_ranges import refused

SRC = Path(__file__).parents[2] / "src" / "afmforce"
CURVE = str(Path(__file__).parents[1] / "data" / "asylum-mfp3d_SiN-tip_air.ibw")


def test_errors_carry_the_keys_their_message_names():
    exc = AnalysisError("no spring constant (give `spring_constant`): no force; or `sensitivity`, `spring_constant`")
    assert exc.keys == ("spring_constant", "sensitivity")
    assert MissingMetadataError("x", keys=("sensitivity",)).keys == ("sensitivity",)
    assert ParameterError("nothing to give").keys == ()
    assert render_keys("give `spring_constant` or `force.thermal_k`", {"spring_constant": "--k"}.get) == \
        "give --k or force.thermal_k"


def test_the_cli_renders_keys_as_its_flags():
    from afmforce.cli import _outcome

    _outcome.start([])
    assert _outcome.render("give `spring_constant`, `tip_radius` or `force.thermal_k`") == \
        "give --spring-constant, --tip-radius or --option force.thermal_k"
    _outcome.RunState.flags["spring_constant"] = "--meta spring_constant=VALUE"   # as `afmforce fit` does
    assert _outcome.render("give `spring_constant`") == "give --meta spring_constant=VALUE"
    _outcome.start([])
    assert _outcome.render("give `spring_constant`") == "give --spring-constant"


def test_a_library_error_names_the_key_and_the_cli_the_flag(capsys):
    from afmforce.contact.fit import fit_indentation

    depth = np.linspace(0, 50e-9, 40)
    with pytest.raises(ParameterError) as info:
        fit_indentation(depth, depth * 1e-3, model="hertz_cone", geometry={})
    assert "(`half_angle`)" in str(info.value) and "--" not in str(info.value)
    assert info.value.keys == ("half_angle",)
    err = refused(capsys, ["fit", CURVE, "--model", "spring", "--free", "xi"])
    assert "use --model beam or drop it from --free" in err and "`" not in err


def _literals_with_flags(path: Path) -> list[tuple[int, str]]:
    tree = ast.parse(path.read_text())
    docs = {id(n.body[0].value) for n in ast.walk(tree)
            if isinstance(n, (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) and n.body
            and isinstance(n.body[0], ast.Expr) and isinstance(n.body[0].value, ast.Constant)}
    return [(n.lineno, n.value) for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, str)
            and id(n) not in docs and re.search(r"(?<![\w-])--[a-z]", n.value)]


@pytest.mark.parametrize("package", ["analysis", "contact"])
def test_analysis_and_contact_messages_quote_no_cli_flag(package):
    found = {str(p.relative_to(SRC)): hits for p in sorted((SRC / package).rglob("*.py"))
             if (hits := _literals_with_flags(p))}
    assert not found, f"library messages quoting CLI flags (write the quantity key as `key`): {found}"
