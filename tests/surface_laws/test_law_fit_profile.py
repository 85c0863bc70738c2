"""A surface-law fit never gives a tight interval the data do not support (profile likelihood).

The Jacobian's standard error is local. A double layer whose Debye length (100 nm) lies far
beyond the data range (1-10 nm), fitted with a free force offset, looks like a line the offset and
the prefactor share: the Jacobian gave 2.6 +- 2.0 nm, excluding the true 100 nm by 48 standard
errors. The profile likelihood, computed here independently (scipy least_squares at each fixed
Debye length, the potential and the offset re-fitted), stays within 3.84 of its minimum up to the
micrometres: the fit must report that interval and no standard error.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq, least_squares

from afmforce import forces
from afmforce.analysis.surface_law_fit import fit_surface_law
from afmforce.surface_laws import law

R = 1e-6
H = np.linspace(1e-9, 10e-9, 60)
REC = law("double_layer")
START = {"debye_length": 10e-9, "surface_potential": -0.02}


def _force(lam: float, psi: float) -> np.ndarray:
    v = {p.name: p.default for p in REC.parameters}
    v.update(REC.example, debye_length=lam, surface_potential=psi)
    return REC.force(H, forces.effective_radius(R, "sphere-flat"), v)[0]


def _data(lam: float, seed: int):
    f = _force(lam, -0.03)
    noise = 0.02 * np.ptp(f) + 1e-12
    return f + noise * np.random.default_rng(seed).standard_normal(H.size), noise


def _profile(lam: float, f: np.ndarray, noise: float, offset: bool) -> float:
    """Independent profile: min over (psi, offset) of the chi-square at a fixed Debye length."""
    def resid(p):
        return (_force(lam, p[0] * 0.01) + (p[1] * noise if offset else 0.0) - f) / noise
    best = min((least_squares(resid, [s, 0.0] if offset else [s], xtol=1e-14, ftol=1e-14, gtol=1e-14)
                for s in (-3.0, -1.0, -0.3)), key=lambda r: r.cost)
    return float(best.fun @ best.fun)


def test_debye_length_beyond_the_data_is_no_tight_interval():
    f, noise = _data(100e-9, 5)
    fit = fit_surface_law(H, f, "double_layer", radius=R, free=["surface_potential", "debye_length"],
                          sigma=noise, fixed=START)
    chi_min = min(_profile(lam, f, noise, True) for lam in np.geomspace(1e-9, 3e-6, 25))
    # independently: the true 100 nm and 1 um both fit within the 95 % threshold
    for lam in (100e-9, 1e-6):
        assert _profile(lam, f, noise, True) - chi_min < 3.84
    low, high = fit.interval.get("debye_length", (None, None))
    assert math.isnan(fit.stderr["debye_length"])                       # no tight standard error
    assert high is None or high > 1e-6                                    # the interval reaches 1 um
    assert low is None or low < 100e-9
    assert "debye_length" in fit.note


def test_debye_length_inside_the_data_keeps_its_interval():
    """3 nm over 1-10 nm, no offset: determined; the interval ends match the independent profile's
    3.84 crossings (brentq on the scipy profile) to 1 %, and the standard error is kept."""
    f, noise = _data(3e-9, 7)
    fit = fit_surface_law(H, f, "double_layer", radius=R, free=["surface_potential", "debye_length"],
                          sigma=noise, fixed=START, offset=False)
    lam = fit.values["debye_length"]
    assert lam == pytest.approx(3e-9, rel=0.05) and math.isfinite(fit.stderr["debye_length"])
    chi0 = _profile(lam, f, noise, False)
    redchi = max(chi0 / (H.size - 2), 1.0)
    cross = lambda x: (_profile(x, f, noise, False) - chi0) / redchi - 3.84  # noqa: E731
    low = brentq(cross, lam * 0.5, lam, xtol=1e-15)
    high = brentq(cross, lam, lam * 2.0, xtol=1e-15)
    assert fit.interval["debye_length"][0] == pytest.approx(low, rel=0.01)
    assert fit.interval["debye_length"][1] == pytest.approx(high, rel=0.01)
    assert fit.note == ""
