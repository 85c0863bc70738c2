"""The running median of a small window kept sorted (issue 35 item 2): scipy's ``median_filter`` (``mode="nearest"``),
the same numbers, on windows up to :data:`~afmforce.analysis._oscillation_kernel.SMALL_WINDOW` samples, with ties,
a coarse ADC's few levels, every start; a record with a NaN goes to the Fenwick tree as before."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.ndimage import median_filter

from afmforce.analysis._oscillation_kernel import SMALL_WINDOW, _running_median_nearest


@pytest.mark.parametrize("seed", range(30))
def test_small_windows_are_scipys(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 900))
    width = int(rng.choice([1, 3, 5, 9, 31, 101, SMALL_WINDOW - 1]))
    p = rng.normal(size=n)
    if seed % 2:
        p = np.round(p * 2.0) / 2.0          # a few levels: many ties
    ref = median_filter(p, size=width, mode="nearest")
    for start in sorted({0, 1, n // 3, n - 1, n}):
        assert np.array_equal(_running_median_nearest(p, width, start), ref[start:])


def test_a_record_with_a_nan_takes_the_tree():
    p = np.arange(40.0)
    p[30] = np.nan
    out = _running_median_nearest(p, 5, 0)   # returns (the search by value would not find a NaN)
    assert np.array_equal(out[:28], median_filter(p, size=5, mode="nearest")[:28])
