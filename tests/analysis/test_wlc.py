"""Worm-like-chain fits of the tethers' rises (analysis.wlc, analysis.tethers.fit_tethers).

Truth: :func:`afmforce.analysis.synthetic.tether_curve` builds each tether with the closed-form chain (its
contour and persistence lengths, rupture forces, temperature and noise known); the fits are asserted to
recover them within their standard errors over several noise seeds, and against an independent fit written
here (scipy's least_squares on the closed form, with its own starting point and covariance).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import least_squares

from afmforce.analysis.options import AdhesionOptions
from afmforce.analysis.pipeline import analyze
from afmforce.analysis.synthetic import tether_curve
from afmforce.analysis.wlc import fit_rise, wlc_force
from afmforce.constants import DEFAULT_TEMPERATURE

KB = 1.380649e-23                 # written here, not imported: the closed forms below are independent
NM, PN = 1e-9, 1e-12
NOISE = 0.1e-9                    # deflection noise [m]: 5 pN on the 0.05 N/m lever
REAL = Path(os.environ.get("AFMFORCE_REAL_DATA", "/work/shared/data/real"))
SMFS = REAL / "jpk-force_float-data_SMFS.jpk-force"


def marko_siggia(x, L, p, T):
    r = x / L
    return KB * T / p * (1.0 / (4.0 * (1.0 - r) ** 2) - 0.25 + r)


def bouchiat(x, L, p, T):
    """Bouchiat et al., Biophys. J. 76, 409 (1999), eq 11."""
    r = x / L
    a = {2: -0.5164228, 3: -2.737418, 4: 16.07497, 5: -38.87607, 6: 39.49944, 7: -14.17718}
    return marko_siggia(x, L, p, T) + KB * T / p * sum(c * r ** i for i, c in a.items())


def independent_fit(x, f, T, law=marko_siggia):
    """L, p and their standard errors: least squares (the chain plus a force offset, the zero of force counted
    as one more sample) from a fixed start, covariance from scipy's Jacobian."""
    def res(q):
        return np.append((law(x, q[0] * NM, q[1] * NM, T) - f) / PN + q[2], q[2])
    sol = least_squares(res, [1.3 * x.max() / NM, 1.0, 0.0],
                        bounds=([x.max() / NM * 1.0001, 1e-3, -1e4], [1e5, 1e4, 1e4]),
                        xtol=1e-14, ftol=1e-14, gtol=1e-14)
    s2 = float(sol.fun[:-1] @ sol.fun[:-1]) / (x.size - 3)
    cov = s2 * np.linalg.inv(sol.jac.T @ sol.jac)
    return sol.x[0] * NM, sol.x[1] * NM, math.sqrt(cov[0, 0]) * NM, math.sqrt(cov[1, 1]) * NM


def test_the_chain_laws_are_the_closed_forms():
    x = np.linspace(0.0, 95e-9, 50)
    assert np.allclose(wlc_force(x, 100e-9, 0.4e-9, 300.0), marko_siggia(x, 100e-9, 0.4e-9, 300.0), rtol=1e-12)
    assert np.allclose(wlc_force(x, 100e-9, 0.4e-9, 300.0, "bouchiat"), bouchiat(x, 100e-9, 0.4e-9, 300.0),
                       rtol=1e-12, atol=1e-30)
    # Bouchiat's correction: within 1 % of Marko-Siggia's interpolation at small and 10 % at large extensions
    assert wlc_force(5e-9, 100e-9, 0.4e-9, model="bouchiat") == pytest.approx(wlc_force(5e-9, 100e-9, 0.4e-9), rel=0.01)


@pytest.mark.parametrize("law, model", [(marko_siggia, "marko-siggia"), (bouchiat, "bouchiat")])
def test_fit_rise_agrees_with_an_independent_least_squares(law, model):
    rng = np.random.default_rng(3)
    x = np.linspace(3e-9, 88e-9, 250)
    f = law(x, 100e-9, 0.3e-9, 300.0) + 5 * PN * rng.standard_normal(x.size)
    fit = fit_rise(x, f, 300.0, model)
    L, p, se_L, se_p = independent_fit(x, f, 300.0, law)
    assert fit.reason == ""
    assert fit.contour_length == pytest.approx(L, rel=1e-6) and fit.persistence_length == pytest.approx(p, rel=1e-5)
    assert fit.contour_length_se == pytest.approx(se_L, rel=1e-3)
    assert fit.persistence_length_se == pytest.approx(se_p, rel=1e-3)
    # and the truth within 3 standard errors
    assert abs(fit.contour_length - 100e-9) < 3 * fit.contour_length_se
    assert abs(fit.persistence_length - 0.3e-9) < 3 * fit.persistence_length_se


