"""The core steps' compiled kernels (``analysis._core_kernel``, issue 35 item 2) give the numbers of the numpy code
they replace, sample for sample: checked against that code run as written (the kernels' reference)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce.analysis import _core_kernel as CK
from afmforce.analysis import dynamic


def _dead_zone_numpy(zm: np.ndarray) -> int:
    """``dynamic.dead_zone``'s numpy path, as written there."""
    n = zm.size
    if n < 30:
        return 0
    d = np.abs(np.diff(zm))
    step = float(np.median(d[d > 0])) if np.any(d > 0) else 0.0
    d2 = np.diff(zm, 2)
    noise = float(np.median(np.abs(d2 - np.median(d2)))) * 1.4826 / math.sqrt(6.0)
    tol = 0.5 * step + 4.0 * noise
    moved = np.flatnonzero(np.abs(zm - zm[0]) > tol)
    if moved.size == 0:
        return 0
    k = int(moved[0]) - 1
    return k if k > 0 and n - k >= max(10, n // 3) else 0


def _ramps():
    rng = np.random.default_rng(7)
    for n in (30, 31, 64, 257, 2000):
        t = np.arange(n, dtype=float)
        yield 1e-6 * t + rng.normal(0, 1e-9, n)                       # a noisy ramp: no dead zone
        for k in (0, 3, n // 5, n // 2):                               # a ramp that starts after k samples at rest
            z = np.where(t < k, 0.0, (t - k) * 2e-9) + rng.normal(0, 2e-11, n)
            yield z
            yield np.round(z / 1e-10) * 1e-10                          # a sensor's steps (many equal differences)
        yield np.zeros(n)                                              # a sensor that never moves
        yield np.r_[np.zeros(n - 3), 1e-9, 2e-9, 3e-9]                 # moves at the very end only


@pytest.mark.parametrize("z", list(_ramps()), ids=lambda z: f"n{z.size}")
def test_dead_zone_kernel_is_the_numpy_path(z):
    assert dynamic.dead_zone(z) == _dead_zone_numpy(z)
    if CK.COMPILED:
        assert CK.dead_zone_kernel(np.ascontiguousarray(z)) == _dead_zone_numpy(z)


def test_a_dead_zone_is_found():
    """Not a test that agrees with itself only: a ramp resting for 40 of 300 samples has a dead zone there."""
    t = np.arange(300.0)
    z = np.where(t < 40, 0.0, (t - 40) * 1e-9)
    assert dynamic.dead_zone(z) == 40
