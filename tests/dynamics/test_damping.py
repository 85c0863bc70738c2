"""Lever damping as a model part (issue 23): a quality factor Q for the spring (m omega0 / Q) and
the beam (Rayleigh damping C = alpha M + beta K giving both free modes their Q), checked against
closed forms and independent computations."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import curve_fit

from afmforce.dynamics import SimulationConfig, simulate
from afmforce.dynamics import models as M
from afmforce.dynamics._params import parameter_vector
from afmforce.dynamics.config import FLAT
from afmforce.dynamics.reference import ReferenceModel, rayleigh_damping, reference_solve
from afmforce.errors import ParameterError
from afmforce.forces import vdw_force, vdw_force_gradient

nm = 1e-9
#: issue 23's load-friction case (issue 12, finding 2)
LOAD = dict(friction="load", xi=0.01, zeta=2e15, velocity=0.5e-6, start=-40e-9, turn=20e-9,
            end=-250e-9)


def _sim(**kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return simulate(**kw)


def _matrices(p):
    """(M, C, K) of the beam from its packed parameter vector."""
    Mm = np.diag([1.0 / p[M.INV_MA], 1.0 / p[M.INV_MB]])
    C = np.array([[p[M.C00], p[M.C01]], [p[M.C10], p[M.C11]]])
    K = -np.array([[p[M.A00], p[M.A01]], [p[M.A10], p[M.A11]]])
    return Mm, C, K


def _modes(Mm, C, K):
    """(undamped frequency |lambda| [rad/s], Q = |lambda| / (2 |Re lambda|)) of each mode of
    M q'' + C q' + K q = 0, from the eigenvalues of its first-order form, ascending."""
    Mi = np.linalg.inv(Mm)
    lam = np.linalg.eigvals(np.block([[np.zeros((2, 2)), np.eye(2)], [-Mi @ K, -Mi @ C]]))
    lam = sorted(lam[lam.imag > 0], key=abs)
    return [(abs(x), abs(x) / (2.0 * abs(x.real))) for x in lam]


def test_undamped_by_default_and_the_names_flow():
    """Q None (default) is the paper's model: no damping in the packed vector, the same run; the
    flat names reach both probes (quality_factor_2: the beam only) and round-trip."""
    cfg = SimulationConfig()
    assert cfg.quality_factor is None and cfg.quality_factor_2 is None
    p = parameter_vector(cfg)
    assert p.shape == (M.P_SIZE,) and not np.any(p[M.C00:M.C11 + 1])
    assert not parameter_vector(SimulationConfig(model="spring"))[M.C00]
    assert FLAT["quality_factor"].models == ("beam", "spring")
    assert FLAT["quality_factor_2"].models == ("beam",)
    damped = SimulationConfig(quality_factor=300, quality_factor_2=50)
    assert SimulationConfig.from_dict(damped.to_dict()) == damped
    assert SimulationConfig(model="spring", quality_factor=30).probe.quality_factor == 30
    with pytest.raises(ParameterError, match="quality_factor_2"):
        SimulationConfig(model="spring", quality_factor_2=30)
    with pytest.raises(ParameterError, match="quality_factor"):
        SimulationConfig(quality_factor=0.0)


@pytest.mark.parametrize("q1, q2", [(300.0, None), (300.0, 30.0), (50.0, 2000.0), (0.7, 3.0),
                                    (None, 30.0)])
def test_beam_free_modes_have_the_requested_quality_factors(q1, q2):
    """Eigen-analysis of (M, C, K) of the packed beam: both free modes have the Q asked for, at
    the damped frequency w sqrt(1 - 1/(4Q^2)); the matrix equals the one the scipy reference
    builds from its definition (generalised eigensolver, linear solve for alpha, beta)."""
    cfg = SimulationConfig(quality_factor=q1, quality_factor_2=q2)
    Mm, C, K = _matrices(parameter_vector(cfg))
    undamped = _modes(Mm, np.zeros((2, 2)), K)
    got = _modes(Mm, C, K)
    want = (q1, q1 if q2 is None else q2)
    for (w0, _), (w, q), qi in zip(undamped, got, want):
        assert q == pytest.approx(qi, rel=1e-9) if qi is not None else q > 1e12
        assert w == pytest.approx(w0, rel=1e-9)       # |lambda| of a Rayleigh-damped mode
    assert np.all(np.linalg.eigvalsh(0.5 * (C + C.T)) > -1e-12 * np.abs(C).max())   # dissipates
    ref = ReferenceModel(cfg).C
    assert np.allclose(C, ref, rtol=1e-10, atol=0.0)
    assert np.allclose(ref, rayleigh_damping(K, Mm, q1, q2), rtol=1e-12)


