"""spike_window = 0 (the spike not asked for): fewer steps, every other event unchanged.

Tolerances are the issue-16 equal-accuracy ones against the tight reference
(approach <= 0.01 nm, pull-off <= 0.5 nm, hysteresis <= 0.005 nm).
"""

import math

import pytest

from afmforce.dynamics import simulate
from afmforce.errors import ParameterError

NM = 1e-9


def _close(a, b):
    assert abs(a.min_apparent_deflection - b.min_apparent_deflection) <= 0.01 * NM
    assert abs(a.jump_in_position - b.jump_in_position) <= 0.01 * NM
    assert abs(a.pull_off_position - b.pull_off_position) <= 0.5 * NM
    assert abs(a.hysteresis_offset - b.hysteresis_offset) <= 0.005 * NM
    assert abs(a.pull_off_force - b.pull_off_force) <= 1e-3 * abs(b.pull_off_force)


def test_fig5_without_spike_matches_the_tight_reference(fig5, fig5_tight):
    fast = simulate(spike_window=0.0)
    e = fast.events
    assert math.isnan(e.spike_height) and math.isnan(e.spike_time)
    _close(e, fig5_tight.events)
    assert fast.solver.steps < fig5.solver.steps / 2     # 1.1k vs 3.7k steps


@pytest.mark.parametrize("xi, v", [(0.01, 0.1e-6), (0.01, 1e-6), (0.1, 1e-6)])
def test_fig6_runs_without_spike_keep_their_events(xi, v):
    ref = simulate(xi=xi, velocity=v, atol=1e-14)
    fast = simulate(xi=xi, velocity=v, spike_window=0.0)
    _close(fast.events, ref.events)
    assert math.isfinite(ref.events.spike_height) and math.isnan(fast.events.spike_height)


def test_negative_window_is_refused():
    with pytest.raises(ParameterError, match="spike_window"):
        simulate(spike_window=-1e-3)
