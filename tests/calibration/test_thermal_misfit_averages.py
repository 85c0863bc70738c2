"""A spectrum the oscillator does not describe gives no spring constant, where the file states its
averages (review of 2026-11-29).

The fit reads the number of averaged periodograms from the scatter of the spectrum about its fit; a
misfit inflates the scatter and was taken for fewer averages, so a clipped peak (the virtual 0.2 N/m
lever's spectrum, 64 averages stated, cut at 1/3, 1/10 and 1/250 of its height) gave k = 0.275, 0.48
and 2.35 N/m with 2 % errors. Reference: the linear model's exact spectrum times chi-square(128)/128
per bin (calibration/virtual.py: 64 averages), whose area is the lever's (equipartition).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce.calibration import fit_thermal
from afmforce.calibration.virtual import linear_thermal_psd, sample_spectrum
from afmforce.cli.main import main
from afmforce.errors import AnalysisError

K, F0, Q, N = 0.2, 20e3, 50.0, 64


def _spectrum(seed):
    m = K / (2 * math.pi * F0) ** 2
    f = np.linspace(30.0, 60e3, 2048)
    return f, sample_spectrum(linear_thermal_psd(f, K, m, m * 2 * math.pi * F0 / Q, [1.0], 295.0), N,
                              np.random.default_rng(seed), white=1e-27)


@pytest.mark.parametrize("seed", range(6))
def test_described_spectra_with_their_averages_pass(seed):
    f, psd = _spectrum(seed)
    r = fit_thermal(f, psd, correction=1.0, averages=N)
    assert abs(r.spring_constant - K) < 3.5 * r.spring_constant_se


@pytest.mark.parametrize("cut", [3.0, 10.0, 250.0])
def test_a_clipped_peak_is_refused(cut):
    f, psd = _spectrum(0)
    clipped = np.minimum(psd, psd.max() / cut)
    unchecked = fit_thermal(f, clipped, correction=1.0)          # averages unknown: not caught
    assert abs(unchecked.spring_constant - K) > 5 * unchecked.spring_constant_se   # the wrong k
    with pytest.raises(AnalysisError, match="does not describe it"):
        fit_thermal(f, clipped, correction=1.0, averages=N)


def test_the_cli_reads_the_stated_averages_and_says_it_in_one_line(tmp_path, capsys):
    f, psd = _spectrum(1)
    p = tmp_path / "clipped.psd"
    rows = "\n".join(f"{a!r},{b!r}" for a, b in zip(f.tolist(), np.minimum(psd, psd.max() / 10).tolist()))
    p.write_text(f"# afmforce thermal spectrum 1\n# unit: m^2/Hz\n# averages: {N}\n# rows: {f.size}\n"
                 f"frequency [Hz],psd [m^2/Hz]\n{rows}\n")
    assert main(["calibrate", "thermal", str(p)]) != 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error:") and f"states {N}" in err[0], err
