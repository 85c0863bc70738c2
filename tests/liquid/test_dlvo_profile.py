"""The DLVO fit of the liquid step never gives a tight interval the data do not support.

Over 2-30 nm, with 10 pN noise, a double layer of Debye length 3 um is only a constant force
(psi^2 / lambda): the covariance gave psi = -0.0027 +- 0.0011 V for a true -0.03 V. The profile
likelihood, computed here independently (scipy least_squares at a fixed psi, lambda and A
re-fitted), stays within the 95 % threshold at the true -0.03 V: the fit must give no standard
error and an interval that holds the truth. A Debye length inside the data range keeps its error,
and its interval ends match the independent profile's crossings.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq, least_squares

from afmforce.analysis.liquid import fit_dlvo
from afmforce.forces import double_layer_force, paper_radius, vdw_force

R = 2e-6
H = np.linspace(2e-9, 30e-9, 150)
SIGMA = 10e-12


def _model(psi, lam, a):
    return (np.asarray(double_layer_force(H, R, psi, lam, None, 78.4, "constant_potential", "sphere-flat"))
            + np.asarray(vdw_force(H, paper_radius(R, "sphere-flat"), a, 0.35e-9)))


def _data(lam, seed):
    return _model(-0.03, lam, 1e-20) + SIGMA * np.random.default_rng(seed).standard_normal(H.size)


def _chi2_fixed(f, index, value, start):
    """Independent profile: the chi-square at parameter ``index`` fixed, the other two re-fitted."""
    scale = np.array([0.01, 1e-8, 1e-20])
    free = [j for j in range(3) if j != index]

    def resid(y):
        p = np.empty(3)
        p[index], p[free] = value, y * scale[free]
        return (_model(*p) - f) / SIGMA
    fit = least_squares(resid, np.asarray(start)[free] / scale[free], xtol=1e-14, ftol=1e-14, gtol=1e-14,
                        bounds=([[-100, 1e-3, 1e-3][j] for j in free], [[100, 1e3, 1e4][j] for j in free]))
    return float(fit.fun @ fit.fun)


def test_psi_of_a_debye_length_beyond_the_data_is_no_tight_interval():
    f = _data(3e-6, 2)
    fit = fit_dlvo(H, f, R, sigma=SIGMA)
    unit = max(fit.redchi, 1.0) * fit.correlation_time
    chi0 = min(_chi2_fixed(f, 0, fit.surface_potential, (fit.surface_potential, lam, 1e-20))
               for lam in (5e-9, 18e-9, 100e-9))
    assert (_chi2_fixed(f, 0, -0.03, (-0.03, 1e-6, 1e-20)) - chi0) / unit < 3.84    # the truth fits
    assert math.isnan(fit.stderr["surface_potential"]) and math.isnan(fit.debye_length)
    low, high = fit.interval["surface_potential"]
    assert low < -0.03 < high
    assert "surface_potential" in fit.note and "debye_length undetermined" in fit.note


def test_debye_length_inside_the_data_keeps_its_error_and_profile_interval():
    f = _data(5e-9, 2)
    fit = fit_dlvo(H, f, R, sigma=SIGMA)
    lam = fit.debye_length
    assert lam == pytest.approx(5e-9, rel=0.02) and math.isfinite(fit.stderr["debye_length"]) and fit.note == ""
    unit = max(fit.redchi, 1.0) * fit.correlation_time
    start = (fit.surface_potential, lam, fit.hamaker)
    chi0 = _chi2_fixed(f, 1, lam, start)
    cross = lambda x: (_chi2_fixed(f, 1, x, start) - chi0) / unit - 3.84  # noqa: E731
    low = brentq(cross, 0.9 * lam, lam, xtol=1e-16)
    high = brentq(cross, lam, 1.1 * lam, xtol=1e-16)
    assert fit.interval["debye_length"][0] == pytest.approx(low, rel=1e-3)
    assert fit.interval["debye_length"][1] == pytest.approx(high, rel=1e-3)
