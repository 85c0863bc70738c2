"""A thermal spectrum in the wrong unit gives no spring constant (review of 2026-11-29).

Equipartition, k = chi kB T / <z^2>, turns a wrong unit or InvOLS into a k off by its square: the
virtual lever's spectrum (k = 0.2 N/m) read as m^2/Hz after a factor 1e10 (a spectrum in V^2/Hz,
~100 nm/V missing) gave k = 1.6e-11 N/m, after a factor 1e-8 k = 1.6e7 N/m, both printed as results
with a 2 % error. Reference: the linear model's exact spectrum (calibration/virtual.py) and the
valid range of a spring constant declared once (``QUANTITIES["spring_constant"]``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce._fields import QUANTITIES
from afmforce.calibration import fit_thermal
from afmforce.calibration.virtual import linear_thermal_psd, sample_spectrum
from afmforce.cli.main import main
from afmforce.errors import AnalysisError

K, F0, Q = 0.2, 20e3, 50.0


def _spectrum(seed=0):
    m = K / (2 * math.pi * F0) ** 2
    f = np.linspace(30.0, 60e3, 2048)
    psd = sample_spectrum(linear_thermal_psd(f, K, m, m * 2 * math.pi * F0 / Q, [1.0], 295.0), 64,
                          np.random.default_rng(seed), white=1e-27)
    return f, psd


def test_the_right_unit_gives_the_lever_within_its_error():
    f, psd = _spectrum()
    r = fit_thermal(f, psd, correction=1.0)
    assert abs(r.spring_constant - K) < 3 * r.spring_constant_se


@pytest.mark.parametrize("scale", [1e10, 1e-8])
def test_a_wrong_unit_is_refused_not_reported(scale):
    f, psd = _spectrum()
    k_would_be = K / scale                     # equipartition: k scales as 1/<z^2>
    assert not QUANTITIES["spring_constant"].contains(k_would_be)
    with pytest.raises(AnalysisError, match="not a spring constant") as exc:
        fit_thermal(f, psd * scale, correction=1.0)
    said = float(str(exc.value).split("gives k = ")[1].split(" N/m")[0])
    assert said == pytest.approx(k_would_be, rel=0.1)      # the k it would have been, named


def test_the_cli_says_it_in_one_line(tmp_path, capsys):
    f, psd = _spectrum()
    p = tmp_path / "volts_as_metres.txt"
    np.savetxt(p, np.c_[f, psd * 1e10], header="frequency [Hz]\tpsd [m^2/Hz]")
    assert main(["calibrate", "thermal", str(p)]) != 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error:") and "--psd-unit" in err[0], err
