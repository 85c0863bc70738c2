"""The fit range ``max_indentation``: a fixed set of samples, ``u <= c_ref + max_indentation`` with c_ref
the whole run's contact point, the same for every contact point tried.

A range that moved with each tried contact point let contact points early in the baseline win by
fitting fewer samples (the shipped cell at 60 nm: E = 159 Pa, the contact at the start of the run;
at 500 nm: 0.057 Pa). Checked against an independent least squares (scipy's curve_fit, in scaled
units) over the same samples, and against the truth of synthetic Hertz curves."""

from __future__ import annotations

import io
import json
import math
from contextlib import redirect_stdout

import numpy as np
import pytest
from scipy.optimize import curve_fit

from afmforce.contact.fit import fit_indentation

E_TRUE, R_TIP, NU = 5e3, 5e-6, 0.5           # Pa, m, -
NOISE = 5e-15                               # N
K = 4 / 3 / (1 - NU * NU) * math.sqrt(R_TIP)  # F = E K delta^1.5


def _curve(seed: int):
    """Hertz approach over 2 um at 1 nm steps: contact off the grid at 0.1-0.2 um, baseline, white noise."""
    rng = np.random.default_rng(500 + seed)
    c = float(rng.uniform(0.1e-6, 0.2e-6))
    b = float(rng.normal(0.0, 1e-11))
    u = np.linspace(-1e-6, 1e-6, 2001)
    F = E_TRUE * K * np.clip(u - c, 0, None) ** 1.5 + b + rng.normal(0.0, NOISE, u.size)
    return u, F, c, b


def _independent(u, F, p0, R=R_TIP, nu=NU):
    """(E [Pa], c [m], b [N]) of the Hertz paraboloid by scipy's Levenberg-Marquardt on all of (u, F), in
    kPa, nm and pN (the SI columns differ by ~1e13), tolerances at machine precision."""
    k = 4 / 3 / (1 - nu * nu) * math.sqrt(R)
    unm, Fpn = u * 1e9, F * 1e12

    def f(x, E, c, b):
        return E * 1e3 * k * np.clip((x - c) * 1e-9, 0, None) ** 1.5 * 1e12 + b

    p, _ = curve_fit(f, unm, Fpn, p0=(p0[0] / 1e3, p0[1] * 1e9, p0[2] * 1e12), xtol=1e-15, ftol=1e-15,
                     gtol=1e-15, maxfev=20000)
    return p[0] * 1e3, p[1] * 1e-9, p[2] * 1e-12


@pytest.mark.parametrize("window", [30e-9, 100e-9, 300e-9, 1e-6])
def test_range_is_fixed_samples_and_covers_the_truth(window):
    """On 20 seeds: the fitted samples are those within ``window`` of the whole run's contact point (found
    by curve_fit independently); E, c and b equal curve_fit's over exactly those samples; the 95 %
    intervals of E and of the contact point (t se) cover the truth on >= 17 of 20 seeds."""
    cover_E = cover_c = 0
    for seed in range(20):
        u, F, c, b = _curve(seed)
        ref = _independent(u, F, (1.2 * E_TRUE, c + 5e-9, b))[1]
        keep = u <= ref + window
        fit = fit_indentation(u, F, "hertz_paraboloid", {"radius": R_TIP}, nu=NU, max_indentation=window)
        assert fit.range_reference == pytest.approx(ref, abs=1e-13)
        np.testing.assert_array_equal(fit.fitted, np.flatnonzero(keep))
        assert fit.n_points == keep.sum()
        E, ci, bi = _independent(u[keep], F[keep], (1.2 * E_TRUE, c + 5e-9, b))
        # the same minimum as curve_fit's (the fit polishes its scan with two Gauss-Newton steps): within a
        # fifth of a standard error, the sums of squares within 0.05 of the noise variance
        assert abs(fit.youngs_modulus - E) < 0.2 * fit.youngs_modulus_se
        assert abs(fit.contact - ci) < 0.2 * fit.contact_se
        assert abs(fit.baseline - bi) < 2e-3 * NOISE                   # its standard error: ~0.03 NOISE

        def ssr(E, c, b):
            return float(np.sum((F[keep] - E * K * np.clip(u[keep] - c, 0, None) ** 1.5 - b) ** 2))
        assert ssr(fit.youngs_modulus, fit.contact, fit.baseline) - ssr(E, ci, bi) < 0.05 * NOISE ** 2
        assert fit.max_indentation == pytest.approx(float(np.max(u[keep] - fit.contact)), rel=1e-12)
        assert fit.max_indentation <= window + 2e-9       # the contact point within ~a sample of c_ref
        t = (fit.youngs_modulus_high - fit.youngs_modulus) / fit.youngs_modulus_se
        cover_E += fit.youngs_modulus_low <= E_TRUE <= fit.youngs_modulus_high
        cover_c += abs(fit.contact - c) <= t * fit.contact_se
    assert cover_E >= 17 and cover_c >= 17, (cover_E, cover_c)


