"""Adhesive fits (issue 34 item 3): exact laws, the optimum is the minimum, honest intervals.

The curves come from tests/contact/adhesive_curves.py: the JKR, DMT and Maugis-Dugdale equations
solved there with brentq (in SI, or for A where afmforce solves for m), never with afmforce's
inversion; each seed draws the contact point (off any grid), the baseline and the noise.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import least_squares

import adhesive_curves as ac
from afmforce.contact import adhesive as A
from afmforce.contact.adhesive_fit import _Problem, fit_adhesive
from afmforce.contact.fit import fit_indentation, model_force

LAWS = ("jkr", "dmt", "maugis")
GEOM = {"radius": ac.R_TIP}


@pytest.mark.parametrize("key, lam", [("jkr", 1.0), ("dmt", 1.0), ("maugis", 0.1), ("maugis", 1.0),
                                      ("maugis", 10.0)])
def test_fast_laws_agree_with_independent_solver(key, lam):
    delta = np.concatenate((np.geomspace(1e-12, 3e-6, 120), np.linspace(-1e-7, 0, 5)))
    if key == "maugis":
        ref = ac.maugis_force(delta, 2e3, 1e-4, ac.R_TIP, lam=lam)
    else:
        ref = ac.LAWS[key](delta, 2e3, 1e-4, ac.R_TIP)
    got = A.adhesive_force(key, delta, 2e3, 1e-4, ac.R_TIP, ac.NU, lam)
    assert np.all(got[delta <= 0] == 0) and np.all(ref[delta <= 0] == 0)
    assert np.max(np.abs(got - ref) / np.abs(ref).max()) < 1e-6
    assert np.max(np.abs(got - ref)[delta > 0] / np.abs(ref[delta > 0])) < 1e-6


def test_jkr_retract_branch_agrees_with_independent_solver():
    delta = np.linspace(-0.4e-6, 1e-6, 200)
    ref = ac.jkr_force(delta, 2e3, 1e-4, ac.R_TIP, retract=True)
    got = A.jkr(delta, 2e3, 1e-4, ac.R_TIP, ac.NU, branch="retract")
    assert np.array_equal(got != 0, ref != 0)  # the neck ends at the same sample
    assert np.max(np.abs(got - ref)) < 1e-6 * np.abs(ref).max()


@pytest.mark.parametrize("key", LAWS)
def test_analytic_jacobian_is_the_gradient(key):
    """The kernel's J^T r equals -1/2 the numerical gradient of the sum of squares (within one gap)."""
    u, F, tr = ac.curve(key, 0, n=200)
    prob = _Problem(u, F, key, ac.R_TIP, ac.NU, ac.LAM, "approach", 0.0)
    x = np.array([tr["E"] * 1.05, tr["w"] * 0.9, tr["c"], tr["b"] + 1e-11])
    from afmforce.contact import _adhesive_kernels as K

    Amat, g = np.zeros((4, 4)), np.zeros(4)
    K.adhesive_normal(u, F, prob.law, x, prob.R, prob.kc, prob.d_end, prob.lam, *prob.tables, 0.0, Amat, g)
    gap = np.diff(np.unique(u)).min()
    steps = np.array([1e-6 * x[0], 1e-6 * x[1], 1e-4 * gap, 1e-13])
    for j in range(4):
        e = np.zeros(4)
        e[j] = steps[j]
        num = (prob.ssr(x + e) - prob.ssr(x - e)) / (2 * steps[j])
        assert math.isclose(-0.5 * num, g[j], rel_tol=2e-5, abs_tol=1e-9 * abs(g).max() / steps[j] * steps[j]), j


def _ssr_independent(key, u, F, x):
    """Sum of squares of the law's public function (not the fit's kernel) at x = (E, w, c, b)."""
    return float(np.sum((F - model_force(key, u - x[2], x[0], GEOM, ac.NU, x[1], ac.LAM) - x[3]) ** 2))


