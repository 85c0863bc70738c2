"""A run's speed in one fit fewer, and the dead zone compiled: the same numbers (issue 35 item 2).

:meth:`afmforce.analysis.state.State.velocity` takes the slope :func:`~afmforce.analysis.dynamic.drive_start_slopes`
already fitted to the same samples (the run after its dead zone, or the whole run when the position is the
recorded one) instead of fitting that line again; the dead zone is found by the compiled
:func:`afmforce.analysis._speed_kernel.dead_zone`. Both are checked against the numpy functions they replace,
bit for bit (``==``): medians select samples, and the reused slope is the same robust line of the same arrays.
"""

from __future__ import annotations

import numpy as np
import pytest

from afmforce.analysis import _speed_kernel
from afmforce.analysis.dynamic import _slope, dead_zone, drive_start, drive_start_slopes, run_velocity
from afmforce.analysis.state import _velocity, prepare


def _arrays():
    """Ramps with and without a resting start, quantised (a sensor's steps), flat, short, with outliers."""
    rng = np.random.default_rng(35)
    out = []
    for _ in range(3000):
        n = int(rng.integers(2, 400))
        k = int(rng.integers(0, n))
        rest = np.zeros(k) + rng.normal(0, 1e-3, k) * rng.integers(0, 2)
        z = np.concatenate([rest, np.linspace(0.0, 1.0, n - k) * rng.normal(1.0, 1.0)])
        if rng.random() < 0.3:
            z = np.round(z, int(rng.integers(1, 4)))   # equal steps: even counts, ties in the medians
        if rng.random() < 0.1:
            z[:] = 0.25
        if rng.random() < 0.1 and n > 3:
            z[rng.integers(0, n)] += 10.0
        out.append(z)
    return out


def test_compiled_dead_zone_is_numpys():
    zones = [(dead_zone(z), int(_speed_kernel.dead_zone(z))) for z in _arrays()]
    assert all(a == b for a, b in zones)
    assert sum(a > 0 for a, _ in zones) > 100           # the zone is found on many, not only the trivial 0
    assert _speed_kernel.dead_zone(np.array([0.0, np.nan] + [1.0] * 40)) == -1   # not finite: numpy's decides


@pytest.fixture(scope="module")
def paper_curve():
    from afmforce.dynamics import simulate
    from afmforce.instrument import build_instrument

    return build_instrument("paper").record(simulate(velocity=8e-6), seed=1)


def test_slopes_are_the_ones_drive_start_compared(paper_curve):
    """``drive_start_slopes`` gives drive_start's start and the robust slopes of the whole run and of the rest."""
    for which in (0, 1):
        idx = np.flatnonzero(np.asarray(paper_curve.segment) == which)
        t, zm = np.asarray(paper_curve.time, float)[idx], np.asarray(paper_curve.piezo_measured, float)[idx]
        k, whole, rest = drive_start_slopes(t, zm)
        assert k == drive_start(t, zm)
        kz = dead_zone(zm)
        assert kz > 0
        assert whole == _slope(t, zm) and rest == _slope(t[kz:], zm[kz:])
        assert drive_start_slopes(t, zm, kz) == (k, whole, rest)
    assert drive_start_slopes(np.arange(50.0), np.arange(50.0)) == (0, *drive_start_slopes(np.arange(50.0),
                                                                                             np.arange(50.0))[1:])


def _three_fits(st, idx):
    """The speed as it was computed before: drive_start, then a third robust line on the chosen samples."""
    t, z = st.time[idx], st.z[idx]
    zm = np.asarray(st.curve.piezo_measured, float)[idx]
    k = drive_start(t, zm)
    if k:
        t, z = t[k:], zm[k:]
    return _velocity(t, z)


def test_velocity_reuses_the_fit_and_keeps_the_number(paper_curve):
    """The paper preset: the approach's dead zone is left out (the rest's slope reused), the retract's kept
    (the whole run's slope reused: the state's position is the recorded one before any step); after a step
    changes the positions (here: shifted by 1 nm) the line is fitted on them, as before."""
    st = prepare(paper_curve)
    assert st.channel == "measured"
    for which in (0, 1):
        idx = st.run_index(which)
        st.cache.clear()
        assert st.velocity(idx) == _three_fits(st, idx)
        assert st.velocity(idx) == pytest.approx(run_velocity(st.time[idx], st.z[idx], measured=True), rel=1e-12)
    moved = st.update(z=st.z + 1e-9)
    for which in (0, 1):
        idx = moved.run_index(which)
        moved.cache.clear()
        assert moved.velocity(idx) == _three_fits(moved, idx)
