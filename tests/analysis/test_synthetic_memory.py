"""static_separation in row blocks: same numbers as one n x grid block, memory linear in n."""

import tracemalloc

import numpy as np
import pytest

from afmforce import forces
from afmforce.analysis import synthetic
from afmforce.constants import HAMAKER, Z0


def _sweep(n):
    half = n // 2
    z = np.concatenate([np.linspace(-60e-9, 30e-9, half), np.linspace(30e-9, -80e-9, n - half)])
    seg = np.concatenate([np.zeros(half, np.int8), np.ones(n - half, np.int8)])
    return z, seg


@pytest.mark.parametrize("rows", [1, 7, 256])
def test_blocks_equal_one_block_bitwise(monkeypatch, rows):
    z, seg = _sweep(3001)
    monkeypatch.setattr(synthetic, "_ROWS", 10**9)  # one block: the former n x grid computation
    whole = synthetic.static_separation(z, seg, spring_constant=0.21, radius=220e-9)
    monkeypatch.setattr(synthetic, "_ROWS", rows)
    blocked = synthetic.static_separation(z, seg, spring_constant=0.21, radius=220e-9)
    assert np.array_equal(whole, blocked)
    # and it is a static equilibrium: Fs(h) = k (h + z), both branches visited
    k = 0.21
    resid = forces.vdw_force(blocked, 1.0, hamaker=HAMAKER * 220e-9, z0=Z0) - k * (blocked + z)
    assert np.max(np.abs(resid)) < 1e-12 * np.max(np.abs(k * (blocked + z))) + 1e-15
    assert (blocked < 3 ** (1 / 6) * Z0).any() and (blocked > 3 ** (1 / 6) * Z0).any()


def test_peak_memory_linear_in_n():
    n = 20_000
    z, seg = _sweep(n)
    tracemalloc.start()
    try:
        synthetic.static_separation(z, seg, spring_constant=0.21, radius=220e-9)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    grid_block = synthetic._ROWS * 3000 * 8 * 4  # a few float64 row blocks of the 3000-point grid
    assert peak < grid_block + 400 * n  # the former n x 3000 float64 array alone: 480 MB here