def test_spring_rings_down_at_omega0_over_2q_after_pull_off():
    """The Fig 1 spring (k 0.21 N/m, 10 ug) with Q = 20, released at pull-off, rings down as
    exp(-omega0 t / 2Q) at omega0 sqrt(1 - 1/4Q^2) (closed form of m x'' + (m omega0/Q) x' + k x
    = 0), fitted far from the surface (h > 50 nm, 5-35 ms after pull-off)."""
    q = 20.0
    tr = _sim(model="spring", velocity=10e-6, start=-30e-9, turn=2e-9, end=-400e-9,
              sample_rate=200e3, quality_factor=q)
    w0 = math.sqrt(0.21 / 1e-8)
    t0 = tr.events.pull_off_time
    m = (tr.time > t0 + 5e-3) & (tr.time < t0 + 35e-3)
    t, x = tr.time[m] - tr.time[m][0], tr.deflection[m]

    def ring(t, a, b, g, w, c, d):
        return np.exp(-g * t) * (a * np.cos(w * t) + b * np.sin(w * t)) + c + d * t

    p, _ = curve_fit(ring, t, x, p0=[x[0], 0.0, w0 / (2 * q), w0, 0.0, 0.0])
    assert math.hypot(p[0], p[1]) > 1 * nm                   # it does ring
    assert p[2] == pytest.approx(w0 / (2 * q), rel=0.005)
    assert p[3] == pytest.approx(w0 * math.sqrt(1 - 1 / (4 * q * q)), rel=1e-4)


def test_damped_jump_in_agrees_with_scipy():
    """The damped vector field and Jacobian against the scipy reference (rtol 1e-8): the
    load-friction case with Q = 30 from -8 nm through the jump-in to 0.2 ms after contact."""
    kw = dict(LOAD, start=-8e-9, turn=-2.6e-9, end=-30e-9, quality_factor=30.0, sample_rate=1e7)
    tr = _sim(**kw, rtol=1e-7, atol=1e-14)
    tc = tr.events.contact_time
    tw = np.linspace(tc - 0.05e-3, tc + 0.2e-3, 251)
    ref = reference_solve(SimulationConfig(**kw), rtol=1e-8, atol=1e-15, t_stop=tc + 0.2e-3,
                          sample_times=tw)
    assert ref.contact_time == pytest.approx(tc, abs=1e-9)
    h = np.interp(ref.time, tr.time, tr.separation)
    assert np.max(np.abs(h - ref.separation)) < 0.5e-12     # 0.09 pm (Q = 25: 5.5 pm, none: 28 pm)


def _quasi_static_hysteresis(cfg, contact, lo, hi):
    """Hysteresis offset and compliance slope of the massless (quasi-static) beam with
    load-dependent friction, independent of the dynamics: B(q) q' = A q + Fs(h) dh + (cd/h) z' dh,
    B = (cd/h) dh dh^T + (xi + zeta Fs^2) dy dy^T (drainage in the friction's load neglected:
    ~1e-15 N), from the static contact at ``contact`` to the turn and back, lines fitted
    over [lo, hi] as the simulation fits them."""
    m = ReferenceModel(cfg)
    R, A, z0, xi, zeta, v = cfg.radius, cfg.hamaker, cfg.z0, cfg.xi, cfg.zeta, cfg.velocity
    cd = 6 * math.pi * cfg.viscosity * R**2 / 4
    q = m.dh * (contact + 0.3e-9) / (m.dh @ m.dh)
    for _ in range(100):                                   # static contact (Newton)
        h = m.dh @ q - contact
        dq = np.linalg.solve(m.Adyn + float(vdw_force_gradient(h, R, A, z0)) * np.outer(m.dh, m.dh),
                             -(m.Adyn @ q + float(vdw_force(h, R, A, z0)) * m.dh))
        q = q + dq
        if np.max(np.abs(dq)) < 1e-24:
            break

    def rate(t, q, z0_, zdot):
        h = m.dh @ q - (z0_ + zdot * t)
        fs = float(vdw_force(h, R, A, z0))
        B = (cd / h) * np.outer(m.dh, m.dh) + (xi + zeta * fs * fs) * np.outer(m.dy, m.dy)
        return np.linalg.solve(B, m.Adyn @ q + fs * m.dh + (cd / h) * zdot * m.dh)

    t1 = (cfg.turn - contact) / v
    zs = np.linspace(lo, hi, 401)
    fits = []
    sa = solve_ivp(rate, (0, t1), q, method="Radau", rtol=1e-10, atol=1e-22, dense_output=True,
                   args=(contact, v))
    sr = solve_ivp(rate, (0, (cfg.turn - lo) / v + 1e-3), sa.y[:, -1], method="Radau", rtol=1e-10,
                   atol=1e-22, dense_output=True, args=(cfg.turn, -v))
    for sol, t in ((sa, (zs - contact) / v), (sr, (cfg.turn - zs) / v)):
        d = cfg.calibration_factor * (m.dth @ sol.sol(t))
        c1, c0 = np.polyfit(d, zs, 1)
        fits.append((c0, c1, d.min(), d.max()))
    (a0, a1, alo, ahi), (b0, b1, blo, bhi) = fits
    dmid = 0.5 * (max(alo, blo) + min(ahi, bhi))
    return (a0 + a1 * dmid) - (b0 + b1 * dmid), cfg.calibration_factor * 0.5 * (a1 + b1)


