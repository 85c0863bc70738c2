"""A shift whose drift bound is wider than the shift itself is reported undetermined on every face: the
result's ``shift`` is NaN (JSON null, CSV empty), the table's cell says ``undetermined (+-B)``, the warning
gives the interval. One rule: :func:`afmforce.analysis.plausibility.undetermined`.

The shipped AFM Workshop export with a time base (``--meta sample_rate=1kHz``): its compliance lines are
69.5 nm apart, but the drift lines extrapolated from its free parts allow +-290 nm; before this rule the table
printed ``69.53`` nm and the JSON ``"shift": 6.95e-08``.
"""

from __future__ import annotations

import json
import math

import pytest

from afmforce.analysis.plausibility import undetermined
from afmforce.cli.main import main

ARGS = ["analyze", "--example", "workshop", "--meta", "sample_rate=1kHz"]


def test_rule():
    assert undetermined(69.5e-9, 290e-9)                  # the interval holds both signs
    assert not undetermined(69.5e-9, 20e-9)               # a number with its error
    assert not undetermined(0.1e-9, 0.3e-9, 0.5e-9)       # a small error on a small number: read to 0.5 nm
    assert not undetermined(1e-9, math.nan)               # no bound assessed: the number stands
    assert not undetermined(math.nan, 1e-9)


def test_workshop_shift_undetermined_everywhere(capsys, tmp_path):
    assert main(ARGS + ["--json"]) == 0
    d = json.loads(capsys.readouterr().out)["results"]["afm-workshop_single.csv"]
    assert d["shift"] is None
    assert d["shift_drift"] == pytest.approx(290e-9, rel=0.05)
    det = d["details"]["shift"]
    assert det["determined"] is False and det["shift"] == pytest.approx(69.5e-9, rel=0.01)
    assert any("shift undetermined" in w and "[-221, 360] nm" in w for w in d["warnings"])
    assert main(ARGS + ["--out", str(tmp_path)]) == 0      # the table, and the summary CSV beside it
    table = capsys.readouterr().out
    assert "undetermined (+-290)" in table and "69.5" not in table.splitlines()[1]
    import pandas as pd

    row = pd.read_csv(next(tmp_path.rglob("summary.csv")), comment="#").iloc[0]
    assert math.isnan(row["shift [m]"]) and row["shift_drift [m]"] == pytest.approx(290e-9, rel=0.05)
