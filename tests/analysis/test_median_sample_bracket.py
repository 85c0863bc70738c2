"""The robust line's medians without a bracket of their own (a first IRLS iteration) look among the values a
sample brackets first (:func:`afmforce.analysis._numeric._sample_bracket`): the same order statistics as a
selection over all of them, also where the sample's bracket misses (sorted, periodic, tied, outlying data)."""

from __future__ import annotations

import numpy as np

from afmforce.analysis._numeric import SAMPLE_BRACKET_MIN, _median_pair, _sample_bracket, middle_bracket


def _cases():
    rng = np.random.default_rng(352)
    for _ in range(1500):
        n = int(rng.integers(SAMPLE_BRACKET_MIN, 5000))
        kind = int(rng.integers(0, 8))
        if kind == 0:
            a = rng.normal(size=n)
        elif kind == 1:
            a = np.sort(rng.normal(size=n))                      # sorted: the sample is the data thinned
        elif kind == 2:
            a = np.round(rng.normal(size=n), 1)                  # ties at the middle
        elif kind == 3:
            a = np.where(np.arange(n) % 128 < 64, -1.0, 1.0) + 1e-3 * rng.normal(size=n)  # aliased with the step
        elif kind == 4:
            a = rng.standard_cauchy(size=n)
        elif kind == 5:
            a = np.full(n, 0.5)
        elif kind == 6:
            a = rng.normal(size=n)
            a[::n // 128] += 100.0                               # the sampled values alone far off: it misses
        else:
            a = np.concatenate([np.zeros(n // 2 + 1), np.ones(n - n // 2 - 1)])[rng.permutation(n)]
        yield a


def test_sample_bracket_gives_the_exact_middle():
    misses = 0
    for a in _cases():
        n = a.size
        half, even = n // 2, n % 2 == 0
        s = np.sort(a)
        want = (s[half - 1] if even else s[half], s[half])
        keep = a.copy()
        got = _median_pair(a, half, even, np.nan, np.nan, np.empty(n), True)
        assert got == want and np.array_equal(a, keep)
        lo_v, hi_v = _sample_bracket(a, half)
        misses += not middle_bracket(a, half, even, lo_v, hi_v, np.empty(n))[2]
    assert misses > 0          # the fallback (a selection over all) ran too: the adversarial draws


def test_given_bracket_narrow_then_wide_gives_the_exact_middle():
    """A bracket given (a later IRLS iteration's, about the previous median): its middle fifth first
    (:data:`~afmforce.analysis._numeric.NARROW`), then all of it, then a sample's, then every value."""
    rng = np.random.default_rng(353)
    for _ in range(1500):
        n = int(rng.integers(3, 3000))
        a = rng.normal(size=n) if rng.random() < 0.8 else np.round(rng.normal(size=n), 1)
        half, even = n // 2, n % 2 == 0
        s = np.sort(a)
        want = (s[half - 1] if even else s[half], s[half])
        centre = want[1] + rng.normal() * 10.0 ** rng.uniform(-3, 0.5)   # near it, off it, far off
        width = 10.0 ** rng.uniform(-3, 0.5)
        got = _median_pair(a, half, even, centre - width, centre + width, np.empty(n), True)
        assert got == want