@pytest.mark.parametrize("q1, q2", [(30.0, None), (50.0, None), (300.0, 30.0)])
def test_damped_load_friction_comes_back_to_the_quasi_static_hysteresis(q1, q2):
    """Issue 23: undamped, the in-contact ringing rectifies through zeta Fz^2 into ~5 nm of
    hysteresis; lever damping that reaches the contact mode (Q <= 50 for both modes, or Q2 = 30)
    brings it back to the quasi-static answer, computed independently (massless beam; 0.3545 nm,
    slope 1.3061e5 nm/rad). (The scipy reference of the full damped equations, rtol 1e-8, gives
    0.35422 nm on a shortened cycle: benchmarks/bench_damping.py, 12 min.)"""
    e = _sim(**LOAD, quality_factor=q1, quality_factor_2=q2).events
    span = e.turn_position - e.contact_position
    cfg = SimulationConfig(**LOAD, quality_factor=q1, quality_factor_2=q2)
    hyst, slope = _quasi_static_hysteresis(cfg, e.contact_position, e.contact_position + span / 4,
                                           e.turn_position - span / 4)
    assert hyst / nm == pytest.approx(0.3545, abs=0.001)
    assert e.hysteresis_offset == pytest.approx(hyst, abs=0.002 * nm)
    assert e.compliance_slope == pytest.approx(slope, rel=1e-4)


#: an undamped spring probe (1 ug, R 220 nm, 7.2 um/s) that bounces in contact: a risky regime
BOUNCING = dict(model="spring", mass=1e-9, radius=220e-9, velocity=7.2e-6)


def test_guard_says_when_a_result_hangs_on_damping_the_model_lacks():
    """check="auto" on a risky undamped run also solves it at Q = 30 and 300 (REALISTIC_Q) and
    reports, in solver.check and a LeverDampingWarning, the events that move (the numbers are
    those of ordinary runs at these Q); a run with a Q, or unchecked, is not compared."""
    from afmforce.dynamics.guard import REALISTIC_Q, LeverDampingWarning, lever_damping_check

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        tr = simulate(**BOUNCING, check="auto")
    assert REALISTIC_Q == (30.0, 300.0)
    low, high = (_sim(**BOUNCING, quality_factor=q).events for q in REALISTIC_Q)
    note = tr.solver.check
    assert "hangs on damping the model lacks" in note
    assert (f"pull_off_force {tr.events.pull_off_force / nm:.4g} nN undamped vs "
            f"{low.pull_off_force / nm:.4g} nN at Q = 30, "
            f"{high.pull_off_force / nm:.4g} nN at Q = 300") in note
    assert abs(low.pull_off_force - tr.events.pull_off_force) > 1 * nm
    assert any(issubclass(w.category, LeverDampingWarning) for w in caught)
    assert "lever damping" not in _sim(**BOUNCING).solver.check                 # check="off"
    cfg = SimulationConfig(**BOUNCING)
    asked = []
    assert lever_damping_check("auto", cfg.replace(quality_factor=300.0), tr.events, asked.append) == ""
    assert lever_damping_check("off", cfg, tr.events, asked.append) == "" and asked == []
    same = lever_damping_check("always", cfg, tr.events, lambda c: asked.append(c) or tr.events)
    assert "no event moves" in same and [c.quality_factor for c in asked] == list(REALISTIC_Q)


def test_cli_takes_the_quality_factor(capsys):
    """`simulate`, `fit` and `plan` take --quality-factor (and -2 for the beam); the spring
    refuses --quality-factor-2; the range is checked while parsing."""
    import json

    from afmforce.cli.fit import model_config
    from afmforce.cli.main import build_parser, main

    argv = ["simulate", "--json", "--model", "spring", "--mass", "1ug", "--radius", "220nm",
            "--velocity", "7.2um/s", "--quality-factor", "30", "--check", "off"]
    assert main(argv) == 0
    s = json.loads(capsys.readouterr().out)
    ref = _sim(**BOUNCING, quality_factor=30.0).events
    assert s["min_deflection"] == ref.min_deflection and s["hysteresis_offset"] == ref.hysteresis_offset
    # this retract ends in contact: no pull-off, so no pull-off force in the summary (the event keeps the
    # most negative force in contact, which the convergence check compares)
    assert math.isnan(ref.pull_off_position) and s["pull_off"]["force"] is None
    for cmd in ("fit", "plan"):
        args = build_parser(cmd).parse_args([cmd, *(["x.txt"] if cmd == "fit" else []),
                                             "--quality-factor", "300", "--quality-factor-2", "40"])
        cfg = model_config(args)
        assert (cfg.quality_factor, cfg.quality_factor_2) == (300.0, 40.0)
    for bad, why in ((["--model", "spring", "--quality-factor-2", "30"], "ignored by --model spring"),
                     (["--quality-factor", "0"], "out of range")):
        try:
            code = main(["simulate", *bad])
        except SystemExit as exc:          # argparse rejects out-of-range values itself
            code = exc.code
        assert code == 2 and why in capsys.readouterr().err
