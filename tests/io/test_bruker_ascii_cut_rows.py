r"""A NanoScope ASCII export cut exactly at a line break (a truncated download) was read short without a word:
the header states the samples per run (``\Samps/line: 512 512`` in its force lists), so a table with fewer rows
is refused, "cut short: N of M rows". Only when every ``\Samps/line`` of the force lists gives one and the same
number: afmToolkit's ``file4`` says ``6656 6633`` and holds 6633 rows, which the header does not tie to a run.

Built on the real corpus file (fodis' ScanAsyst export, NanoScope 9.2, 512 rows), cut in the test."""

from __future__ import annotations

from pathlib import Path

import pytest

from afmforce.errors import FileFormatError
from afmforce.io import load

SRC = Path(__file__).resolve().parents[1] / "data" / "corpus" / "bruker-ascii_fodis_ScanAsyst-glass.txt"


def _cut(tmp_path: Path, keep: int, name: str = "cut.txt", edit=None) -> Path:
    """The file with only its first ``keep`` data rows, ending at a line break."""
    lines = SRC.read_bytes().splitlines(keepends=True)
    names = next(i for i, ln in enumerate(lines) if ln.startswith(b"Defl_"))   # the column names' row
    data = b"".join(lines[:names + 1 + keep])
    if edit:
        data = edit(data)
    path = tmp_path / name
    path.write_bytes(data)
    return path


def test_the_whole_file_states_its_rows():
    (c,) = load(SRC)
    assert b'"\\Samps/line: 512 512"' in SRC.read_bytes() and len(c.time) == 2 * 512   # extend and retract, each 512


@pytest.mark.parametrize("keep", (511, 300, 2))
def test_a_table_cut_at_a_line_break_is_refused_naming_the_rows(keep, tmp_path):
    path = _cut(tmp_path, keep)
    assert path.read_bytes().endswith(b"\n")          # cut at a line break: nothing else tells it
    with pytest.raises(FileFormatError, match=rf"cut short: {keep} of 512 rows .*copy or export it again"):
        load(path)


def test_all_rows_read_and_an_ambiguous_header_is_not_held_against_the_file(tmp_path):
    assert len(load(_cut(tmp_path, 512, "whole.txt"))[0].time) == 1024
    # the force lists disagree (as afmToolkit's file4: "6656 6633"): no count is stated for the table
    mixed = _cut(tmp_path, 300, "mixed.txt", lambda b: b.replace(b"Samps/line: 512 512", b"Samps/line: 512 300"))
    assert len(load(mixed)[0].time) == 600
