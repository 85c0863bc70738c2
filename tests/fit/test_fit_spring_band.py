"""The spring constant's plausible band is declared once, with the quantity, and the fit warns by it.

``afmforce._fields.QUANTITIES["spring_constant"]`` holds the valid range (a value outside is refused)
and ``plausible``, the cantilevers made (a value outside is accepted and warned about: the colleague's
``spring_constant=200`` for 0.2 N/m). The analysis's :data:`SPRING_CONSTANT_RANGE`, which the fit's
preparation warns by, is that declaration, not a second copy.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

import afmforce.datasets
from afmforce._fields import QUANTITIES
from afmforce.analysis.plausibility import SPRING_CONSTANT_RANGE
from afmforce.fit import prepare_curves
from afmforce.io.native.rawfile import read_raw

SPEC = QUANTITIES["spring_constant"]


def test_band_declared_once_inside_the_valid_range():
    assert SPRING_CONSTANT_RANGE is SPEC.plausible
    lo, hi = SPEC.plausible
    assert SPEC.lo < lo < hi < SPEC.hi


@pytest.fixture(scope="module")
def curve():
    # a packaged virtual curve (221 samples, k 0.1387 N/m): no simulation
    return read_raw(Path(afmforce.datasets.__file__).parent / "data" / "fit-speed-4.txt")


def _notes(curve, k: float) -> str:
    c = dataclasses.replace(curve, metadata={**curve.metadata, "spring_constant": k})
    return " ".join(prepare_curves([c])[0].metadata.get("preparation_notes", []))


def test_fit_warns_outside_the_declared_band(curve):
    lo, hi = SPEC.plausible
    assert SPEC.lo <= 200.0 <= SPEC.hi and not lo <= 200.0 <= hi      # valid, not plausible
    text = _notes(curve, 200.0)
    assert "outside the range of cantilevers made" in text and f"({lo:g}..{hi:g} N/m)" in text
    assert "cantilevers made" not in _notes(curve, curve.metadata["spring_constant"])
