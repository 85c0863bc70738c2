"""`afmforce analyze --indentation-model jkr ...` (docs/contact.md) shows the work of adhesion it fitted in
its table, in mJ/m^2, the --json value; the table of a run without an adhesive model has no such column."""

from __future__ import annotations

import json

import pytest

from afmforce.cli.main import main

JKR = ["analyze", "--example", "jpk-cell", "--indentation-model", "jkr", "--tip-radius", "5um",
       "--option", "indentation.run=retract"]


def _table(out: str) -> dict[str, str]:
    """The first row of the table by header (headers are separated by two spaces or more)."""
    import re

    lines = out.splitlines()
    starts = [m.start() for m in re.finditer(r"(?:(?<=  )|^)\S", lines[0])]
    cells = lambda ln: [ln[a:b].strip() for a, b in zip(starts, starts[1:] + [None])]  # noqa: E731
    return dict(zip(cells(lines[0]), cells(lines[1])))


def test_the_fitted_work_of_adhesion_is_in_the_table(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(JKR + ["--json"]) == 0
    w = json.loads(capsys.readouterr().out)["results"]["jpk_cellhesion_spot3.jpk-force"]["work_of_adhesion"]
    assert w is not None and w >= 0
    assert main(JKR) == 0
    row = _table(capsys.readouterr().out)
    assert float(row["w [mJ/m^2]"]) == pytest.approx(w * 1e3, rel=1e-3)
    assert main(["analyze", "--example", "jpk-cell"]) == 0
    assert "w [mJ/m^2]" not in _table(capsys.readouterr().out)
