"""Park Systems spectroscopy TIFF (``park-tiff``): a synthetic file written here in Park's layout from
known arrays (every number chosen here, so every number read back is checked exactly), and the real
public file ``ForceCurve_009.tiff`` (nanoAFMr, AGPL: not in the repository; skipped without
``shared/data/real/park-xe_nanoAFMr_ForceCurve_009.tiff``) checked against its own header and Force
channel."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from afmforce.errors import FileFormatError, MissingMetadataError
from afmforce.io import find_format, in_folder, is_supported, load
from afmforce.io.curve import SEGMENT_APPROACH, SEGMENT_RETRACT

from realdata import real_file  # noqa: E402  (tests/ is on sys.path: tests/conftest.py)
from _park_build import DT_US, K, N_APP, N_RET, SENS_V_PER_UM, SPEED_UM_S, _arrays, write_park  # noqa: E402 (tests/io on sys.path)

REAL = "park-xe_nanoAFMr_ForceCurve_009.tiff"


def test_synthetic_park_file_comes_back_exactly(tmp_path):
    path = write_park(tmp_path / "fc.tiff")
    assert find_format(path).identifier == "park-tiff" and in_folder(path)
    curves = load(path)
    assert len(curves) == 2
    for p, c in enumerate(curves):
        v_app, v_ret, z_app, z_ret, t_app, t_ret = _arrays(p)[1]
        f32 = lambda a: a.astype("<f4").astype(float)   # noqa: E731  (the file stores float32)
        np.testing.assert_array_equal(c.segment, np.r_[np.full(N_APP, SEGMENT_APPROACH), np.full(N_RET, SEGMENT_RETRACT)])
        np.testing.assert_array_equal(c.deflection_signal, np.r_[f32(v_app), f32(v_ret)])
        # z grows towards the sample: Park's Z Scan [um] negated, in m
        np.testing.assert_allclose(c.piezo_nominal, -1e-6 * np.r_[f32(z_app), f32(z_ret)], rtol=1e-15)
        np.testing.assert_allclose(c.time, 1e-6 * (np.r_[f32(t_app), f32(t_ret)] - 100.0), rtol=1e-12, atol=1e-15)
        assert c.deflection_unit == "V" and c.piezo_measured is None
        md = c.metadata
        assert md["spring_constant"] == K and md["sensitivity"] == pytest.approx(1e-6 / SENS_V_PER_UM, rel=1e-15)
        assert md["velocity"] == md["retract_velocity"] == pytest.approx(SPEED_UM_S * 1e-6, rel=1e-7)
        assert md["sample_rate"] == pytest.approx(1e6 / DT_US, rel=1e-6)
        assert (md["position_x"], md["position_y"]) == (pytest.approx((1.0 + p) * 1e-6), pytest.approx(2e-6))
        assert md["curve_index"] == p and md["reader"] == "park-tiff"
        # the Force channel written as k / sensitivity x V agrees: no note
        assert md["park_force_ratio"] == pytest.approx(1.0, abs=1e-6) and "spring_constant_note" not in md


def test_force_channel_off_the_header_calibration_is_said(tmp_path):
    """A Force channel 8 % above k x InvOLS x V (as the real file's) is said in a note; the header's
    calibration is used."""
    path = write_park(tmp_path / "fc.tiff", points=1, k=K / 1.08)
    md = load(path)[0].metadata
    assert md["spring_constant"] == pytest.approx(K / 1.08) and md["park_force_ratio"] == pytest.approx(1.08, rel=1e-6)
    assert "8 % above" in md["spring_constant_note"]


def test_the_intensity_factor_divides_the_deflection_its_sensitivity_calibrates(tmp_path):
    """The image header's intensityFactor (A+B)/3 at byte 424: Park's Force channel is k x InvOLS x (A-B) / it.
    A file written so (header k 0.8 x K, intensity 0.8, Force channel K / S x V) comes back with the InvOLS
    1e-6 / (S x 0.8) and forces equal to its Force channel (no note); the same Force channel beside an
    intensity factor the header's k does not carry is said, naming the factor."""
    md = load(write_park(tmp_path / "if.tiff", points=1, k=K * 0.8, intensity=0.8))[0].metadata
    assert md["park_intensity_factor"] == 0.8
    assert md["sensitivity"] == pytest.approx(1e-6 / (SENS_V_PER_UM * 0.8), rel=1e-15)
    assert md["park_force_ratio"] == pytest.approx(1.0, abs=1e-6) and "spring_constant_note" not in md
    md = load(write_park(tmp_path / "off.tiff", points=1, intensity=0.8))[0].metadata
    assert md["park_force_ratio"] == pytest.approx(0.8, rel=1e-6)
    assert "20 % below" in md["spring_constant_note"] and "intensity factor 0.8" in md["spring_constant_note"]
    # the note reaches the user: `afmforce analyze` lists it among the curve's warnings
    import io
    import json
    from contextlib import redirect_stdout

    from afmforce.cli.main import main

    out = io.StringIO()
    with redirect_stdout(out):
        assert main(["analyze", str(tmp_path / "off.tiff"), "--json"]) == 0
    (res,) = json.loads(out.getvalue())["results"].values()
    assert any("20 % below" in w and "intensity factor 0.8" in w for w in res["warnings"])
    # a sensitivity the user gives is the one used, as given (the raw A-B volts' InvOLS)
    md = load(tmp_path / "if.tiff", meta_override={"sensitivity": 50e-9})[0].metadata
    assert md["sensitivity"] == 50e-9


def test_version1_header_without_calibration_names_the_flags(tmp_path):
    from afmforce.io import require_metadata

    c = load(write_park(tmp_path / "v1.tiff", points=1, version=1))[0]
    assert "spring_constant" not in c.metadata and "sensitivity" not in c.metadata
    assert c.metadata["spring_constant_note"] == ("this Park TIFF's spectroscopy header stores no spring constant "
                                                  "and no sensitivity (a version-1 header: no calibration fields): "
                                                  "give `spring_constant` and `sensitivity`")
    with pytest.raises(MissingMetadataError, match="`spring_constant` and `sensitivity`"):
        require_metadata(c)
    c = load(tmp_path / "v1.tiff", meta_override={"spring_constant": 0.2, "sensitivity": 50e-9})[0]
    assert c.metadata["spring_constant"] == 0.2 and c.metadata["sensitivity"] == 50e-9


@pytest.mark.parametrize("kind, word", [(0, "an image"), (1, "a line profile")])
def test_park_image_is_refused_in_one_line(tmp_path, kind, word):
    path = write_park(tmp_path / "topo.tif", kind=kind)
    with pytest.raises(FileFormatError) as err:
        load(path)
    msg = str(err.value)
    assert "\n" not in msg and f"holds {word} (Topography, 1 x 1 px)" in msg and "not a force curve" in msg
    assert is_supported(path) and not in_folder(path)     # a folder scan skips it


def test_truncated_and_foreign_tiffs_are_refused_in_one_line(tmp_path):
    path = write_park(tmp_path / "fc.tiff", points=1)
    cut = tmp_path / "cut.tiff"
    cut.write_bytes(path.read_bytes()[:-100])
    with pytest.raises(FileFormatError, match="truncated"):
        load(cut)
    photo = tmp_path / "photo.tiff"
    photo.write_bytes(b"II*\x00" + struct.pack("<I", 8) + struct.pack("<H", 1) + struct.pack("<HHII", 256, 4, 1, 1)
                      + b"\0" * 4)
    with pytest.raises(FileFormatError) as err:
        load(photo)
    assert "a TIFF image" in str(err.value) and "not a force curve" in str(err.value) and not in_folder(photo)


def test_real_park_force_curves_match_their_header_and_force_channel():
    """ForceCurve_009.tiff (XE series, SmartScan, NCHR lever): 7 spectra of 1024 samples per channel,
    Vertical (A-B) [V], Force [nN], Z Scan [um], Z Detector [um, not moving], Time Stamp [usec]; header
    k = 42 N/m, sensitivity 59.988 V/um (16.67 nm/V), speed 0.02 um/s. Each run holds 42-46 real samples
    (+1 end sample), the rest of its 512 repeat the last one."""
    curves = load(real_file(REAL))
    assert len(curves) == 7
    assert [int(c.approach.sum()) for c in curves] == [47, 47, 43, 46, 45, 45, 47]
    assert [int(c.retract.sum()) for c in curves] == [47, 47, 43, 46, 45, 45, 47]
    for c in curves:
        md = c.metadata
        assert md["spring_constant"] == 42.0
        # the speed the header states against the ramp the samples trace: 6.25 nm per 313.34 ms step
        z, t = c.piezo_nominal[c.approach], c.time[c.approach]
        assert md["velocity"] == pytest.approx(2e-8, rel=1e-7)
        assert np.median(np.diff(z) / np.diff(t)) == pytest.approx(2e-8, rel=5e-3)
        assert md["sample_rate"] == pytest.approx(1 / 0.31334, rel=1e-6)
        # 0.26-0.29 um ramp; the deflection rises in contact (positive up) to 1.9-2.1 V above its baseline
        assert 0.25e-6 < np.ptp(z) < 0.30e-6
        d = c.deflection_signal[c.approach]
        assert 1.8 < d.max() - np.median(d[:10]) < 2.2
        # Park's own Force channel is 1.0826050 x k x (header's InvOLS) x V: the inverse of the image header's
        # intensityFactor (A+B)/3 = 0.9236979 at byte 424, by which Park divides the A-B volts its sensitivity
        # calibrates; the InvOLS used is the header's over it (16.67 -> 18.047 nm/V) and the forces are Park's
        assert md["park_intensity_factor"] == pytest.approx(0.9236979, rel=1e-7)
        assert md["sensitivity"] == pytest.approx(16.67e-9 / 0.9236979236205419, rel=1e-9)
        assert md["park_force_ratio"] == pytest.approx(1.0, abs=1e-7) and "spring_constant_note" not in md


def test_the_example_in_tests_data_is_the_builders_file(tmp_path):
    """``tests/data/park-tiff_synthetic_2-spectra.tiff`` is ``make_park_example.py``'s output byte for byte."""
    from realdata import DATA

    assert (DATA / "park-tiff_synthetic_2-spectra.tiff").read_bytes() == write_park(tmp_path / "x.tiff").read_bytes()
