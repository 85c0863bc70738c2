"""Every recomputable number of the paper passes against the paper and our reference."""

import pytest

from afmforce.paper import CHECKS, evaluate_checks


@pytest.mark.parametrize("check", CHECKS, ids=[c.key for c in CHECKS])
def test_check_passes(check):
    (r,) = evaluate_checks((check,))
    assert r.ours == pytest.approx(check.reference, rel=check.reference_tolerance)
    if check.gate == "check":
        assert abs(r.ours - check.paper) <= check.tolerance * abs(check.paper)
    elif check.gate == "bound":
        assert r.ours <= check.paper
    assert r.passed


def test_a_wrong_value_fails():
    """The gates can fail: a check computed 30 % off the paper, a bound exceeded."""
    import dataclasses

    c = next(c for c in CHECKS if c.key == "constant_offset")
    (r,) = evaluate_checks((dataclasses.replace(c, compute=lambda: 1.3 * 0.76),))
    assert r.passed is False
    b = next(c for c in CHECKS if c.key == "bare_lever_R")
    (r,) = evaluate_checks((dataclasses.replace(b, compute=lambda: 0.2, reference=None),))
    assert r.passed is False
