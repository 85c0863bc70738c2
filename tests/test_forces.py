"""Surface-force laws (paper section 2.1, spec section 2)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from afmforce import forces
from afmforce.constants import HAMAKER, Z0

R = 100e-9


def test_force_at_z0_is_max_attraction_closed_form():
    # spec 2: Fs(z0) = -A R / (16 z0^2)
    assert forces.vdw_force(Z0, R) == pytest.approx(-HAMAKER * R / (16 * Z0**2), rel=1e-14)


def test_zero_force_separation_eq2():
    # below eq 2: h0 = z0 / 2^(1/3) is where Fs vanishes
    h0 = forces.zero_force_separation()
    assert h0 == pytest.approx(Z0 / 2 ** (1 / 3))
    assert abs(forces.vdw_force(h0, R)) < 1e-12 * abs(forces.vdw_force(Z0, R))


def test_max_attraction_at_z0_gradient_vanishes():
    assert forces.max_attraction_separation() == Z0
    assert abs(forces.vdw_force_gradient(Z0, R)) < 1e-9
    h = np.linspace(0.3e-9, 2e-9, 2001)
    assert h[np.argmin(forces.vdw_force(h, R))] == pytest.approx(Z0, abs=1e-12)


def test_gradient_matches_finite_difference():
    h = np.linspace(0.5e-9, 20e-9, 50)
    d = 1e-15
    fd = (forces.vdw_force(h + d, R) - forces.vdw_force(h - d, R)) / (2 * d)
    np.testing.assert_allclose(forces.vdw_force_gradient(h, R), fd, rtol=1e-5)


def test_gradient_at_5nm_fig1():
    # section 2.1: |Fs'(5 nm)| = 0.067 N/m for R = 100 nm (closed form (AR/6)(h^-3 - z0^6 h^-9))
    g = forces.vdw_force_gradient(5e-9, 100e-9)
    assert g == pytest.approx(HAMAKER * R / 6 * (5e-9**-3 - Z0**6 * 5e-9**-9), rel=1e-12)
    assert abs(g) == pytest.approx(0.067, rel=0.01)  # paper's rounding


def test_surface_energy_section_2_1():
    # gamma = A/(16 pi z0^2): closed form 0.08120 J/m^2; paper prints 0.08
    assert forces.surface_energy() == pytest.approx(5e-19 / (16 * math.pi * 0.35e-9**2), rel=1e-14)
    assert forces.surface_energy() == pytest.approx(0.0812, rel=1e-3)
    assert forces.surface_energy() == pytest.approx(0.08, rel=0.05)


def test_pull_off_jkr_and_dmt():
    g = forces.surface_energy()
    assert forces.pull_off_force_jkr(g, R) == pytest.approx(-3 * math.pi * g * R / 4)
    # DMT (rigid) pull-off equals the maximum attraction of eq 2
    assert forces.pull_off_force_dmt(g, R) == pytest.approx(forces.max_attraction_force(R), rel=1e-12)


def test_radius_from_jump_out_fig9():
    # section 3: 200 nm jump-out with k = 0.21 N/m gives R = 220 nm (closed form 219.5 nm)
    r = forces.radius_from_jump_out(0.21, 200e-9, forces.surface_energy())
    assert r == pytest.approx(4 * 0.21 * 200e-9 / (3 * math.pi * forces.surface_energy()))
    assert r == pytest.approx(220e-9, rel=0.01)


def test_static_jump_in_fig9():
    # section 3: static jump-in at 4.4 nm for R = 220 nm, k = 0.21 N/m
    h = forces.static_jump_in_separation(0.21, 220e-9)
    assert h == pytest.approx(4.4e-9, rel=0.01)
    # the defining condition Fs'(h) = k, and it is the largest such h
    assert forces.vdw_force_gradient(h, 220e-9) == pytest.approx(0.21, rel=1e-9)
    hh = np.linspace(h * 1.0001, 100e-9, 1000)
    assert np.all(forces.vdw_force_gradient(hh, 220e-9) < 0.21)


def test_static_jump_in_spec7():
    # spec 7: R = 100 nm, k = 0.1387 N/m -> h = 3.92 nm
    assert forces.static_jump_in_separation(0.1387, 100e-9) == pytest.approx(3.92e-9, rel=2e-3)


def test_no_jump_for_very_stiff_spring():
    assert math.isnan(forces.static_jump_in_separation(1e6, 100e-9))


def test_drainage_opposes_motion():
    # after eq 1: Fd = -6 pi eta R^2 hdot / (4 h)
    f = forces.drainage_force(10e-9, -1e-6, R)
    assert f == pytest.approx(6 * math.pi * 1.8e-5 * R**2 * 1e-6 / (4 * 10e-9))
    assert f > 0


def test_energy_per_area_derjaguin_convention():
    # Fig 9 convention: E = F/(pi R); Fs(z0)/(pi R) = -gamma
    e = forces.energy_per_area(forces.vdw_force(Z0, R), R)
    assert e == pytest.approx(-forces.surface_energy(), rel=1e-12)


def test_scalar_in_scalar_out_array_in_array_out():
    assert np.ndim(forces.vdw_force(1e-9, R)) == 0
    assert forces.vdw_force(np.array([1e-9, 2e-9]), R).shape == (2,)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(min_value=0.2e-9, max_value=1e-6), min_size=1, max_size=20),
       st.floats(min_value=1e-9, max_value=1e-5))
def test_vectorised_equals_scalar(hs, radius):
    arr = forces.vdw_force(np.array(hs), radius)
    grad = forces.vdw_force_gradient(np.array(hs), radius)
    for i, h in enumerate(hs):
        assert arr[i] == forces.vdw_force(h, radius)
        assert grad[i] == forces.vdw_force_gradient(h, radius)


@settings(max_examples=50, deadline=None)
@given(st.floats(min_value=1e-3, max_value=10), st.floats(min_value=1e-8, max_value=1e-5))
def test_jump_in_condition_holds(k, radius):
    h = forces.static_jump_in_separation(k, radius)
    if not math.isnan(h):
        assert forces.vdw_force_gradient(h, radius) == pytest.approx(k, rel=1e-7)
