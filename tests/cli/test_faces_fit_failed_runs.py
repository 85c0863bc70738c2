"""A fit whose best point is a failed run of the model is refused, not printed (faces audit,
2026-11-29). ``afmforce fit bruker-nanoscope_sapphire_TAP525.001 --free hamaker --xi 0`` (the one-speed
refusal's own advice, typed as it says) exited 0 with a table of a failed run: chi2 504,000,000 for
504 points (the search's penalty, :data:`afmforce.fit.model.FAILED_RESIDUAL` = 1e3 a sample), the
curve's offset and drift ``nan``, A at its search bound with std. error ``nan``, "likelihood ratio
nan, p = nan". Now: one ``error:`` line, exit 1, nothing printed on stdout as a result."""

from __future__ import annotations

import json
import re
from pathlib import Path

from afmforce.cli.main import main

SAPPHIRE = Path(__file__).parents[1] / "data" / "bruker-nanoscope_sapphire_TAP525.001"


def test_a_fit_at_a_failed_run_is_one_error_line(capsys):
    code = main(["fit", str(SAPPHIRE), "--free", "hamaker", "--xi", "0", "--no-profile", "--json"])
    cap = capsys.readouterr()
    assert code == 1, cap.err
    lines = [line for line in cap.err.splitlines() if not line.startswith("warning:")]
    assert len(lines) == 1 and lines[0].startswith("error: the model could not be integrated"), cap.err
    out = json.loads(cap.out)                      # --json: one object, the error's
    assert out["error"]["type"] == "SolverError" and not re.search(r"(?<![A-Za-z])nan(?![A-Za-z])", cap.out)
