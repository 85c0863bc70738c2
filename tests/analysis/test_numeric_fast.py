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


def _robust_line_numpy(x, y, n_iter=6, tuning=4.685):
    """Tukey bisquare IRLS line as the textbook writes it, in numpy: ``np.median`` for the medians
    (``mad_sigma`` of the recentred residuals), the weighted line and the standard errors by sums
    taken in sample order (``np.cumsum``: the compiled loops' order, so the numbers are bitwise theirs)."""
    def total(v):
        return np.cumsum(v)[-1] if v.size else 0.0

    def line(w):
        sw = total(w)
        if sw <= 0:
            return np.nan, np.nan
        mx, my = total(w * x) / sw, total(w * y) / sw
        dx = x - mx
        sxx, sxy = total(w * dx * dx), total(w * dx * (y - my))
        if sxx <= 0:
            return my, np.nan
        return my - sxy / sxx * mx, sxy / sxx

    n = x.size
    w = np.ones(n)
    a, b = line(w)
    sigma = np.nan
    with np.errstate(all="ignore"):
        for _ in range(n_iter):
            r = y - (a + b * x)
            med = np.median(r) if n else np.nan
            a += med
            r = r - med
            sigma = 1.4826 * np.median(np.abs(r - np.median(r))) if n else np.nan
            if not sigma > 0:
                break
            u = r / (tuning * sigma)
            w_new = np.where(np.abs(u) < 1.0, (1.0 - u * u) ** 2, 0.0)
            if total(w_new) <= 2.0:
                break
            w = w_new
            a2, b2 = line(w)
            if not (np.isfinite(a2) and np.isfinite(b2)):
                break
            a, b = a2, b2
        sw = total(w)
        n_used = int(np.count_nonzero(w > 0))
        mx = total(w * x) / sw if sw > 0 else np.nan
        sxx = total(w * (x - mx) ** 2)
        ssr = total(w * (y - a - b * x) ** 2)
        s2 = ssr / max(sw, 1e-300) * n_used / max(n_used - 2, 1)
        se_b = np.sqrt(s2 / sxx) if sxx > 0 else np.nan
        se_a = np.sqrt(s2 * (1.0 / max(n_used, 1) + mx * mx / sxx)) if sxx > 0 else np.nan
    if not sigma > 0:
        sigma = np.sqrt(s2)
    return a, b, se_a, se_b, sigma, n_used


def _robust_cases(seed):
    """Lines with noise over 4 decades, spikes (zero weights), a coarse ADC (ties), 40 % one-sided
    outliers (medians that move far between iterations), two levels (a zero MAD), a NaN, an inf in x,
    a constant x, and the sizes 0-2."""
    rng = np.random.default_rng(seed)
    for n in (0, 1, 2, 3, 4, 5, 10, 11, 64, 999, 1000, 1400, 2001):
        for trial in range(7):
            x = np.sort(rng.uniform(-1, 1, n)) * 10.0 ** rng.uniform(-9, 0)
            y = 0.7 * x + rng.normal(size=n) * 10.0 ** rng.uniform(-12, -8)
            y[rng.integers(0, max(n, 1), n // 10)] += 1e-7
            if trial == 1:
                y = np.round(y * 1e10) / 1e10
            if trial == 2:
                y[rng.uniform(size=n) < 0.4] += 10.0 ** rng.uniform(-10, -6)
            if trial == 3:
                y = np.where(np.arange(n) < n // 2, 1.0, 2.0)
            if trial == 4 and n:
                y[rng.integers(0, n)] = np.nan
            if trial == 5 and n:
                x[rng.integers(0, n)] = np.inf
            if trial == 6:
                x = np.full(n, 0.5)
            yield x, y


@pytest.mark.parametrize("seed", [0, 1])
def test_robust_line_equals_the_numpy_irls(seed):
    from afmforce.analysis._numeric import robust_line, robust_line_thin

    for x, y in _robust_cases(seed):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            got, ref = robust_line(x, y), _robust_line_numpy(x, y)
        assert np.array_equal(np.array(got, float), np.array(ref, float), equal_nan=True), (x.size, got, ref)
        assert isinstance(got[5], int)
    x = np.linspace(0.0, 1e-6, 9001)
    y = 0.3 * x + 1e-10 * np.random.default_rng(seed).normal(size=x.size)
    keep = np.linspace(0, x.size - 1, 4001).astype(np.int64)  # robust_line_thin: 4001 samples of a long run
    assert robust_line_thin(x, y) == _robust_line_numpy(x[keep], y[keep])