def test_a_rise_that_cannot_determine_the_chain_says_so():
    rng = np.random.default_rng(0)
    # too few samples
    x = np.linspace(10e-9, 90e-9, 8)
    fit = fit_rise(x, marko_siggia(x, 100e-9, 0.4e-9, DEFAULT_TEMPERATURE))
    assert math.isnan(fit.contour_length) and math.isnan(fit.persistence_length) and "too few samples" in fit.reason
    # the entropic regime only (a third of the contour length): l_p L fixed, neither alone
    x = np.linspace(3e-9, 33e-9, 200)
    f = marko_siggia(x, 100e-9, 0.4e-9, DEFAULT_TEMPERATURE) + 5 * PN * rng.standard_normal(x.size)
    fit = fit_rise(x, f, noise=5 * PN)
    assert math.isnan(fit.contour_length) and math.isnan(fit.contour_length_se)
    assert math.isnan(fit.persistence_length) and math.isnan(fit.persistence_length_se)
    assert fit.reason and math.isnan(fit.slope)
    # an independent fit of the same rise: its L is indeed unconstrained (or its error larger than a third)
    L, p, se_L, se_p = independent_fit(x, f, DEFAULT_TEMPERATURE)
    assert not se_L < L / 3 or not se_p < p / 3 or L / NM > 1e4 * 0.99 or x.max() / L < 0.5
    # a stiff chain's few noisy samples near its end: the contour length is fixed, the persistence length is not
    x = np.linspace(60e-9, 98e-9, 12)
    f = marko_siggia(x, 100e-9, 10e-9, DEFAULT_TEMPERATURE) + 10 * PN * np.random.default_rng(0).standard_normal(12)
    fit = fit_rise(x, f, noise=10 * PN)
    assert math.isfinite(fit.contour_length) and abs(fit.contour_length - 100e-9) < 3 * fit.contour_length_se
    assert math.isnan(fit.persistence_length) and "l_p to" in fit.reason
    *_, se_p = independent_fit(x, f, DEFAULT_TEMPERATURE)
    assert se_p > 10e-9 / 3


def _truth_rate(curve, i):
    """dF/dt at the last attached sample of the noise-free truth [N/s] (a backward difference)."""
    d, k, fs = curve.truth["deflection"], curve.metadata["spring_constant"], curve.metadata["sample_rate"]
    return -k * (d[i] - d[i - 1]) * fs


@pytest.mark.parametrize("tether", [(120e-9, 0.4e-9, 100e-9), (60e-9, 0.8e-9, 52e-9), (200e-9, 0.25e-9, 170e-9)])
def test_the_pipeline_recovers_the_chain_over_seeds(tether):
    """L_c, l_p and the loading rate within 3 standard errors of the truth for every seed; the standard errors
    neither far too tight nor far too loose against the scatter over seeds."""
    Ls, ps, seL, sep = [], [], [], []
    for seed in range(4):
        curve = tether_curve(tethers=(tether,), noise=NOISE, seed=seed, end=-1.6 * tether[0] - 50e-9)
        res = analyze(curve)
        ts = [t for t in res.details["adhesion"].tethers if t.tether]
        assert len(ts) == 1, res.adhesion_verdict
        t, truth = ts[0], curve.truth["ruptures"][0]
        fit = t.wlc
        assert fit.reason == "" and fit.temperature == 298.15      # the file's temperature (its metadata)
        assert abs(fit.contour_length - tether[0]) < 3 * fit.contour_length_se + 0.5 * NM   # zero of h: +-0.5 nm
        assert abs(fit.persistence_length - tether[1]) < 3 * fit.persistence_length_se
        assert t.force == pytest.approx(truth["force"], abs=3 * 5 * PN + 0.03 * abs(truth["force"]))
        rate = _truth_rate(curve, truth["index"])
        assert t.loading_rate_method == "chain" and abs(t.loading_rate - rate) < 3 * t.loading_rate_se + 0.02 * rate
        # the table carries the tether of the largest pull (the only one here)
        assert res.tether_contour_length == fit.contour_length and res.tether_loading_rate == t.loading_rate
        Ls.append(fit.contour_length), ps.append(fit.persistence_length)
        seL.append(fit.contour_length_se), sep.append(fit.persistence_length_se)
    for values, errors in ((Ls, seL), (ps, sep)):
        ratio = float(np.std(values, ddof=1) / np.mean(errors))
        assert 0.2 < ratio < 3.0, (values, errors)


