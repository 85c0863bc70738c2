"""The modulus fit's compiled Gauss-Newton terms (issue 35 item 2) are the numpy expressions' numbers, bit for bit.

``contact._kernels.power_law_terms`` replaces, for the power laws, the residuals and Jacobian that
``contact.fit._linear_fit`` and ``_fit_samples`` built from ``models.shape_and_slope`` and ``_weights``;
every sample's operations are the same, so the arrays must be equal (not close), and a whole fit through
it equal to the fit through numpy.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce.contact import fit as fit_module
from afmforce.contact._kernels import COMPILED, power_law_terms
from afmforce.contact._weights import weights
from afmforce.contact.fit import _POWER, fit_indentation
from afmforce.contact.models import shape_and_slope

pytestmark = pytest.mark.skipif(not COMPILED, reason="the kernel runs compiled only")

GEOM = {"radius": 2.5e-6, "half_angle": math.radians(17.5)}


@pytest.mark.parametrize("key", sorted(_POWER))
@pytest.mark.parametrize("width", [0.0, 40e-9])
def test_terms_equal_the_numpy_expressions(key, width):
    rng = np.random.default_rng(5)
    u = np.sort(rng.uniform(-300e-9, 900e-9, 777))
    F = 1e-9 * rng.standard_normal(u.size) + 2e-3 * np.clip(u, 0, None) ** 1.5
    nu = 0.45
    E, c, b = 3.3e3, 12.7e-9, -1.1e-10
    d = u - c
    phi, dphi = shape_and_slope(key, d, GEOM, nu)
    q = weights(d, width)
    r_np = q * (F - E * phi - b)
    J_np = q[:, None] * np.column_stack((phi, -E * dphi, np.ones_like(phi)))
    kf, p = _POWER[key]
    r, J, shape = power_law_terms(u, F, E, c, b, kf(GEOM, 1.0 / (1.0 - nu * nu)), p, width, True)
    np.testing.assert_array_equal(r, r_np)
    np.testing.assert_array_equal(J, J_np)
    np.testing.assert_array_equal(shape, phi)
    assert J.flags.c_contiguous
    r2, J2, _ = power_law_terms(u, F, E, c, b, kf(GEOM, 1.0 / (1.0 - nu * nu)), p, width, False)
    np.testing.assert_array_equal(r2, r_np)
    assert J2.size == 0


@pytest.mark.parametrize("key", ["hertz_paraboloid", "hertz_cone"])
@pytest.mark.parametrize("width", [0.0, 30e-9])
def test_a_whole_fit_is_the_numpy_paths(key, width, monkeypatch):
    rng = np.random.default_rng(11)
    u = np.linspace(-1e-6, 0.6e-6, 1500)
    kf, p = _POWER[key]
    F = 4e3 * kf(GEOM, 1.0 / 0.75) * np.clip(u - 0.05e-6, 0, None) ** p + 5e-12 * rng.standard_normal(u.size)
    fast = fit_indentation(u, F, key, GEOM, weight_width=width)
    monkeypatch.setattr(fit_module, "_power_terms", lambda *a, **k: None)
    slow = fit_indentation(u, F, key, GEOM, weight_width=width)
    for name in ("youngs_modulus", "youngs_modulus_se", "youngs_modulus_low", "contact", "contact_se", "baseline", "rms"):
        a, b = getattr(fast, name), getattr(slow, name)
        assert a == b or (math.isnan(a) and math.isnan(b)), (name, a, b)
    np.testing.assert_array_equal(fast.residuals, slow.residuals)
