"""Standard errors of the velocity-force fit ``F_v = v (c + beta / h)`` (velocity_force_fit), checked
against scipy's ``curve_fit`` and by the coverage of their 95 % intervals over many noise draws with
known truth; undetermined (NaN and the reason) where the data cannot determine c and beta."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import curve_fit
from scipy.signal import lfilter

from afmforce.analysis.liquid import VELOCITY_FIT_MIN_POINTS, velocity_force_fit

C = 1e-5                                          # lever drag [N s/m]
BETA = 6 * math.pi * 0.89e-3 * (5e-6) ** 2        # 6 pi eta R^2 [N s], water, R 5 um
V = 20e-6                                         # [m/s]
H = np.linspace(60e-9, 350e-9, 300)               # [m]
SIGMA = 2e-12                                     # force noise of one sample [N]


def _draw(seed: int, rho: float = 0.0):
    """Velocity force with Gaussian noise of rms SIGMA, white or AR(1) with lag-one correlation rho."""
    e = np.random.default_rng(seed).normal(0.0, SIGMA, H.size)
    if rho:
        e = lfilter([math.sqrt(1 - rho ** 2)], [1.0, -rho], e)
    return V * (C + BETA / H) + e


def test_values_and_errors_are_curve_fits_widened_by_the_correlation_time():
    fv = _draw(0)
    vf = velocity_force_fit(H, fv, V, 50e-9, 400e-9)
    popt, pcov = curve_fit(lambda x, c, b: c + b * x, 1.0 / H, fv / V)   # unscaled: s^2 (X'X)^-1
    assert vf.undetermined == "" and vf.n == H.size
    assert (vf.lever_drag, vf.drainage_coefficient) == pytest.approx(tuple(popt), rel=1e-9)
    se = np.sqrt(np.diag(pcov)) * math.sqrt(vf.correlation_time)
    assert (vf.lever_drag_se, vf.drainage_coefficient_se) == pytest.approx(tuple(se), rel=1e-6)
    assert 1.0 <= vf.correlation_time < 1.5          # white noise: about 1


@pytest.mark.parametrize("rho, low, high, plain_high", [(0.0, 0.92, 0.98, 1.0), (0.9, 0.82, 0.99, 0.5)])
def test_95_percent_intervals_cover_the_truth(rho, low, high, plain_high):
    """400 draws: white noise covered c 380 and beta 379 times (0.95); AR(1) noise of correlation time
    19 (drift, 1/f) 353 and 355 (0.88) with the widening, 153 and 148 (0.38) without it."""
    n = 400
    hits, plain = np.zeros(2), np.zeros(2)
    for seed in range(n):
        vf = velocity_force_fit(H, _draw(seed, rho), V, 50e-9, 400e-9)
        err = np.abs([vf.lever_drag - C, vf.drainage_coefficient - BETA])
        se = np.array([vf.lever_drag_se, vf.drainage_coefficient_se])
        hits += err < 1.96 * se
        plain += err < 1.96 * se / math.sqrt(vf.correlation_time)
    assert np.all((low <= hits / n) & (hits / n <= high)), hits / n
    assert np.all(plain / n <= plain_high), plain / n


@pytest.mark.parametrize("h, velocity, words", [
    (H[:VELOCITY_FIT_MIN_POINTS - 1], V, "fewer than"),          # too few samples in the range
    (H, 0.0, "not positive"),                                    # no speed: no velocity force
    (H, math.nan, "not positive"),
    (np.full(50, 200e-9), V, "collinear"),                        # one separation: no spread of 1/h
])
def test_undetermined_when_the_data_cannot_determine_them(h, velocity, words):
    vf = velocity_force_fit(h, V * (C + BETA / h), velocity, 50e-9, 400e-9)
    assert words in vf.undetermined
    assert all(math.isnan(x) for x in (vf.lever_drag, vf.drainage_coefficient, vf.lever_drag_se,
                                       vf.drainage_coefficient_se))


def test_the_range_selects_the_samples():
    vf = velocity_force_fit(H, _draw(1), V, 100e-9, 200e-9)
    assert vf.n == int(np.sum((H >= 100e-9) & (H <= 200e-9))) and vf.undetermined == ""
