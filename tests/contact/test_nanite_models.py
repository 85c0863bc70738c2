"""afmforce's indentation laws against nanite 4.2.3's model functions (the registry's keys nanite also has:
``hertz_para``, ``sneddon_spher_approx``, ``hertz_cone``, ``hertz_pyr3s``), on a grid of indentations and
geometries, and the exact Sneddon sphere against its closed parametric form at depths where the paraboloid and
nanite's power series no longer hold. nanite only via ``pytest.importorskip``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce.contact import models as M

#: indentations [m] (some negative: no contact) and geometries of the grid
DELTA = np.r_[-1e-7, 0.0, np.logspace(-10, -5, 41)]
RADII = (10e-9, 2e-7, 5e-6, 25e-6)
ANGLES_DEG = (5.0, 17.5, 20.0, 35.0, 70.0)
NUS = (0.0, 0.3, 0.5)
E = 3.7e4


def _nanite(key):
    pytest.importorskip("nanite")
    from nanite.model import models_available

    return models_available[key].module.model_func


def test_nanite_has_the_keys_the_docs_name():
    """docs/contact.md names nanite's key beside each law: they exist in nanite (``sneddon_spher`` does not
    in 4.2.3, ``hertz_pyr4s`` neither: the four-sided pyramid has no nanite counterpart)."""
    pytest.importorskip("nanite")
    from nanite.model import models_available

    assert {"hertz_para", "sneddon_spher_approx", "hertz_cone", "hertz_pyr3s"} <= set(models_available)


@pytest.mark.parametrize("nu", NUS)
@pytest.mark.parametrize("radius", RADII)
def test_paraboloid_equals_nanite_hertz_para(radius, nu):
    """Same force to 1e-12 relative: nanite's delta is the tip position (negative into the sample), its
    contact point 0; the radius is R (not the diameter), E* = E / (1 - nu^2) applied once."""
    f = _nanite("hertz_para")
    ours = M.hertz_paraboloid(DELTA, E, radius, nu)
    theirs = f(-DELTA, E, radius, nu, 0.0, 0.0)
    np.testing.assert_allclose(ours, theirs, rtol=1e-12, atol=0)
    assert np.all(ours[DELTA <= 0] == 0) and np.all(ours[DELTA > 0] > 0)


@pytest.mark.parametrize("nu", NUS)
@pytest.mark.parametrize("alpha", ANGLES_DEG)
def test_cone_equals_nanite_hertz_cone_with_the_half_angle(alpha, nu):
    """afmforce's ``half_angle`` [rad] is nanite's ``alpha`` [deg], the half cone angle (not the full angle:
    a full angle would change tan by a factor 2.2-26 over this grid)."""
    f = _nanite("hertz_cone")
    np.testing.assert_allclose(M.hertz_cone(DELTA, E, math.radians(alpha), nu),
                               f(-DELTA, E, alpha, nu, 0.0, 0.0), rtol=1e-12, atol=0)


@pytest.mark.parametrize("nu", NUS)
@pytest.mark.parametrize("alpha", ANGLES_DEG)
def test_three_sided_pyramid_equals_nanite_hertz_pyr3s_with_the_face_angle(alpha, nu):
    """Bilodeau's three-sided pyramid: the face angle in both (nanite's parameter ``alpha``, "Face Angle")."""
    f = _nanite("hertz_pyr3s")
    np.testing.assert_allclose(M.bilodeau_pyramid3(DELTA, E, math.radians(alpha), nu),
                               f(-DELTA, E, alpha, nu, 0.0, 0.0), rtol=1e-12, atol=0)


@pytest.mark.parametrize("radius", RADII)
def test_exact_sphere_against_nanite_power_series(radius):
    """nanite's ``sneddon_spher_approx`` is the exact sphere's power series in x = delta/R truncated after
    x^4: they agree to the first omitted term's order (x^5 relative: 1e-9 at x = 0.01, under 1e-4 at
    x = 1) and part beyond (x = 5: 14 % apart; x = 10: the series is 5.9 x the exact law's force, x^4.5 growing
    where the sphere, sunk, tends to E* R (2 delta - R))."""
    f = _nanite("sneddon_spher_approx")
    x = np.r_[1e-4, 1e-3, 1e-2, 0.1, 0.3, 1.0]
    ours = M.sneddon_sphere(x * radius, E, radius, 0.5)
    theirs = f(-x * radius, E, radius, 0.5, 0.0, 0.0)
    rel = np.abs(ours / theirs - 1)
    assert np.all(rel <= np.maximum(2e-4 * x ** 5, 1e-13)), rel
    deep = float(M.sneddon_sphere(10 * radius, E, radius, 0.5) / f(np.array([-10 * radius]), E, radius, 0.5)[0])
    assert deep == pytest.approx(0.1702, abs=1e-3)


def _sneddon_parametric(a_over_r, radius: float, E: float, nu: float):
    """(delta, F) of a rigid sphere at contact radius a, Sneddon 1965 eqs 6.13 and 6.15 written out here and
    evaluated forwards (no inversion) in 50-digit decimal arithmetic: delta = a/2 ln((R+a)/(R-a)),
    F = E/(2(1-nu^2)) [(a^2+R^2) ln((R+a)/(R-a)) - 2aR]."""
    from decimal import Decimal, localcontext

    out = []
    with localcontext() as ctx:
        ctx.prec = 50
        R = Decimal(repr(radius))
        for s in a_over_r:
            a = Decimal(repr(float(s))) * R
            lg = ((R + a) / (R - a)).ln()
            f = Decimal(repr(E)) / (2 * (1 - Decimal(repr(nu)) ** 2)) * ((a * a + R * R) * lg - 2 * a * R)
            out.append((float(a / 2 * lg), float(f)))
    return np.array([o[0] for o in out]), np.array([o[1] for o in out])


#: contact radii a/R: shallow (where the closed form cancels: 1e-8 of its digits lost at 1e-4) to deep (0.999 R
#: at delta = 3.8 R; 1 - 1e-9 at delta = 10.7 R)
A_OVER_R = np.r_[1e-6, 1e-4, 1e-3, 0.01, 0.1, 0.3, 0.49, 0.51, 0.7, 0.8336, 0.9, 0.95, 0.99, 0.999, 1 - 1e-6, 1 - 1e-9]


@pytest.mark.parametrize("nu", NUS)
@pytest.mark.parametrize("radius", RADII)
def test_exact_sphere_equals_sneddon_parametric_form_at_every_depth(radius, nu):
    """The exact sphere against the parametric form in decimal arithmetic, to 1e-12, from a = 1e-6 R (delta =
    1e-12 R) to a = R (1 - 1e-9) (delta = 10.7 R; the paraboloid is 2.3 x too stiff there). Before: the closed
    form in floats lost 7e-5 of the force at a = 1e-4 R, and a clipped at R (1 - 1e-15) held the force constant
    beyond delta ~ 18 R (a 5 nm tip pressed 500 nm into a gel: 0.6 of the law's force at 30 R, 0.2 at 100 R)."""
    delta, force = _sneddon_parametric(A_OVER_R, radius, E, nu)
    np.testing.assert_allclose(M.sneddon_sphere(delta, E, radius, nu), force, rtol=1e-12, atol=0)
    np.testing.assert_allclose(M.sphere_contact_radius(delta, radius), A_OVER_R * radius, rtol=1e-12)
    f, fp = M.shape_and_slope("sneddon_sphere", delta, {"radius": radius}, nu)
    np.testing.assert_allclose(f * E, force, rtol=1e-12)
    np.testing.assert_allclose(fp * E, 2 * E / (1 - nu * nu) * A_OVER_R * radius, rtol=1e-12)  # dF/dd = 2 E* a
    assert float(M.hertz_paraboloid(delta[-1], E, radius, nu) / force[-1]) == pytest.approx(2.2884, abs=1e-4)


@pytest.mark.parametrize("depth", [10.0, 30.0, 100.0, 1e4])
def test_exact_sphere_deep_tends_to_its_asymptote(depth):
    """delta >> R: a -> R, ln((R+a)/(R-a)) = 2 delta/a -> 2 delta/R, so F -> E*/2 (2R^2 2 delta/R - 2R^2) =
    E* R (2 delta - R) (the sphere sunk: a flat punch of radius R plus the cap), to 1e-12 from 10 R on."""
    r = 5e-9
    es = E / (1 - 0.3 ** 2)
    assert float(M.sneddon_sphere(depth * r, E, r, 0.3)) == pytest.approx(es * r * (2 * depth * r - r), rel=1e-12)


@pytest.mark.parametrize("key,geom", [("hertz_paraboloid", {"radius": 5e-6}), ("sneddon_sphere", {"radius": 2e-7}),
                                      ("hertz_cone", {"half_angle": math.radians(20)}),
                                      ("bilodeau_pyramid3", {"half_angle": math.radians(35)}),
                                      ("bilodeau_pyramid4", {"half_angle": math.radians(35)})])
def test_fit_shape_is_the_law_and_its_slope(key, geom):
    """The fit's ``shape_and_slope`` is the law per unit E (1e-12) and its derivative (central differences)."""
    law = getattr(M, key)
    d = np.logspace(-9, -6.2, 30)
    f, fp = M.shape_and_slope(key, d, geom, 0.3)
    np.testing.assert_allclose(f * E, law(d, E, *geom.values(), nu=0.3), rtol=1e-12)
    h = d * 1e-6
    fd = (M.shape_and_slope(key, d + h, geom, 0.3)[0] - M.shape_and_slope(key, d - h, geom, 0.3)[0]) / (2 * h)
    np.testing.assert_allclose(fp, fd, rtol=1e-6)
