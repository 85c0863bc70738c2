"""Static friction analysis (paper section 2.2, eqs 16-21; Figs 3, 4)."""

import math

import pytest

from afmforce import InclinedCantilever
from afmforce.constants import FIG3, FIG3_MU, FIG4_LAMBDA, FIG5
from afmforce.errors import ParameterError
from afmforce.statics import (
    FRICTION_MODELS,
    constant_friction_force_difference,
    constant_friction_offset,
    load_friction_constants,
    load_friction_gap,
    pinned_calibration_factor,
    pinned_spring_constant,
    static_analysis,
    viscous_friction_force,
)


@pytest.fixture
def c():
    return InclinedCantilever(**FIG3)


@pytest.fixture
def c5():
    g = FIG5
    return InclinedCantilever(L0=g["L0"], L1=g["L1"], L2=g["L2"], theta0=g["theta0"], B=g["B"])


def test_eq17_force_difference(c):
    assert constant_friction_force_difference(c, FIG3_MU) == pytest.approx(3.104e-9, rel=1e-3)


def test_eq16_offset_fig3(c):
    off = constant_friction_offset(c, FIG3_MU)
    assert off == pytest.approx(0.7622e-9, rel=1e-3)  # closed form
    assert off == pytest.approx(0.76e-9, rel=0.01)  # paper Fig 3


def test_eq16_offset_equals_compliance_difference(c):
    # Independent route: solve the compliance matrix at fixed theta for Fy = +-mu.
    C, g = c.compliance_matrix, c.angle_compliance
    mu = FIG3_MU
    theta = 1e-5
    fz_p = (theta - g[1] * mu) / g[0]
    fz_m = (theta + g[1] * mu) / g[0]
    z_p = C[0, 0] * fz_p + C[0, 1] * mu
    z_m = C[0, 0] * fz_m - C[0, 1] * mu
    assert constant_friction_offset(c, mu) == pytest.approx(z_p - z_m, rel=1e-10)
    assert constant_friction_force_difference(c, mu) == pytest.approx(fz_p - fz_m, rel=1e-10)


def test_constant_friction_leaves_k_and_beta(c):
    r = static_analysis(c, "constant", mu=FIG3_MU)
    assert r.spring_constant == c.spring_constant
    assert r.calibration_factor == c.calibration_factor


def test_fig4_load_friction(c):
    # eqs 18, 19 with lambda = 2 (spec 4.2 references)
    k_in, b_in = load_friction_constants(c, FIG4_LAMBDA, +1)
    k_out, b_out = load_friction_constants(c, FIG4_LAMBDA, -1)
    assert k_in == pytest.approx(0.3434, rel=2e-4)
    assert b_in * 1e9 == pytest.approx(1.3654e5, rel=1e-4)
    assert k_out == pytest.approx(0.0859, rel=1e-3)
    assert b_out * 1e9 == pytest.approx(1.2772e5, rel=1e-4)
    assert k_in * 10e-9 == pytest.approx(3.4e-9, rel=0.015)  # paper: Fz = 3.4 nN at z2 = 10 nm


def test_eqs18_19_written_out(c):
    L0, B, a, b, lam = c.L0, c.B, c.a, c.b, FIG4_LAMBDA
    co, s = math.cos(c.theta0), math.sin(c.theta0)
    for sign in (+1, -1):
        inv_k = (1 / (2 * B)) * ((2 / 3 * L0**3 * co + a * L0**2) * (co + sign * lam * s)
                                 + (L0**2 * co + 2 * a * L0) * (a + sign * b * lam))
        k = 1 / inv_k
        inv_beta = k / (2 * B) * (L0**2 * (co + sign * lam * s) + 2 * L0 * (a + sign * b * lam))
        kk, bb = load_friction_constants(c, lam, sign)
        assert kk == pytest.approx(k, rel=1e-12)
        assert bb == pytest.approx(1 / inv_beta, rel=1e-12)


def test_fig4_gap(c):
    gap = load_friction_gap(c, FIG4_LAMBDA, 10e-9)
    assert gap == pytest.approx(0.646e-9, rel=2e-3)  # closed form
    assert gap == pytest.approx(0.65e-9, rel=0.01)  # paper "horizontal displacement 0.65 nm"


def test_zero_lambda_recovers_frictionless(c):
    k, beta = load_friction_constants(c, 0.0, +1)
    assert k == pytest.approx(c.spring_constant)
    assert beta == pytest.approx(c.calibration_factor)


def test_eq21_pinned(c):
    beta = pinned_calibration_factor(c)
    assert beta == pytest.approx(c.a - c.b / math.tan(c.theta0), rel=1e-14)
    assert beta * 1e9 == pytest.approx(-1.5455e4, rel=1e-4)
    assert beta < 0  # paper: pinning reverses the sign of the calibration factor


def test_pinned_spring_constant_independent(c):
    # y2 = 0 constraint solved directly: Fy = -Cyz/Cyy Fz
    C = c.compliance_matrix
    fz = 1e-9
    fy = -C[1, 0] / C[1, 1] * fz
    z2 = C[0, 0] * fz + C[0, 1] * fy
    assert pinned_spring_constant(c) == pytest.approx(fz / z2, rel=1e-12)
    assert pinned_spring_constant(c) > c.spring_constant


def test_viscous_steady_sliding(c5):
    # section 2.3 / spec 7: xi = 0.1 kg/s at 0.1 um/s -> Fy = 3.00 nN, offset 0.453 nm (B = 3.5e-13)
    fy = viscous_friction_force(c5, 0.1, 0.1e-6)
    assert fy == pytest.approx(3.00e-9, rel=2e-3)
    off = constant_friction_offset(c5, fy)
    assert off == pytest.approx(0.453e-9, rel=2e-3)
    assert off == pytest.approx(0.5e-9, rel=0.12)  # paper: "about 0.5 nm"
    r = static_analysis(c5, "viscous", xi=0.1, velocity=0.1e-6)
    assert r.extra["friction_force"] == pytest.approx(fy)
    assert r.extra["hysteresis_offset"] == pytest.approx(off)


def test_registry_dispatch_and_errors(c):
    assert set(FRICTION_MODELS) == {"none", "constant", "load", "pinned", "viscous"}
    with pytest.raises(ParameterError, match="needs mu"):
        static_analysis(c, "constant")
    with pytest.raises(ParameterError, match="needs xi"):
        static_analysis(c, "viscous", velocity=1e-7)
    with pytest.raises(ParameterError, match="unknown friction"):
        static_analysis(c, "sticky")
    with pytest.raises(ParameterError):
        static_analysis(c, "constant", mu=-1e-9)
    with pytest.raises(ParameterError, match="does not take"):
        static_analysis(c, "none", mu=1e-9)
    r = static_analysis(c, "pinned")
    assert r.calibration_factor < 0
