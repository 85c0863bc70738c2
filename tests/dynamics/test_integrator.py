"""The compiled Radau IIA integrator: order, agreement with scipy, failure handling."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

from afmforce.dynamics import SimulationConfig, simulate
from afmforce.dynamics import models as M
from afmforce.dynamics import radau as R
from afmforce.dynamics.drive import initial_state
from afmforce.dynamics.reference import reference_solve
from afmforce.errors import SolverError

SIM = sys.modules["afmforce.dynamics.simulate"]


def _fixed_step(cfg, t1, nsteps):
    """State at t1 from fixed-step Radau IIA on the approach from rest at cfg.start."""
    model = M.MODEL_IDS[cfg.model]
    p = SIM.parameter_vector(cfg)
    y = initial_state(cfg)
    n = y.size
    atol = np.full(n, 1e-19)
    atol[n // 2:] = 1e-19 * 1e4
    rtolv = np.zeros(n)
    ev = np.full(R.E_SIZE, np.nan)
    ev[R.E_IN_CONTACT] = 0.0
    ev[R.E_H_CONTACT] = 1e-9
    ev[R.E_SPIKE_WINDOW] = 1e-3
    ev[R.E_JUMP_FACTOR] = 2.0
    state = R.new_state(y, ev)
    work, stats = state[2], state[6]
    h = t1 / nsteps
    work[R.W_H] = h
    status = R.integrate_segment(
        model, p, R.drive_record(R.APPROACH, 0.0, cfg.start, cfg.velocity, t1),
        R.tolerance_record(1e-12, rtolv, atol),
        R.control_record(0.0, 1.0, 0.0, 0.0, 10**7, 2**62, h_fixed=h),
        R.sampling_record(0.0, 1.0, False, np.zeros(1, dtype=np.int64), np.zeros((0, n))),
        state)
    assert status == R.DONE
    assert stats[R.S_ACCEPTED] == nsteps
    return y


def test_convergence_order_is_five_on_a_smooth_window():
    """Radau IIA has order 5 (Hairer & Wanner IV.5): halving the step divides the error by ~32.

    Window: the Fig 1 spring (m = 10 ug, k = 0.21 N/m) released at rest at z = -12 nm while
    the drive moves at 10 um/s, for 0.6 ms (the 730 Hz mode is excited: a smooth,
    non-trivial solution).
    """
    cfg = SimulationConfig(model="spring", velocity=10e-6, start=-12e-9, turn=0.0, end=-100e-9)
    t1 = 0.6e-3
    ref = _fixed_step(cfg, t1, 1024)
    ns = (4, 8, 16, 32)
    err = [abs(_fixed_step(cfg, t1, n)[0] - ref[0]) for n in ns]
    slopes = [math.log2(err[i] / err[i + 1]) for i in range(len(ns) - 1)]
    assert all(4.5 < s < 5.6 for s in slopes), (err, slopes)


def test_fig5_approach_matches_scipy_radau_at_rtol_1e8(sim):
    """Approach of Fig 5 through the jump-in: sampled deflection and angle, and the events,
    against scipy solve_ivp(Radau, rtol 1e-8) of an independent implementation."""
    tr = sim(sample_rate=20e3)
    t = tr.time[(tr.time < tr.events.contact_time)]
    ref = reference_solve(SimulationConfig(), rtol=1e-8, atol=1e-15,
                          t_stop=tr.events.contact_time + 1e-4, sample_times=t)
    np.testing.assert_allclose(tr.deflection[: t.size], ref.deflection, rtol=0, atol=2e-12)
    beta = tr.calibration_factor
    np.testing.assert_allclose(tr.apparent_deflection[: t.size], beta * ref.angle, rtol=0,
                               atol=2e-12)
    e = tr.events
    assert e.jump_in_position == pytest.approx(ref.jump_in_position, abs=0.002e-9)
    assert e.contact_position == pytest.approx(ref.contact_position, abs=0.002e-9)
    assert e.min_apparent_deflection == pytest.approx(ref.min_apparent_deflection, abs=0.002e-9)
    assert e.min_deflection == pytest.approx(ref.min_deflection, abs=0.002e-9)


def test_fig1_spring_approach_matches_scipy_radau_at_rtol_1e8(sim):
    """Fig 1 spring at 10 um/s (inertia matters) up to contact, against scipy (rtol 1e-8)."""
    kw = dict(model="spring", velocity=10e-6, start=-30e-9, turn=2e-9, end=-150e-9,
              sample_rate=1e6)
    tr = sim(**kw)
    t = tr.time[tr.time < tr.events.contact_time]
    ref = reference_solve(SimulationConfig(**kw), rtol=1e-8, atol=1e-16,
                          t_stop=tr.events.contact_time + 1e-6, sample_times=t)
    np.testing.assert_allclose(tr.deflection[: t.size], ref.deflection, rtol=0, atol=5e-12)
    assert tr.events.jump_in_position == pytest.approx(ref.jump_in_position, abs=0.005e-9)


def test_full_cycle_matches_tight_reference(fig5, fig5_tight):
    """Default tolerances against the same integrator at a 100x tighter atol (whole cycle)."""
    a, b = fig5.events, fig5_tight.events
    for name, tol in (("min_apparent_deflection", 0.01e-9), ("jump_in_position", 0.01e-9),
                      ("contact_position", 0.01e-9), ("hysteresis_offset", 0.002e-9),
                      ("spike_height", 0.02e-9), ("pull_off_position", 0.5e-9),
                      ("pull_off_force", 0.01e-9)):
        assert getattr(a, name) == pytest.approx(getattr(b, name), abs=tol), name
    # sampled curves before contact (no ringing there) agree too
    m = fig5.time < fig5.events.contact_time
    np.testing.assert_allclose(fig5.deflection[m], fig5_tight.deflection[m], atol=0.01e-9)
    np.testing.assert_allclose(fig5.apparent_deflection[m], fig5_tight.apparent_deflection[m],
                               atol=0.01e-9)


def test_ringing_damp_and_resolve_agree(sim):
    """Numerical damping of the in-contact ringing leaves the measured quantities unchanged."""
    a = sim(atol=1e-13).events
    b = sim(atol=1e-13, ringing="resolve").events
    for name in ("min_apparent_deflection", "jump_in_position", "hysteresis_offset",
                 "spike_height", "pull_off_position"):
        assert getattr(a, name) == pytest.approx(getattr(b, name), abs=0.005e-9), name


def test_progress_pauses_do_not_change_the_result(monkeypatch, sim):
    """Pausing for progress reports resumes the integrator exactly (same steps, same samples)."""
    monkeypatch.setattr(SIM, "PROGRESS_CHUNK", 37)
    seen = []
    a = simulate(xi=0.01, velocity=1e-6, progress=seen.append)
    b = sim(xi=0.01, velocity=1e-6)
    assert a.solver.steps == b.solver.steps
    np.testing.assert_array_equal(a.deflection, b.deflection)
    frac = [p.fraction for p in seen]
    assert len(seen) > 10 and frac[-1] == 1.0 and all(np.diff(frac) >= 0)
    assert {p.unit for p in seen} == {"s"} and seen[-1].done == pytest.approx(b.time[-1], abs=1 / 10e3)


def test_failed_solve_raises_instead_of_returning():
    """A truncated solve never returns quietly (step budget exhausted -> SolverError)."""
    with pytest.raises(SolverError, match="max_steps"):
        simulate(max_steps=50)


def test_solver_statistics_are_reported(fig5):
    s = fig5.solver
    assert s.status == "success"
    assert s.accepted + s.rejected == s.steps
    assert s.rhs_evaluations > s.steps and s.jacobian_evaluations > 0 and s.wall_time > 0


def test_records_follow_their_named_tuples_and_fix_the_types():
    """integrate_segment takes plain tuples in the field order of the named tuples; the
    packers give one type per field whatever the caller passes (one compiled variant)."""
    n = 4
    a = np.zeros(n)
    recs = [
        (R.Drive, R.drive_record(1, 0, 1, 2, 3, R.TERM_FORCE, 5)),
        (R.Tolerances, R.tolerance_record(1, a, a)),
        (R.StepControl, R.control_record(1, 2, 0, 100, 10, 5)),
        (R.Sampling, R.sampling_record(0, 1, 0, np.zeros(1, dtype=np.int64), np.zeros((1, n)))),
        (R.SolverState, R.new_state(a, np.zeros(R.E_SIZE))),
    ]
    for cls, rec in recs:
        assert type(rec) is tuple and len(rec) == len(cls._fields)
    drive = R.Drive(*recs[0][1])
    assert isinstance(drive.kind, int) and isinstance(drive.t_a, float)
    assert isinstance(drive.term_kind, int) and drive.term_level == 5.0
    control = R.StepControl(*recs[2][1])
    assert isinstance(control.max_steps, int) and control.h_fixed == 0.0
    assert R.Sampling(*recs[3][1]).average is False


def test_step_size_controller_follows_radau5():
    """Gustafsson's predictive controller (Hairer & Wanner IV.8, eq 8.25) as RADAU5 applies it."""
    from afmforce.dynamics._radau_control import controller, next_step_factor, safety_factor

    # no history: factor err^-1/4
    assert controller(1e-6, 0.0, 0.0, 0.5) == pytest.approx(0.5 ** -0.25, rel=1e-15)
    # with history: min(1, h/h_old (err_old/err)^1/4) err^-1/4
    h, h_old, e_old, e = 2e-6, 1e-6, 0.8, 0.1
    mult = h / h_old * (e_old / e) ** 0.25
    assert controller(h, h_old, e_old, e) == pytest.approx(min(1.0, mult) * e ** -0.25)
    assert controller(h, h_old, e_old, 0.0) == 10.0
    # safety 0.9 (2 nmax + 1) / (2 nmax + iterations), nmax = 6
    assert safety_factor(1) == pytest.approx(0.9)
    assert safety_factor(6) == pytest.approx(0.9 * 13 / 18)
    # after a rejection never larger; below 1.2 the step (and its factors) is kept
    assert next_step_factor(h, 0.0, 0.0, 1e-6, 0.9, True, False) == 1.0
    assert next_step_factor(h, 0.0, 0.0, 1e-6, 0.9, False, False) == 10.0
    assert next_step_factor(h, 0.0, 0.0, 0.9, 0.9, False, False) == 1.0
    assert next_step_factor(h, 0.0, 0.0, 0.9, 0.9, False, True) == pytest.approx(
        0.9 * 0.9 ** -0.25)


