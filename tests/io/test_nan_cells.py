"""A NaN cell inside an AFM Workshop CSV is named as such, as the native readers name theirs
(tests/io/test_validation.py).

Was: afmformats drops the column holding the NaN (a warning, silenced) and its reader then asks
for it by name; the user read "could not read it: the file lacks the entry "Column 'force' not
defined!" that the reader looks up", and was told to give metadata."""

from __future__ import annotations

from pathlib import Path

import pytest

from afmforce.errors import FileFormatError
from afmforce.io import load

SRC = Path(__file__).resolve().parents[1] / "data" / "afm-workshop_single.csv"


@pytest.mark.parametrize("cell", ["nan", "NaN"])
def test_a_nan_force_cell_is_named(tmp_path, cell):
    pytest.importorskip("afmformats")
    lines = SRC.read_text(encoding="latin-1").splitlines()
    rows = [i for i, ln in enumerate(lines) if ln[:1].isdigit() or ln[:2].lstrip("-")[:1].isdigit()]
    i = rows[len(rows) // 2]
    sep = "\t" if "\t" in lines[i] else ","
    cells = lines[i].split(sep)
    cells[-1] = cell
    lines[i] = sep.join(cells)
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(lines) + "\n", encoding="latin-1")
    assert len(load(SRC)) == 1
    with pytest.raises(FileFormatError) as exc:
        load(bad)
    text = str(exc.value)
    assert "column force has empty or non-numeric cells (nan)" in text and "lacks the entry" not in text
    assert "remove those rows" in text