def test_whole_run_is_the_range_past_the_deepest_point():
    """A range beyond the deepest indentation fits every sample: the same numbers as no range."""
    u, F, c, b = _curve(0)
    whole = fit_indentation(u, F, "hertz_paraboloid", {"radius": R_TIP}, nu=NU)
    wide = fit_indentation(u, F, "hertz_paraboloid", {"radius": R_TIP}, nu=NU, max_indentation=5e-6)
    assert math.isnan(whole.range_reference) and wide.range_reference == whole.contact
    assert (wide.youngs_modulus, wide.contact, wide.n_points) == (whole.youngs_modulus, whole.contact, whole.n_points)


def test_a_range_of_too_few_samples_is_refused():
    from afmforce.errors import AnalysisError, ParameterError

    u, F, c, b = _curve(1)
    with pytest.raises(AnalysisError, match="max_indentation"):
        fit_indentation(u[::200], F[::200], "hertz_paraboloid", {"radius": R_TIP}, nu=NU, max_indentation=1e-9)
    with pytest.raises(ParameterError, match="max_indentation"):
        fit_indentation(u, F, "hertz_paraboloid", {"radius": R_TIP}, nu=NU, max_indentation=-1e-9)


def test_adhesive_law_uses_the_same_fixed_range():
    """JKR: the samples fitted are those within the range of the whole run's contact point."""
    import adhesive_curves as ac

    u, F, tr = ac.curve("jkr", 3, n=300)
    whole = fit_indentation(u, F, "jkr", {"radius": ac.R_TIP}, nu=ac.NU)
    fit = fit_indentation(u, F, "jkr", {"radius": ac.R_TIP}, nu=ac.NU, max_indentation=0.6e-6)
    assert fit.range_reference == whole.contact
    np.testing.assert_array_equal(fit.fitted, np.flatnonzero(u <= whole.contact + 0.6e-6))
    assert fit.youngs_modulus_low <= tr["E"] <= fit.youngs_modulus_high


def _cli(path, *options) -> dict:
    """``afmforce analyze PATH --json --option ...``: the indentation details."""
    from afmforce.cli.main import main

    out = io.StringIO()
    with redirect_stdout(out):
        assert main(["analyze", str(path), "--json", *sum((["--option", o] for o in options), [])]) == 0
    return next(iter(json.loads(out.getvalue())["results"].values()))["details"]["indentation"]


def test_cell_curve_range_fits_the_samples_within_the_range():
    """The shipped JPK cell, a 5 um bead, 60 nm: the fitted samples are those of the whole run within 60 nm
    of its contact point, E is curve_fit's over them, and a cell's modulus (kPa; the moving window gave
    159 Pa with the contact at the start of the run)."""
    from afmforce.datasets import path

    whole = _cli(path("jpk-cell"), "indentation.tip_radius=5um")
    got = _cli(path("jpk-cell"), "indentation.tip_radius=5um", "indentation.max_indentation=60nm")
    u_all = whole["contact_depth"] + np.asarray(whole["indentation"])
    F_all = np.asarray(whole["fit_force"]) + np.asarray(whole["residuals"])
    assert whole["n_points"] == u_all.size
    keep = u_all <= whole["contact_depth"] + 60e-9
    assert got["n_points"] == keep.sum() < u_all.size
    u = got["contact_depth"] + np.asarray(got["indentation"])
    F = np.asarray(got["fit_force"]) + np.asarray(got["residuals"])
    np.testing.assert_allclose(np.sort(u), np.sort(u_all[keep]), rtol=0, atol=1e-15)
    E, c, b = _independent(u, F, (got["youngs_modulus"] * 1.3, got["contact_depth"] - 5e-9, got["baseline"]),
                           R=got["tip_radius"], nu=got["poisson"])
    # the same minimum: within a hundredth of a standard error
    assert abs(got["youngs_modulus"] - E) < 0.01 * got["youngs_modulus_se"]
    assert abs(got["contact_depth"] - c) < 0.01 * got["contact_point_se"]
    assert 1e3 < got["youngs_modulus"] < 1e5
    assert abs(got["contact_depth"] - whole["contact_depth"]) < 60e-9


def _linear_E_b(u, F, c, R=R_TIP, nu=NU):
    """(E, b) of the Hertz paraboloid at the contact point c by numpy's least squares, in scaled columns."""
    phi = 4 / 3 / (1 - nu * nu) * math.sqrt(R) * np.clip(u - c, 0, None) ** 1.5
    s = phi.max()
    (e, b), *_ = np.linalg.lstsq(np.column_stack((phi / s, np.ones_like(phi))), F, rcond=None)
    return e / s, b