@pytest.mark.parametrize("tethers", [((100e-9, 0.2e-9, 88e-9), (250e-9, 0.2e-9, 222e-9), (400e-9, 0.25e-9, 350e-9)),
                                     ((100e-9, 0.4e-9, 88e-9), (300e-9, 0.4e-9, 270e-9))])
def test_tethers_pulled_in_parallel_are_recovered_or_widened(tethers):
    """Parallel tethers add their forces: the first rise of three held 100 nm, 0.2 nm with the later two; fitted
    alone it came out 101.9 +- 0.14 nm, 0.160 +- 0.003 nm. With the later chains taken out every tether is
    within its errors; where the residuals cannot tell alone from parallel (a later chain's small force), the
    two fits' difference widens the errors (l_p 0.354 +- 0.011 nm alone for 0.4 nm)."""
    curve = tether_curve(tethers=tethers, noise=NOISE, end=-600e-9)
    ts = [t for t in analyze(curve).details["adhesion"].tethers if t.tether]
    assert len(ts) == len(tethers)
    for t, (L, p, _) in zip(ts, tethers):
        fit = t.wlc
        assert abs(fit.contour_length - L) < 3 * fit.contour_length_se + 0.5 * NM
        assert abs(fit.persistence_length - p) < 3 * fit.persistence_length_se
    assert ts[-1].wlc.parallel == 0


def test_the_temperature_is_the_files_else_the_declared_default():
    curve = tether_curve(tethers=((120e-9, 0.4e-9, 100e-9),), noise=NOISE, temperature=350.0, end=-300e-9)
    hot = analyze(curve).details["adhesion"].tethers[0].wlc
    meta = {k: v for k, v in curve.metadata.items() if k != "temperature"}
    bare = analyze(type(curve)(time=curve.time, piezo_nominal=curve.piezo_nominal,
                               piezo_measured=curve.piezo_measured, deflection_signal=curve.deflection_signal,
                               segment=curve.segment, metadata=meta, deflection_unit="V")).details["adhesion"]
    cold = bare.tethers[0].wlc
    assert hot.temperature == 350.0 and cold.temperature == DEFAULT_TEMPERATURE == 295.0
    assert abs(hot.persistence_length - 0.4e-9) < 3 * hot.persistence_length_se
    # kT / l_p is what the rise measures: l_p scales with the temperature, L_c does not
    assert cold.persistence_length / hot.persistence_length == pytest.approx(295.0 / 350.0, rel=1e-4)
    assert cold.contour_length == pytest.approx(hot.contour_length, rel=1e-6)


def test_bouchiats_chain_is_recovered_with_its_model():
    curve = tether_curve(tethers=((120e-9, 0.4e-9, 105e-9),), noise=NOISE, end=-300e-9, wlc_model="bouchiat")
    fit = analyze(curve, options=[AdhesionOptions(wlc_model="bouchiat")]).details["adhesion"].tethers[0].wlc
    assert fit.model == "bouchiat" and fit.reason == ""
    assert abs(fit.contour_length - 120e-9) < 3 * fit.contour_length_se + 0.5 * NM
    assert abs(fit.persistence_length - 0.4e-9) < 3 * fit.persistence_length_se