def _brute_minimum(key, u, F, x_start, span=12, w_fixed=None):
    """The least sum of squares over the gaps between samples near x_start's contact point, each by
    scipy's least_squares (the contact point bounded to the gap, numerical Jacobian) on afmforce's
    public law; ``w_fixed``: w held there."""
    us = np.unique(u)
    k0 = int(np.searchsorted(us, x_start[2]) - 1)
    E0, w0 = x_start[0], (w_fixed if w_fixed is not None else max(x_start[1], 1e-9))
    best = math.inf

    def resid(z, lo, gap):  # z = (E/E0, w/w0, (c - lo)/gap, b/1e-11)
        w = w_fixed if w_fixed is not None else z[1] * w0
        return (F - model_force(key, u - (lo + z[2] * gap), z[0] * E0, GEOM, ac.NU, w, ac.LAM) - z[3] * 1e-11) / 1e-11

    for k in range(max(k0 - span, 0), min(k0 + span, us.size - 2) + 1):
        lo, gap = us[k], us[k + 1] - us[k]
        sol = least_squares(resid, [1.0, 1.0, 0.5, x_start[3] / 1e-11], args=(lo, gap), x_scale="jac",
                            bounds=([1e-6, 0.0, 1e-6, -np.inf], [np.inf, np.inf, 1 - 1e-6, np.inf]),
                            xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=1000)
        best = min(best, 2 * sol.cost * 1e-22)
    return best


@pytest.mark.parametrize("key", LAWS)
def test_optimum_is_the_minimum(key):
    """The reported optimum's sum of squares is no larger than the truth's, than an independent
    optimiser's over every gap near it, nor than any small step away from it (DMT's was 8x)."""
    for seed in range(3):
        u, F, tr = ac.curve(key, seed, n=200)
        fit = fit_indentation(u, F, key, GEOM, nu=ac.NU, transition=ac.LAM)
        x = np.array([fit.youngs_modulus, fit.work_of_adhesion, fit.contact, fit.baseline])
        S = _ssr_independent(key, u, F, x)
        assert math.isclose(S, float(np.sum(fit.residuals ** 2)), rel_tol=1e-9)
        assert S <= _ssr_independent(key, u, F, [tr["E"], tr["w"], tr["c"], tr["b"]])
        assert S <= _brute_minimum(key, u, F, x) * (1 + 1e-7)
        for j, h in enumerate((1e-4 * x[0], 1e-3 * x[1], 1e-11, 1e-13)):
            for sgn in (-1, 1):
                y = x.copy()
                y[j] += sgn * h
                assert _ssr_independent(key, u, F, y) >= S * (1 - 1e-12), (seed, j, sgn)


@pytest.mark.parametrize("key", LAWS)
def test_intervals_cover_the_truth(key):
    """95 % intervals of E, w and (E +- 1.96 se) of the contact point cover the truth on >= 18 of 20 seeds."""
    cover = {"E": 0, "w": 0, "c": 0}
    for seed in range(20):
        u, F, tr = ac.curve(key, seed, n=200)
        fit = fit_indentation(u, F, key, GEOM, nu=ac.NU, transition=ac.LAM)
        cover["E"] += fit.youngs_modulus_low <= tr["E"] <= fit.youngs_modulus_high
        cover["w"] += fit.work_of_adhesion_low <= tr["w"] <= fit.work_of_adhesion_high
        cover["c"] += abs(fit.contact - tr["c"]) <= 1.97 * fit.contact_se
        assert abs(fit.youngs_modulus / tr["E"] - 1) < 0.02 and abs(fit.work_of_adhesion / tr["w"] - 1) < 0.05
        assert fit.youngs_modulus_low < fit.youngs_modulus < fit.youngs_modulus_high
        assert fit.work_of_adhesion_low < fit.work_of_adhesion < fit.work_of_adhesion_high
    assert min(cover.values()) >= 18, cover


def test_no_adhesion_gives_an_upper_bound_of_w():
    """w = 0 in the data: the interval is [0, upper end by profile likelihood], which holds the truth, and
    the fit says so; E stays right."""
    held = 0
    for seed in range(6):
        u, F, tr = ac.curve("jkr", seed, n=200, w=0.0)
        fit = fit_indentation(u, F, "jkr", GEOM, nu=ac.NU)
        assert abs(fit.youngs_modulus / tr["E"] - 1) < 0.01
        assert fit.youngs_modulus_low <= tr["E"] <= fit.youngs_modulus_high
        if fit.work_of_adhesion_low == 0.0:
            held += 1
            assert fit.work_of_adhesion < fit.work_of_adhesion_high < 5e-6
            assert any("not distinguishable from 0" in w for w in fit.warnings)
    assert held >= 5


