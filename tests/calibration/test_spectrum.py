"""Thermal files: afmforce's own spectrum format and JPK thermal noise data (.tnd) (issue 34).

Every thermal file in tests/data (by glob) is read, its header checked against an independent
parse (numpy.loadtxt and the header text), and fitted: the spring constant agrees with the
vendor's own calibration stored in the file within 5 %.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from afmforce.calibration import ThermalSpectrum, fit_thermal, read_spectrum, write_spectrum
from afmforce.calibration.sader import sader_rectangular
from afmforce.errors import FileFormatError, MissingMetadataError, ParameterError

DATA = Path(__file__).resolve().parents[1] / "data"
THERMAL = sorted(DATA.glob("*.tnd")) + sorted(DATA.glob("*.psd"))
JPK = DATA / "jpk-tnd_PFQNM-water_thermal-noise_0-80kHz.tnd"


def test_there_are_thermal_files():
    assert JPK in THERMAL


@pytest.mark.parametrize("path", THERMAL, ids=lambda p: p.name)
def test_every_thermal_file_matches_its_vendor_calibration(path):
    sp = read_spectrum(path)
    rows = [line.replace(",", " ").split() for line in path.read_text(encoding="utf-8").splitlines()
            if line[:1].isdigit()]                                  # the data rows, parsed apart
    np.testing.assert_array_equal(sp.frequency, [float(r[0]) for r in rows])
    r = fit_thermal(sp.frequency, sp.displacement_psd(), temperature=sp.temperature, correction=sp.correction)
    assert r.spring_constant == pytest.approx(sp.vendor["spring_constant"], rel=0.05)


def test_jpk_header_read_independently():
    """The header as printed in the file: sensitivity 11.0399 nm/V, spring constant 45.8785 mN/m,
    f 24.25 kHz, Q 2.050, 25.0 C, Water, correction factor 0.9000, angle 10 deg, 54 x 4.5 um."""
    sp = read_spectrum(JPK)
    head = JPK.read_text(encoding="utf-8").splitlines()[:25]
    assert "# sensitivity: 11.0399 nm/V" in head and "# spring constant: 45.8785 mN/m" in head
    assert sp.unit == "V^2/Hz" and sp.sensitivity == pytest.approx(11.0399e-9)
    assert sp.vendor["spring_constant"] == pytest.approx(45.8785e-3)
    assert sp.vendor["resonance_frequency"] == pytest.approx(24.25e3)
    assert sp.vendor["quality_factor"] == pytest.approx(2.05)
    assert sp.temperature == pytest.approx(298.15) and sp.medium == "water"
    assert sp.correction == pytest.approx(0.9) and sp.tilt == pytest.approx(math.radians(10))
    assert (sp.vendor["length"], sp.vendor["width"]) == pytest.approx((54e-6, 4.5e-6))
    cols = np.loadtxt(JPK, comments="#")
    np.testing.assert_array_equal(sp.psd, cols[:, 2])                       # the 'average' column
    np.testing.assert_allclose(sp.displacement_psd(), cols[:, 2] * 11.0399e-9**2)


def test_jpk_vendor_numbers_are_equipartition_of_their_fit():
    """JPK's k is chi kB T / (A^2 pi f Q / 2 s^2) of its own fit parameters (A 92.12 uV/sqrt(Hz)):
    our reading of the file's convention (0.9, 298.15 K, the InvOLS) reproduces it to 0.1 %."""
    a2 = (92.12e-6) ** 2
    area = a2 * math.pi * 24.25e3 * 2.05 / 2 * 11.0399e-9**2
    assert 0.9 * 1.380649e-23 * 298.15 / area == pytest.approx(45.8785e-3, rel=1e-3)


def test_jpk_fit_and_sader_cross_check():
    sp = read_spectrum(JPK)
    r = fit_thermal(sp.frequency, sp.displacement_psd(), temperature=sp.temperature, correction=sp.correction)
    assert r.resonance_frequency == pytest.approx(24.25e3, rel=0.06)
    assert r.quality_factor == pytest.approx(2.05, rel=0.06)
    # in water the resonance is no exact harmonic oscillator: k moves with the window by ~4 %
    # (43.4-46.1 mN/m), which the interval includes; the vendor's k lies within it
    assert 0.02 < r.spring_constant_se_window / r.spring_constant < 0.06
    assert abs(r.spring_constant - 45.8785e-3) < 2 * r.spring_constant_se
    sader = sader_rectangular(54e-6, 4.5e-6, r.resonance_frequency, r.quality_factor, "water")
    assert sader.spring_constant == pytest.approx(45.8785e-3, rel=0.05)


