"""One rule decides whether a compliance line determines an InvOLS, for ``afmforce calibrate invols`` and for
``afmforce analyze`` where the slope would calibrate (:func:`afmforce.analysis.invols.line_notes`).

The shipped JPK calibration curve (raw volts, 204.8 Hz, no sensitivity stored) has 6 samples in its approach
line and a retract line 100 % off it: ``calibrate invols`` calls its InvOLS undetermined. Before,
``analyze --calibration fit`` used the slope's 932 nm/V over a sensitivity the user gave, with only a
"fitted on only 6 contact samples" warning; now the fit is refused and the user's 50 nm/V is kept, said in
a warning; without any other sensitivity the slope's is used and said to be undetermined.
"""

from __future__ import annotations

import json

import pytest

from afmforce.analysis.invols import MIN_POINTS, line_notes
from afmforce.cli.main import main

ARGS = ["analyze", "--example", "jpk-calibration", "--steps", "calibration", "--json", "--calibration", "fit"]
NAME = "jpk_calibration-curve_raw-volts.jpk-force"


def _analyze(capsys, *extra):
    assert main(ARGS + list(extra)) == 0
    return json.loads(capsys.readouterr().out)["results"][NAME]


def test_calibrate_invols_undetermined(capsys):
    assert main(["calibrate", "invols", "--example"]) == 0
    out = capsys.readouterr().out
    assert "undetermined" in out and f"only 6 samples in the approach compliance line (need {MIN_POINTS})" in out


def test_analyze_fit_refused_for_the_users_sensitivity(capsys):
    d = _analyze(capsys, "--sensitivity", "50nm/V")
    assert d["sensitivity_used"] == pytest.approx(50e-9, rel=1e-9)        # before: 9.32e-07 (the slope's)
    assert d["calibration_source"] == "metadata"
    w = [x for x in d["warnings"] if "InvOLS from the compliance slope undetermined" in x]
    assert len(w) == 1 and "refused" in w[0] and "only 6 samples" in w[0] and "apart" in w[0]


def test_analyze_without_another_sensitivity_says_undetermined(capsys):
    d = _analyze(capsys)
    assert d["calibration_source"] == "fit" and d["sensitivity_used"] == pytest.approx(932e-9, rel=0.01)
    assert d["details"]["calibration"]["determined"] is False
    assert any("InvOLS from the compliance slope undetermined" in x and "every separation and force" in x
               for x in d["warnings"])


def test_line_notes_closed_cases():
    from types import SimpleNamespace as NS

    def line(slope, n):
        return NS(slope=slope, n_points=n, found=n > 0)

    # slopes [V/m]: 2e7 V/m is 50 nm/V
    assert line_notes(NS(approach=line(2e7, 50), retract=line(2.1e7, 50)), "approach") == []   # 5 % apart
    notes = line_notes(NS(approach=line(2e7, 50), retract=line(1.5e7, 50)), "approach")        # 33 % apart
    assert len(notes) == 1 and "(33% apart)" in notes[0] and "50 and 66.67 nm/V" in notes[0]
    notes = line_notes(NS(approach=line(2e7, MIN_POINTS - 1), retract=line(0.0, 0)), "approach")
    assert len(notes) == 1 and f"only {MIN_POINTS - 1} samples" in notes[0]
