"""simulate_many: the same trajectories as separate simulate() calls; errors and warnings."""

import warnings

import numpy as np
import pytest

from afmforce.dynamics import DynamicsWarning, SimulationConfig, simulate, simulate_many
from afmforce.errors import ParameterError, SolverError

FAST = dict(velocity=1e-6, start=-30e-9, turn=5e-9, end=-200e-9, sample_rate=20e3)


def _same(a, b):
    assert a.events == b.events
    for col in ("time", "piezo_position", "deflection", "apparent_deflection", "normal_force"):
        np.testing.assert_array_equal(getattr(a, col), getattr(b, col))
    assert a.solver.steps == b.solver.steps and a.solver.rejected == b.solver.rejected


@pytest.mark.parametrize("threads", [1, 2])
def test_many_equals_separate_calls(threads):
    cfgs = [SimulationConfig(xi=xi, **FAST) for xi in (0.01, 0.1)] + [
        dict(model="spring", velocity=10e-6), dict(FAST, xi=0.05, turn_force=0.3e-9)]
    got = simulate_many(cfgs, threads=threads)
    assert len(got) == len(cfgs)
    for c, tr in zip(cfgs, got):
        ref = simulate(c) if isinstance(c, SimulationConfig) else simulate(**c)
        _same(tr, ref)
        assert tr.config == ref.config


def test_reduce_keeps_only_what_is_asked():
    cfgs = [SimulationConfig(xi=xi, **FAST) for xi in (0.01, 0.1, 0.02)]
    ev = simulate_many(cfgs, threads=2, reduce=lambda tr: tr.events)
    assert ev == [simulate(c).events for c in cfgs]


def test_bad_config_raises_before_any_run_or_is_returned():
    bad = dict(FAST, start=-2e-9)            # starts in contact
    with pytest.raises(ParameterError, match="already in contact"):
        simulate_many([dict(FAST), bad])
    out = simulate_many([dict(FAST), bad, dict(FAST, xi=0.02)], on_error="return", threads=2)
    assert isinstance(out[1], ParameterError)
    _same(out[0], simulate(**FAST))
    _same(out[2], simulate(**FAST, xi=0.02))
    with pytest.raises(ParameterError, match="on_error"):
        simulate_many([FAST], on_error="ignore")
    with pytest.raises(ParameterError, match="threads"):
        simulate_many([FAST], threads=0)


def test_solver_failure_is_returned_in_place():
    starved = dict(FAST, max_steps=50)
    with pytest.raises(SolverError, match="max_steps"):
        simulate_many([FAST, starved], threads=2)
    out = simulate_many([starved, FAST], on_error="return", threads=2)
    assert isinstance(out[0], SolverError) and "max_steps = 50" in str(out[0])
    _same(out[1], simulate(**FAST))


def test_warnings_are_issued_as_by_simulate():
    no_contact = dict(FAST, turn=-20e-9)
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        simulate_many([no_contact, FAST], threads=2)
    msgs = [str(w.message) for w in rec if issubclass(w.category, DynamicsWarning)]
    assert len(msgs) == 1 and "never reached contact" in msgs[0]


def test_config_caches_do_not_leak_between_configs():
    """Cached cantilever / static solutions are keyed on every field they depend on."""
    a = SimulationConfig(k0=0.1)
    b = SimulationConfig(k0=0.2)
    assert b.force_constant == pytest.approx(2 * a.force_constant, rel=1e-12)
    assert a.cantilever.k0 == 0.1 and b.cantilever.k0 == 0.2
    fresh = SimulationConfig(k0=0.2).replace(L2=1e-6)
    assert fresh.cantilever.L2 == 1e-6 and fresh.calibration_factor != b.calibration_factor
    with pytest.raises(ParameterError, match="at most one"):
        SimulationConfig(k0=0.1, B=1e-13)
    s = SimulationConfig(model="spring", spring_constant=0.5)
    assert s.force_constant == 0.5 and np.isnan(s.calibration_factor)


def test_columns_do_not_hold_the_unused_part_of_the_sample_buffer():
    """The sampled columns are written into buffers sized for the longest possible run
    (allocated in the preparing thread); a run that turns early at a load gets copies of
    its rows, a full run views of the whole buffer."""
    import sys

    setup = sys.modules["afmforce.dynamics.simulate"]._setup
    full = simulate(**FAST)
    cfg = SimulationConfig(**dict(FAST, turn=100e-9, xi=0.05, turn_force=0.3e-9))
    early = simulate(cfg)
    assert full.time.size == setup(full.config).nbuf
    assert early.time.size < 0.75 * setup(cfg).nbuf      # turned at 1.9 nm, not 100 nm
    for tr in (full, early):
        for col in ("time", "piezo_position", "normal_force", "apparent_deflection",
                    "apparent_separation", "segment"):
            a = getattr(tr, col)
            base = a if a.base is None else a.base
            while base.base is not None:
                base = base.base
            assert base.shape[0] <= 4 * a.shape[0] // 3 + 1, col
    np.testing.assert_array_equal(full.apparent_separation,
                                  full.apparent_deflection - full.piezo_position)
