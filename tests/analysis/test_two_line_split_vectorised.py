"""The contact split's search (:func:`afmforce.analysis._numeric.two_line_split`) gives the split it gave before its
loop was split in two (every split's residual sums first, then the first smallest: issue 35 item 2).

The reference is the earlier kernel, kept here verbatim (one loop doing both), compiled the same way; the
two must agree on every input, ties and flat parts included, and both find a clear break where it is.
"""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from afmforce.analysis._numeric import two_line_split


@njit
def _before(x, y, min_points):
    n = x.size
    if n < 2 * min_points:
        return -1
    mx = x.mean()
    my = y.mean()
    sx = 0.0
    sy = 0.0
    for i in range(n):
        sx = max(sx, abs(x[i] - mx))
        sy = max(sy, abs(y[i] - my))
    sx = sx if sx > 0 else 1.0
    sy = sy if sy > 0 else 1.0
    c = np.zeros((n + 1, 5))
    for i in range(n):
        u = (x[i] - mx) / sx
        v = (y[i] - my) / sy
        c[i + 1, 0] = c[i, 0] + u
        c[i + 1, 1] = c[i, 1] + v
        c[i + 1, 2] = c[i, 2] + u * u
        c[i + 1, 3] = c[i, 3] + u * v
        c[i + 1, 4] = c[i, 4] + v * v
    best = np.inf
    kbest = -1
    for k in range(min_points, n - min_points + 1):
        sse = 0.0
        for part in range(2):
            if part == 0:
                m = k
                s0, s1, s2, s3, s4 = c[k, 0], c[k, 1], c[k, 2], c[k, 3], c[k, 4]
            else:
                m = n - k
                s0 = c[n, 0] - c[k, 0]
                s1 = c[n, 1] - c[k, 1]
                s2 = c[n, 2] - c[k, 2]
                s3 = c[n, 3] - c[k, 3]
                s4 = c[n, 4] - c[k, 4]
            sxx = s2 - s0 * s0 / m
            sxy = s3 - s0 * s1 / m
            syy = s4 - s1 * s1 / m
            r = syy - (sxy * sxy / sxx if sxx > 1e-300 else 0.0)
            sse += max(r, 0.0)
        if sse < best:
            best = sse
            kbest = k
    return kbest


@pytest.mark.parametrize("seed", range(60))
def test_the_split_is_the_earlier_kernels(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(4, 3000))
    x = np.sort(rng.normal(size=n)) * 10.0 ** rng.integers(-9, 1)
    y = np.where(x > np.median(x), 3.0 * x, 0.0) + rng.normal(size=n) * 10.0 ** rng.integers(-12, -6)
    if seed % 3 == 0:
        y = np.round(y * 1e9) / 1e9          # a coarse ADC: ties
    if seed % 7 == 0:
        y[: n // 2] = 0.0                    # a flat, noise-free part
    if seed % 11 == 0:
        x[:] = 1.0                           # no spread in x: every split alike, the first wins
    min_points = int(rng.integers(1, max(2, n // 3)))
    assert two_line_split(x, y, min_points) == _before(x, y, min_points)


def test_a_clear_break_and_too_few_points():
    x = np.linspace(-1.0, 1.0, 401)
    y = np.where(x >= 0.2, 1.0 + 5.0 * (x - 0.2), 0.0)   # a jump at the break
    assert two_line_split(x, y, 10) == int(np.argmax(x >= 0.2)) == _before(x, y, 10)
    assert two_line_split(x[:15], y[:15], 8) == -1
