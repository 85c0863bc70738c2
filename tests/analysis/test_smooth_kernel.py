"""The smooth step's compiled running mean (analysis._smooth_kernel.smooth_runs, issue 35 item 2)
gives ``_numeric.running_mean`` of each run bit for bit (the step's numbers before the kernel), and
that running mean is the mean of each shrinking window to rounding (numpy, independently)."""

from __future__ import annotations

import numpy as np
import pytest

from afmforce.analysis import _smooth_kernel as SK
from afmforce.analysis._numeric import running_mean


def _window_means(x, w):
    half = w // 2
    return np.array([x[i - h:i + h + 1].mean() for i, h in
                     ((i, min(half, i, x.size - 1 - i)) for i in range(x.size))])


@pytest.mark.parametrize("window", [1, 3, 11, 25])
def test_runs_are_running_means(window):
    """Runs interleaved in the record (a pause before the approach, a dwell, samples of other
    segments left alone), runs shorter than the window, a run absent."""
    rng = np.random.default_rng(window)
    for layout in ([(3, 40), (0, 300), (2, 7), (1, 280), (2, 30)], [(0, 5), (1, 9), (0, 3)], [(1, 600)],
                   [(0, 12), (2, 1), (0, 12), (1, 2)]):
        seg = np.concatenate([np.full(m, g, np.int8) for g, m in layout])
        z = np.cumsum(rng.normal(1e-9, 1e-9, seg.size))
        out, change = SK.smooth_runs(z, seg, window)
        expect = z.copy()
        for g in (0, 1, 2):
            run = np.flatnonzero(seg == g)
            if run.size:
                expect[run] = running_mean(z[run], window)
                np.testing.assert_allclose(out[run], _window_means(z[run], window), rtol=1e-12, atol=1e-21)
        assert np.array_equal(out, expect)
        assert change == np.max(np.abs(out - z))
