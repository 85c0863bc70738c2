"""The fringe fit's compiled kernel never divides by zero (issue 32, item 7): one curve of the
real NanoScope force volume took a Levenberg-Marquardt trial step to log(P/P0) < -745, where
P = P0 exp(q) underflows to 0 and 2 pi / P raised ZeroDivisionError, failing the whole file.
A trial step whose period under- or overflows is rejected (cost +inf), the fit goes on."""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce.analysis._fringe_kernel import _prepare, lm_fit, vp_eval


def _run(n: int = 400, period: float = 150e-9):
    rng = np.random.default_rng(3)
    z = np.linspace(0, 1.2e-6, n)
    r = 0.02 * np.cos(2 * np.pi * z / period + 0.4) + 0.002 * rng.standard_normal(n)
    return z, r, _prepare(z, r, None)


def test_trial_period_underflow_or_overflow_is_rejected_not_raised():
    z, r, p = _run()
    res, J = np.empty(z.size), np.empty((z.size, 1))
    for q0 in (-800.0, 800.0):  # exp(-800) = 0, exp(800) = inf
        cost = vp_eval(np.array([q0]), False, 150e-9, 0.0, 0, p.x, p.x2, p.x3, p.zm, p.L, p.Q0, p.r_perp,
                       res, J, False)
        assert cost == math.inf
    finite = vp_eval(np.array([0.0]), False, 150e-9, 0.0, 0, p.x, p.x2, p.x3, p.zm, p.L, p.Q0, p.r_perp,
                     res, J, True)
    assert 0 < finite < 0.5 * np.sum(p.r_perp ** 2) * 0.2  # the true period explains most of the variance


def test_fit_from_a_far_start_ends_without_error():
    """Started at log(P/P0) = -740 (P about 1e-321 m: the next steps underflow), LM returns a finite
    cost no worse than its start, or +inf for a start it cannot evaluate, never an exception."""
    z, r, p = _run()
    for start in (-740.0, 700.0, 0.2):
        q, cost, status = lm_fit(np.array([start]), False, 150e-9, 0.0, 0, p.x, p.x2, p.x3, p.zm, p.L, p.Q0,
                                 p.r_perp, 200, 1e-6, 1e-7)
        assert status in (0, 1) and (math.isinf(cost) or cost <= 0.5 * np.sum(p.r_perp ** 2))
    q, cost, _ = lm_fit(np.array([0.03]), False, 150e-9, 0.0, 0, p.x, p.x2, p.x3, p.zm, p.L, p.Q0, p.r_perp,
                        200, 1e-10, 1e-12)
    assert 150e-9 * math.exp(q[0]) == pytest.approx(150e-9, rel=0.01)  # converges to the period
