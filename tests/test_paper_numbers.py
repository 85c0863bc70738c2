"""Every recomputable number of the paper passes against the paper and our reference."""

import pytest

from afmforce.paper import CHECKS, evaluate_checks


@pytest.mark.parametrize("check", CHECKS, ids=[c.key for c in CHECKS])
def test_check_passes(check):
    (r,) = evaluate_checks((check,))
    assert r.ours == pytest.approx(check.reference, rel=check.reference_tolerance)
    if check.paper is not None:
        assert abs(r.ours - check.paper) <= check.tolerance * abs(check.paper)
    assert r.passed
