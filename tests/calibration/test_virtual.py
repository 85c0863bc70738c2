"""Virtual thermal spectra: the linear model's PSD obeys equipartition, both modes, any damping;
the probes of afmforce.dynamics give their force constant back (issue 34)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from afmforce.calibration import BOLTZMANN, fit_thermal
from afmforce.calibration.virtual import linear_thermal_psd, mode_shares, sample_spectrum
from afmforce.dynamics.parts import BeamProbe, SpringProbe
from afmforce.dynamics.thermal import probe_matrices, thermal_spectrum


def test_spring_psd_is_the_closed_form():
    k, m, c, T = 0.2, 1e-11, 2e-7, 290.0
    f = np.array([100.0, 5e3, 20e3])
    w = 2 * np.pi * f
    expected = 4 * BOLTZMANN * T * c / ((k - m * w**2) ** 2 + (c * w) ** 2)
    np.testing.assert_allclose(linear_thermal_psd(f, k, m, c, [1.0], T), expected, rtol=1e-12)


def test_two_modes_integrate_to_equipartition():
    """<y^2> = kB T c^T K^-1 c (quadrature of eq 1 over both modes), for Rayleigh damping."""
    K = np.array([[3.0, -1.0], [-1.0, 1.0]])
    M = np.diag([1e-11, 2e-12])
    C = 2e-7 * M / 1e-11 + 1e-9 * K
    out = np.array([0.3, 1.0])
    T = 295.0
    freqs, shares = mode_shares(K, M, out)
    edges = [0.0, *sorted([*freqs * 0.5, *freqs, *freqs * 2]), np.inf]
    total = sum(quad(lambda f: linear_thermal_psd(f, K, M, C, out, T)[0], a, b, limit=400)[0]
                for a, b in zip(edges[:-1], edges[1:]))
    assert total == pytest.approx(BOLTZMANN * T * out @ np.linalg.solve(K, out), rel=1e-6)
    assert shares.sum() == pytest.approx(1.0) and np.all(shares > 0)


def test_chi_square_scatter_of_averages():
    rng = np.random.default_rng(3)
    x = sample_spectrum(np.ones(200_000), 16, rng)
    assert x.mean() == pytest.approx(1.0, abs=0.01)
    assert x.var() == pytest.approx(1 / 16, rel=0.03)       # chi-square(2N)/(2N): variance 1/N


def test_probe_deflection_compliance_is_the_force_constant():
    """The virtual AFM's deflection (the probe height h) has compliance 1/k of the probe."""
    for probe in (BeamProbe(quality_factor=10.0), SpringProbe(quality_factor=10.0)):
        K, M, C, out = probe_matrices(probe)
        assert out @ np.linalg.solve(K, out) * probe.force_constant == pytest.approx(1.0, rel=1e-9)


@pytest.mark.parametrize("probe", [
    SpringProbe(spring_constant=0.2, mass=0.2 / (2 * math.pi * 20e3) ** 2, quality_factor=50.0),
    SpringProbe(spring_constant=0.05, mass=0.05 / (2 * math.pi * 8e3) ** 2, quality_factor=2.0),
    BeamProbe(quality_factor=30.0),
    BeamProbe(quality_factor=3.0, quality_factor_2=10.0),
], ids=["spring-air", "spring-water", "beam-Q30", "beam-Q3"])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_equipartition_on_virtual_spectra_within_2_percent(probe, seed):
    """The first mode's equipartition with the spectrum's own correction (its share of <h^2>)
    gives the probe's force constant within 2 % (2048 averages: the scatter is 0.3-0.5 %, 4-6
    standard errors below the tolerance; with 256 it is 1-1.4 %) and within 4 standard errors."""
    sp = thermal_spectrum(probe, averages=2048, white=1e-30, seed=seed)
    r = fit_thermal(sp.frequency, sp.psd, temperature=sp.temperature, correction=sp.correction)
    assert abs(r.spring_constant / probe.force_constant - 1) < 0.02
    assert abs(r.spring_constant - probe.force_constant) < 4 * r.spring_constant_se
    assert r.quality_factor == pytest.approx(probe.quality_factor, rel=0.1)
    assert r.resonance_frequency == pytest.approx(sp.vendor["resonance_frequency"], rel=0.01)


def test_beam_spectrum_holds_both_modes():
    probe = BeamProbe(quality_factor=3.0, quality_factor_2=10.0)
    sp = thermal_spectrum(probe, seed=None)
    f2 = sp.vendor["resonance_frequency_2"]
    near = np.abs(sp.frequency - f2) < 0.02 * f2
    assert sp.frequency[-1] > f2 and sp.psd[near].max() > 5 * np.interp(0.8 * f2, sp.frequency, sp.psd)
    assert 0.99 < sp.correction < 1.0


def test_beam_modes_are_the_dynamics_free_modes():
    """mode_shares (scipy's generalized eigenproblem) against the closed-form 2x2 free modes of
    afmforce.dynamics.damping that the lever damping is built on."""
    from afmforce.dynamics.damping import free_modes
    from afmforce.dynamics.models import beam_matrices

    probe = BeamProbe(quality_factor=10.0)
    K, M, _, out = probe_matrices(probe)
    A, masses = beam_matrices(probe.cantilever, probe.m_joint, probe.m_base)
    freqs, _ = mode_shares(K, M, out)
    np.testing.assert_allclose(freqs, free_modes(A, masses) / (2 * math.pi), rtol=1e-10)


@pytest.mark.parametrize("white", [float("inf"), float("nan"), -1e-27])
def test_a_white_floor_that_is_no_finite_psd_is_refused(white, capsys, tmp_path):
    """``afmforce calibrate virtual --white inf`` (or 1e400) wrote a spectrum of infinite bins (audit);
    the library and the command refuse it, and nothing is written."""
    from afmforce.cli.main import main
    from afmforce.dynamics.parts import SpringProbe
    from afmforce.dynamics.thermal import thermal_spectrum
    from afmforce.errors import ParameterError

    with pytest.raises(ParameterError, match=r"^white must be zero or positive \[m\^2/Hz\]"):
        thermal_spectrum(SpringProbe(quality_factor=30.0), white=white)
    out = tmp_path / "v.psd"
    assert main(["calibrate", "virtual", "--white", str(white), "--spectrum", str(out)]) == 2
    assert "--white must be a finite, non-negative PSD" in capsys.readouterr().err
    assert not out.exists()
