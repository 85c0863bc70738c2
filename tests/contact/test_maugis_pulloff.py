"""Maugis-Dugdale's pull-off at fixed load across the transition parameter, against an independent solve of
Maugis's (1992) equations written here: for each m = c/a, A from the first equation by brentq (not the quadratic
formula the library uses), P from the second, and the load-controlled pull-off the minimum of P over m (bounded
scalar minimisation in ln(m - 1)). The library's value: the minimum over D of its exact branch
(:func:`afmforce.contact.adhesive.branch`). Limits: DMT -2 (lambda -> 0), JKR -3/2 (lambda -> infinity)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce.contact import adhesive as A

scipy_optimize = pytest.importorskip("scipy.optimize")


def _pull_off_independent(lam: float) -> float:
    def p_of(s: float) -> float:
        m = 1.0 + math.exp(s)
        q = math.sqrt(m * m - 1.0)
        at = math.atan(q)

        def first(a: float) -> float:   # Maugis's first equation, = 0
            return lam * a * a / 2 * (q + (m * m - 2) * at) + 4 * lam * lam * a / 3 * (q * at - m + 1) - 1

        hi = 1.0
        while first(hi) < 0:
            hi *= 2
        a = scipy_optimize.brentq(first, 0.0, hi, xtol=1e-15, rtol=1e-15)
        return a ** 3 - lam * a * a * (q + m * m * at)

    return scipy_optimize.minimize_scalar(p_of, bounds=(-25, 12), method="bounded", options={"xatol": 1e-12}).fun


def _pull_off_library(lam: float) -> float:
    d_end, _ = A.branch_end("maugis", lam)
    return scipy_optimize.minimize_scalar(lambda d: float(A.branch("maugis", np.array([d]), lam)[0][0]),
                                          bounds=(d_end, d_end + 5), method="bounded",
                                          options={"xatol": 1e-12}).fun


@pytest.mark.parametrize("lam,expected", [(0.01, -1.99829), (0.1, -1.95059), (0.3, -1.81556), (1.0, -1.60073),
                                          (3.0, -1.51676), (10.0, -1.50162), (100.0, -1.50002)])
def test_maugis_pull_off_equals_independent_solve(lam, expected):
    """Measured 2e-12 relative or better; P/(pi w R) from -2 (DMT) to -3/2 (JKR), -1.6007 at lambda = 1."""
    ind = _pull_off_independent(lam)
    assert _pull_off_library(lam) == pytest.approx(ind, rel=1e-9)
    assert ind == pytest.approx(expected, abs=1e-5)
    assert -2.0 < ind < -1.5