def test_own_format_round_trip(tmp_path):
    f = np.linspace(10, 1e4, 50)
    sp = ThermalSpectrum(f, 1e-26 * (1 + f / 1e4), unit="m^2/Hz", temperature=296.5, medium="air",
                         correction=0.95, tilt=0.1, averages=32, vendor={"spring_constant": 0.1}, source="test")
    path = write_spectrum(tmp_path / "s.psd", sp)
    back = read_spectrum(path)
    np.testing.assert_array_equal(back.frequency, f)
    np.testing.assert_allclose(back.psd, sp.psd, rtol=1e-9)
    assert (back.temperature, back.medium, back.correction, back.tilt, back.averages) == (296.5, "air", 0.95, 0.1, 32)
    assert back.vendor == {"spring_constant": 0.1} and back.unit == "m^2/Hz"
    assert [p.name for p in tmp_path.iterdir()] == ["s.psd"]               # atomic: nothing left behind


def test_volts_spectrum_needs_a_sensitivity():
    sp = ThermalSpectrum(np.arange(1.0, 11.0), np.ones(10), unit="V^2/Hz")
    with pytest.raises(MissingMetadataError, match="sensitivity"):
        sp.displacement_psd()
    assert sp.displacement_psd(2e-8)[0] == pytest.approx(4e-16)


def test_refusals(tmp_path):
    bad = tmp_path / "x.psd"
    bad.write_text("hello\n1,2\n")                       # one row: no spectrum
    with pytest.raises(FileFormatError, match="not a thermal spectrum"):
        read_spectrum(bad)
    bad.write_text("# afmforce thermal spectrum 1\nfrequency [Hz],psd [m^2/Hz]\n1;2\n")
    with pytest.raises(FileFormatError, match="line 3"):
        read_spectrum(bad)
    with pytest.raises(ParameterError, match="unit"):
        ThermalSpectrum(np.arange(10.0), np.ones(10), unit="W")


def test_tnd_variants(tmp_path):
    """Two columns in m²/Hz, the temperature in K, a Greek mu, an unreadable Q: read as written."""
    text = ("# thermal noise data\n# sensitivity: 50.0 μm/V\n# spring constant: 0.2 N/m\n# parameter.Q: n/a\n"
            "# settings.temperature: 300 K\n# Channels: 'Frequency' 'average' \n# Units: 'Hz' 'm²/Hz' \n"
            + "".join(f"{f} 1e-26\n" for f in range(1, 20)))
    path = tmp_path / "v.tnd"
    path.write_text(text, encoding="utf-8")
    sp = read_spectrum(path)
    assert sp.unit == "m^2/Hz" and sp.temperature == 300.0 and sp.sensitivity == pytest.approx(50e-6)
    assert "quality_factor" not in sp.vendor and sp.psd[0] == 1e-26
    path.write_text(text.replace("5 1e-26", "5 oops"), encoding="utf-8")
    with pytest.raises(FileFormatError, match="line"):
        read_spectrum(path)


def test_plain_text_spectra(tmp_path):
    """Two columns with the unit in the header (a power or an amplitude spectral density, which is
    squared), or given; a header without a unit is refused, naming the quantity."""
    rows = "".join(f"{f}\t{2e-4}\n" for f in range(1, 20))
    a = tmp_path / "a.txt"
    a.write_text("Frequency (Hz)\tAmplitude (V/sqrt(Hz))\n" + rows)
    sp = read_spectrum(a)
    assert sp.unit == "V^2/Hz" and sp.psd[0] == pytest.approx(4e-8) and sp.frequency[-1] == 19.0
    b = tmp_path / "b.csv"
    b.write_text("f,psd [m^2/Hz]\n" + rows.replace("\t", ","))
    assert read_spectrum(b).unit == "m^2/Hz" and read_spectrum(b).psd[0] == 2e-4
    c = tmp_path / "c.txt"
    c.write_text("frequency spectrum\n" + rows)
    with pytest.raises(FileFormatError, match="psd_unit"):
        read_spectrum(c)
    assert read_spectrum(c, unit="m^2/Hz").unit == "m^2/Hz"
    with pytest.raises(ParameterError, match="psd_unit"):
        read_spectrum(c, unit="W")
