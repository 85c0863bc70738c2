"""analysis._median.median: np.median's number, bit for bit (the pipeline's checks use it; issue 35)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce.analysis._median import median


def _same(a: float, b: float) -> bool:
    """Equal bits: the same value and sign of zero, or both NaN."""
    return (math.isnan(a) and math.isnan(b)) or (a == b and math.copysign(1.0, a) == math.copysign(1.0, b))


@pytest.mark.parametrize("kind", ["normal", "ties", "signed_zeros", "scaled", "nan", "infinities", "tiny"])
def test_median_is_numpys(kind):
    rng = np.random.default_rng(abs(hash(kind)) % 2**32)
    for trial in range(3000):
        n = int(rng.integers(1, 40)) if trial % 10 else int(rng.integers(40, 2000))
        if kind == "normal":
            a = rng.normal(size=n)
        elif kind == "ties":
            a = rng.integers(-3, 4, size=n).astype(float)
        elif kind == "signed_zeros":  # np.mean of the middle pair starts from +0.0: a median of -0.0 is +0.0
            a = rng.choice([0.0, -0.0, 1.0, -1.0], size=n)
        elif kind == "scaled":
            a = rng.normal(size=n) * 10.0 ** float(rng.integers(-300, 300))
        elif kind == "nan":
            a = rng.normal(size=n)
            a[rng.integers(0, n)] = np.nan
        elif kind == "infinities":
            a = rng.normal(size=n)
            a[rng.integers(0, n, 2)] = [np.inf, -np.inf]
        else:
            a = rng.choice([-0.0, 0.0, 1e-300, -1e-300, 5e-324, -5e-324], size=n)
        with np.errstate(invalid="ignore"):
            want = float(np.median(a))
            got = median(a)
        assert _same(got, want), (kind, n, got, want)
        assert _same(median(a[::2]), float(np.median(a[::2]))) or a.size < 2  # a strided view


def test_median_other_inputs_go_to_numpy():
    assert median(np.array([3, 1, 2])) == 2.0                  # integers
    with pytest.warns(RuntimeWarning):                         # empty: numpy's own warning and NaN
        assert math.isnan(median(np.array([])))
    x = np.arange(12.0).reshape(3, 4)
    assert median(x) == float(np.median(x))                    # not 1-D
    assert median(np.array([1.0, 2.0], dtype=np.float32)) == float(np.median(np.array([1.0, 2.0], np.float32)))


def test_glitches_local_noise_uses_the_one_median_and_gives_numpys_number():
    """The glitch finder's local noise near the ends took its medians from a second helper (a sorted list):
    one median now (``analysis._median.median``), and every candidate's local noise is np.median's robust sigma
    of its window, bit for bit (the window as :data:`~afmforce.analysis.glitches._WINDOW` cuts it at the ends)."""
    from afmforce.analysis import glitches as G

    assert not hasattr(G, "_median")
    rng = np.random.default_rng(5)
    for trial in range(300):
        n = int(rng.integers(8, 80))
        d2 = rng.normal(size=n) if trial % 3 else rng.integers(-2, 3, size=n).astype(float) * 0.0
        cand = np.arange(n)
        got = G._local_noise(d2, cand)
        for i in cand.tolist():
            near = np.r_[d2[max(0, i - 1 - G.GLITCH_WINDOW): max(0, i - 2)], d2[i + 1: i + G.GLITCH_WINDOW]]
            want = (1.4826 * float(np.median(np.abs(near - float(np.median(near))))) / math.sqrt(1.5)
                    if near.size else 0.0)
            assert _same(float(got[i]), want), (trial, i)
