"""simulate()'s lean path (issue 16): cached setup, compiled sampling, results as before.

simulate() integrates each drive segment in one compiled call, with a thin layer of Python
around (the setup cached per configuration and shared parts); with a progress callback the
integrator pauses every 5,000 steps and resumes. Both must give bit-identical trajectories
and events (the suite's stored references check them against the physics); the hysteresis
must be the compliance-line fit of the returned columns; the setup cache must not leak
between configurations.
"""

import math
import pickle
import warnings

import numpy as np
import pytest

from afmforce.dynamics import SimulationConfig, simulate, simulate_many
from afmforce.dynamics.events import compliance_lines
from afmforce.dynamics.trajectory import COLUMNS
from afmforce.errors import SolverError

FAST = dict(velocity=1e-6, start=-30e-9, turn=5e-9, end=-200e-9, sample_rate=20e3)
CASES = {
    "beam": dict(FAST, xi=0.05),
    "turn_force_dwell_average": dict(FAST, xi=0.02, turn_force=0.3e-9, dwell=1e-3,
                                     sampling="average"),
    "turn_deflection_point": dict(FAST, turn_deflection=0.5e-9, dwell=0.5e-3),
    "no_spike": dict(FAST, spike_window=0.0),
    "spring": dict(model="spring", velocity=10e-6),
    "no_contact": dict(FAST, turn=-20e-9),
}


def _identical(a, b, resumed=False):
    for name in COLUMNS:
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and x.shape == y.shape, name
        assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), name
    da, db = a.events.to_dict(), b.events.to_dict()
    for k in da:
        assert da[k] == db[k] or (isinstance(da[k], float) and math.isnan(da[k])
                                  and math.isnan(db[k])), k
    sa, sb = a.solver.to_dict(), b.solver.to_dict()
    sa.pop("wall_time"), sb.pop("wall_time")
    if resumed:     # a resumed call evaluates f at its start and factorizes anew
        for k in ("rhs_evaluations", "lu_decompositions"):
            assert sb.pop(k) >= sa.pop(k)
    assert sa == sb


@pytest.mark.parametrize("name", CASES)
def test_paused_and_resumed_runs_are_identical(name, monkeypatch):
    import importlib

    monkeypatch.setattr(importlib.import_module("afmforce.dynamics.simulate"), "PROGRESS_CHUNK", 97)
    calls = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fast = simulate(**CASES[name])
        slow = simulate(**CASES[name], progress=calls.append)
    assert len(calls) > fast.solver.steps // 97 - 3, "the runs did not pause"
    _identical(fast, slow, resumed=True)


def test_turned_at_load_and_dwell_segments():
    tr = simulate(**CASES["turn_force_dwell_average"])
    e = tr.events
    assert e.turn_position < FAST["turn"]              # turned at the load, before `turn`
    kinds = [int(k) for k in np.unique(tr.segment)]
    assert kinds == [0, 1, 2]
    # the turn point lies on the approach line z = start + v t
    assert e.turn_position == pytest.approx(FAST["start"] + FAST["velocity"] * e.turn_time,
                                            rel=0, abs=1e-18)


def test_hysteresis_is_the_compliance_fit_of_the_columns():
    tr = simulate(**CASES["beam"])
    offset, slope = compliance_lines(tr.piezo_position, tr.apparent_deflection, tr.separation,
                                     tr.segment, tr.config.contact_separation,
                                     tr.events.contact_position, tr.events.turn_position,
                                     tr.calibration_factor)
    assert math.isfinite(offset) and math.isfinite(slope)
    assert tr.events.hysteresis_offset == offset and tr.events.compliance_slope == slope


def test_failures_raise_the_same_with_and_without_progress():
    starved = dict(FAST, max_steps=50)
    with pytest.raises(SolverError) as fast:
        simulate(**starved)
    with pytest.raises(SolverError) as slow:
        simulate(**starved, progress=lambda p: None)
    assert str(fast.value) == str(slow.value)
    assert "max_steps = 50" in str(fast.value) and "in the approach" in str(fast.value)
    # a failure after the turn names the segment it happened in
    total = simulate(**FAST).solver.steps
    late = dict(FAST, max_steps=total - 5)
    with pytest.raises(SolverError, match="in the retract") as fast:
        simulate(**late)
    with pytest.raises(SolverError) as slow:
        simulate(**late, progress=lambda p: None)
    assert str(fast.value) == str(slow.value)


def test_setup_cache_follows_every_part():
    """Configurations sharing parts share the cached setup, yet each run uses its own
    friction, drive and probe; a pickled configuration leaves the cache behind."""
    base = SimulationConfig(**FAST)
    runs = [base.replace(xi=0.01), base.replace(xi=0.1), base.replace(xi=0.01, velocity=2e-6),
            base.replace(xi=0.01, k0=0.2)]
    got = simulate_many(runs, threads=1)
    for cfg, tr in zip(runs, got):
        fresh = pickle.loads(pickle.dumps(cfg))
        assert "_setup" not in fresh.__dict__
        _identical(tr, simulate(fresh))
    assert got[0].events.pull_off_position != got[1].events.pull_off_position
    assert got[0].time.size != got[2].time.size
    assert got[0].spring_constant != got[3].spring_constant


def test_events_of_identical_runs_compare_equal():
    """Missing events are the one math.nan, so Events of identical runs are == (NaN fields too)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a, b = simulate(**CASES["no_contact"]), simulate(**CASES["no_contact"])
    assert math.isnan(a.events.contact_time) and math.isnan(a.events.hysteresis_offset)
    assert a.events == b.events


def test_results_are_complete_dataclasses():
    """simulate() builds Events, SolverStats and Trajectory without their __init__: every
    field is set, and each equals the one the constructor builds from the same fields."""
    import dataclasses

    from afmforce.dynamics.events import Events
    from afmforce.dynamics.trajectory import SolverStats, Trajectory

    tr = simulate(**CASES["beam"])
    for obj, cls in ((tr, Trajectory), (tr.events, Events), (tr.solver, SolverStats)):
        assert not hasattr(cls, "__post_init__")
        names = [f.name for f in dataclasses.fields(cls)]
        assert set(vars(obj)) == set(names)
        if cls is not Trajectory:       # (arrays: == is elementwise)
            assert cls(**{n: getattr(obj, n) for n in names}) == obj
    with pytest.raises(dataclasses.FrozenInstanceError):
        tr.events.pull_off_position = 0.0