@pytest.mark.parametrize("window", [math.inf, 100e-9])
def test_fixed_contact_point_fits_E_and_the_baseline_only(window):
    """contact_point given (the truth): E and b are numpy's linear least squares over the samples within
    the range of it, the contact point is reported with standard error 0 and a note; the 95 % interval
    of E covers the truth on >= 17 of 20 seeds."""
    cover = 0
    for seed in range(20):
        u, F, c, b = _curve(seed)
        fit = fit_indentation(u, F, "hertz_paraboloid", {"radius": R_TIP}, nu=NU, contact_point=c,
                              max_indentation=window)
        keep = u <= c + window
        np.testing.assert_array_equal(fit.fitted, np.flatnonzero(keep))
        E, bi = _linear_E_b(u[keep], F[keep], c)
        assert fit.youngs_modulus == pytest.approx(E, rel=1e-9)
        assert fit.baseline == pytest.approx(bi, abs=1e-6 * NOISE)   # normal equations vs QR
        assert fit.contact == c and fit.contact_se == 0.0
        assert "fixed" in fit.warnings[0]
        cover += fit.youngs_modulus_low <= E_TRUE <= fit.youngs_modulus_high
    assert cover >= 17, cover


def test_fixed_contact_point_refusals():
    from afmforce.errors import AnalysisError, ParameterError
    import adhesive_curves as ac

    u, F, c, b = _curve(2)
    with pytest.raises(AnalysisError, match="contact point fixed"):
        fit_indentation(u, F, "hertz_paraboloid", {"radius": R_TIP}, nu=NU, contact_point=2e-6)   # past the run
    u, F, tr = ac.curve("jkr", 0, n=100)
    with pytest.raises(ParameterError, match="contact_point"):
        fit_indentation(u, F, "jkr", {"radius": ac.R_TIP}, nu=ac.NU, contact_point=tr["c"])


def test_cell_curve_with_the_contact_point_given():
    """The shipped cell through the CLI option indentation.contact_point: fixed at the whole run's fitted
    contact point, E is the whole run's (its optimum over c), with standard error 0 on the contact."""
    from afmforce.datasets import path

    whole = _cli(path("jpk-cell"), "indentation.tip_radius=5um")
    c = whole["contact_depth"]
    got = _cli(path("jpk-cell"), "indentation.tip_radius=5um", f"indentation.contact_point={c!r}")
    assert got["contact_depth"] == c and got["contact_point_se"] == 0.0
    assert abs(got["youngs_modulus"] - whole["youngs_modulus"]) < 0.01 * whole["youngs_modulus_se"]
    assert got["youngs_modulus_se"] < whole["youngs_modulus_se"]      # c no longer uncertain
    assert got["n_points"] == whole["n_points"]


def test_fit_adhesive_fits_every_sample_given():
    """fit_adhesive has no window that moves with the contact point tried (the old per-candidate
    ``max_ind``, which let contact points early in the baseline win by fitting fewer samples): every
    sample given is fitted, with weight 1 (no ``width``). A fit range is chosen before, by
    fit_indentation's ``max_indentation``."""
    from afmforce.contact.adhesive_fit import fit_adhesive
    import adhesive_curves as ac

    u, F, tr = ac.curve("dmt", 0, n=100)
    fit = fit_adhesive(u, F, "dmt", ac.R_TIP, ac.NU)
    assert fit.n == u.size and np.array_equal(fit.weights, np.ones(u.size))
    assert abs(fit.c - tr["c"]) < 0.05 * (u.max() - u.min())  # the contact found, not a baseline point


def test_a_modulus_from_three_points_of_indentation_is_undetermined():
    """Hertz (closed form) on a curve with 3 samples past the contact point, 12 noise draws: before,
    the covariance's interval had a negative lower end and missed the truth 21 times in 30 seeds (e.g.
    196 Pa [-1103, 1495] for 10 kPa); now [0, open] with a warning, and 30 points in contact keep a
    finite interval that covers the truth."""
    import math

    import numpy as np

    from afmforce.contact.fit import fit_indentation

    R, E, nu = 5e-6, 10e3, 0.5
    K = 4.0 / 3.0 * E / (1 - nu * nu) * math.sqrt(R)
    u = np.arange(200) * 1e-9
    covered = 0
    for seed in range(12):
        for n_contact in (3, 30):
            c = u[200 - n_contact - 1] + 0.3e-9
            F = K * np.clip(u - c, 0, None) ** 1.5 + np.random.default_rng(seed).normal(0, 5e-12, u.size)
            fit = fit_indentation(u, F, "hertz_paraboloid", {"radius": R}, nu=nu)
            assert fit.youngs_modulus_low >= 0
            if n_contact == 3:
                assert fit.youngs_modulus_low == 0 and math.isnan(fit.youngs_modulus_high)
                assert any("modulus is undetermined" in w for w in fit.warnings)
            else:
                covered += fit.youngs_modulus_low <= E <= fit.youngs_modulus_high
    assert covered >= 10          # 95 % of 12: 11.4 expected
