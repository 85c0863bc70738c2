"""The fringe fit's compiled variable projection (``analysis._fringe_kernel``, issue 35 item 2)
against plain numpy and scipy: the residual and Kaufman's Jacobian of one evaluation, and the
minimum the Levenberg-Marquardt loop reaches against ``scipy.optimize.least_squares`` on the full
(linear and nonlinear) model."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import least_squares

from afmforce.analysis._fringe_kernel import _prepare, lm_fit, vp_eval

P0 = 150e-9


def _chirped_run(n=400, a2=0.04, noise=0.002):
    rng = np.random.default_rng(5)
    z = np.linspace(1.0e-6, 2.2e-6, n)
    prep0 = _prepare(z, np.zeros(n), None, 1.0)
    x = prep0.x
    u = prep0.zm + prep0.L * (x + a2 * x * x)
    r = 0.02 * np.cos(2 * np.pi * u / 152e-9 + 0.4) + 0.003 + 0.001 * x + noise * rng.standard_normal(n)
    return z, r, _prepare(z, r, None)


def _numpy_vp(q, p, known=False, period=0.0):
    """Residual, half SSR and Kaufman's Jacobian of the projected model, in numpy calls."""
    c1, P = (q[0], period) if known else (1.0, P0 * math.exp(q[0]))
    a2, a3 = (list(q[1:]) + [0.0, 0.0])[:2]
    w = 2 * math.pi / P
    poly = p.x + a2 * p.x2 + a3 * p.x3
    th = w * (p.zm + c1 * p.L * poly)
    C = np.column_stack([np.cos(th), np.sin(th)])
    Cp = C - p.Q0 @ (p.Q0.T @ C)
    A = Cp.T @ Cp
    A += (1e-12 * np.trace(A) + 1e-300) * np.eye(2)
    Ai = np.linalg.inv(A)
    coef = Ai @ (Cp.T @ p.r_perp)
    res = Cp @ coef - p.r_perp
    gd = C[:, 1] * coef[0] * -1.0 + C[:, 0] * coef[1]  # d(C coef)/dtheta
    dth = [w * p.L * poly if known else -th, w * c1 * p.L * p.x2, w * c1 * p.L * p.x3][:q.size]
    J = np.empty((p.x.size, q.size))
    for j, d in enumerate(dth):
        V = gd * d
        Vp = V - p.Q0 @ (p.Q0.T @ V)
        J[:, j] = Vp - Cp @ (Ai @ (Cp.T @ Vp))
    return res, 0.5 * float(res @ res), J


@pytest.mark.parametrize("q", [[0.01], [0.013, 0.03], [0.013, 0.03, -0.01]])
def test_one_evaluation_equals_numpy(q):
    z, r, p = _chirped_run()
    q = np.array(q)
    res, J = np.empty(z.size), np.empty((z.size, q.size))
    cost = vp_eval(q, False, P0, 0.0, q.size - 1, p.x, p.x2, p.x3, p.zm, p.L, p.Q0, p.r_perp, res, J, True, False)
    res_np, cost_np, J_np = _numpy_vp(q, p)
    assert cost == pytest.approx(cost_np, rel=1e-10)
    assert np.max(np.abs(res - res_np)) <= 1e-10 * np.max(np.abs(res_np))
    for j in range(q.size):
        assert np.max(np.abs(J[:, j] - J_np[:, j])) <= 1e-9 * np.max(np.abs(J_np[:, j]))


def test_known_period_evaluation_equals_numpy():
    z, r, p = _chirped_run()
    q = np.array([0.99, 0.03])
    res, J = np.empty(z.size), np.empty((z.size, 2))
    cost = vp_eval(q, True, P0, 152e-9, 1, p.x, p.x2, p.x3, p.zm, p.L, p.Q0, p.r_perp, res, J, True, False)
    res_np, cost_np, J_np = _numpy_vp(q, p, known=True, period=152e-9)
    assert cost == pytest.approx(cost_np, rel=1e-10)
    assert np.max(np.abs(J - J_np)) <= 1e-9 * np.max(np.abs(J_np))


def test_fit_reaches_scipy_least_squares_minimum():
    """The quadratic map on a chirped run: LM on the projected problem and scipy's trust region on
    all six parameters (p, q, e0, e1 with the map) find the same period and a2."""
    z, r, p = _chirped_run(noise=0.0005)
    q, cost, status = lm_fit(np.array([0.0, 0.0]), False, P0, 0.0, 1, p.x, p.x2, p.x3, p.zm, p.L, p.Q0,
                             p.r_perp, 200, 1e-14, 1e-14, False)
    assert status == 1

    def full(v):
        P, a2, cp, sp, e0, e1 = v
        u = p.zm + p.L * (p.x + a2 * p.x2)
        th = 2 * math.pi * u / (P * 1e-9)
        return cp * np.cos(th) + sp * np.sin(th) + e0 + e1 * p.x - r

    ref = least_squares(full, [P0 * math.exp(q[0]) * 1e9 * 1.001, q[1] * 0.9, 0.01, 0.01, 0.0, 0.0],
                        xtol=1e-15, ftol=1e-15, gtol=1e-15, method="lm")
    assert P0 * math.exp(q[0]) == pytest.approx(ref.x[0] * 1e-9, rel=1e-8)
    assert q[1] == pytest.approx(ref.x[1], rel=1e-6)
    assert cost == pytest.approx(0.5 * np.sum(ref.fun ** 2), rel=1e-8)
    assert P0 * math.exp(q[0]) == pytest.approx(152e-9, rel=1e-3) and q[1] == pytest.approx(0.04, rel=0.05)


def test_thinning_equals_numpy():
    """The evenly thinned samples of the nonlinear fit: numpy's linspace, rounded, deduplicated."""
    from afmforce.analysis._fringe_kernel import _thin_indices

    rng = np.random.default_rng(9)
    cases = [(n, m) for n in (17, 201, 401, 1344, 4001, 11935) for m in (2, 3, 200, 201, n - 1)]
    cases += [(int(n), int(rng.integers(2, n))) for n in rng.integers(17, 100_000, 300)]
    for n, m in cases:
        if 2 <= m < n:
            expected = np.unique(np.linspace(0, n - 1, m).round().astype(np.int64))
            assert np.array_equal(_thin_indices(n, m), expected), (n, m)
