"""Bruker NanoScope binary files of issue 32: a v9.2 force volume whose 4-byte samples hold the
16-bit counts shifted by 8 bits (header: ``Bytes/pixel: 2``), a stiff lever whose Height Sensor
list holds a stale spring constant, image files refused by name, and 4-byte data beyond the ADC.

Expected values are the header's, read independently (shared/data/real/README.md, rows of
2026-11-28), and the raw bytes decoded here with numpy. The trimmed 2 x 2 force volume
(tests/data/make_bruker_force_volume_trimmed.py) runs without the shared folder."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from afmforce.errors import FileFormatError
from afmforce.io import find_format, load
from realdata import real_file  # noqa: E402  (tests/ is on sys.path: tests/conftest.py)
from test_nanoscope import _write  # noqa: E402  (tests/io is the rootdir of this module's imports)

DATA = Path(__file__).resolve().parents[1] / "data"
TRIMMED = DATA / "bruker-nanoscope_force-volume_2x2_trimmed.spm"
VLSB = 0.000375  # [V/LSB] of the deflection channel (\@4:Z scale)
ADC = 2**15 * VLSB  # the 16-bit ADC's range [V]
HEADER = 80960  # [bytes]


def _check_force_volume(curves, n: int, nx: int, width: float) -> None:
    """Header values (README: k 0.1332 N/m, DeflSens 27.39 nm/V, Zsens 13.203 nm/V, ramp 2.0 um,
    1024 + 1024 points at 1.01725 Hz = 2083 Hz, trigger 1.2 V relative) and grid positions."""
    assert len(curves) == n
    for i, c in enumerate(curves):
        md = c.metadata
        assert md["spring_constant"] == 0.1332 and md["sensitivity"] == pytest.approx(27.39e-9)
        assert md["radius"] == pytest.approx(20e-9)  # \Tip Radius: 20 [nm]
        assert (c.approach.sum(), c.retract.sum()) == (1024, 1024)
        ramp = 151.4807 * 13.203e-9  # \@4:Ramp Size [V] x Zsens [nm/V]
        assert ramp == pytest.approx(2.0e-6, rel=1e-3)
        assert np.ptp(c.piezo_nominal) == pytest.approx(ramp, rel=2e-3)
        assert md["velocity"] == pytest.approx(2 * ramp * 1.01725, rel=1e-4)  # the ramp, twice per cycle
        assert md["sample_rate"] == pytest.approx(2083.33, rel=1e-4)  # Effective BW
        v = c.deflection_signal
        assert np.abs(v).max() < ADC and md["adc_range"] == pytest.approx(ADC)  # within the ADC's range
        a = v[c.approach]
        assert a.max() - np.median(a[:200]) == pytest.approx(1.2, rel=0.07)  # relative trigger 1.2 V (+ overshoot)
        assert (md["map_x"], md["map_y"], md["map_nx"], md["map_ny"]) == (i % nx, i // nx, nx, nx)
        assert md["position_x"] == pytest.approx((i % nx + 0.5) * width / nx)
        assert md["position_y"] == pytest.approx((i // nx + 0.5) * width / nx)


def test_trimmed_force_volume_counts_shifted_back():
    """Four curves of the v9.2 force volume: int32 at offset 80960 / 256 x 0.000375 V/LSB."""
    assert find_format(TRIMMED).identifier == "bruker-nanoscope"
    curves = load(TRIMMED)
    _check_force_volume(curves, 4, 2, 2000e-9)
    raw = np.frombuffer(TRIMMED.read_bytes(), "<i4", count=4 * 2048, offset=HEADER).reshape(4, 2048)
    assert np.all((raw % 256 == 0) | (raw % 256 == 255))  # what the reader relies on
    for c, row in zip(curves, raw):
        volts = row / 256 * VLSB
        np.testing.assert_allclose(c.deflection_signal[c.approach], volts[:1024][::-1], rtol=1e-12)
        np.testing.assert_allclose(c.deflection_signal[c.retract], volts[1024:], rtol=1e-12)


def test_real_force_volume_16x16():
    path = real_file("bruker-nanoscope_force-volume_v9.2_Egel.spm")
    curves = load(path)
    _check_force_volume(curves, 256, 16, 2000e-9)
    a = curves[0].deflection_signal[curves[0].approach]
    assert a.max() - np.median(a[:200]) == pytest.approx(3190 * VLSB, rel=0.01)  # README: 3253 x 0.000375 V peak
    assert len({(c.metadata["map_x"], c.metadata["map_y"]) for c in curves}) == 256


def test_stiff_lever_spring_constant_is_the_deflection_lists():
    """TAP525 on sapphire: k = 90 N/m in the Deflection Error list, 0.0678 N/m (stale) in the Height
    Sensor list; DeflSens 72.77 nm/V, 512 + 512 points, ramp 16.72241 V x 35.88 nm/V = 600 nm at
    1.028 Hz."""
    c = load(DATA / "bruker-nanoscope_sapphire_TAP525.001")[0]
    md = c.metadata
    assert md["spring_constant"] == 90.0 and md["radius"] == pytest.approx(8e-9)
    assert md["sensitivity"] == pytest.approx(72.76923e-9)
    assert (c.approach.sum(), c.retract.sum()) == (512, 512)
    assert np.ptp(c.piezo_nominal) == pytest.approx(600e-9, rel=2e-3)
    assert md["velocity"] == pytest.approx(2 * 600e-9 * 1.02796, rel=2e-3)
    assert np.abs(c.deflection_signal).max() < ADC
    raw = np.frombuffer((DATA / "bruker-nanoscope_sapphire_TAP525.001").read_bytes(), "<i2", count=1024,
                        offset=40960) * VLSB
    np.testing.assert_allclose(c.deflection_signal[c.retract], raw[512:], rtol=1e-12)
    assert "map_x" not in md  # a single curve


def test_image_file_refused_by_name(tmp_path):
    """A NanoScope image (first line \\*File list) with a force-like ending: named, not 'unknown'."""
    header = ("\\*File list\r\n\\Version: 0x09200000\r\n\\Data length: 40960\r\n\\*Ciao image list\r\n"
              "\\Data offset: 40960\r\n\\Data length: 8\r\n\\@2:Image Data: S [Height] \"Height\"\r\n"
              "\\*File list end\r\n").encode("latin-1")
    for name in ("image.spm", "image.001", "image.pfc"):
        path = tmp_path / name
        path.write_bytes(header + b"\0" * (40960 - len(header)) + bytes(8))
        with pytest.raises(FileFormatError, match=r"NanoScope image file.*not a force file"):
            load(path)


def test_peakforce_capture_refused_by_name(tmp_path):
    """An image file that also holds force image lists (PeakForce capture: a curve per pixel): named as such."""
    header = ("\\*File list\r\n\\Version: 0x09200000\r\n\\*Ciao image list\r\n\\Data offset: 40960\r\n"
              "\\Data length: 8\r\n\\@2:Image Data: S [Height] \"Height\"\r\n\\*Ciao force image list\r\n"
              "\\Data offset: 40968\r\n\\Data length: 8\r\n\\@4:Image Data: S [DeflectionError] \"Deflection Error\"\r\n"
              "\\*File list end\r\n").encode("latin-1")
    path = tmp_path / "capture.pfc"
    path.write_bytes(header + b"\0" * (40960 - len(header)) + bytes(16))
    with pytest.raises(FileFormatError, match=r"PeakForce capture file.*does not read"):
        load(path)


def test_shifted_and_out_of_range_four_byte_samples(tmp_path):
    n = 100
    rng = np.random.default_rng(7)
    app, ret = rng.integers(-9000, 9000, n), rng.integers(-9000, 9000, n)
    shifted = tmp_path / "shifted.spm"
    _write(shifted, app * 256, ret * 256)  # 4-byte samples, low byte empty
    c = load(shifted)[0]
    np.testing.assert_allclose(c.deflection_signal[c.retract], ret * VLSB, rtol=1e-12)
    noisy = tmp_path / "noisy.spm"
    _write(noisy, app * 256 + 3, ret * 256)  # beyond the ADC and the low bits carry data
    with pytest.raises(FileFormatError, match="beyond the 16-bit ADC range"):
        load(noisy)
