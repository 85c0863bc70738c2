"""The adhesion's baseline systematic in one compiled call (issue 35 item 2).

:func:`afmforce.analysis.unbinding.baseline_spread` runs
:func:`afmforce.analysis._adhesion_kernel.baseline_spread_core` when compiled: the same selections (the
free samples within the threshold of the line, the far half by the median) and the same two fits by
normal equations, summed in order where numpy's BLAS sums in an order of its own. Checked here against
the numpy code it replaces (the function with the kernels off) and, independently, against
``np.polyfit`` on the samples the docstring names.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce.analysis import unbinding
from afmforce.analysis._adhesion_kernel import baseline_spread_core
from afmforce.analysis.unbinding import baseline_spread


def _numpy(monkeypatch, *args):
    with monkeypatch.context() as m:
        m.setattr(unbinding, "COMPILED", False)
        return baseline_spread(*args)


def _case(seed: int):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(40, 3000))
    x = np.sort(rng.uniform(-50e-9, 400e-9, n))[::-1].copy()   # a retract from the contact outwards
    bend = rng.uniform(-3e-3, 3e-3) * (x / 400e-9) ** 2 * 1e-9 * rng.uniform(0, 5)
    y = 1e-9 * rng.uniform(-2, 2) + rng.uniform(-1e-3, 1e-3) * x + bend + rng.normal(0, 1e-11, n)
    y[rng.integers(0, n, 5)] -= 5e-10                              # glitches: left out by the threshold
    free = x > rng.uniform(0, 200e-9)
    a, b, xm = float(np.median(y[free])), float(rng.uniform(-1e-3, 1e-3)), float(x[free].mean()) if free.any() else 0.0
    j = int(rng.integers(0, n))
    thr = float(rng.uniform(2e-11, 2e-9))
    return x, y, free, a, b, xm, j, thr


@pytest.mark.parametrize("seed", range(40))
def test_compiled_spread_is_the_numpy_one(monkeypatch, seed):
    args = _case(seed)
    got, want = baseline_spread(*args), _numpy(monkeypatch, *args)
    if math.isnan(want):
        assert math.isnan(got)
    else:
        assert got == pytest.approx(want, rel=1e-10, abs=1e-24)


def test_the_spread_against_polyfit():
    """Independently of the code: the largest gap at the dip between the line and np.polyfit's quadratic
    through the kept free samples and its line through their far half."""
    x, y, free, a, b, xm, j, thr = _case(3)
    xf, yf = x[free], y[free]
    keep = np.abs(yf - (a + b * (xf - xm))) <= thr
    xf, yf = xf[keep], yf[keep]
    line = a + b * (x[j] - xm)
    quad = np.polyval(np.polyfit(xf, yf, 2), x[j])
    far = xf <= np.median(xf) if x[j] > xf.mean() else xf >= np.median(xf)
    lin = np.polyval(np.polyfit(xf[far], yf[far], 1), x[j])
    want = max(abs(quad - line), abs(lin - line))
    assert baseline_spread(x, y, free, a, b, xm, j, thr) == pytest.approx(want, rel=1e-6)


def test_few_samples_and_non_finite_ones(monkeypatch):
    x, y, free, a, b, xm, j, thr = _case(5)
    few = np.zeros_like(free)
    few[:9] = True
    assert math.isnan(baseline_spread(x, y, few, a, b, xm, j, 1.0))          # fewer than 10: NaN, as numpy
    y2 = y.copy()
    y2[np.flatnonzero(free)[0]] = np.nan
    assert not baseline_spread_core(x, y2, free, a, b, xm, j, thr)[1]       # handed back to numpy's code
    want = _numpy(monkeypatch, x, y2, free, a, b, xm, j, thr)
    got = baseline_spread(x, y2, free, a, b, xm, j, thr)
    assert (math.isnan(got) and math.isnan(want)) or got == want
