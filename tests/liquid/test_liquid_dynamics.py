"""Liquid dynamics (issue 25): the compiled model against the independent scipy reference
(dynamics/reference.py, built from the force laws of afmforce.forces) at tight tolerance."""

import math
import warnings

import numpy as np
import pytest

from afmforce.dynamics import SimulationConfig, simulate
from afmforce.dynamics import models as M
from afmforce.dynamics._params import parameter_vector
from afmforce.dynamics.reference import reference_solve
from afmforce.dynamics.static import surface_jump_in, surface_static_force
from afmforce import forces as F

LIQUID = dict(model="spring", spring_constant=0.1, mass=1e-11, radius=2e-6, geometry="sphere-flat",
              hamaker=1e-20, viscosity=0.89e-3, permittivity=78.5, double_layer="constant_potential",
              surface_potential=-0.04, debye_length=9.6e-9, slip_length=5e-9, lever_drag=5e-5,
              velocity=10e-6, start=-500e-9, turn=30e-9, end=-500e-9, sample_rate=20e3)


@pytest.mark.parametrize("law", ["weak_overlap", "constant_potential", "constant_charge"])
def test_compiled_force_and_jacobian_match_the_laws(law):
    cfg = SimulationConfig(**{**LIQUID, "double_layer": law, "surface_potential_2": -0.02,
                              "lever_height": 20e-6})
    p = parameter_vector(cfg)
    s = cfg.surface
    for h in (0.5e-9, 3e-9, 20e-9, 300e-9):
        for hd in (-1e-5, 3e-6):
            y = np.array([h, hd])       # spring: x = h at zd = 0, vd = 0
            out = np.empty(2)
            assert M.rhs(M.MODEL_SPRING, p, 0.0, 0.0, y, out)
            want = (float(F.vdw_force(h, F.paper_radius(s.radius, s.geometry), s.hamaker, s.z0))
                    + float(F.double_layer_force(h, s.radius, s.surface_potential, s.debye_length,
                                                 s.surface_potential_2, s.permittivity, law, s.geometry))
                    + float(F.slip_drainage_force(h, hd, s.radius, s.viscosity, s.slip_length, s.geometry))
                    + float(F.lever_drag_force(h, hd, s.lever_drag, s.lever_height)))
            assert out[1] == pytest.approx((-0.1 * h + want) / 1e-11, rel=1e-10)
            J = np.empty((2, 2))
            assert M.jac(M.MODEL_SPRING, p, 0.0, 0.0, y, J)
            num = np.empty((2, 2))
            for j, d in enumerate((1e-7 * h, 1e-7 * abs(hd))):
                yp, ym, op, om = y.copy(), y.copy(), np.empty(2), np.empty(2)
                yp[j] += d
                ym[j] -= d
                M.rhs(M.MODEL_SPRING, p, 0.0, 0.0, yp, op)
                M.rhs(M.MODEL_SPRING, p, 0.0, 0.0, ym, om)
                num[:, j] = (op - om) / (2 * d)
            assert J[1] == pytest.approx(num[1], rel=1e-5)


def test_air_default_has_no_liquid_terms_and_geometry_doubles_the_radius():
    p = parameter_vector(SimulationConfig())
    assert np.all(p[M.DL_A:] == 0)
    flat = parameter_vector(SimulationConfig(geometry="sphere-flat"))
    assert flat[M.AR] == pytest.approx(2 * p[M.AR]) and flat[M.CD] == pytest.approx(4 * p[M.CD])


def test_debye_length_from_salt_and_round_trip():
    cfg = SimulationConfig(salt_concentration=1.0)          # 1 mM
    assert cfg.debye_length == pytest.approx(9.6e-9, rel=5e-3)
    assert SimulationConfig.from_dict(cfg.to_dict()).debye_length == cfg.debye_length
    assert cfg.replace(debye_length=5e-9).salt_concentration is None