def test_profile_upper_end_is_where_the_sum_of_squares_rises():
    """The upper end of w's interval at w = 0 is where the re-minimised sum of squares exceeds the
    minimum by t^2 s^2 (checked with scipy's optimiser, w held there)."""
    from afmforce.contact.fit import _t95

    u, F, tr = ac.curve("dmt", 1, n=200, w=0.0)
    fit = fit_indentation(u, F, "dmt", GEOM, nu=ac.NU)
    assert fit.work_of_adhesion_low == 0.0
    n = fit.n_points
    S = float(np.sum(fit.residuals ** 2))
    s2 = S / (n - 4)
    wh = fit.work_of_adhesion_high
    x = [fit.youngs_modulus, wh, fit.contact, fit.baseline]

    def profile(w):
        return _brute_minimum("dmt", u, F, x, span=3, w_fixed=w)

    thr = _t95(n - 4) ** 2
    assert (profile(0.97 * wh) - S) / s2 < thr < (profile(1.03 * wh) - S) / s2


def test_retract_branch_fit():
    """JKR's neck on the retract (negative indentations down to the pull-off at fixed position)."""
    rng = np.random.default_rng(7)
    u = np.linspace(-2e-6, 1.5e-6, 300)
    F = ac.jkr_force(u - 0.3e-6, 2e3, 1e-4, ac.R_TIP, retract=True) + 3e-11 + rng.normal(0, 2e-11, u.size)
    fit = fit_indentation(u, F, "jkr", GEOM, nu=ac.NU, branch="retract")
    assert abs(fit.youngs_modulus / 2e3 - 1) < 0.01 and abs(fit.work_of_adhesion / 1e-4 - 1) < 0.01
    assert abs(fit.contact - 0.3e-6) < 5 * fit.contact_se + 1e-9
    assert fit.youngs_modulus_low <= 2e3 <= fit.youngs_modulus_high


def test_fit_adhesive_refuses_a_curve_without_contact():
    from afmforce.errors import AnalysisError

    u = np.linspace(0, 1e-6, 50)
    with pytest.raises(AnalysisError, match="positive modulus"):
        fit_adhesive(u, -1e-9 * u / 1e-6, "jkr", ac.R_TIP)


def test_pipeline_step_fits_jkr_on_the_retract():
    """The analysis step and the fast path (as a map runs them) with JKR on the retract of a calibrated raw
    curve: an approach without adhesion (a soft contact, no jump-in), a retract with JKR's neck."""
    from afmforce.analysis.indentation import fast_modulus
    from afmforce.analysis.options import IndentationOptions
    from afmforce.analysis.pipeline import analyze
    from afmforce.contact.models import hertz_paraboloid
    from afmforce.io.curve import RawCurve

    k, sens, n, c = 0.05, 40e-9, 300, 0.31e-6
    rng = np.random.default_rng(11)
    u = np.linspace(-2e-6, 1.5e-6, n)
    Fa = hertz_paraboloid(u - c, ac.E_TRUE, ac.R_TIP, ac.NU) + rng.normal(0, ac.NOISE, n)
    Fr = ac.jkr_force(u - c, ac.E_TRUE, ac.W_TRUE, ac.R_TIP, retract=True) + rng.normal(0, ac.NOISE, n)
    z = 5e-6 + np.concatenate((u + Fa / k, (u + Fr / k)[::-1]))  # the piezo: tip depth + the lever's deflection
    volts = np.concatenate((Fa, Fr[::-1])) / k / sens + 0.3
    curve = RawCurve(time=np.arange(2 * n) * 1e-3, piezo_nominal=z, deflection_signal=volts,
                     segment=np.repeat(np.array([0, 1], dtype=np.int8), n), deflection_unit="V",
                     metadata={"spring_constant": k, "sensitivity": sens})
    opts = IndentationOptions(model="jkr", tip_radius=ac.R_TIP, run="retract")
    for res in (fast_modulus(curve, opts), analyze(curve, steps=["indentation"], options=[opts])):
        assert abs(res.youngs_modulus / ac.E_TRUE - 1) < 0.02, res.youngs_modulus
        assert abs(res.work_of_adhesion / ac.W_TRUE - 1) < 0.02, res.work_of_adhesion
        assert abs(res.contact_point - (5e-6 + c)) < 5e-9  # piezo position at contact [m]
