"""`--fast-map` prints one line per warning, not one per number in it (review of 2026-11-29).

The Nanosurf 10 x 10 map with a 10 nm tip printed 36 lines "warning (1 of 100 curves): indentation 10.32 nm
exceeds 1 x the tip radius ..." (one per depth) and hid the others behind "... and 31 other warning(s)".
Reference: the count of pixels carrying the warning, counted here from the table's column by hand.
"""

from __future__ import annotations

import pandas as pd

from afmforce.cli._analyze_fast import warning_lines


def _table(cells):
    return pd.DataFrame({"warnings": cells})


def test_warnings_that_differ_in_their_numbers_are_one_line_with_their_count():
    deep = [f"indentation: indentation {d:.4g} nm exceeds 1 x the tip radius: the paraboloid law does not hold"
            for d in (10.32, 12.4, 11.83, 11.84, 10.04, 1.5e1)]
    other = "spring constant 200 N/m is outside the cantilevers made"
    cells = deep + [f"{deep[0]} | {other}", other, "", None]
    lines = warning_lines(_table(cells))
    assert len(lines) == 2, lines
    assert lines[0].startswith(f"  warning ({len(deep) + 1} of {len(cells)} curves, e.g.): indentation: indentation 10.32 nm")
    assert lines[1].startswith(f"  warning (2 of {len(cells)} curves): spring constant 200 N/m")


def test_one_text_is_not_marked_as_an_example():
    lines = warning_lines(_table(["the same warning 3 nm"] * 3))
    assert lines == ["  warning (3 of 3 curves): the same warning 3 nm"]


def test_different_words_stay_different_lines():
    lines = warning_lines(_table(["a 1 nm warning", "another 1 nm warning"]))
    assert len(lines) == 2
