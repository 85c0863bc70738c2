"""Vector fields, Jacobians, start state and friction registry (spec sections 3, 5)."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

from afmforce.constants import FIG5
from afmforce.dynamics import FRICTION_LAWS, SimulationConfig
from afmforce.dynamics import models as M
from afmforce.dynamics.drive import initial_state
from afmforce.dynamics.reference import ReferenceModel

SIM = sys.modules["afmforce.dynamics.simulate"]

CONFIGS = {
    "spring": SimulationConfig(model="spring"),
    "beam-viscous": SimulationConfig(),
    "beam-load": SimulationConfig(friction="load", zeta=3e14),
    "beam-none": SimulationConfig(friction="none"),
}


def _states(cfg, rng, n=6):
    """Random states near contact (h from 0.25 to 8 nm) with sizeable velocities."""
    y0 = initial_state(cfg)
    out = []
    for _ in range(n):
        y = y0.copy()
        k = y.size // 2
        y[:k] *= rng.uniform(0.5, 2.0, k)
        y[k:] = rng.normal(0, 1e-4, k)
        out.append(y)
    return out


@pytest.mark.parametrize("name", list(CONFIGS))
def test_rhs_matches_independent_numpy_implementation(name):
    """Compiled f(t, y) equals the numpy/scipy reference written from eqs 1, 22-28."""
    cfg = CONFIGS[name]
    p = SIM.parameter_vector(cfg)
    model = M.MODEL_IDS[cfg.model]
    ref = ReferenceModel(cfg)
    rng = np.random.default_rng(1)
    for y in _states(cfg, rng):
        for z in (-30e-9, -3e-9, 0.5e-9 + ref.separation(y, 0.0, 0.0)[0] - 1.0e-9):
            h = ref.separation(y, z, 0.0)[0]
            if h <= 0.2e-9:
                continue
            out = np.empty_like(y)
            assert M.rhs(model, p, z, 1e-7, y, out)
            expect = ref.fun(0.0, y, lambda t: z, 1e-7)
            np.testing.assert_allclose(out, expect, rtol=1e-10, atol=1e-12 * np.abs(expect).max())


@pytest.mark.parametrize("name", list(CONFIGS))
def test_analytic_jacobian_matches_finite_differences(name):
    """Analytic df/dy (the integrator's Newton matrix) against central differences."""
    cfg = CONFIGS[name]
    p = SIM.parameter_vector(cfg)
    model = M.MODEL_IDS[cfg.model]
    rng = np.random.default_rng(2)
    for y in _states(cfg, rng):
        z = -2.5e-9 if cfg.model == "beam" else -2e-9
        n = y.size
        f = np.empty(n)
        if not M.rhs(model, p, z, 1e-7, y, f):
            continue
        J = np.empty((n, n))
        assert M.jac(model, p, z, 1e-7, y, J)
        Jfd = np.empty((n, n))
        for j in range(n):
            step = 1e-6 * max(abs(y[j]), 1e-12 if j < n // 2 else 1e-9)
            yp, ym = y.copy(), y.copy()
            yp[j] += step
            ym[j] -= step
            fp, fm = np.empty(n), np.empty(n)
            M.rhs(model, p, z, 1e-7, yp, fp)
            M.rhs(model, p, z, 1e-7, ym, fm)
            Jfd[:, j] = (fp - fm) / (2 * step)
        scale = np.abs(Jfd).max(axis=1, keepdims=True) + 1e-300
        np.testing.assert_allclose(J / scale, Jfd / scale, atol=2e-6)


def test_force_law_guard_rejects_trial_states_at_or_below_zero_separation():
    """h <= guard (0.2 z0) is inadmissible: eq 2 would turn attractive at h -> 0."""
    cfg = SimulationConfig(model="spring")
    p = SIM.parameter_vector(cfg)
    out = np.empty(2)
    J = np.empty((2, 2))
    for h in (-1e-9, 0.0, 0.5 * SIM.H_GUARD_FRACTION * cfg.z0):
        y = np.array([h, 0.0])
        assert not M.rhs(M.MODEL_SPRING, p, 0.0, 0.0, y, out)
        assert not M.jac(M.MODEL_SPRING, p, 0.0, 0.0, y, J)
    assert M.rhs(M.MODEL_SPRING, p, 0.0, 0.0, np.array([0.3e-9, 0.0]), out)


@pytest.mark.parametrize("name", list(CONFIGS))
def test_start_state_is_a_static_equilibrium(name):
    """At rest at the start position all accelerations vanish (no friction at rest)."""
    cfg = CONFIGS[name]
    p = SIM.parameter_vector(cfg)
    y = initial_state(cfg)
    f = np.empty_like(y)
    assert M.rhs(M.MODEL_IDS[cfg.model], p, cfg.start, 0.0, y, f)
    n = y.size // 2
    # accelerations small compared with the elastic term alone
    scale = (cfg.force_constant * 1e-9) * (p[M.INV_M] if cfg.model == "spring" else p[M.INV_MB])
    assert np.all(np.abs(f[n:]) < 1e-6 * scale)
    assert np.all(f[:n] == 0.0)


def test_beam_dynamical_matrix_reproduces_eq13_spring_constant():
    """Statics of eqs 22-27 (A q + Fz dh/dq = 0) give k of eq 13 and beta of eq 15."""
    cfg = SimulationConfig()
    cant = cfg.cantilever
    A, _ = M.beam_matrices(cant, cfg.m_joint, cfg.m_base)
    hq, yq, tq = M.beam_couplings(cant)
    q = np.linalg.solve(-A, hq)          # response to a unit Fz
    dz2 = hq @ q
    dtheta = tq @ q
    assert 1.0 / dz2 == pytest.approx(cant.spring_constant, rel=1e-12)
    assert dz2 / dtheta == pytest.approx(1.294e-4, rel=2e-4)           # eq 15: 1.294e5 nm/rad
    # the free beam's lowest resonance is the paper's "4 kHz" (section 2.3), a rounded value:
    # 4.062 kHz from eqs 7-12 (tests/paper/test_paper_numbers.py recomputes it independently)
    m = np.diag([cfg.m_joint + cfg.m_base / 4, cfg.m_base / 3])
    w2 = np.linalg.eigvals(np.linalg.solve(m, -A)).real
    assert math.sqrt(w2.min()) / (2 * math.pi) == pytest.approx(4.0e3, rel=0.02)


def test_friction_registry():
    """Registry entries give the coefficients of Fy = -(xi + zeta Fz^2) y2' (eq 28 and after)."""
    assert set(FRICTION_LAWS) == {"none", "viscous", "load"}
    assert FRICTION_LAWS["none"].coefficients(0.1, 5.0) == (0.0, 0.0)
    assert FRICTION_LAWS["viscous"].coefficients(0.1, 5.0) == (0.1, 0.0)
    assert FRICTION_LAWS["load"].coefficients(0.1, 5.0) == (0.1, 5.0)
    assert "eq 28" in FRICTION_LAWS["viscous"].formula


def test_b_decision_gives_k0_013():
    """Spec section 5 decision: B = 3.5e-13 N m^2 gives k0 = 3B/L0^3 = 0.131 N/m."""
    assert SimulationConfig().cantilever.k0 == pytest.approx(3 * FIG5["B"] / FIG5["L0"] ** 3)
    assert SimulationConfig().cantilever.k0 == pytest.approx(0.13, rel=0.02)


def test_docs_list_every_registered_option():
    """docs/dynamics.md documents every friction law and ringing treatment of the registries."""
    from pathlib import Path

    from afmforce.dynamics import RINGING

    doc = (Path(__file__).resolve().parents[2] / "docs" / "dynamics.md").read_text()
    for key, law in FRICTION_LAWS.items():
        assert f"`{key}`" in doc, key
    for key in RINGING:
        assert f'ringing="{key}"' in doc, key
