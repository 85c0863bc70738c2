"""Indentation laws against closed forms and published relations (issue 26, items 1 and 5)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce.contact import INDENTATION_MODELS, indentation_model
from afmforce.contact import adhesive as A
from afmforce.contact import models as M
from afmforce.contact.fit import fit_indentation, model_force
from afmforce.errors import ParameterError
from afmforce.forces import pull_off_force_dmt, pull_off_force_jkr

E, R, NU = 2e3, 5e-6, 0.5
ES = E / (1 - NU ** 2)


def test_elastic_laws_closed_forms():
    d = np.array([-1e-7, 0.0, 1e-7, 1e-6])
    assert np.allclose(M.hertz_paraboloid(d, E, R, NU), 4 / 3 * ES * math.sqrt(R) * np.maximum(d, 0) ** 1.5)
    a = math.radians(20)
    assert np.allclose(M.hertz_cone(d, E, a, NU), 2 * math.tan(a) / math.pi * ES * np.maximum(d, 0) ** 2)
    assert np.allclose(M.bilodeau_pyramid3(d, E, a, NU), 0.8887 * math.tan(a) * ES * np.maximum(d, 0) ** 2)
    assert np.allclose(M.bilodeau_pyramid4(d, E, a, NU), 0.7453 * math.tan(a) * ES * np.maximum(d, 0) ** 2)


def test_exact_sphere_matches_sneddon_power_series_and_hertz_limit():
    d = np.array([1e-9, 1e-7, 1e-6, 4e-6])
    x = d / R  # nanite's / JPK's truncated series of the same law
    series = 1 - x / 10 - x ** 2 / 840 + 11 / 15120 * x ** 3 + 1357 / 6652800 * x ** 4
    ratio = M.sneddon_sphere(d, E, R, NU) / M.hertz_paraboloid(d, E, R, NU)
    assert np.allclose(ratio, series, rtol=1e-4)
    a = M.sphere_contact_radius(d, R)  # the parametric relation it solves
    assert np.allclose(a / 2 * np.log((R + a) / (R - a)), d, rtol=1e-10)
    # at delta = R (a = 0.83356 R, brentq): Sneddon 1.19968 E* R^2, Hertz 4/3: Hertz 11.1 % stiffer
    assert math.isclose(float(M.hertz_paraboloid(R, E, R, NU) / M.sneddon_sphere(R, E, R, NU)), 1.11141,
                        rel_tol=1e-4)


def test_shape_slopes_are_derivatives():
    d = np.linspace(1e-8, 2e-6, 50)
    geo = {"radius": R, "half_angle": 0.3, "thickness": 4e-6, "bonded": True}
    for key in M.LINEAR_KEYS:
        f, fp = M.shape_and_slope(key, d, geo, NU)
        h = 1e-12
        num = (M.shape_and_slope(key, d + h, geo, NU)[0] - M.shape_and_slope(key, d - h, geo, NU)[0]) / (2 * h)
        assert np.allclose(fp, num, rtol=1e-4), key


def test_dimitriadis_coefficients_published_for_nu_half():
    # Dimitriadis et al. 2002: bonded 1.133 chi + 1.283 chi^2 + 0.769 chi^3; not bonded 0.884, 0.781, 0.386, 0.0048
    c = M._dimitriadis_coefficients(0.5, True)
    assert np.allclose(c[:3], (1.133, 1.283, 0.769), atol=1e-3)
    c = M._dimitriadis_coefficients(0.5, False)
    assert np.allclose(c, (0.884, 0.781, 0.386, 0.0048), atol=1e-3)
    assert M.dimitriadis_factor(0.0, R, 1e-6) == 1.0  # no indentation: the half space


def test_jkr_published_relations():
    fs = math.pi * 0.02 * R
    Dt, Pt = A._jkr_table()
    assert math.isclose(Pt[0], -5 / 6, rel_tol=1e-9)  # displacement control: the branch ends at -5/6 pi w R
    _, P = A.jkr_dimensionless(np.linspace(-0.9, 5, 20001))
    assert math.isclose(P.min(), -1.5, rel_tol=1e-6)  # load control: pull-off at -3/2 pi w R
    # forces.py in the paper's convention: its gamma is the work of adhesion w, its R is 2 R_eff
    assert math.isclose(-1.5 * fs, pull_off_force_jkr(0.02, 2 * R), rel_tol=1e-12)
    # at zero indentation: -4/3 pi w R (8/9 of the pull-off); and the SI law agrees with the dimensionless one
    assert math.isclose(float(A.jkr(1e-15, E, 0.02, R, NU)), -4 / 3 * fs, rel_tol=1e-4)
    # the force-indentation relation: delta = a^2/R - sqrt(2 pi w a / E*), F = 4 E* a^3/(3R) - sqrt(8 pi w E* a^3)
    w = 0.02
    a = (math.pi * w * R ** 2 / (4 / 3 * ES)) ** (1 / 3) * np.linspace(0.8, 4, 7)  # on the stable branch
    delta = a ** 2 / R - np.sqrt(2 * math.pi * w * a / ES)
    F = 4 * ES * a ** 3 / (3 * R) - np.sqrt(8 * math.pi * w * ES * a ** 3)
    assert np.allclose(A.jkr(delta, E, w, R, NU, branch="retract"), F, rtol=2e-4)


def test_dmt_published_relation():
    d = np.array([1e-7, 5e-7])
    w = 0.01
    assert np.allclose(A.dmt(d, E, w, R, NU), M.hertz_paraboloid(d, E, R, NU) - 2 * math.pi * w * R)
    assert math.isclose(-2 * math.pi * w * R, pull_off_force_dmt(w, 2 * R), rel_tol=1e-12)


@pytest.mark.parametrize("lam, other", [(1e-4, "dmt"), (100.0, "jkr")])
def test_maugis_limits(lam, other):
    D = np.array([0.5, 2.0, 5.0, 20.0])
    Dt, Pt, _ = A.maugis_dimensionless(lam)
    P = np.interp(D, Dt, Pt)
    ref = D ** 1.5 - 2 if other == "dmt" else A.jkr_dimensionless(D)[1]
    assert np.allclose(P, ref, rtol=0.02, atol=0.04)  # DMT is reached slowly (~lambda^0.45)
    assert math.isclose(Pt.min(), -2.0 if other == "dmt" else -1.5, rel_tol=1e-3)


def test_registry_records():
    for key, m in INDENTATION_MODELS.items():
        assert m.key == key and m.name and m.reference and m.validity and m.geometry
    with pytest.raises(ParameterError, match="choose from"):
        indentation_model("hertz")


@pytest.mark.parametrize("key, geom", [("hertz_paraboloid", {"radius": R}), ("sneddon_sphere", {"radius": 2e-6}),
                                       ("hertz_cone", {"half_angle": 0.35}), ("bilodeau_pyramid4", {"half_angle": 0.3}),
                                       ("hertz_thin_layer", {"radius": R, "thickness": 3e-6})])
def test_fit_recovers_modulus_and_contact(key, geom):
    rng = np.random.default_rng(3)
    u = np.linspace(-2e-6, 1.5e-6, 300)
    F = model_force(key, u - 0.3e-6, E, geom, NU) + 1e-11 + rng.normal(0, 2e-11, u.size)
    fit = fit_indentation(u, F, key, geom, nu=NU)
    assert abs(fit.youngs_modulus - E) < 4 * fit.youngs_modulus_se + 1e-3 * E
    assert abs(fit.contact - 0.3e-6) < 5e-9
    assert fit.youngs_modulus_low < E < fit.youngs_modulus_high or abs(fit.youngs_modulus / E - 1) < 0.02


@pytest.mark.parametrize("key", ["dmt", "jkr"])
def test_adhesive_fit_recovers_work_of_adhesion(key):
    rng = np.random.default_rng(4)
    u = np.linspace(-2e-6, 1.5e-6, 300)
    F = model_force(key, u - 0.3e-6, E, {"radius": R}, NU, w=1e-4) + rng.normal(0, 2e-11, u.size)
    fit = fit_indentation(u, F, key, {"radius": R}, nu=NU)
    assert abs(fit.work_of_adhesion / 1e-4 - 1) < 0.03 and abs(fit.youngs_modulus / E - 1) < 0.02


def test_validity_flags_deep_indentation_and_thin_samples():
    from afmforce.contact.fit import validity

    assert any("tip radius" in w for w in validity("hertz_paraboloid", {"radius": 1e-6}, 2e-6, n_contact=50))
    assert any("tenth of the sample" in w for w in validity("hertz_cone", {"half_angle": 0.3}, 2e-6, 5e-6, 50))
    assert validity("hertz_paraboloid", {"radius": 5e-6}, 1e-6, 50e-6, 50) == ()
