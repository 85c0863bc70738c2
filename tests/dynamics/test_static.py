"""Quasi-static deflection curves (spec sections 2, 3 and 7)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce.dynamics import SimulationConfig, static_curve, static_deflection, static_jump_in
from afmforce.forces import vdw_force, vdw_force_gradient


def test_static_jump_in_spec_section7():
    """Spec 7: R = 100 nm, k = 0.1387 N/m: static jump-in h = 3.92 nm, deflection -1.96 nm."""
    k = SimulationConfig().force_constant
    assert k == pytest.approx(0.1387, abs=1e-4)
    h, z, d = static_jump_in(k, 100e-9)
    assert h == pytest.approx(3.92e-9, abs=0.005e-9)
    assert d == pytest.approx(-1.96e-9, abs=0.005e-9)
    assert z == pytest.approx(d - h)                      # h = z2 - z (spec 1)
    assert float(vdw_force_gradient(h, 100e-9)) == pytest.approx(k, rel=1e-9)


def test_static_jump_in_fig9():
    """Spec 2: R = 220 nm, k = 0.21 N/m jumps in at h = 4.4 nm."""
    assert static_jump_in(0.21, 220e-9)[0] == pytest.approx(4.4e-9, abs=0.05e-9)


def test_static_curve_obeys_hookes_law_and_marks_unstable_branch():
    """z2 = Fs(h)/k; stable where Fs' < k; the unstable part lies between z0 and h_J."""
    k, R = 0.21, 100e-9
    c = static_curve(k, R)
    np.testing.assert_allclose(c.deflection * k, vdw_force(c.separation, R), rtol=1e-12)
    np.testing.assert_allclose(c.separation, c.deflection - c.piezo_position, rtol=1e-12)
    unstable = c.separation[~c.stable]
    assert unstable.min() > 0.35e-9 and unstable.max() < c.jump_in_separation
    assert np.all(c.stable[c.separation > c.jump_in_separation * 1.001])
    assert np.all(c.stable[c.separation < 0.35e-9])       # contact branch (repulsive wall)
    # the drive position is extremal (a fold) at the jump-in: dz/dh = 0
    i = np.argmin(np.abs(c.separation - c.jump_in_separation))
    assert np.all(c.piezo_position[c.separation > c.separation[i]] <= c.jump_in_position + 1e-15)


def test_static_deflection_inverts_the_curve_and_stops_at_jump_in():
    """static_deflection(z) lies on the stable out-of-contact branch; NaN past the jump."""
    k, R = 0.1387, 100e-9
    h = np.linspace(4e-9, 40e-9, 50)
    z = vdw_force(h, R) / k - h
    np.testing.assert_allclose(static_deflection(z, k, R), vdw_force(h, R) / k, rtol=1e-9,
                               atol=1e-18)
    hj, zj, _ = static_jump_in(k, R)
    assert math.isnan(static_deflection(zj + 0.01e-9, k, R))
    assert not math.isnan(static_deflection(zj - 0.01e-9, k, R))
