"""Issue 23: no verdict without a model that fits; one-sided intervals; the noise models.

Numbers are checked against closed forms (chi-square quantiles), Monte Carlo of the
estimators they describe, and the static model (a cheap, exact forward model).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.stats import chi2 as chi2_dist

from afmforce.fit.adequacy import redchi_threshold, residual_site
from afmforce.fit.core import base_config
from afmforce.fit.data import FitCurve, _noise_sigma
from afmforce.fit.model import Evaluator
from afmforce.fit.noise import pink_correlation
from afmforce.fit.problem import Problem, local_fit
from afmforce.fit.result import wald_interval
from afmforce.fit.uncertainty import profile_interval
from afmforce.instrument.noise import pink_noise


def test_threshold_is_the_chi2_quantile_inflated_by_the_noise_estimate():
    curves = [SimpleNamespace(mask=np.ones(n, bool), noise_samples=nb)
              for n, nb in ((800, 500), (400, 250), (200, 120))]
    dof = 1390
    s = math.sqrt(sum((n / 1400) ** 2 * (140 / 36) / nb
                      for n, nb in ((800, 500), (400, 250), (200, 120))))
    expect = chi2_dist.ppf(0.999, dof) / dof * (1 + 3 * s)
    assert redchi_threshold(dof, curves) == pytest.approx(expect, rel=1e-12)
    assert 1.15 < expect < 1.45     # the typical set: a reduced chi-square of 1.37 is refused


def test_second_difference_noise_estimate_spread():
    # the threshold's 140/36: relative sd of the sigma^2 estimate = 1.97 / sqrt(n)
    rng = np.random.default_rng(3)
    n = 400
    est = np.array([_noise_sigma(rng.normal(0, 1.0, n + 2)) ** 2 for _ in range(3000)])
    assert np.mean(est) == pytest.approx(1.0, abs=0.01)
    assert np.std(est) == pytest.approx(math.sqrt(140 / 36 / n), rel=0.08)


def test_pink_correlation_matches_the_instrument_noise():
    rng = np.random.default_rng(5)
    n = 512
    x = np.array([pink_noise(n, 1.0, rng) for _ in range(1500)])
    for lag in (1, 8, 64):
        emp = float(np.mean(np.sum(x[:, :-lag] * x[:, lag:], axis=1) / n))
        assert emp == pytest.approx(pink_correlation(n)[lag], abs=0.03)
    assert pink_correlation(n)[0] == 1.0


def test_wald_interval_is_one_sided_at_a_search_bound():
    (lo, hi), note = wald_interval(9.0, 1.0, 0.95, 0.0, 10.0)
    assert lo == pytest.approx(9.0 - 1.959964, abs=1e-5) and hi is None
    assert "no upper end" in note and "10" in note
    (lo, hi), note = wald_interval(1e-4, 1e-3, 0.95, 0.0, 10.0, physical_lower=True)
    assert lo == 0.0 and hi == pytest.approx(1e-4 + 1.959964e-3, rel=1e-6) and note == ""
    (lo, hi), note = wald_interval(1e-4, 1e-3, 0.95, 0.0, 10.0)     # 0 is a search bound here
    assert lo is None and "no lower end" in note


def _static_curve(base, hamaker, seed, n=400, sigma=0.02e-9, shift=3e-9):
    """A static-model approach with white noise (the static model is exact and cheap)."""
    z = np.linspace(-30e-9, 8e-9, n)
    c = FitCurve(name="static", time=np.arange(n) / 1e4, position=z + shift,
                 deflection=np.zeros(n), velocity=3.8e-6, sample_rate=1e4, sigma=sigma,
                 jump_index=0, mask=np.ones(n, bool), noise_samples=300)
    ev = Evaluator([c], base, "static", drift=False)
    y = ev._static(c, {"hamaker": hamaker}, shift)
    c.deflection = y + np.random.default_rng(seed).normal(0, sigma, n)
    c.jump_index = int(np.argmin(np.diff(y))) + 1
    c.mask[c.jump_index - 2:c.jump_index + 2] = False
    return c, ev


def test_profile_interval_open_at_a_search_bound():
    # data with (almost) no attraction: A has no lower end above the search bound 1e-22 J
    base = base_config("beam")
    c, ev = _static_curve(base, 1e-22, seed=1, sigma=0.1e-9)
    prob = Problem(ev, ("hamaker",))
    x, _ = local_fit(prob, prob.pack({"hamaker": 1e-21}, [3e-9]), 40)
    chi2 = prob.chi2(x)
    lo, hi, pts, note = profile_interval(prob, x, chi2, "hamaker", 1e-21, 1.0, 0.95)
    assert lo is None and hi is not None and hi < 1e-19
    assert "one-sided" in note and "lower" in note
    assert min(pts["value"]) == pytest.approx(1e-22)       # the profile went to the bound ...
    assert max(pts["delta_chi2"]) >= 3.84                   # ... and crossed on the upper side


def test_profile_interval_two_sided_covers_the_truth():
    base = base_config("beam")
    c, ev = _static_curve(base, 5e-19, seed=2)
    prob = Problem(ev, ("hamaker",))
    x, _ = local_fit(prob, prob.pack({"hamaker": 4e-19}, [3e-9]), 40)
    lo, hi, _, note = profile_interval(prob, x, prob.chi2(x), "hamaker", 1e-20, 1.0, 0.95)
    assert note == "" and lo < 5e-19 < hi and hi / lo < 1.2


def test_residual_site_names_the_region_and_positions():
    n = 300
    z = np.linspace(-20e-9, 10e-9, n)
    c = FitCurve(name="curve 3", time=np.arange(n) / 1e4, position=z, deflection=np.zeros(n),
                 velocity=3e-6, sample_rate=1e4, sigma=1e-11, jump_index=200,
                 mask=np.ones(n, bool))
    r = np.random.default_rng(0).normal(0, 1, n)
    r[(z > 2e-9) & (z < 8e-9)] *= 10.0       # misfit in contact between 2 and 8 nm
    site = residual_site(c, r, shift=0.0)
    assert site.startswith("curve 3:") and "in contact" in site
    lo, hi = (float(v) for v in site.split("z - shift = ")[1].split(" nm")[0].split(" to "))
    assert 1.5 < lo < 3.5 and 6.5 < hi < 8.5


def test_pink_noise_estimated_from_the_residuals_and_whitened():
    # a static-model approach with 0.05 nm white + 0.05 nm 1/f noise (as the typical preset)
    from afmforce.fit.noise import estimate_pink, set_noise_model

    base = base_config("beam")
    rng = np.random.default_rng(11)
    got = []
    for seed in range(6):
        c, ev = _static_curve(base, 5e-19, seed=seed, sigma=1e-15, n=600)
        c.deflection = c.deflection + pink_noise(c.n, 0.05e-9, rng) \
            + rng.normal(0, 0.05e-9, c.n)
        c.sigma = _noise_sigma(c.deflection[: c.jump_index - 5])
        c.jump_index = c.n - 100       # the free approach: all but the last 100 samples
        prob = Problem(ev, ("hamaker",))
        x, _ = local_fit(prob, prob.pack({"hamaker": 5e-19}, [3e-9]), 40)
        s2p, signif = estimate_pink(prob, x, drift=False)
        got.append(math.sqrt(s2p))
        assert signif > 3.0                                   # the excess is significant
        chi2_white = prob.chi2(x) / int(c.mask.sum())
        set_noise_model([c], s2p)
        chi2_gls = prob.chi2(x) / int(c.mask.sum())
        assert chi2_white > 1.3 and abs(chi2_gls - 1.0) < 0.25
    assert np.median(got) == pytest.approx(0.05e-9, rel=0.3)


def test_fringe_columns_absorb_a_fringe_before_contact():
    # a 0.4 nm, 335 nm-period fringe in the separation: gone from the residual with --fringes,
    # not without (the static model and the data share everything else)
    base = base_config("beam")
    c, ev = _static_curve(base, 5e-19, seed=7, sigma=0.01e-9)
    z = c.position - 3e-9
    h = np.clip(z[c.jump_index] - z, 0.0, None)          # separation before contact
    clean = c.deflection.copy()
    c.deflection = clean + 0.4e-9 * np.cos(2 * np.pi * h / 335e-9 + 1.0)
    for fringes, limit in ((False, 2.5), (True, 1.3)):
        e = Evaluator([c], base, "static", drift=True, fringes=fringes)
        prob = Problem(e, ("hamaker",), {})
        chi = prob.chi2(prob.pack({"hamaker": 5e-19}, [3e-9])) / int(c.mask.sum())
        assert (chi > limit) if not fringes else (chi < limit)


def test_profile_figure_draws_a_one_sided_interval(tmp_path):
    """A profile interval open at a search bound ([lo, None]) is drawn with its one end
    (matplotlib's axvline(None) raised a TypeError)."""
    from types import SimpleNamespace

    from afmforce.fit.figures import plot_profiles

    est = SimpleNamespace(value=2.0, interval=(1.0, None), unit="kg/s")
    res = SimpleNamespace(profiles={"xi": {"value": [1.0, 2.0, 3.0], "delta_chi2": [4.0, 0.0, 1.0]}},
                          parameters={"xi": est}, level=0.95)
    path = plot_profiles(res, tmp_path / "profiles.png")
    assert path.is_file() and path.stat().st_size > 1000


def test_a_profile_open_on_both_sides_is_undetermined_not_a_tight_standard_error():
    """Data that bound A on neither side (noise 100x the signal of a weak attraction): the profile
    stays below the 95 % threshold out to both search bounds, and the estimate is reported
    undetermined with no standard error, whatever the Jacobian's curvature says (a parameter the data
    cannot determine is never given a tight interval)."""
    from afmforce.fit.uncertainty import profiled_estimate

    base = base_config("beam")
    c, ev = _static_curve(base, 1e-21, seed=4, sigma=5e-9)
    prob = Problem(ev, ("hamaker",))
    x, _ = local_fit(prob, prob.pack({"hamaker": 1e-20}, [3e-9]), 40)
    lo, hi, pts, note = profile_interval(prob, x, prob.chi2(x), "hamaker", 1e-21, 1.0, 0.95)
    assert lo is None and hi is None, (lo, hi)
    assert max(pts["delta_chi2"]) < 3.84                    # flat as far as the profile went
    method, se, text = profiled_estimate("hamaker", lo, hi, note, 1e-21, "J")
    assert method == "undetermined" and math.isnan(se) and "undetermined" in text
    # a bounded profile keeps its standard error and method
    assert profiled_estimate("hamaker", 1e-20, None, "", 2e-21, "J")[:2] == ("profile", 2e-21)


def _jump_curves(k=3, n=600, jump=400):
    mask = np.ones(n, bool)
    mask[jump - 2: jump + 30] = False          # the jump-in gap, as prepare_curve leaves it out
    return [SimpleNamespace(name=f"curve {i + 1}", mask=mask, n=n, jump_index=jump, retract_start=None,
                            noise_samples=300) for i in range(k)]


def test_jump_windows_threshold_is_the_bonferroni_chi2_quantile():
    from afmforce.fit.adequacy import JUMP_SAMPLES, jump_misfit

    curves = _jump_curves()
    m = int(curves[0].mask.sum())
    r = [np.zeros(m) for _ in curves]
    r[1][np.flatnonzero(np.flatnonzero(curves[1].mask) >= 400)[:JUMP_SAMPLES]] = 100.0
    (w,) = jump_misfit(curves, r)
    expect = chi2_dist.ppf(1 - 0.001 / 6, JUMP_SAMPLES) * (1 + 3 * math.sqrt(140 / 36 / 300))
    assert w["curve"] == "curve 2" and w["where"] == "on landing in contact"
    assert w["threshold"] == pytest.approx(expect, rel=1e-12) and w["n"] == JUMP_SAMPLES


def test_jump_windows_catch_a_local_misfit_the_global_test_passes():
    """Unit-variance residuals: the windows of 3 curves flag at most the 0.1 % they are built for
    (expected 0.4 of 400 sets); a coherent 3-sigma offset over the 15 samples before one
    curve's jump-in (what a missing repulsion leaves) is flagged (window chi-square ~150 against
    ~70), while the global reduced chi-square (1.08 expected) stays under its threshold."""
    from afmforce.fit.adequacy import jump_misfit

    curves = _jump_curves()
    m = int(curves[0].mask.sum())
    rng = np.random.default_rng(11)
    false = sum(bool(jump_misfit(curves, [rng.normal(0, 1, m) for _ in curves])) for _ in range(400))
    assert false <= 3                        # expected 0.4 (0.1 % of 400)
    hits = 0
    for _ in range(20):
        r = [rng.normal(0, 1, m) for _ in curves]
        before = np.flatnonzero(np.flatnonzero(curves[0].mask) < 400)[-15:]
        r[0][before] += 3.0
        chi2_all = sum(float(x @ x) for x in r)
        assert chi2_all / (3 * m) < redchi_threshold(3 * m, curves)
        hits += bool(jump_misfit(curves, r))
    assert hits >= 19
