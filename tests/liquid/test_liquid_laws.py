"""Liquid force laws (issue 25) against closed forms, published values and limits."""

import math

import numpy as np
import pytest

from afmforce import forces as F
from afmforce.errors import ParameterError


def test_debye_length_of_1mM_NaCl_is_9_6_nm():
    # 0.304 nm / sqrt(I [mol/L]) for a 1:1 salt in water at 25 C (Israelachvili)
    assert F.debye_length(1e-3) == pytest.approx(9.6e-9, rel=5e-3)
    assert F.debye_length([1e-3, 0.1]) == pytest.approx(0.304e-9 / np.sqrt([1e-3, 0.1]), rel=5e-3)
    with pytest.raises(ParameterError):
        F.debye_length(0.0)


def test_geometry_effective_radius_and_paper_laws_unchanged():
    h = np.geomspace(0.5e-9, 50e-9, 20)
    # sphere-flat: -A R / (6 h^2) (1 - z0^6/4h^6) = the paper's eq 2 with 2R
    r = 2e-6
    flat = -5e-19 * r / (6 * h**2) * (1 - (0.35e-9 / h) ** 6 / 4)
    assert F.vdw_force(h, F.paper_radius(r, "sphere-flat")) == pytest.approx(flat, rel=1e-13)
    assert F.paper_radius(r, "sphere-sphere") == r
    # drainage: paper (sphere-sphere) and Reynolds (sphere-flat, -6 pi eta R^2 h'/h)
    hd = -1e-6
    assert F.slip_drainage_force(h, hd, r, 1e-3) == pytest.approx(F.drainage_force(h, hd, r, 1e-3), rel=1e-13)
    assert F.slip_drainage_force(h, hd, r, 1e-3, geometry="sphere-flat") == pytest.approx(
        -6 * math.pi * 1e-3 * r**2 * hd / h, rel=1e-13)
    with pytest.raises(ParameterError):
        F.effective_radius(r, "cube")


def test_slip_factor_limits():
    h = np.geomspace(1e-10, 1e-6, 50)
    assert F.slip_factor(h, 0.0) == pytest.approx(1.0, rel=1e-15)
    # b -> 0: f* -> 1 - u/3 + u^2/6 (u = 6b/h), continuous across the series switch
    b = 1e-15
    u = 6 * b / h
    assert F.slip_factor(h, b) == pytest.approx(1 - u / 3 + u * u / 6, rel=1e-12)
    hh = 6 * 1e-9 / np.array([0.999e-3, 1.001e-3])
    f = F.slip_factor(hh, 1e-9)
    assert f[0] == pytest.approx(f[1], rel=1e-5)
    # h << b: f* ~ (h/3b) ln(6b/h), the next order (h/3b)(ln(6b/h) - 1) to O((h/b) ln(b/h))
    b, hs = 1e-6, np.array([1e-12, 1e-11])
    lead = hs / (3 * b) * np.log(6 * b / hs)
    assert F.slip_factor(hs, b) == pytest.approx(hs / (3 * b) * (np.log(6 * b / hs) - 1), rel=1e-5)
    assert F.slip_factor(hs, b) / lead == pytest.approx(1 - 1 / np.log(6 * b / hs), rel=1e-5)
    # the exact formula at a moderate point, written out independently
    h1, b1 = 10e-9, 5e-9
    exact = h1 / (3 * b1) * ((1 + h1 / (6 * b1)) * math.log(1 + 6 * b1 / h1) - 1)
    assert F.slip_factor(h1, b1) == pytest.approx(exact, rel=1e-14)
    assert 0 < exact < 1


@pytest.mark.parametrize("law", ["weak_overlap", "constant_potential", "constant_charge"])
def test_double_layer_gradient_is_the_derivative(law):
    h = np.geomspace(0.3e-9, 60e-9, 40)
    args = dict(surface_potential=-0.04, debye_length=9.6e-9, surface_potential_2=-0.025, law=law,
                geometry="sphere-flat")
    d = 1e-6 * h
    num = (F.double_layer_force(h + d, 2e-6, **args) - F.double_layer_force(h - d, 2e-6, **args)) / (2 * d)
    assert F.double_layer_force_gradient(h, 2e-6, **args) == pytest.approx(num, rel=1e-6)


def test_hhf_tends_to_weak_overlap_and_orders_correctly():
    lam, p1, p2, eps = 9.6e-9, -0.04, -0.03, 78.5
    weak = 2 * eps * F.EPS0 / lam * p1 * p2 * np.exp(-np.array([1.0, 5.0, 10.0]))
    h = lam * np.array([1.0, 5.0, 10.0])
    w_w = F.double_layer_energy(h, p1, lam, p2, eps, "weak_overlap")
    assert w_w == pytest.approx(weak, rel=1e-13)
    for law in ("constant_potential", "constant_charge"):
        w = F.double_layer_energy(h, p1, lam, p2, eps, law)
        rel = np.abs(w / w_w - 1)
        assert rel[2] < 1e-4 and rel[1] < 1e-2 and rel[0] > rel[1]
    # close in: constant charge > weak overlap > constant potential (symmetric potentials)
    hc = 0.5e-9
    cc, wo, cp = (F.double_layer_energy(hc, p1, lam, None, eps, law)
                  for law in ("constant_charge", "weak_overlap", "constant_potential"))
    assert cc > wo > cp > 0
    # symmetric constant potential at contact: W(0) = c (2 psi^2) * lim [csch - coth + 1] = eps eps0 kappa psi^2
    assert F.double_layer_energy(1e-15, p1, lam, None, eps, "constant_potential") == pytest.approx(
        eps * F.EPS0 / lam * p1**2, rel=1e-5)
    # Derjaguin: F = 2 pi R_eff W
    assert F.double_layer_force(h, 1e-6, p1, lam, p2, eps, "weak_overlap", "sphere-flat") == pytest.approx(
        2 * math.pi * 1e-6 * weak, rel=1e-13)
    assert np.all(F.double_layer_force(h, 1e-6, p1, lam, law="none") == 0)


def test_lever_drag():
    assert F.lever_drag_force(1e-6, -2e-6, 5e-5) == pytest.approx(1e-10)
    assert F.lever_drag_force(np.array([0.0, 10e-6]), 1e-6, 5e-5, 10e-6) == pytest.approx([-5e-11, -2.5e-11])


def test_quadratic_photodiode_response():
    from afmforce.instrument import Photodiode, get_preset
    pd = Photodiode(sensitivity=30e-9, offset=0.1, nonlinearity_length=3e-6)
    d = np.array([-50e-9, 0.0, 100e-9])
    assert pd.optical(d) == pytest.approx((d + d**2 / 3e-6) / 30e-9 + 0.1, rel=1e-14)
    with pytest.raises(ParameterError):
        Photodiode(sensitivity=30e-9, nonlinearity_length=0.0)
    assert get_preset("liquid").photodiode.nonlinearity_length == 3e-6
