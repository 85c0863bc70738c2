"""The compiled oscillation search (issue 35 item 2) gives the numbers of its numpy/scipy version.

:func:`afmforce.analysis.oscillation.find_peak` runs the kernels of ``_oscillation_kernel`` when
compiled; ``_find_peak_numpy`` (``np.polyfit``-equivalent detrend, ``np.hanning``,
``scipy.ndimage.median_filter``) is the independent computation of the same quantities.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.ndimage import median_filter

from afmforce.analysis import oscillation as osc
from afmforce.analysis._oscillation_kernel import _running_median_nearest


def _close(a: float, b: float) -> bool:
    return (math.isnan(a) and math.isnan(b)) or math.isclose(a, b, rel_tol=1e-12, abs_tol=0.0)


@pytest.mark.parametrize("case", ["line", "noise", "coloured", "short", "cubic"])
def test_find_peak_equals_numpy_version(case):
    rng = np.random.default_rng(len(case))
    n = {"short": 40}.get(case, 1500)
    t = 1.0 + np.arange(n) / 5000.0
    r = rng.normal(scale=1e-10, size=n)
    if case == "line":
        r += 3e-10 * np.sin(2 * np.pi * 640.0 * t + 0.3)
    elif case == "coloured":
        r = np.cumsum(r) * 0.1
    elif case == "cubic":
        r += 1e-8 * (t - 1.1) ** 3 + 2e-10 * np.sin(2 * np.pi * 900.0 * t)
    ours = osc.find_peak(t, r, 2e-6, "approach")
    theirs = osc._find_peak_numpy(t, r, 2e-6, "approach", min_cycles=osc._Osc.min_cycles,
                                  false_alarm=osc._Osc.false_alarm, max_nyquist_fraction=0.8)
    for f in dataclasses.fields(ours):
        a, b = getattr(ours, f.name), getattr(theirs, f.name)
        assert (a == b) if isinstance(a, (str, bool)) else _close(a, b), f.name
    if case == "line":
        assert ours.found and ours.frequency == pytest.approx(640.0, rel=2e-3)


@pytest.mark.parametrize("m,width", [(16, 9), (57, 9), (400, 41), (1000, 101), (300, 299)])
def test_running_median_equals_scipy(m, width):
    rng = np.random.default_rng(m)
    p = rng.exponential(size=m)
    p[::7] = p[3]  # ties
    assert np.array_equal(_running_median_nearest(p, width), median_filter(p, size=width, mode="nearest"))


def test_median_step_is_numpys():
    """The sample step of a run too short for a search (its Nyquist frequency) is
    np.median(np.diff(t[index])) exactly: even and odd counts, repeated stamps, uneven steps,
    a NaN stamp (NaN, as numpy's)."""
    from afmforce.analysis._oscillation_kernel import median_step

    rng = np.random.default_rng(4)
    for n in (2, 3, 4, 7, 8, 301, 1000):
        t = np.cumsum(rng.choice([0.0, 1e-4, 2e-4, 2.5e-4], size=n)) + 0.3
        for index in (np.arange(n), np.sort(rng.choice(n, max(2, n // 2), replace=False))):
            assert median_step(t, index) == np.median(np.diff(t[index]))
    t = np.arange(10) / 1e3
    t[4] = np.nan
    assert math.isnan(median_step(t, np.arange(10)))