def test_the_figure_marks_tether_ruptures_and_draws_each_fit():
    from afmforce.plotting.curves import plot_force_separation

    tethers = ((100e-9, 0.2e-9, 88e-9), (250e-9, 0.2e-9, 222e-9))
    res = analyze(tether_curve(tethers=tethers, noise=NOISE, end=-400e-9))
    ax = plot_force_separation(res)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "2 tether ruptures" in labels and "worm-like-chain fits" in labels
    assert not any("unbinding step" in s for s in labels)     # before: the ruptures were drawn as unbinding steps
    lines = [ln for ln in ax.get_lines() if ln.get_color() == "k" and len(ln.get_xdata()) == 200]
    ts = [t for t in res.details["adhesion"].tethers if t.tether]
    assert len(lines) == len(ts) == 2
    assert [t.wlc.parallel for t in ts] == [1, 0]   # the first rise holds both chains
    for m, (ln, t) in enumerate(zip(lines, ts)):   # each drawn curve is its tether's fit, ending at its rupture
        h = np.asarray(ln.get_xdata()) * NM
        assert h[-1] == pytest.approx(t.separation)
        pull = sum(marko_siggia(h, q.wlc.contour_length, q.wlc.persistence_length, 298.15) for q in ts[m:]
                   if q is t or t.wlc.parallel)
        assert np.allclose(np.asarray(ln.get_ydata()) * NM, -pull - t.wlc.force_offset, rtol=1e-9)


@pytest.mark.skipif(not SMFS.exists(), reason="the shared real files are not here")
def test_jpk_smfs_tethers_fit_as_an_independent_least_squares_does(capsys):
    """The SMFS sawtooth's rises: each determined fit agrees with the independent fit of the same samples,
    its contour length lies beyond its rupture, and `afmforce analyze FILE` prints one line per tether."""
    from afmforce.cli.main import main
    from afmforce.io import load

    res = analyze(load(SMFS)[0])
    ts = [t for t in res.details["adhesion"].tethers if t.tether]
    assert len(ts) == 5
    done = 0
    for t in ts:
        fit = t.wlc
        if math.isnan(fit.contour_length) or math.isnan(fit.persistence_length):
            assert fit.reason
            continue
        sel = np.arange(t.fit_start, t.index)
        sel = sel[res.separation[sel] > 0]
        L, p, se_L, se_p = independent_fit(res.separation[sel], -res.force[sel], DEFAULT_TEMPERATURE)
        assert fit.points == sel.size
        assert fit.contour_length == pytest.approx(L, rel=1e-5) and fit.persistence_length == pytest.approx(p, rel=1e-4)
        # the fit's residual scale is at least the baseline noise: its errors are never below the independent's
        assert se_L * 0.999 <= fit.contour_length_se <= 3 * se_L and se_p * 0.999 <= fit.persistence_length_se <= 3 * se_p
        assert fit.contour_length > t.separation and 0.1e-9 < fit.persistence_length < 2e-9
        assert t.loading_rate > 0 and t.loading_rate_se < t.loading_rate / 3
        done += 1
    assert done >= 3
    # the last, largest pull: the table's tether columns
    assert res.tether_contour_length == ts[-1].wlc.contour_length
    assert main(["analyze", str(SMFS)]) == 0
    out = capsys.readouterr().out
    for n, t in enumerate(ts, 1):
        assert f"tether {n} at {t.separation * 1e9:.4g} nm: rupture {t.force * 1e12:.4g} pN" in out
    assert f"L_c {ts[-1].wlc.contour_length * 1e9:.4g} +- " in out


def test_the_pulls_own_slope_is_a_parabolas_derivative_at_the_rupture():
    """The loading rate's fallback (no determined chain): the slope of a known parabola at its last sample,
    within 3 standard errors, and undetermined when the pull does not rise above its noise."""
    from afmforce.analysis.wlc import loading_rate

    t = np.arange(40) / 2048.0
    truth = 2e-10 + 3e-9 * t + 4e-6 * t ** 2
    slopes, errors = [], []
    for seed in range(20):
        f = truth + 5 * PN * np.random.default_rng(seed).standard_normal(t.size)
        rate, se, why = loading_rate(t, f, 5 * PN)
        assert why == "" and abs(rate - (3e-9 + 8e-6 * t[-1])) < 3 * se
        slopes.append(rate), errors.append(se)
    assert 0.4 < np.std(slopes, ddof=1) / np.mean(errors) < 2.0
    rate, se, why = loading_rate(t[:12], 2e-10 + 5 * PN * np.random.default_rng(1).standard_normal(12), 5 * PN)
    assert math.isnan(rate) and math.isnan(se) and "does not rise significantly" in why


def test_an_impossible_temperature_in_the_file_is_refused_by_name():
    from afmforce.errors import ParameterError

    curve = tether_curve(tethers=((120e-9, 0.4e-9, 100e-9),), end=-300e-9)
    curve.metadata["temperature"] = -5.0
    with pytest.raises(ParameterError, match="temperature"):
        analyze(curve)
