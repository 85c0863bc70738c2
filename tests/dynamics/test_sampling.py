"""``sampling="average"``: each sample is the mean of the state over its interval.

Checked against an independent computation: a tight point-sampled run at 32x the
rate, averaged over each centred window by the trapezoid rule.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from afmforce.dynamics import SAMPLING, SimulationConfig, simulate
from afmforce.errors import ParameterError

FS = 5e3
M = 32
DRIVE = dict(start=-30e-9, turn=10e-9, end=-200e-9)   # Fig 5 beam (viscous friction), short cycle


@pytest.fixture(scope="module")
def runs():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        avg = simulate(sample_rate=FS, sampling="average", **DRIVE)
        point = simulate(sample_rate=FS, **DRIVE)
        fine = simulate(sample_rate=FS * M, rtol=1e-7, atol=1e-14, **DRIVE)
    return avg, point, fine


def _window_means(fine: np.ndarray, n: int) -> np.ndarray:
    ref = np.full(n, np.nan)
    for k in range(1, n):
        lo, hi = k * M - M // 2, k * M + M // 2
        if hi < fine.size:
            w = fine[lo:hi + 1]
            ref[k] = 0.5 * (w[1:] + w[:-1]).sum() / M
    return ref


def test_average_is_the_interval_mean(runs):
    avg, point, fine = runs
    assert avg.time.size == point.time.size
    np.testing.assert_array_equal(avg.segment, point.segment)
    ref = _window_means(fine.apparent_deflection, avg.time.size)
    # leave out the ringing that the jump-in, the turn and the pull-off excite, where the
    # 160 kHz reference cannot resolve the 367 kHz contact mode (or 41 kHz free mode) itself
    ev, t = avg.events, avg.time
    quiet = np.isfinite(ref)
    quiet &= ~((t > ev.jump_in_time - 2 / FS) & (t < ev.contact_time + 2 * avg.config.spike_window))
    quiet &= ~(np.abs(t - ev.turn_time) < 2e-3)
    quiet &= ~((t > ev.pull_off_time - 2e-3) & (t < ev.pull_off_time + 30e-3))
    assert quiet.sum() > 0.8 * t.size
    err = np.abs(avg.apparent_deflection - ref)[quiet]
    # the default run's own accuracy (atol 1 pm per step): its largest deviation, in the free
    # ringing after pull-off, moves between 0.5 and 4 pm when rtol or atol change by 1 %
    assert err.max() < 5e-3 * 1e-9            # measured: 0.5-4 pm max, 1e-9 nm median
    assert np.median(err) < 1e-6 * 1e-9
    # a point sample differs from the interval mean where the curve bends (contact, jump)
    assert np.nanmax(np.abs(point.apparent_deflection - ref)) > 10 * err.max()


def test_events_do_not_depend_on_sampling(runs):
    avg, point, _ = runs
    for name in ("jump_in_position", "contact_position", "pull_off_position", "pull_off_force",
                 "spike_height"):
        assert getattr(avg.events, name) == pytest.approx(getattr(point.events, name), rel=1e-9)


def test_sampling_registry_and_bad_name():
    assert set(SAMPLING) == {"point", "average"}
    assert SimulationConfig().sampling == "point"
    with pytest.raises(ParameterError, match="sampling must be one of"):
        SimulationConfig(sampling="boxcar")
