"""A small spring-model cycle on which the surface force laws' tests run the compiled model
against the independent scipy reference (afmforce.dynamics.reference)."""

import math
import warnings

import numpy as np
import pytest

from afmforce.dynamics import SimulationConfig, simulate
from afmforce.dynamics.reference import reference_solve

#: A 20 nm sphere on a flat on a 1 N/m spring, 10 um/s (a 9 ms cycle: the reference is slow),
#: the lever damped (Q = 2: the ringing after a jump dies out in a few periods).
CYCLE = dict(model="spring", spring_constant=1.0, mass=1e-11, radius=20e-9, geometry="sphere-flat",
             hamaker=1e-20, viscosity=0.0, velocity=10e-6, start=-30e-9, turn=3e-9, end=-60e-9,
             sample_rate=200e3, quality_factor=2.0)


def cycle_against_reference(**law_values):
    """(trajectory, reference solution, |deflection difference| per sample [m]) of one cycle with
    a law on; asserts what every law must meet: picometres before the jump-in, 0.05 nm overall
    (the undamped ringing after the jumps), the events to 0.05 nm."""
    cfg = SimulationConfig(**CYCLE, **law_values)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tr = simulate(cfg)
    ref = reference_solve(cfg, rtol=1e-9, atol=1e-15, sample_times=tr.time)
    n = min(len(ref.time), len(tr.time))
    err = np.abs(ref.deflection[:n] - tr.deflection[:n])
    e = tr.events
    assert math.isfinite(e.contact_position)
    before = tr.time[:n] < (e.jump_in_time if math.isfinite(e.jump_in_time) else e.contact_time)
    assert before.sum() > 100 and np.max(err[before]) < 2e-12
    assert np.max(err) < 0.05e-9
    for a, b in ((e.jump_in_position, ref.jump_in_position), (e.contact_position, ref.contact_position),
                 (e.pull_off_position, ref.pull_off_position)):
        assert (math.isnan(a) and math.isnan(b)) or a == pytest.approx(b, abs=0.05e-9)
    return tr, ref, err
