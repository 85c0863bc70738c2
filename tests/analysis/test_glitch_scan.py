"""The glitch search's compiled first pass (``_glue_kernel.glitch_scan``, issue 35 item 2) gives numpy's second
differences and robust noise bit for bit, and ``find_glitches`` the same indices with it as with its numpy path
(random walks over 15 decades, quantised signals, added glitches, a NaN)."""

from __future__ import annotations

import math

import numpy as np

from afmforce.analysis import glitches as G
from afmforce.analysis._glue_kernel import glitch_scan


def _signals(count=1500, seed=35):
    rng = np.random.default_rng(seed)
    for trial in range(count):
        n = int(rng.integers(5, 3000))
        s = np.cumsum(rng.standard_normal(n)) * 10 ** rng.uniform(-12, 3)
        if trial % 3 == 0:
            s = np.round(s / s.std() * 3) * 1e-9          # quantised: the noise from the step
        if trial % 5 == 0 and n > 10:
            for _ in range(int(rng.integers(1, 4))):
                s[rng.integers(2, n - 2)] += s.std() * rng.uniform(0, 2000)
        if trial % 97 == 0:
            s[rng.integers(0, n)] = np.nan
        yield s


def test_scan_equals_numpy_to_the_bit():
    scanned = 0
    for s in _signals():
        d2 = s[1:-1] - 0.5 * (s[:-2] + s[2:])
        out, sigma, hit, ok = glitch_scan(s, G.GLITCH_SIGMAS)
        if not ok:
            continue
        scanned += 1
        assert np.array_equal(out, d2)
        assert sigma == G._noise(s, d2) == 1.4826 * float(np.median(np.abs(d2 - np.median(d2)))) / math.sqrt(1.5)
        assert hit == bool(np.any(np.abs(d2[1:-1]) > G.GLITCH_SIGMAS * sigma))
    assert scanned > 500


def test_find_glitches_the_same_with_and_without_the_scan(monkeypatch):
    found = 0
    for s in _signals(600, seed=36):
        got = G.find_glitches(s)
        monkeypatch.setattr(G, "COMPILED", False)
        want = G.find_glitches(s)
        monkeypatch.setattr(G, "COMPILED", True)
        assert np.array_equal(got, want)
        found += got.size > 0
    assert found > 20
