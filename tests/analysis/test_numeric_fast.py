"""The compiled replacements of numpy calls in the analysis (issue 35 item 2) give numpy's numbers.

Each is checked against the numpy or LAPACK call it replaces, on the shapes the steps use and on
the ill-conditioned inputs where it must hand over to numpy.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from afmforce.analysis import contact_point as cp
from afmforce.analysis import drift as dr
from afmforce.analysis import fringes as fr
from afmforce.analysis._numeric import lstsq_qr, polyfit, ptp


@pytest.mark.parametrize("deg", [1, 2, 3])
def test_polyfit_equals_numpy(deg):
    rng = np.random.default_rng(deg)
    for _ in range(40):
        n = int(rng.integers(deg + 2, 3000))
        scale, offset = 10.0 ** rng.uniform(-9, 2), rng.uniform(-1, 1) * 10.0 ** rng.uniform(-9, 2)
        x = np.sort(rng.uniform(-1, 1, n)) * scale + offset
        y = rng.normal(size=n) * 10.0 ** rng.uniform(-12, 2) + 3.0 * x
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the worst-scaled draws: both hand over to / are numpy's lstsq
            ours, theirs = polyfit(x, y, deg), np.polyfit(x, y, deg)
        fit_o, fit_t = np.polyval(ours, x), np.polyval(theirs, x)
        assert np.max(np.abs(fit_o - fit_t)) <= 1e-9 * np.max(np.abs(fit_t))


def test_polyfit_hands_ill_conditioned_input_to_numpy():
    x = 1.0 + np.linspace(0, 1e-10, 50)  # the two columns equal to 1e-10: the QR would lose 6 digits
    y = np.linspace(0, 1, 50)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert np.array_equal(polyfit(x, y, 1), np.polyfit(x, y, 1))  # numpy's own answer


def test_lstsq_qr_equals_lapack():
    rng = np.random.default_rng(7)
    for n, m in ((20, 2), (400, 4), (3000, 3)):
        A = rng.normal(size=(n, m))
        b = rng.normal(size=n)
        x, ok = lstsq_qr(A, b)
        assert ok
        np.testing.assert_allclose(x, np.linalg.lstsq(A, b, rcond=None)[0], rtol=1e-12, atol=1e-14)
    A = np.column_stack([np.ones(30), np.ones(30) + 1e-13 * np.arange(30)])
    assert not lstsq_qr(A, np.arange(30.0))[1]  # rank-deficient to rounding: the caller uses LAPACK


def test_ptp_equals_numpy():
    a = np.random.default_rng(3).normal(size=1001)
    assert ptp(a) == np.ptp(a)
    assert ptp(np.arange(5)) == np.ptp(np.arange(5))


@pytest.mark.parametrize("case", ["fringes", "noise", "chirp"])
def test_compiled_periodogram_equals_numpy(case):
    rng = np.random.default_rng(11)
    z = np.sort(rng.uniform(0, 4e-6, 1500))
    r = rng.normal(scale=0.02, size=z.size)
    if case == "fringes":
        r += 0.3 * np.cos(2 * np.pi * z / 317e-9 + 0.4) + 0.1 * z / 4e-6
    elif case == "chirp":
        r += 0.2 * np.cos(2 * np.pi * (z + 0.1 * z**2 / 4e-6) / 500e-9)
    p_ref, f_ref = fr._periodogram(z, r)
    p, f = fr._periodogram_fast(z, r)
    assert p == p_ref  # a grid value: the fit starts from the same period
    assert f == pytest.approx(f_ref, rel=1e-12)
    if case == "fringes":
        assert p == pytest.approx(317e-9, rel=0.02) and f > 0.5


def _family_numpy(X, y, E, cap):
    """The settling-candidate search in numpy calls only (the code before issue 35)."""
    p = X.shape[1]
    c0 = dr._wls(X, y, np.ones(y.size)) if p else np.empty(0)
    r0 = y - X @ c0 if p else y
    best, coef, used = float(np.sum(np.minimum(r0 * r0, cap))), c0, -1
    K = E.shape[1]
    M = np.empty((K, p + 1, p + 1))
    rhs = np.empty((K, p + 1))
    M[:, :p, :p] = X.T @ X
    xe = X.T @ E
    M[:, :p, p] = xe.T
    M[:, p, :p] = xe.T
    M[:, p, p] = np.einsum("ij,ij->j", E, E)
    rhs[:, :p] = X.T @ y
    rhs[:, p] = E.T @ y
    C = np.linalg.solve(M, rhs[..., None])[..., 0]
    R = y[:, None] - X @ C[:, :p].T - E * C[:, p]
    costs = np.sum(np.minimum(R * R, cap), axis=0)
    costs[~(C[:, p] < 0)] = np.inf
    k = int(np.argmin(costs))
    if costs[k] < best:
        best, coef, used = float(costs[k]), C[k, :p], k
    return best, coef, used


@pytest.mark.parametrize("p", [0, 1, 2])
@pytest.mark.parametrize("settling", [False, True])
def test_compiled_settling_search_equals_numpy(p, settling):
    rng = np.random.default_rng(5 + p)
    t = np.linspace(0.0, 0.2, 300)
    y = 0.01 * rng.normal(size=t.size) + 0.3 * t
    if settling:
        y -= 0.5 * np.exp(-t / 0.01)  # a lever relaxing from below after the pull-off
    X = np.column_stack([np.ones_like(t), t / 0.2])[:, :p] if p else np.empty((t.size, 0))
    E = dr._transient(t)
    cap = (4.685 * 0.01) ** 2
    best, coef, used = dr._family(X, y, E, cap)
    best_ref, coef_ref, used_ref = _family_numpy(X, y, E, cap)
    assert used == used_ref and (used >= 0 or not settling)
    assert best == pytest.approx(best_ref, rel=1e-9)
    assert np.array_equal(coef, coef_ref)  # the line's coefficients: numpy's, bit for bit


def test_contact_grid_equals_direct_least_squares():
    rng = np.random.default_rng(2)
    x = np.linspace(0, 1, 300) + 0.002 * rng.normal(size=300)  # a measured approach: rising, not monotonic
    y = 0.1 * x + 4.0 * np.clip(x - 0.6, 0, None) ** 1.75 + 0.003 * rng.normal(size=300)
    cands = np.linspace(0.3, 0.9, 25)
    coef, rss = cp._fit_grid(x, y, cands, 1.75)
    for k, c in enumerate(cands):
        A = np.column_stack([np.ones_like(x), x, np.clip(x - c, 0, None) ** 1.75])
        sol, *_ = np.linalg.lstsq(A, y, rcond=None)
        np.testing.assert_allclose(coef[k], sol, rtol=1e-6, atol=1e-9)
        if sol[2] > 0:
            assert rss[k] == pytest.approx(np.sum((A @ sol - y) ** 2), rel=1e-6, abs=1e-12)
    assert abs(cands[int(np.argmin(rss))] - 0.6) < 0.05