def test_integrator_modules_stay_readable():
    """Issue 11.8: the compiled integrator in pieces, no module over 400 lines."""
    from pathlib import Path

    import afmforce.dynamics as D

    root = Path(D.__file__).parent
    for name in ("radau", "_radau_newton", "_radau_control", "_radau_tableau", "_sampling",
                 "_locate", "_linalg"):
        lines = (root / f"{name}.py").read_text().count("\n")
        assert lines <= 400, (name, lines)


def test_failed_damping_step_falls_back_to_the_controller_step():
    """Issue 16 (the damping retry loop): with the masses x100 (contact mode 10x slower) nearly
    every damping step's Newton iteration fails. Each failure used to halve down from the
    damping step through ~4 more failures (7.4k failures for 2.7k accepted steps); now it
    falls back to the controller's step. The run still obeys the exact time-rescaling
    similarity (t/10, v x10, xi/10, m/100 without drainage) with an ordinary-mass run."""
    a = simulate(xi=0.1, velocity=1e-6, m_joint=1e-8, m_base=1e-8, viscosity=0.0)
    b = simulate(xi=0.01, velocity=1e-5, viscosity=0.0)
    assert a.solver.newton_failures < a.solver.accepted
    nm = 1e-9
    for name, tol in (("min_apparent_deflection", 0.002), ("jump_in_position", 0.002),
                      ("contact_position", 0.002), ("hysteresis_offset", 0.005),
                      ("pull_off_position", 0.5)):
        assert getattr(a.events, name) == pytest.approx(getattr(b.events, name), abs=tol * nm), name
