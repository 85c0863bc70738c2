"""A NanoScope force volume whose scan list describes a finer topography image than its grid of curves
(corpus5): JSotres/FSAS' NanoScope 8.15 ``Test.003`` (MultiMode, mica in air, BSD-2-Clause) says
``Samps/line: 64`` and ``Lines: 64`` in its ``\\*Ciao scan list`` (its 64 x 64 height image) but holds
16 x 16 curves, the grid of the force volume's own Deflection Error image after them (``\\*Ciao image
list``, ``Samps/line: 16``, ``Number of lines: 16``). afmforce took the grid from the scan list (4096
curves), found 256 curves of 2-byte or 128 of 4-byte samples both fitting the channel's 524288 bytes
and refused the file ("the sample width, hence the curves, cannot be told; damaged file").

The trimmed file (tests/data/make_nanoscope_fv_image_grid_trimmed.py: 4 corner curves as a 2 x 2
grid, the 64 x 64 scan list and height image kept) runs everywhere; the whole file where
``AFMFORCE_REAL_DATA`` holds it. Expected values: the header's text and the int16 samples decoded here
with numpy (value x 0.000375 V/LSB, ``\\@4:Z scale``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from afmforce.io import find_format, load
from realdata import real_file  # noqa: E402  (tests/ is on sys.path: tests/conftest.py)

DATA = Path(__file__).resolve().parents[1] / "data"
TRIMMED = DATA / "bruker-nanoscope_v8.15_force-volume_64x64-scan_2x2-curves_trimmed.000"
VLSB = 0.000375        # [V/LSB] \@4:Z scale of the Deflection Error force list
CURVES = 49152         # [bytes] \Data offset of the force data
PER = 1024             # samples per curve: \Samps/line: 512 512
SCAN_RATE = 5.58036    # [Hz] \Scan rate of the force list: one ramp cycle of 1024 samples
VELOCITY = 274.894     # [V/s] \Forward vel. and \Reverse vel.: 512 samples over 24.63054 V of ramp
RAMP = 24.63054 * 12.18e-9  # [m] \@4:Ramp size [V] x \@Sens. Zsens [nm/V] = 300 nm (FSAS' Test.txt)


def _check(curves, nx: int, raw: np.ndarray) -> None:
    assert len(curves) == nx * nx == raw.shape[0]
    for i, (c, row) in enumerate(zip(curves, raw)):
        md = c.metadata
        assert md["spring_constant"] == 0.999 and md["sensitivity"] == pytest.approx(41.14015e-9)
        assert (md["map_x"], md["map_y"], md["map_nx"], md["map_ny"]) == (i % nx, i // nx, nx, nx)
        assert md["position_x"] == pytest.approx((i % nx + 0.5) * 2e-6 / nx)  # \Scan Size: 2000 nm
        assert md["position_y"] == pytest.approx((i // nx + 0.5) * 2e-6 / nx)
        assert md["sample_rate"] == pytest.approx(512 * VELOCITY / 24.63054, rel=1e-9)
        assert md["sample_rate"] == pytest.approx(PER * SCAN_RATE, rel=1e-5)  # the scan rate agrees
        # -32768 (the int16 minimum) marks a slot the controller did not record (curve 223's farthest
        # approach sample): the reader drops it and says so
        app, ret = row[:512][::-1], row[512:]
        app, ret = app[app != -32768], ret[ret != -32768]
        assert (c.approach.sum(), c.retract.sum()) == (app.size, ret.size)
        assert md.get("unrecorded_samples", 0) == 1024 - app.size - ret.size
        assert np.ptp(c.piezo_nominal) == pytest.approx(RAMP, rel=3e-3)
        np.testing.assert_allclose(c.deflection_signal[c.approach], app * VLSB, rtol=1e-12)
        np.testing.assert_allclose(c.deflection_signal[c.retract], ret * VLSB, rtol=1e-12)


def test_the_grid_is_the_force_volume_images_not_the_scan_lists():
    head = TRIMMED.read_bytes()[:40960].decode("latin-1")
    scan = head[head.index("\\*Ciao scan list"):head.index("\\*Ciao force list")]
    assert "\\Samps/line: 64\r" in scan and "\\Lines: 64\r" in scan  # the quirk is in the file
    assert find_format(TRIMMED).identifier == "bruker-nanoscope"
    raw = np.frombuffer(TRIMMED.read_bytes(), "<i2", count=4 * PER, offset=CURVES).reshape(4, PER)
    _check(load(TRIMMED), 2, raw)


def test_the_whole_real_file_holds_16_x_16_curves():
    path = real_file("bruker-nanoscope_v8.15_FSAS_force-volume_Test.003")
    raw = np.frombuffer(path.read_bytes(), "<i2", count=256 * PER, offset=CURVES).reshape(256, PER)
    curves = load(path)
    _check(curves, 16, raw)
    assert [c.metadata.get("unrecorded_samples", 0) for c in curves].count(1) == 1  # curve 223's
    # every curve is a hard contact on mica: the approach rises by about the trigger threshold, 0.5 V relative
    rise = [np.ptp(c.deflection_signal[c.approach]) for c in curves]
    assert 0.5 < min(rise) and max(rise) < 2.5
