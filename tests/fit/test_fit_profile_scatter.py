"""A profile whose refits scatter gives no interval tighter than that scatter allows.

Found 2026-11-29 on the `typical` virtual AFM written as a NanoScope force volume (``simulate
--instrument typical --seed 3`` at 0.5, 2 and 8 um/s, ``afmforce fit`` as typed): the Hamaker
profile (Delta chi-square at 1, 2, 3, 4.5 standard errors) went 1.31, 0.61, 3.24, 4.90 below the
value and 1.85, 0.66, 3.39, 0.88, 1.47, 3.04, 1.19 above it. A profile cannot fall away from its
minimum: the falls (up to 2.5) are the short refits' error. The lower end was put at the first
point above 3.84, 2 % below the value, and the simulation's A (6 % below) lay outside it.

Reference: closed-form profiles ``Delta chi2 = ((v - best) / w)^2`` (the interval at 95 % is
``best +- 1.96 w`` exactly, the root being linear) with and without a known scatter added; the
refits are replaced by the closed form, so only the interval's logic is under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import chi2 as chi2_dist

from afmforce.fit import uncertainty
from afmforce.fit.params import PARAMETERS

BEST, SE = 5.3e-19, 3.0e-21
Z = math.sqrt(chi2_dist.ppf(0.95, 1))


class _Prob:
    free = ("hamaker", "xi")

    def unpack(self, x):
        return {"hamaker": float(x[0]) * PARAMETERS["hamaker"].scale, "xi": 0.1}, None


def _profile(monkeypatch, delta):
    """profile_interval of ``hamaker`` with the refit's chi-square ``delta(v)`` above the optimum."""
    monkeypatch.setattr(uncertainty, "_sub_problem", lambda prob, name, v: v)
    monkeypatch.setattr(uncertainty, "_refit", lambda v, x0, n: (100.0 + delta(v), np.asarray(x0)))
    x = np.array([BEST / PARAMETERS["hamaker"].scale, 1.0])
    return uncertainty.profile_interval(_Prob(), x, 100.0, "hamaker", SE, 1.0, 0.95)


def test_a_clean_profile_gives_the_closed_form_interval(monkeypatch):
    w = 2.0 * SE
    lo, hi, pts, note = _profile(monkeypatch, lambda v: ((v - BEST) / w) ** 2)
    assert lo == pytest.approx(BEST - Z * w, rel=1e-9) and hi == pytest.approx(BEST + Z * w, rel=1e-9)
    assert note == ""


def _scatter(v):
    """The refits' error: +2.5 at 1, 3 and 9 standard errors (a fall of up to 2.5 outward)."""
    k = round(abs(v - BEST) / SE * 2)     # half standard errors
    return 2.5 if k % 4 == 2 else 0.0


@pytest.mark.parametrize("w_se", [2.0, 4.0, 8.0])
def test_a_scattered_profile_is_never_tighter_than_the_clean_one(monkeypatch, w_se):
    """The interval with the scatter contains the scatter-free one (or is open), and says why."""
    w = w_se * SE
    lo, hi, pts, note = _profile(monkeypatch, lambda v: ((v - BEST) / w) ** 2 + _scatter(v))
    d = np.asarray(pts["delta_chi2"])
    assert np.any(np.diff(d[np.asarray(pts["value"]) >= BEST]) < -1.0)     # the profile does fall
    assert lo is None or lo <= BEST - Z * w * (1 - 1e-9)
    assert hi is None or hi >= BEST + Z * w * (1 - 1e-9)
    assert "scatter" in note


def test_the_found_case_no_end_two_percent_below(monkeypatch):
    """The measured profile points, flat above and noisy below: no lower end within 2 % now."""
    meas = {-4.5: 4.9039, -3: 3.2359, -2: 0.6112, -1: 1.3117, 1: 1.8471, 2: 0.6585, 3: 3.3908,
            4.5: 0.8817, 6.5: 1.4677, 9: 3.0397, 13: 1.1887}

    def delta(v):
        k = (v - BEST) / SE
        key = min(meas, key=lambda m: abs(m - k))
        if abs(key - k) < 1e-6:
            return meas[key]
        return 1.1887 if k > 0 else 4.9039 + 0.5 * (abs(k) - 4.5)   # beyond: flat above, rising below
    lo, hi, pts, note = _profile(monkeypatch, delta)
    assert hi is None                                      # flat above: open, as before
    assert lo is None or lo < BEST - 4.5 * SE              # not at the noisy 4.90 point any more


def test_a_scattered_profile_wider_than_13_standard_errors_is_followed_out(monkeypatch):
    """The curvature at the optimum says 1 standard error, the profile's width is 12 of them: with
    scatter the profile goes on past 13 (PROFILE_STEPS_FAR) and finds ends outside the clean ones."""
    w = 12.0 * SE
    lo, hi, pts, note = _profile(monkeypatch, lambda v: ((v - BEST) / w) ** 2 + _scatter(v))
    assert max(abs(v - BEST) for v in pts["value"]) > 13.5 * SE
    assert lo is not None and hi is not None
    assert lo <= BEST - Z * w and hi >= BEST + Z * w
    assert hi - lo < 2 * 50 * SE
