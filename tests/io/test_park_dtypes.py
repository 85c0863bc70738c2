"""Park spectroscopy TIFFs whose data are int16, int32 or float32 numbers scaled by each channel's gain and
offset, and Park force maps (volume images): files written here in Park's layout (tests/io/_park_build.py,
the fields as Park's own reader, pspylib's ``TiffReader``, and atomicJ's Park reader name them: channel gain
at byte 80 of each 96-byte channel record, channel offsets at 808, volume flag at 804, points per x and the
grid size at 936, data type at 1108: 0 int16, 1 int32, 2 float32), every number chosen here. The value of a
sample is ``number x gain + offset`` in the channel's unit (the real ``ForceCurve_009.tiff`` holds float32
with gain 1 and offset 0, so it cannot tell the order of the two; an offset shifts a whole channel, which
no step of the analysis sees: the deflection's baseline and the contact point are found from the data)."""

from __future__ import annotations

import numpy as np
import pytest

from afmforce.io import load

from _park_build import CHANNELS, N_APP, N_RET, _arrays, grid_xy, stored, write_park  # noqa: E402

#: per channel (Vertical (A-B) [V], Force [nN], Z Scan [um], Time Stamp [usec]): gains and offsets of each type
SCALES = {
    "i2": ((2e-4, 1e-3, 2e-5, 4.0), (0.1, 0.0, -0.05, 100.0)),
    "i4": ((1e-7, 1e-6, 1e-9, 0.01), (-0.2, 0.5, 0.03, -50.0)),
    "f4": ((2.0, 0.5, 0.25, 8.0), (0.3, -1.0, -0.01, 20.0)),
}


def _expected(p: int, dtype: str):
    """What the reader must give for spectrum ``p``: the stored numbers x gain + offset, in SI."""
    gains, offsets = SCALES[dtype]
    cols = []
    for a, g, o in zip(_arrays(p)[0], gains, offsets):
        cols.append(stored(a, g, o, dtype).astype(float) * g + o)
    keep = np.r_[np.arange(N_APP), 32 + np.arange(N_RET)]   # 20 + 17 real samples of each 32
    return [c[keep] for c in cols]


@pytest.mark.parametrize("dtype", ["i2", "i4", "f4"])
def test_each_data_type_is_scaled_by_its_channels_gain_and_offset(tmp_path, dtype):
    gains, offsets = SCALES[dtype]
    curves = load(write_park(tmp_path / f"{dtype}.tiff", dtype=dtype, gains=gains, offsets=offsets))
    assert len(curves) == 2
    for p, c in enumerate(curves):
        volts, force, z_um, t_us = _expected(p, dtype)
        assert (int(c.approach.sum()), int(c.retract.sum())) == (N_APP, N_RET)   # the padding is dropped
        np.testing.assert_allclose(c.deflection_signal, volts, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(c.piezo_nominal, -1e-6 * z_um, rtol=1e-12, atol=1e-21)
        np.testing.assert_allclose(c.time, 1e-6 * (t_us - t_us[0]), rtol=1e-12, atol=1e-18)
        # the scaled values are the arrays written, to the type's resolution (half a count x gain)
        v_app, v_ret, z_app, z_ret = _arrays(p)[1][:4]
        np.testing.assert_allclose(c.deflection_signal, np.r_[v_app, v_ret], atol=gains[0] / 2 + 1e-6)
        np.testing.assert_allclose(c.piezo_nominal, -1e-6 * np.r_[z_app, z_ret], atol=1e-6 * (gains[2] / 2 + 1e-7))
        # the file's Force channel (k / sensitivity x volts, stored the same way) still agrees: no note
        assert c.metadata["park_force_ratio"] == pytest.approx(1.0, abs=2e-3)
        assert "spring_constant_note" not in c.metadata


def test_a_version1_header_with_int16_data_is_read(tmp_path):
    """A version-1 header (936 bytes) has no data type field: 2 bytes a sample are int16 (the file was refused
    as damaged: 4-byte float32 assumed)."""
    gains, offsets = SCALES["i2"]
    path = write_park(tmp_path / "v1.tiff", points=1, version=1, dtype="i2", gains=gains, offsets=offsets)
    c = load(path, meta_override={"spring_constant": 0.35, "sensitivity": 40e-9})[0]
    volts, _, z_um, _ = _expected(0, "i2")
    np.testing.assert_allclose(c.deflection_signal, volts, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(c.piezo_nominal, -1e-6 * z_um, rtol=1e-12, atol=1e-21)


@pytest.mark.parametrize("serpentine", [False, True])
def test_a_park_force_map_gives_each_spectrum_its_grid_cell(tmp_path, serpentine):
    """A 3 x 2 volume image over 6 x 4 um: map_nx 3, map_ny 2, map_width/height 6/4 um, and each spectrum's
    cell found from its position in the point table (rows both ways: back and forth when serpentine)."""
    volume = (3, 2, 6.0, 4.0, serpentine)
    curves = load(write_park(tmp_path / "map.tiff", points=6, volume=volume, dtype="i2",
                             gains=SCALES["i2"][0], offsets=SCALES["i2"][1]))
    assert len(curves) == 6
    cells = set()
    for p, c in enumerate(curves):
        md = c.metadata
        x_um, y_um = grid_xy(p, volume)
        assert (md["position_x"], md["position_y"]) == (pytest.approx(x_um * 1e-6), pytest.approx(y_um * 1e-6))
        assert (md["map_nx"], md["map_ny"]) == (3, 2)
        assert (md["map_width"], md["map_height"]) == (pytest.approx(6e-6), pytest.approx(4e-6))
        assert md["map_x"] == round((x_um - 0.5) / 3.0) and md["map_y"] == round((y_um + 1.0) / 4.0)
        cells.add((md["map_x"], md["map_y"]))
    assert cells == {(i, j) for i in range(3) for j in range(2)}


def test_spectra_at_free_points_carry_no_grid(tmp_path):
    md = load(write_park(tmp_path / "free.tiff"))[0].metadata
    assert not any(key.startswith("map_") for key in md)


def test_a_volume_whose_points_make_no_grid_keeps_positions_only(tmp_path):
    """6 spectra said to hold 4 points per x: no grid (no cells made up), each spectrum's position kept."""
    import struct

    path = write_park(tmp_path / "map.tiff", points=6, volume=(3, 2, 6.0, 4.0, False))
    data = bytearray(path.read_bytes())
    at = data.index("Vertical (A-B)".encode("utf-16-le"))   # the spectroscopy header's start
    assert struct.unpack_from("<i", data, at + 936)[0] == 3
    struct.pack_into("<i", data, at + 936, 4)
    path.write_bytes(bytes(data))
    curves = load(path)
    assert len(curves) == 6 and not any(k.startswith("map_") for k in curves[0].metadata)
    assert curves[5].metadata["position_x"] == pytest.approx(grid_xy(5, (3, 2, 6.0, 4.0, False))[0] * 1e-6)


def test_the_channels_are_those_written():
    assert [c[:2] for c in CHANNELS] == [("Vertical (A-B)", "V"), ("Force", "nN"), ("Z Scan", "um"),
                                         ("Time Stamp", "usec")]
