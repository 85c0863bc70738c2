"""Thermal-noise calibration: the SHO fit and equipartition (issue 34).

References: the area of eq (1) is pi P_dc f0 Q / 2 (closed form, checked by quadrature); the
spectra come from the linear model's exact PSD (calibration/virtual.py, itself checked against
equipartition by quadrature in test_virtual.py), so the truth is known.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from afmforce.calibration import BOLTZMANN, BUTT_JASCHKE, DEFAULT_TEMPERATURE, fit_thermal, sho_psd
from afmforce.calibration.virtual import linear_thermal_psd, sample_spectrum
from afmforce.errors import AnalysisError, ParameterError


def _spring(k=0.1, f0=15e3, q=30.0):
    m = k / (2 * math.pi * f0) ** 2
    return k, m, m * 2 * math.pi * f0 / q


def test_sho_area_is_the_closed_form():
    f0, q, p_dc = 12e3, 7.0, 3e-26
    area = sum(quad(lambda f: sho_psd(f, f0, q, p_dc), a, b, limit=500)[0]
               for a, b in ((0, f0 / 2), (f0 / 2, 2 * f0), (2 * f0, np.inf)))
    assert area == pytest.approx(math.pi * p_dc * f0 * q / 2, rel=1e-8)


def test_boltzmann_and_defaults():
    assert BOLTZMANN == 1.380649e-23 and DEFAULT_TEMPERATURE == 295.0 and BUTT_JASCHKE == 0.817


@pytest.mark.parametrize("q", [2.0, 30.0, 300.0])
def test_exact_spectrum_gives_k_f0_q(q):
    k, m, c = _spring(q=q)
    f = np.linspace(50.0, 60e3, 6000)
    psd = linear_thermal_psd(f, k, m, c, [1.0], 300.0) + 1e-29
    r = fit_thermal(f, psd, temperature=300.0, correction=1.0)
    assert r.spring_constant == pytest.approx(k, rel=1e-6)
    assert r.resonance_frequency == pytest.approx(15e3, rel=1e-7)
    assert r.quality_factor == pytest.approx(q, rel=1e-6)
    assert r.white == pytest.approx(1e-29, rel=1e-3)
    assert r.spring_constant_se_window < 1e-5 * k          # an exact oscillator: no window effect


@pytest.mark.parametrize("seed", range(5))
def test_equipartition_on_noisy_spectra_within_2_percent(seed):
    """256 averaged periodograms, white floor: k within 2 % and within 3.5 standard errors."""
    k, m, c = _spring(q=20.0)
    f = np.linspace(10.0, 40e3, 4000)
    psd = sample_spectrum(linear_thermal_psd(f, k, m, c, [1.0], 295.0), 256, np.random.default_rng(seed),
                          white=2e-28)
    r = fit_thermal(f, psd, correction=1.0)
    assert r.temperature == 295.0                       # the default
    assert abs(r.spring_constant / k - 1) < 0.02
    assert abs(r.spring_constant - k) < 3.5 * r.spring_constant_se
    assert 0.003 < r.spring_constant_se / k < 0.02       # an interval, neither zero nor useless
    assert r.averages == pytest.approx(256, rel=0.2)     # the averaging read from the scatter
    assert r.reduced_deviance == pytest.approx(1.0, abs=0.15)


def test_single_periodogram_is_unbiased():
    """One periodogram per bin (chi-square, 2 dof): a least-squares fit of ln P would be 44 % low
    (exp(-Euler gamma)); the Whittle fit is not: the mean of 40 seeds within 4 % (each scatters
    by ~8 %), and the 95 % intervals cover the truth in at least 80 % of them."""
    k, m, c = _spring(q=50.0)
    f = np.linspace(10.0, 40e3, 8000)
    exact = linear_thermal_psd(f, k, m, c, [1.0], 295.0)
    rs = [fit_thermal(f, sample_spectrum(exact, 1, np.random.default_rng(s), 1e-28), correction=1.0)
          for s in range(40)]
    ks = np.array([r.spring_constant for r in rs])
    assert abs(ks.mean() / k - 1) < 0.04
    assert np.mean([abs(r.spring_constant - k) < 1.96 * r.spring_constant_se for r in rs]) >= 0.8


def test_correction_temperature_and_tilt_scale_k():
    k, m, c = _spring()
    f = np.linspace(50.0, 60e3, 3000)
    psd = linear_thermal_psd(f, k, m, c, [1.0], 300.0)
    r1 = fit_thermal(f, psd, temperature=300.0, correction=1.0)
    r2 = fit_thermal(f, psd, temperature=600.0, correction=BUTT_JASCHKE, tilt=math.radians(10))
    assert r2.spring_constant == pytest.approx(r1.spring_constant * 2 * 0.817, rel=1e-9)
    assert r2.spring_constant_normal == pytest.approx(r2.spring_constant / math.cos(math.radians(10)) ** 2)


def test_pink_background_is_fitted_or_dropped():
    k, m, c = _spring(q=5.0)
    f = np.linspace(20.0, 60e3, 6000)
    psd = linear_thermal_psd(f, k, m, c, [1.0], 295.0) + 1e-28 + 3e-24 / f
    r = fit_thermal(f, psd, correction=1.0, pink=True)
    assert r.spring_constant == pytest.approx(k, rel=1e-4)
    assert r.pink == pytest.approx(3e-24, rel=1e-2)


def test_given_window_and_refusals():
    k, m, c = _spring()
    f = np.linspace(50.0, 60e3, 3000)
    psd = linear_thermal_psd(f, k, m, c, [1.0], 295.0)
    r = fit_thermal(f, psd, correction=1.0, f_range=(10e3, 20e3))
    assert r.f_min >= 10e3 and r.f_max <= 20e3 and r.spring_constant == pytest.approx(k, rel=1e-6)
    with pytest.raises(AnalysisError, match="bins"):
        fit_thermal(f, psd, f_range=(10e3, 10.05e3))
    with pytest.raises(ParameterError, match="temperature"):
        fit_thermal(f, psd, temperature=-1.0)
    with pytest.raises(ParameterError, match="correction"):
        fit_thermal(f, psd, correction=0.0)


def test_electrical_lines_are_masked():
    """Mains harmonics (one bin each, 1000x the floor) below and inside the window: the resonance
    is still found and k is that of the clean spectrum; the lines in the window are reported."""
    k, m, c = _spring(q=30.0)
    f = np.arange(1, 6001) * 10.0
    clean = linear_thermal_psd(f, k, m, c, [1.0], 295.0) + 1e-28
    dirty = clean.copy()
    for line in (50, 150, 250, 13_000, 16_000):
        dirty[f == line] *= 1e3 if line < 1000 else 30
    dirty[f == 50] = 1e3 * clean.max()                  # the highest bin of the spectrum
    r0 = fit_thermal(f, clean, correction=1.0)
    r = fit_thermal(f, dirty, correction=1.0)
    assert r.resonance_frequency == pytest.approx(15e3, rel=1e-6)
    assert r.spring_constant == pytest.approx(r0.spring_constant, rel=1e-6)
    assert r.masked == 2 and r0.masked == 0


def test_a_resonance_three_bins_wide_is_found():
    """A high-Q lever on a coarse grid (line width f0/Q = 50 Hz, bins of 20 Hz) is no electrical line."""
    k, m, c = _spring(f0=15e3, q=300.0)
    f = np.arange(1, 3001) * 20.0 + 7.0
    psd = linear_thermal_psd(f, k, m, c, [1.0], 295.0) + 1e-30
    r = fit_thermal(f, psd, correction=1.0)
    assert r.resonance_frequency == pytest.approx(15e3, rel=1e-6) and r.spring_constant == pytest.approx(k, rel=1e-4)


@pytest.mark.parametrize("case", ["above_nyquist", "buried"])
def test_no_resonance_above_the_noise_is_refused_not_fitted(case):
    """A spectrum whose peak lies above its highest frequency, or 20 dB under the detector floor:
    before, a noise blip was fitted as the resonance (f0 680 Hz, Q 11 +- 10, k 5e4 or 0.44 N/m against
    a true 70 kHz, 0.1 N/m lever); now the fit says no resonance stands above the noise."""
    rng = np.random.default_rng(0)
    f = np.arange(20.0, 200e3, 20.0)
    k, f0, q = 0.1, (300e3 if case == "above_nyquist" else 70e3), 100.0
    area = BUTT_JASCHKE * BOLTZMANN * DEFAULT_TEMPERATURE / k           # equipartition, eq (2)
    white = 1e-28 if case == "above_nyquist" else 1e-22
    p = sho_psd(f, f0, q, 2 * area / (math.pi * f0 * q), white) * rng.gamma(4, 0.25, f.size)
    with pytest.raises(AnalysisError, match="no resonance stands above the noise"):
        fit_thermal(f, p)
    # the same lever with its peak in view and the floor 1000x lower is fitted (k within 3 se)
    p = sho_psd(f, 70e3, q, 2 * area / (math.pi * 70e3 * q), 1e-25) * rng.gamma(4, 0.25, f.size)
    fit = fit_thermal(f, p)
    assert abs(fit.spring_constant - k) < 3 * fit.spring_constant_se < 0.2 * k
