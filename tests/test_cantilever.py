"""Cantilever geometry and compliance (paper section 2.2, eqs 7-15)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from afmforce import InclinedCantilever, SimpleSpring
from afmforce.constants import FIG3
from afmforce.errors import AfmforceError, ParameterError


@pytest.fixture
def fig3():
    return InclinedCantilever(**FIG3)


def test_eq14_tilt_factor():
    # eq 14: k = k0/cos^2(theta0) = 1.07 k0 at -15 deg (closed form 1.0718)
    c = InclinedCantilever(**FIG3)
    assert c.spring_constant_tilt_only / c.k0 == pytest.approx(1 / math.cos(math.radians(15)) ** 2)
    assert c.spring_constant_tilt_only / c.k0 == pytest.approx(1.0718, abs=1e-4)
    assert c.spring_constant_tilt_only / c.k0 == pytest.approx(1.07, abs=0.005)  # paper rounding


def test_eq13_spring_constant_fig3(fig3):
    # eq 13 written out as in the paper, against the compliance-matrix implementation
    L0, B, a = fig3.L0, fig3.B, fig3.a
    co = math.cos(fig3.theta0)
    inv_k = co / (2 * B) * (2 / 3 * L0**3 * co + a * L0**2) + a / (2 * B) * (L0**2 * co + 2 * a * L0)
    assert fig3.spring_constant == pytest.approx(1 / inv_k, rel=1e-12)
    assert fig3.spring_constant == pytest.approx(0.13741, rel=1e-4)  # spec 4.1 reference


def test_eq15_calibration_factor_fig3(fig3):
    L0, B, a, k = fig3.L0, fig3.B, fig3.a, fig3.spring_constant
    inv_beta = k / (2 * B) * (L0**2 * math.cos(fig3.theta0) + 2 * L0 * a)
    assert fig3.calibration_factor == pytest.approx(1 / inv_beta, rel=1e-12)
    assert fig3.calibration_factor * 1e9 == pytest.approx(1.29391e5, rel=1e-5)  # nm/rad
    assert fig3.calibration_factor * 1e9 == pytest.approx(1.3e5, rel=0.01)  # paper rounding


def test_a_b_eq10(fig3):
    t = math.radians(-15)
    assert fig3.a == pytest.approx(2e-6 * math.cos(t) + 4e-6 * math.sin(t))
    assert fig3.b == pytest.approx(2e-6 * math.sin(t) - 4e-6 * math.cos(t))
    assert fig3.b < 0


def test_tip_position_eqs_7_to_12(fig3):
    # direct evaluation of eqs 7-12 for some forces
    Fz, Fy = 2e-9, -1e-9
    c, s = math.cos(fig3.theta0), math.sin(fig3.theta0)
    F0 = Fz * c + Fy * s
    tau = fig3.a * Fz + fig3.b * Fy
    B, L0 = fig3.B, fig3.L0
    x = (2 / 3 * F0 * L0**3 + tau * L0**2) / (2 * B)
    th = (F0 * L0**2 + 2 * L0 * tau) / (2 * B)
    z2, y2 = fig3.tip_position(Fz, Fy)
    assert z2 == pytest.approx(x * c + fig3.a * th, rel=1e-12)
    assert y2 == pytest.approx(x * s + fig3.b * th, rel=1e-12)
    assert fig3.angle(Fz, Fy) == pytest.approx(th, rel=1e-12)


def test_stiffness_is_inverse_compliance(fig3):
    np.testing.assert_allclose(fig3.beam_stiffness @ fig3.beam_compliance, np.eye(2), atol=1e-9)


def test_k0_and_B_are_alternatives():
    a = InclinedCantilever(200e-6, 2e-6, 4e-6, -0.2, k0=0.13)
    b = InclinedCantilever(200e-6, 2e-6, 4e-6, -0.2, B=a.B)
    assert b.k0 == pytest.approx(0.13)
    assert a.spring_constant == pytest.approx(b.spring_constant)


@pytest.mark.parametrize("kw", [
    dict(L0=0), dict(L0=-1e-6), dict(L1=0), dict(L2=-1e-6), dict(theta0=math.pi / 2),
    dict(theta0=-2.0), dict(k0=0), dict(k0=-0.1), dict(k0=float("nan")),
])
def test_bad_geometry_raises(kw):
    args = dict(FIG3)
    args.update(kw)
    with pytest.raises(ParameterError):
        InclinedCantilever(**args)


def test_both_or_neither_stiffness_raises():
    with pytest.raises(AfmforceError):
        InclinedCantilever(200e-6, 2e-6, 4e-6, -0.2)
    with pytest.raises(AfmforceError):
        InclinedCantilever(200e-6, 2e-6, 4e-6, -0.2, k0=0.1, B=1e-13)


def test_simple_spring():
    s = SimpleSpring(0.21, 1e-8)
    assert s.resonance_frequency == pytest.approx(math.sqrt(0.21 / 1e-8) / (2 * math.pi))
    with pytest.raises(ParameterError):
        SimpleSpring(0.21, 0)
    with pytest.raises(ParameterError):
        SimpleSpring(-1, 1e-8)


geom = st.tuples(st.floats(50e-6, 500e-6), st.floats(0.1e-6, 20e-6), st.floats(0, 20e-6),
                 st.floats(-1.4, 1.4), st.floats(0.01, 50))


@settings(max_examples=60, deadline=None)
@given(geom)
def test_maxwell_betti_symmetry(g):
    c = InclinedCantilever(*g[:4], k0=g[4])
    C = c.compliance_matrix
    assert C[0, 1] == pytest.approx(C[1, 0], rel=1e-12, abs=1e-30)
    # positive definite (elastic energy positive)
    assert np.all(np.linalg.eigvalsh(C) > -1e-12 * np.abs(C).max())


@settings(max_examples=40, deadline=None)
@given(st.floats(-1.3, 1.3), st.floats(0.01, 10))
def test_eq14_limit_small_base_and_probe(theta0, k0):
    # k -> k0/cos^2(theta0) as L1, L2 -> 0
    c = InclinedCantilever(200e-6, 1e-12, 0.0, theta0, k0=k0)
    assert c.spring_constant == pytest.approx(k0 / math.cos(theta0) ** 2, rel=1e-6)
