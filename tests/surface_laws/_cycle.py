"""A small spring-model cycle on which the surface force laws' tests run the compiled model
against the independent scipy reference (afmforce.dynamics.reference)."""

import math
import warnings

import numpy as np

from afmforce.dynamics import SimulationConfig, simulate
from afmforce.dynamics.reference import reference_solve

#: A 20 nm sphere on a flat on a 1 N/m spring, 1 um/s.
CYCLE = dict(model="spring", spring_constant=1.0, mass=1e-11, radius=20e-9, geometry="sphere-flat",
             hamaker=1e-20, viscosity=0.0, velocity=1e-6, start=-60e-9, turn=5e-9, end=-120e-9,
             sample_rate=20e3)


def cycle_against_reference(**law_values):
    """(trajectory, reference solution, largest deflection error [m]) of one cycle with a law on."""
    cfg = SimulationConfig(**CYCLE, **law_values)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tr = simulate(cfg)
    ref = reference_solve(cfg, rtol=1e-10, atol=1e-16, sample_times=tr.time)
    n = min(len(ref.time), len(tr.time))
    err = np.abs(ref.deflection[:n] - tr.deflection[:n])
    assert math.isfinite(tr.events.jump_in_position) or math.isfinite(tr.events.contact_position)
    return tr, ref, err
