"""The Python examples of the README and docs/*.md run as written, and every value a comment states
beside an expression (``res.shift  # 5.68e-08 m: ...``) is the value the expression gives.

A page's blocks run in order in one namespace in an empty folder, as a reader pastes them into one
session (docs/analysis.md's second block uses the first's ``analyze``). The file names the examples
use are the files afmforce ships or its test data (``asylum.ibw`` is ``--example asylum-air``,
``gel.spm`` is ``--example bruker-gel``, ``cells.jpk-qi-data`` a corpus QI file), linked into the folder.

A stated value is the comment's head (up to the first ``:`` or `` (``), one item per element of the
expression's value when it is a tuple: a number with its unit, checked to the digits printed (one
unit in its last digit: half for the rounding, half for a re-run's), or a quoted string, checked
equal. A comment that does not start with a number or a quoted string states no value.
"""

from __future__ import annotations

import ast
import math
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TEST_DATA = ROOT / "tests" / "data"

#: The files the examples name, as the shipped dataset or test file they stand for.
FILES = {"asylum.ibw": ("example", "asylum-air"), "a.ibw": ("example", "asylum-air"),
         "gel.spm": ("example", "bruker-gel"),
         "cells.jpk-qi-data": ("test", "corpus/jpk-qi-data_2020.02.07.jpk-qi-data")}

#: (page, blocks run in order): fast pages run always; Dask clusters and fits are marked slow.
PAGES = [
    pytest.param("README.md", id="README"),
    pytest.param("docs/analysis_paper_preset.md", id="analysis_paper_preset"),
    pytest.param("docs/dynamics.md", id="dynamics"),
    pytest.param("docs/contact.md", id="contact", marks=pytest.mark.slow),     # a local Dask cluster
    pytest.param("docs/analysis.md", id="analysis", marks=pytest.mark.slow),   # a local Dask cluster
    pytest.param("docs/instrument.md", id="instrument"),
    pytest.param("docs/fit.md", id="fit", marks=pytest.mark.slow),             # a dynamic fit, ~10 s
    pytest.param("docs/sweep.md", id="sweep", marks=pytest.mark.slow),         # a local Dask cluster
]
#: Pages whose Python is a sketch, not a program: said so on the page.
SKETCHES = {"docs/liquid.md"}

_NUMBER = re.compile(r"^[-+\u2212]?(\d+\.?\d*|\.\d+)(e[-+\u2212]?\d+)?", re.I)


def python_blocks(page: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", (ROOT / page).read_text(encoding="utf-8"), flags=re.S)


def stated_values(comment: str) -> list | None:
    """The values a comment states (numbers as (value, tolerance), strings as str), or None."""
    head = re.split(r":\s| \(", comment.strip(), maxsplit=1)[0]
    out = []
    for item in head.split(", "):
        item = item.strip()
        if item[:1] in "'\"" and item[-1:] == item[:1] and len(item) > 1:
            out.append(item[1:-1])
            continue
        m = _NUMBER.match(item)
        if not m:
            return None
        text = m.group(0).replace("\u2212", "-")
        mantissa = m.group(1)
        decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
        exponent = int(m.group(2)[1:].replace("\u2212", "-")) if m.group(2) else 0
        out.append((float(text), 10.0 ** (exponent - decimals)))
    return out


def _flat(value) -> list:
    return list(value) if isinstance(value, tuple) else [value]


def _link_files(folder: Path) -> None:
    from afmforce import datasets

    for name, (kind, what) in FILES.items():
        target = datasets.path(what) if kind == "example" else TEST_DATA / what
        (folder / name).symlink_to(target)


def run_page(page: str) -> list[tuple[str, object, str]]:
    """Run the page's Python blocks; return (expression, value, comment) of each commented expression."""
    namespace: dict = {"__name__": "__docs__"}
    checked = []
    for index, source in enumerate(python_blocks(page)):
        comments = {i + 1: line.split("  # ", 1)[1] for i, line in enumerate(source.splitlines())
                    if "  # " in line}
        for node in ast.parse(source).body:
            code = ast.get_source_segment(source, node)
            where = f"{page} block {index + 1}: {code.splitlines()[0]}"
            try:
                if isinstance(node, ast.Expr):
                    value = eval(compile(ast.Expression(node.value), where, "eval"), namespace)
                    if node.end_lineno in comments:
                        checked.append((where, value, comments[node.end_lineno]))
                else:
                    exec(compile(ast.Module([node], []), where, "exec"), namespace)
            except Exception as exc:  # noqa: BLE001 - the example failed: say which line
                raise AssertionError(f"{where}\n  raised {type(exc).__name__}: {exc}") from exc
    return checked


def test_every_page_with_python_is_run_or_called_a_sketch():
    pages = {p for p in ["README.md", *(f"docs/{f.name}" for f in (ROOT / "docs").glob("*.md"))]
             if python_blocks(p)}
    assert pages == {p.values[0] for p in PAGES} | SKETCHES
    for page in SKETCHES:
        assert "sketch" in (ROOT / page).read_text(encoding="utf-8")


def test_stated_values_are_read_from_comments():
    assert stated_values("'hard', -1.27e-08 N, 1.1841 N/m (the file's k)") == [
        "hard", (-1.27e-08, pytest.approx(1e-10)), (1.1841, pytest.approx(1e-4))]
    assert stated_values("5.68e-08 m: the detector backlash (Fig 7C: +57 nm)") == [
        (5.68e-08, pytest.approx(1e-10))]
    assert stated_values("[m]") is None and stated_values("flat attributes read the parts") is None


@pytest.mark.parametrize("page", PAGES)
def test_the_pages_python_runs_and_gives_the_values_it_states(page, tmp_path, monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)
    _link_files(tmp_path)
    wrong = []
    for where, value, comment in run_page(page):
        stated = stated_values(comment)
        if stated is None:
            continue
        got = _flat(value)
        assert len(got) >= len(stated), (where, comment)
        for want, have in zip(stated, got):
            if isinstance(want, str):
                ok = have == want
            else:
                ok = isinstance(have, (int, float)) and math.isfinite(have) and abs(have - want[0]) <= want[1]
            if not ok:
                wrong.append(f"{where}\n  the comment says {comment.split(':')[0]!r}, it gives {got!r}")
    assert not wrong, "\n".join(wrong)
