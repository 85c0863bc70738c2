"""The caps of afmforce.limits: what a refusal names."""

from __future__ import annotations

from afmforce.cli.main import main


def test_a_long_dwell_is_named_among_what_to_change(capsys):
    """``simulate --dwell 1000s --sample-rate 100MHz``: 1e11 samples, all of them the dwell's; the
    message listed start, turn and end only (audit)."""
    assert main(["simulate", "--dwell", "1000s", "--sample-rate", "100MHz"]) == 2
    err = capsys.readouterr().err
    assert "about 1e+11 samples" in err and "--dwell" in err, err
