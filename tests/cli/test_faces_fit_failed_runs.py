"""A fit whose best point is a failed run of the model says so and prints no ``nan`` (faces audit,
2026-11-29). ``afmforce fit bruker-nanoscope_sapphire_TAP525.001 --free hamaker --xi 0`` (the one-speed
refusal's own advice, typed as it says) printed a failed run's table as a fit: chi2 504,000,000 for
504 points (the search's penalty, :data:`afmforce.fit.model.FAILED_RESIDUAL` = 1e3 a sample), the
curve's offset and drift ``nan``, A's std. error ``nan``, "likelihood ratio nan, p = nan", with only
"3 trial simulations failed during the fit" as a hint. Now a warning names the curve and says the
values are of no run of the model; every cell without a number is ``-``."""

from __future__ import annotations

import re
from pathlib import Path

from afmforce.cli.main import main

SAPPHIRE = Path(__file__).parents[1] / "data" / "bruker-nanoscope_sapphire_TAP525.001"
NAN = re.compile(r"(?<![A-Za-z])(nan|inf)(?![A-Za-z])", re.IGNORECASE)


def test_a_fit_at_a_failed_run_says_so_and_prints_no_nan(capsys):
    code = main(["fit", str(SAPPHIRE), "--free", "hamaker", "--xi", "0", "--no-profile"])
    cap = capsys.readouterr()
    assert code == 0, cap.err
    assert not NAN.search(cap.out), cap.out
    assert "the model could not be integrated at the fit's best parameters for " \
           "bruker-nanoscope_sapphire_TAP525.001" in cap.out
    assert "the values reported are of no run of the model, not a fit" in cap.err
    assert "undetermined" in cap.out           # and the verdict gives none
