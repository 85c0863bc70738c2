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


#: Library files allowed to quote a CLI flag in a message, with the reason (none left: issue 31 item 4).
ALLOWED: dict[str, str] = {}


def _library_files() -> list[Path]:
    """Every module of the library outside the two faces that own their vocabulary (cli/, web/)."""
    return [p for p in sorted(SRC.rglob("*.py")) if p.relative_to(SRC).parts[0] not in ("cli", "web")]


def test_library_messages_quote_no_cli_flag():
    """The library names a quantity by its key (`` `spring_constant` ``); the CLI renders flags."""
    found = {rel: hits for p in _library_files()
             if (rel := str(p.relative_to(SRC))) not in ALLOWED and (hits := _literals_with_flags(p))}
    assert not found, f"library messages quoting CLI flags (write the quantity key as `key`): {found}"
    assert set(ALLOWED) <= {str(p.relative_to(SRC)) for p in _library_files()}   # no stale entry


def test_the_flag_scan_finds_a_flag_in_a_message_not_in_a_docstring(tmp_path):
    src = tmp_path / "m.py"
    src.write_text('"""Module doc: afmforce analyze --verbose."""\n'
                   'def f():\n    """Doc: --out."""\n    raise ValueError(f"give --spring-constant {1}")\n')
    assert [line for line, _ in _literals_with_flags(src)] == [4]


def test_the_cli_renders_a_metadata_key_as_meta_where_the_command_has_no_flag_for_it(capsys):
    from afmforce.cli import _outcome

    _outcome.start([])
    _outcome.RunState.options = frozenset({"--meta", "--spring-constant", "--out"})     # like analyze
    assert _outcome.flag_of("spring_constant") == "--spring-constant"
    assert _outcome.flag_of("sample_rate") == "--meta sample_rate=VALUE"
    assert _outcome.render("`meta_override` x; `ranges`; `sets`; `store`") == "--meta x; --range; --set; --out"
    _outcome.start([])
    assert _outcome.flag_of("sample_rate") == "--sample-rate"
    # end to end: a sweep file that is not there, named by its flag; a sampler without a range
    err = refused(capsys, ["sweep", "--config", "nowhere.toml"])
    assert "--config nowhere.toml: no such file" in err and "`" not in err
    err = refused(capsys, ["sweep", "--grid", "xi=0.1,0.2", "--sample", "lhs", "--n", "3"])
    assert "--sample lhs needs at least one --range entry" in err


def test_web_renders_the_same_key_as_its_field():
    from afmforce.errors import ParameterError
    from afmforce.sweep import build_spec

    with pytest.raises(ParameterError) as info:
        build_spec(["xi=0.1,0.2"], sample="lhs", n=3)
    assert "`sample` lhs needs at least one `ranges` entry" in str(info.value)
    assert render_keys(str(info.value), lambda key: key).startswith("sample lhs needs at least one ranges entry")


def test_calibrate_medium_choices_are_the_sader_presets():
    from afmforce.calibration.sader import FLUIDS
    from afmforce.cli.main import build_parser

    parser = build_parser("calibrate")
    sub = next(a for a in parser._actions if a.choices and "calibrate" in a.choices).choices["calibrate"]
    methods = next(a for a in sub._actions if a.choices and "sader" in a.choices).choices
    for method in ("thermal", "sader"):
        (medium,) = [a for a in methods[method]._actions if "--medium" in a.option_strings]
        assert tuple(medium.choices) == tuple(FLUIDS) == ("air", "water")


def test_a_reader_s_missing_metadata_is_given_with_the_command_s_flags(capsys):
    """The reader names keys; `analyze` renders its own flags for them (it has both)."""
    gel = str(Path(__file__).parents[1] / "data" / "ntmdt_gel-in-water.txt")
    assert main(["analyze", gel]) == 1
    err = capsys.readouterr().err
    assert "give --spring-constant and --sensitivity" in err and "`" not in err
