"""The fringe search's padded power spectrum (issue 35 item 2) against a direct DFT.

:func:`afmforce.analysis.fringes._padded_power` takes pocketfft's route or Bluestein's chirp-z
(bins whose count has a large prime factor); both must give ``|sum_n y_n exp(-2 pi i k n / 8N)|^2``
of the zero-padded series, computed here term by term.
"""

from __future__ import annotations

import numpy as np
import pytest

from afmforce.analysis import fringes as fr


def _direct_power(y: np.ndarray) -> np.ndarray:
    nb = y.size
    n = np.arange(nb)
    k = np.arange(4 * nb + 1)
    phase = 2 * np.pi * ((np.outer(k, n)) % (8 * nb)) / (8 * nb)  # reduced exactly before the cosine
    return (np.cos(phase) @ y) ** 2 + (np.sin(phase) @ y) ** 2


@pytest.mark.parametrize("nb", [64, 97, 446, 733, 761])
def test_padded_power_equals_direct_dft(nb):
    uses_chirp = fr._largest_prime_factor(nb) > fr.CHIRP_PRIME
    assert uses_chirp == (nb in (446, 733, 761))
    rng = np.random.default_rng(nb)
    x = np.arange(nb)
    y = 0.3 * np.cos(2 * np.pi * x / 37.3 + 0.2) + rng.normal(scale=0.05, size=nb)
    ours, direct = fr._padded_power(y), _direct_power(y)
    assert ours.shape == direct.shape
    assert np.max(np.abs(ours - direct)) <= 1e-10 * direct.max()
    assert int(np.argmax(ours)) == int(np.argmax(direct))


def test_largest_prime_factor():
    assert [fr._largest_prime_factor(n) for n in (64, 102, 267, 446, 733, 1344)] == [2, 17, 89, 223, 733, 7]


@pytest.mark.parametrize("n", [733, 761])
def test_periodogram_of_a_prime_count_equals_numpy(n):
    """The search on a baseline of a prime number of samples (the chirp-z route) finds the period of
    the numpy periodogram (a grid value) and its fraction of the variance."""
    rng = np.random.default_rng(n)
    z = np.sort(rng.uniform(0, 3e-6, n))
    r = 0.2 * np.cos(2 * np.pi * z / 290e-9 + 0.3) + rng.normal(scale=0.03, size=n)
    p_ref, f_ref = fr._periodogram(z, r)
    p, f = fr._periodogram_fast(z, r)
    assert p == p_ref
    assert f == pytest.approx(f_ref, rel=1e-12)
    assert p == pytest.approx(290e-9, rel=0.02) and f > 0.5
