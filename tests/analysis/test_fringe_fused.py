"""The fringe fit's fused compiled parts (issue 35 item 2) give the numbers of the code they replace,
to the bit: ``fit_orders`` (the map orders and their starts in one call) against the per-order loop
written here in Python around the same ``lm_fit``; ``variance`` and ``finish_stats`` against numpy's
``var``, ``mean``, ``polyval`` and ``max`` (numpy's pairwise summation, also as plain Python: the
first run's ``NUMBA_DISABLE_JIT``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce.analysis import _fringe_kernel as K
from afmforce.analysis.fringes import MAX_NFEV


def _orders_in_python(p, P0, period, o_first, o_last):
    """The former ``fit_fringes`` loop: each order warm-started from the lower one when that converged,
    the cubic from a3 = 0 and from +-0.05 while its cost does not beat the lower order's, the best
    order by BIC (the first of equals)."""
    known = bool(period)
    n = p.x.size
    fits = []
    for o in range(o_first, o_last + 1):
        n_map = max(0, min(o, 3) - 1)
        ref = 0.5 * n * fits[-1]["res"] ** 2 if fits and math.isfinite(fits[-1]["res"]) else None
        warm = fits[-1] if fits and fits[-1]["conv"] and math.isfinite(fits[-1]["P"]) else None
        q0 = np.zeros(1 + n_map)
        q0[0] = 1.0 if known else 0.0
        if warm is not None:
            q0[0] = warm["c1"] if known else math.log(warm["P"] / P0)
            if n_map >= 1:
                q0[1] = warm["a2"]
        best = None
        for a3 in (0.0,) if n_map < 2 else (0.0, 0.05, -0.05):
            q = q0.copy()
            if n_map >= 2:
                q[2] = a3
            qs, cost, status = K.lm_fit(q, known, float(P0), float(period or 0.0), n_map, p.x, p.x2, p.x3,
                                        float(p.zm), float(p.L), p.Q0, p.r_perp, MAX_NFEV, 1e-6, 1e-7, False)
            if best is None or cost < best[1]:
                best = (qs, cost, status)
            if ref is not None and best[1] < ref:
                break
        qs, cost, status = best
        c1, P = (qs[0], float(period)) if known else (1.0, P0 * math.exp(qs[0]))
        fits.append({"P": P, "c1": c1, "a2": qs[1] if n_map >= 1 else 0.0, "a3": qs[2] if n_map >= 2 else 0.0,
                     "res": math.sqrt(2.0 * cost / n), "conv": status > 0})
    bic = [n * math.log(max(f["res"], 1e-300) ** 2) + (o + 3) * math.log(n) if math.isfinite(f["res"]) else math.inf
           for o, f in zip(range(o_first, o_last + 1), fits)]
    f = fits[int(np.argmin(bic))]
    return f["P"], f["c1"], f["a2"], f["a3"], f["conv"], f["res"]


def _run(seed, n, a2, a3, amp, known):
    rng = np.random.default_rng(seed)
    z = np.linspace(1.0e-6, 2.2e-6, n)
    x = (z - 1.6e-6) / 0.6e-6
    u = 1.6e-6 + 0.6e-6 * (x + a2 * x * x + a3 * x ** 3)
    r = amp * np.cos(2 * np.pi * u / 152e-9 + 0.4) + 0.001 * x + 0.002 * rng.standard_normal(n)
    t = np.linspace(0.0, 0.5, n) if seed % 2 else None
    return K._prepare(z, r, t), (152e-9 if known else 0.0)


@pytest.mark.parametrize("seed,n,a2,a3,amp,known,P0", [
    (1, 400, 0.04, 0.0, 0.02, False, 149e-9),   # clean chirped fringes: every order converges
    (2, 300, 0.3, -0.2, 0.02, False, 149e-9),   # a strongly bent map: fits that spend their budget
    (3, 250, 0.0, 0.0, 0.0, False, 149e-9),     # noise only
    (4, 500, 0.1, 0.05, 0.01, True, 152e-9),    # known period: the scale c1 fitted
    (2, 200, 0.0, 0.0, 0.003, False, 447e-9),   # a start far off: the cubic's three starts, none converges
    (9, 200, 1.5, 0.0, 0.003, False, 745e-9),   # the cubic's third start converges
    (12, 200, 0.0, 0.0, 0.003, False, 447e-9),  # the linear map wanders: the quadratic starts cold
])
def test_fit_orders_equals_the_per_order_loop(seed, n, a2, a3, amp, known, P0):
    p, period = _run(seed, n, a2, a3, amp, known)
    for o_first, o_last in ((1, 3), (2, 2), (3, 3), (1, 1)):
        want = _orders_in_python(p, P0, period, o_first, o_last)
        got = K.fit_orders(o_first, o_last, known, P0, period, p.x, p.x2, p.x3, float(p.zm), float(p.L), p.Q0,
                           p.r_perp, MAX_NFEV, 1e-6, 1e-7, False)
        assert tuple(got[:6]) == tuple(want)  # the same floats, bit for bit (libm's cos and sin: fast False)


SIZES = [1, 2, 7, 8, 9, 15, 16, 17, 127, 128, 129, 255, 256, 257, 300, 1000, 1344, 4000, 4099]


@pytest.mark.parametrize("compiled", [True, False])
def test_variance_and_statistics_equal_numpy_to_the_bit(compiled):
    rng = np.random.default_rng(11)
    var = K._var if compiled else K._var.py_func
    stats = K._finish_stats if compiled else K._finish_stats.py_func
    for n in SIZES if compiled else SIZES[:-3]:
        a = rng.standard_normal(n) * 10.0 ** rng.uniform(-6, 6) + rng.uniform(-50, 50)
        assert var(a) == np.var(a)
        assert K.variance(a) == float(np.var(a))
        u, z = rng.standard_normal(n), rng.uniform(-1e-6, 1e-6, n)
        p = np.array([rng.normal(), rng.normal()])
        dev, v, rms = stats(a, u, z, p[0], p[1])
        assert dev == np.max(np.abs(u - np.polyval(p, z)))
        assert v == np.var(a)
        assert rms == np.sqrt(np.mean(a ** 2))
        assert K.finish_stats(a, u, z, p[0], p[1]) == (dev, v, rms)
    with pytest.warns(RuntimeWarning):
        assert math.isnan(K.variance(np.array([])))  # numpy's NaN and its warning for no samples


def test_statistics_propagate_nan():
    a = np.array([1.0, np.nan, 3.0] * 50)
    dev, v, rms = K.finish_stats(a, a, np.zeros(a.size), 0.0, 0.0)
    assert math.isnan(dev) and math.isnan(v) and math.isnan(rms)
