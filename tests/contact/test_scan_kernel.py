"""The compiled contact-point scan of the modulus fit (afmforce.contact._kernels): the unweighted fast
path gives the generic loop's numbers bit for bit, the scan the closed-form least squares, and the
one-call search the rounds of np.unique / np.linspace / scan it replaces."""

import math

import numpy as np
import pytest

from afmforce.contact._kernels import scan_power_law, search_power_law


def _curve(n, p, seed=1):
    rng = np.random.default_rng(seed)
    u = np.sort(rng.uniform(0.0, 1e-6, n)) + rng.normal(0.0, 2e-9, n)  # not monotonic: noise
    F = 2e3 * np.maximum(u - 6e-7, 0.0) ** p + rng.normal(0.0, 1e-11, n)
    return u, F


def _cands(u):
    lo, hi = u.min(), u.max()
    span = hi - lo
    return np.unique(np.concatenate((hi - span * np.geomspace(1e-3, 1.0, 64), np.linspace(lo, hi, 33)[1:-1])))


@pytest.mark.parametrize("p", [1.5, 2.0, 1.7])
def test_unweighted_fast_path_equals_generic_loop(p):
    u, F = _curve(700, p)
    c = _cands(u)
    fast = scan_power_law(u, F, c, 3.0, p, 0.0)            # ascending, unit weights: the fast path
    slow = scan_power_law(u, F, c[::-1].copy(), 3.0, p, 0.0)  # descending: the loop over every sample
    for a, b in zip(fast, slow):
        assert np.array_equal(a, b[::-1], equal_nan=True)


@pytest.mark.parametrize("width", [0.0, 5e-8])
def test_scan_is_the_weighted_least_squares(width):
    u, F = _curve(500, 1.5, seed=2)
    c = np.linspace(4e-7, 8e-7, 7)
    E, b, ssr = scan_power_law(u, F, c, 3.0, 1.5, width)
    for j, cj in enumerate(c):  # independent: lstsq on sqrt(w)-scaled columns
        d = u - cj
        w = np.ones_like(d) if width <= 0 else np.minimum(np.abs(d) / width, 1.0)
        phi = 3.0 * np.maximum(d, 0.0) ** 1.5
        A = np.column_stack((phi, np.ones_like(phi))) * w[:, None]
        (e, bb), *_ = np.linalg.lstsq(A, F * w, rcond=None)
        assert E[j] == pytest.approx(e, rel=1e-6)
        assert b[j] == pytest.approx(bb, rel=1e-6, abs=1e-16)
        r = F * w - A @ np.array([e, bb])
        assert ssr[j] == pytest.approx(float(r @ r), rel=1e-6, abs=1e-30)


@pytest.mark.parametrize("n,stride", [(900, 1), (4500, 2)])
def test_search_equals_the_rounds_it_replaces(n, stride):
    u, F = _curve(n, 1.5, seed=3)
    cands = np.concatenate((_cands(u), 6e-7 + 1e-6 * np.linspace(-0.02, 0.02, 9)))
    ok, c, E, b, s = search_power_law(u, F, cands, 3.0, 1.5, 0.0, stride)
    for rnd in range(4):  # fit._linear_fit's rounds as numpy writes them
        cands = np.unique(cands)
        us, Fs = (u[::stride].copy(), F[::stride].copy()) if rnd < 3 else (u, F)
        Er, br, sr = scan_power_law(us, Fs, cands, 3.0, 1.5, 0.0)
        i = int(np.argmin(sr))
        c0 = cands[i]
        cands = np.linspace(cands[max(i - 1, 0)], cands[min(i + 1, cands.size - 1)], 17)
    assert ok and (c, E, b, s) == (c0, Er[i], br[i], sr[i])
    assert c == pytest.approx(6e-7, abs=5e-9)
    assert math.isfinite(E) and E == pytest.approx(2e3 / 3.0, rel=0.05)


def test_search_refuses_a_curve_that_never_rises():
    u = np.linspace(0.0, 1e-6, 200)
    F = -1e-9 * u / 1e-6  # falling: no positive modulus anywhere
    ok, *_ = search_power_law(u, F, np.linspace(1e-8, 9e-7, 30), 3.0, 1.5, 0.0, 1)
    assert not ok