def test_static_jump_in_with_double_layer_is_where_the_gradient_equals_k():
    cfg = SimulationConfig(**LIQUID)
    hj, zj, dj = surface_jump_in(0.1, cfg.surface)
    f, df = surface_static_force(cfg.surface, np.array([hj, hj * 1.01]))
    assert df[0] == pytest.approx(0.1, rel=1e-9) and df[1] < 0.1
    assert dj == pytest.approx(f[0] / 0.1, rel=1e-12) and zj == pytest.approx(dj - hj)


@pytest.mark.parametrize("model", ["spring", "beam"])
def test_liquid_cycle_matches_a_tight_reference_solve(model):
    cfg = SimulationConfig(**LIQUID)
    if model == "beam":
        cfg = cfg.replace(model="beam", k0=0.1, m_joint=1e-11, m_base=1e-11, xi=0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tr = simulate(cfg)
    ref = reference_solve(cfg, rtol=1e-9, atol=1e-15, sample_times=tr.time)
    n = min(len(ref.time), len(tr.time))
    # away from the jumps the deflection agrees to picometres; in the snap-out transient to 0.05 nm
    err = np.abs(ref.deflection[:n] - tr.deflection[:n])
    far = (np.abs(tr.separation[:n]) > 20e-9) & (tr.time[:n] < tr.events.pull_off_time)
    assert np.max(err[far]) < 2e-12 and np.max(err) < 0.05e-9
    for a, b in ((tr.events.jump_in_position, ref.jump_in_position),
                 (tr.events.contact_position, ref.contact_position),
                 (tr.events.pull_off_position, ref.pull_off_position)):
        assert math.isfinite(a) and a == pytest.approx(b, abs=0.05e-9)
    # the lever drag offsets the far-field deflection by c v / k on approach
    k = cfg.force_constant
    i = np.searchsorted(tr.time, 0.02)
    h_far = tr.separation[i]
    expect = float(F.lever_drag_force(h_far, -cfg.velocity, 5e-5)
                   + F.slip_drainage_force(h_far, -cfg.velocity, 2e-6, 0.89e-3, 5e-9, "sphere-flat")
                   + F.double_layer_force(h_far, 2e-6, -0.04, 9.6e-9, law="constant_potential",
                                          geometry="sphere-flat")
                   + F.vdw_force(h_far, 4e-6, 1e-20)) / k
    assert tr.deflection[i] == pytest.approx(expect, rel=2e-3)


def test_guard_counts_lever_drag_and_the_liquid_run_is_converged():
    from afmforce.dynamics.guard import EVENT_TOLERANCES, damping_ratio
    cfg = SimulationConfig(**LIQUID)
    assert damping_ratio(cfg) == pytest.approx(5e-5 / (2 * math.sqrt(0.1 * 1e-11)), rel=1e-12)
    assert damping_ratio(cfg.replace(lever_drag=0.0)) == 0.0
    with warnings.catch_warnings():
        warnings.simplefilter("error")       # no ConvergenceWarning
        tr = simulate(cfg.replace(lever_drag=1e-7), check="always")   # underdamped: ratio 0.05
    assert tr.solver.event_errors and all(
        err <= EVENT_TOLERANCES[name][0] for name, err in tr.solver.event_errors.items())


def test_trajectory_figure_draws_the_liquid_static_curve():
    from afmforce.plotting.trajectory import plot_trajectory
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tr = simulate(SimulationConfig(**LIQUID))
    _, ax1 = plot_trajectory(tr)
    static = [ln for ln in ax1.get_lines() if ln.get_label() == "static"][0]
    h, d = static.get_data()
    f, _ = surface_static_force(tr.config.surface, np.asarray(h) * 1e-9)
    ok = np.isfinite(d)
    assert ok.sum() > 100 and np.allclose(np.asarray(d)[ok] * 1e-9, (f / tr.spring_constant)[ok], rtol=1e-9)
