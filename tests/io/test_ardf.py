"""Asylum Research ARDF force maps (:mod:`afmforce.io.ardf`).

No public ARDF file under an MIT-compatible licence could be found (PyFMlab_DyNaMo's repository
holds none; gnezd/ARDF_read's test map is absent from its snapshot and unlicensed), so the files
are built here byte by byte with ``struct`` (tests/io/_ardf_build.py, from the public description
of the layout, without afmforce) from real data: the curve and wave note of
``asylum-ibw_no-date_ForceMap.ibw`` (an MFP-3D curve exported from an ARDF force map: channels
Raw, Defl, ZSnsr in m). Expected values are read from the built file's bytes with ``re`` and
``struct``, or from the .ibw itself. A real ARDF placed in the shared data folder
(``AFMFORCE_REAL_DATA``, any ``*.ARDF``) is read and checked the same way (skipped without one).

The virtual AFM's soft map written as ARDF is analysed curve by curve: its modulus and
topography equal the known fields within their intervals.
"""

from __future__ import annotations

import re
import struct
import warnings
from pathlib import Path

import numpy as np
import pytest

from _ardf_build import SOURCE, build_ardf, source_curve, write_ardf  # noqa: E402 (tests/io on sys.path)
from afmforce.cli.main import main
from afmforce.errors import FileFormatError, MissingMetadataError
from afmforce.io import find_format, load
from afmforce.io.ardf import count_curves
from afmforce.io.map_curves import open_map
from realdata import SHARED  # noqa: E402

NX, NY = 4, 3


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    path = tmp_path_factory.mktemp("ardf") / "ForceMap0001.ARDF"
    return path, build_ardf(path, nx=NX, ny=NY)


def _note_of(path: Path) -> dict[str, str]:
    """The main note, found in the raw bytes: the first TEXT record (uint32, uint32 length, text)."""
    raw = path.read_bytes()
    at = raw.index(b"TEXT") - 8
    length = struct.unpack("<I", raw[at + 20:at + 24])[0]
    text = raw[at + 24:at + 24 + length].decode("latin-1")
    out: dict[str, str] = {}
    for key, value in re.findall(r"([^:\r\n]+):[ \t]*([^\r\n]*)", text):
        out.setdefault(key.strip(), value.strip())  # the first of a key repeated
    return out


def test_detected_and_read_with_the_notes_values(built):
    path, info = built
    note = _note_of(path)
    assert find_format(path).identifier == "asylum-ardf"
    curves = load(path)
    assert len(curves) == NX * NY == count_curves(path)
    for c in curves:
        md = c.metadata
        assert md["spring_constant"] == float(note["SpringConstant"]) == 0.018189
        assert md["sensitivity"] == float(note["InvOLS"]) == 1e-7
        assert md["sample_rate"] == float(note["NumPtsPerSec"]) == 2000
        # UseVelocity 0: the ramp runs at Velocity (2 x ForceDist x ForceScanRate) both ways, and the data agree
        assert note["UseVelocity"] == "0" and md["velocity"] == md["retract_velocity"] == float(note["Velocity"])
        assert md["velocity"] == pytest.approx(2 * float(note["ForceDist"]) * float(note["ForceScanRate"]), rel=1e-3)
        ret = c.retract
        slope = -np.polyfit(c.time[ret], c.position()[ret], 1)[0]
        assert slope == pytest.approx(md["velocity"], rel=0.05)
        assert md["map_width"] == float(note["FastScanSize"]) == 9e-6
        assert c.deflection_unit == "m"


def test_grid_positions_and_curves_equal_the_bytes_written(built):
    path, info = built
    curves = load(path)
    width = 9e-6
    for c, w in zip(curves, info["curves"]):
        md = c.metadata
        assert (md["map_x"], md["map_y"], md["map_nx"], md["map_ny"]) == (w["x"], w["y"], NX, NY)
        assert md["position_x"] == pytest.approx((w["x"] + 0.5) * width / NX)
        assert md["position_y"] == pytest.approx((w["y"] + 0.5) * width / NY)
        cols = w["columns"]
        n = cols["Defl"].size
        np.testing.assert_array_equal(c.deflection_signal, cols["Defl"].astype(float))
        # z grows on the approach in the file already (Raw rises over the extend): kept as stored
        np.testing.assert_array_equal(c.piezo_nominal, cols["Raw"].astype(float))
        np.testing.assert_array_equal(c.piezo_measured, cols["ZSnsr"].astype(float))
        np.testing.assert_allclose(c.time, np.arange(n) / 2000.0)
        # the note's Indexes 0,224,1232,1260 and Direction NaN,1,-1,0: extend, retract, then away
        assert (c.approach.sum(), c.retract.sum()) == (224, 1232 - 224)
        assert np.all(c.segment[1232:] == 2)


def test_units_and_ranges_are_physical(built):
    path, _ = built
    for c in load(path):
        z = c.position()
        ramp = np.ptp(z)
        assert 1e-9 < ramp < 20e-6                                  # a ramp of nm..um, in metres
        app = c.approach
        assert z[app][-1] > z[app][0]                              # z grows towards the sample
        rise = c.deflection_signal[app].max() - c.deflection_signal[app][:20].mean()
        assert 0 < rise < ramp                                     # the lever bends less than z moves
        assert np.all(np.abs(c.deflection_signal) < 1e-5)          # metres, not volts or nanometres


def test_agrees_with_the_asylum_ibw_reader_on_the_same_curve(built):
    """Curve (0, 0) is stored unshifted: afmforce's .ibw reader (through afmformats) gives the force
    k x Defl and the same positions."""
    path, _ = built
    (ibw,) = load(SOURCE)
    ardf = load(path)[0]
    k = ardf.metadata["spring_constant"]
    assert ibw.deflection_unit == "N"
    np.testing.assert_allclose(ibw.deflection_signal, k * ardf.deflection_signal, rtol=1e-6, atol=1e-18)
    np.testing.assert_allclose(ibw.position(), ardf.position(), rtol=1e-6)
    assert ibw.approach.sum() == ardf.approach.sum() and ibw.retract.sum() == ardf.retract.sum()


def test_streamed_one_curve_at_a_time(built):
    path, _ = built
    whole = load(path)
    reader = open_map(path, "asylum-ardf")
    try:
        assert len(reader) == NX * NY
        for i in (7, 0, 11, 3):  # any order: offsets of the line last read are kept
            np.testing.assert_array_equal(reader.read(i).deflection_signal, whole[i].deflection_signal)
        with pytest.raises(FileFormatError, match="no curve 12"):
            reader.read(12)
    finally:
        reader.close()


def test_memory_flat_in_the_map_size(tmp_path):
    """Issue 35: a 32 x 32 map (15 MB) read curve by curve allocates a small fraction of the file at its peak
    (tracemalloc, numpy's buffers included): the line table and one curve, never the map."""
    import tracemalloc

    path = tmp_path / "big.ARDF"
    info = build_ardf(path, nx=32, ny=32)
    assert info["size"] > 15e6
    tracemalloc.start()
    try:
        reader = open_map(path, "asylum-ardf")
        total = 0.0
        for i in range(len(reader)):
            total += float(reader.read(i).deflection_signal[-1])
        reader.close()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert len(reader) == 1024 and np.isfinite(total)
    assert peak < 1.5e6, peak


def test_a_stopped_map_holds_the_curves_recorded(tmp_path):
    path = tmp_path / "stopped.ARDF"
    build_ardf(path, nx=3, ny=4, lines_done=2, last_line=2)
    curves = load(path)
    assert len(curves) == 3 + 2
    assert [(c.metadata["map_x"], c.metadata["map_y"]) for c in curves] == [(0, 0), (1, 0), (2, 0), (0, 1), (1, 1)]
    assert curves[0].metadata["map_ny"] == 4


def test_padding_after_the_curves_is_not_a_curve(built, tmp_path):
    path, _ = built
    padded = tmp_path / "padded.ARDF"
    padded.write_bytes(path.read_bytes() + b"\0" * 64)
    assert len(load(padded)) == NX * NY


def test_user_calibration_wins_and_rescales_the_metres(built):
    path, _ = built
    (c0,) = load(path)[:1]
    c = load(path, meta_override={"sensitivity": 2e-7, "spring_constant": 0.05})[0]
    assert c.metadata["spring_constant"] == 0.05 and c.metadata["sensitivity"] == 2e-7
    np.testing.assert_allclose(c.deflection_signal, 2 * c0.deflection_signal)  # Defl = volts x InvOLS


@pytest.mark.parametrize("key,value", [("SpringConstant", "0"), ("InvOLS", "-1e-7"), ("SpringConstant", "NaN")])
def test_impossible_calibration_in_the_note_is_refused(tmp_path, key, value):
    _, note = source_curve()
    bad = re.sub(rf"(?<![A-Za-z]){key}:[^\r]*", f"{key}: {value}", note)
    assert bad != note
    path = tmp_path / "bad.ARDF"
    build_ardf(path, nx=2, ny=1, note=bad)
    with pytest.raises(FileFormatError, match=key):
        load(path)
    ours = "spring_constant" if key == "SpringConstant" else "sensitivity"
    assert load(path, meta_override={ours: 0.02 if ours == "spring_constant" else 5e-8})


def test_a_map_without_spring_constant_asks_for_it(tmp_path):
    _, note = source_curve()
    path = tmp_path / "nok.ARDF"
    build_ardf(path, nx=2, ny=1, note=re.sub(r"(?<![A-Za-z])SpringConstant:[^\r]*\r", "", note))
    with pytest.raises(MissingMetadataError, match="spring_constant"):
        load(path)
    assert count_curves(path) == 2  # planning a batch needs no calibration
    assert load(path, meta_override={"spring_constant": 0.02})[0].metadata["spring_constant"] == 0.02


def test_channels_choose_unit_and_position(tmp_path):
    """A map holding the deflection in volts only (DeflV) gives volts; one without ZSnsr takes Raw alone; one
    without a deflection channel is refused naming the channels it has."""
    volts = tmp_path / "volts.ARDF"
    info = build_ardf(volts, nx=2, ny=1, channels=("Raw", "DeflV", "ZSnsr"))
    c = load(volts)[0]
    assert c.deflection_unit == "V" and c.metadata["sensitivity"] == 1e-7
    np.testing.assert_array_equal(c.deflection_signal, info["curves"][0]["columns"]["DeflV"].astype(float))
    raw_only = tmp_path / "raw.ARDF"
    build_ardf(raw_only, nx=2, ny=1, channels=("Raw", "Defl"))
    c = load(raw_only)[1]
    assert c.piezo_measured is None and c.metadata["position_channel"] == "Raw"
    none = tmp_path / "none.ARDF"
    build_ardf(none, nx=2, ny=1, channels=("Raw", "ZSnsr"))
    with pytest.raises(FileFormatError, match="no deflection channel.*Raw, ZSnsr"):
        load(none)


@pytest.mark.parametrize("cut", [20, 100, 3000, -5000, -10])
def test_truncated_copy_gives_a_clean_error(built, tmp_path, cut):
    path, _ = built
    raw = path.read_bytes()
    bad = tmp_path / "cut.ARDF"
    bad.write_bytes(raw[:cut] if cut > 0 else raw[:len(raw) + cut])
    with pytest.raises(FileFormatError, match="truncated|too short|damaged|ends inside"):
        load(bad)
    assert bad.read_bytes() == (raw[:cut] if cut > 0 else raw[:len(raw) + cut])


def test_damaged_sizes_and_renamed_files_are_refused_by_name(built, tmp_path):
    path, _ = built
    raw = bytearray(path.read_bytes())
    at = raw.index(b"VDEF")
    raw[at + 4:at + 12] = struct.pack("<II", 0, 10**6)  # a grid of 0 x 10^6
    (tmp_path / "grid.ARDF").write_bytes(bytes(raw))
    with pytest.raises(FileFormatError, match="grid"):
        load(tmp_path / "grid.ARDF")
    other = tmp_path / "image.ARDF"
    other.write_bytes(SOURCE.read_bytes())  # an .ibw renamed
    with pytest.raises(FileFormatError, match=r"not recognised|renamed\? give it its own ending \(\.ibw\)"):
        load(other)
    with pytest.raises(FileFormatError, match="ARDF"):
        load(other, format="asylum-ardf")


def test_cli_refuses_a_truncated_map_in_one_line(built, tmp_path, capsys):
    path, _ = built
    bad = tmp_path / "cut.ARDF"
    bad.write_bytes(path.read_bytes()[:-3000])
    code = main(["analyze", str(bad), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code != 0 and "Traceback" not in err and "truncated" in err


def _summary(out: Path):
    import pandas as pd

    (summary,) = out.glob("batch-*/summary.csv")
    return pd.read_csv(summary)


def _analyze(args, capsys) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["analyze", *map(str, args)]) == 0
    capsys.readouterr()


def test_analyze_as_a_user_types_it_equals_the_ibw_of_the_same_curve(tmp_path, capsys):
    """``afmforce analyze map.ARDF --out DIR``: four cells of the real curve (z shifted per cell) give, cell
    by cell, the numbers ``afmforce analyze`` gives for the .ibw of that curve (afmformats' reader, force in
    N): the same analysis of the same data, read by two readers. z shifts move no force or distance."""
    path = tmp_path / "map.ARDF"
    build_ardf(path, nx=2, ny=2)
    _analyze([path, "--out", tmp_path / "ardf"], capsys)
    _analyze([SOURCE, "--out", tmp_path / "ibw"], capsys)
    table, ibw = _summary(tmp_path / "ardf"), _summary(tmp_path / "ibw")
    assert len(table) == 4 and table["error"].isna().all()
    assert sorted(zip(table["map_y"], table["map_x"])) == [(0, 0), (0, 1), (1, 0), (1, 1)]
    assert list(table["map_nx"]) == [2] * 4 and list(table["position_x [m]"]) == [2.25e-6, 6.75e-6] * 2
    assert (table["deflection_unit"] == "m").all() and ibw["deflection_unit"][0] == "N"
    compared = 0
    for column in ("spring_constant [N/m]", "sensitivity_fit [m/V]", "indentation [m]", "adhesion_distance [m]",
                   "adhesion_noise [N]", "force_gradient [N/m]", "velocity [m/s]"):
        want = ibw[column][0]  # NaN where the analysis refuses it (the curve's indentation: negative, impossible)
        np.testing.assert_allclose(table[column], want, rtol=1e-4, err_msg=column, equal_nan=True)
        compared += bool(np.isfinite(want))
    # (5: the soft contact's sensitivity_fit is NaN in both, its slope no sensitivity: steps.calibration.SOFT_SLOPE)
    assert compared >= 5 and (table["contact_kind"] == ibw["contact_kind"][0]).all()
    assert list(tmp_path.glob("ardf/batch-*/map.ARDF.maps.h5"))        # the map outputs, as for a JPK map


def test_virtual_soft_map_as_ardf_gives_its_modulus_and_topography(tmp_path, capsys):
    """The virtual AFM's 4 x 4 soft map (tests/contact/test_map_vendor.py), its deflection stored in metres
    as an MFP-3D stores it, analysed with ``afmforce analyze soft.ARDF --tip-radius R --out DIR``: the
    modulus and the contact points (topography) equal the known fields within their intervals; none is
    impossible and every contact point lies within its curve's ramp."""
    from afmforce.instrument.soft_map import SoftMapConfig, soft_map_curves, soft_map_fields  # noqa: I001

    cfg = SoftMapConfig(nx=4, ny=4, seed=11)
    rows, ramps = [], {}
    for c in soft_map_curves(cfg):
        n_app = int(c.approach.sum())
        z = np.asarray(c.position(), dtype=float)
        x, y = c.metadata["map_x"], c.metadata["map_y"]
        ramps[(y, x)] = (z.min(), z.max())
        rows.append((x, y, {"Raw": z, "Defl": np.asarray(c.deflection_signal) * cfg.sensitivity, "ZSnsr": z}))
    rate = c.metadata["sample_rate"]
    note = "\r".join([f"SpringConstant: {cfg.spring_constant}", f"InvOLS: {cfg.sensitivity}",
                      f"NumPtsPerSec: {rate}", f"Velocity: {cfg.velocity}",
                      f"FastScanSize: {cfg.step * cfg.nx}", f"SlowScanSize: {cfg.step * cfg.ny}", ""])
    path = tmp_path / "soft.ARDF"
    write_ardf(path, rows, nx=cfg.nx, ny=cfg.ny, note=note, ends=(n_app, len(z), len(z)))
    quantities = ("youngs_modulus", "contact_point", "adhesion")
    # --no-plot: no per-curve figure (16 of them: the test alone 20.8 -> 7.8-9.0 s of CPU, warm); none is
    # asserted here, the map images are still drawn, and the test above draws an ARDF curve's figure
    _analyze([path, "--tip-radius", f"{cfg.radius}m", "--poisson", cfg.poisson, "--out", tmp_path / "out",
              "--no-plot", *[a for q in quantities for a in ("--map-quantity", q)]], capsys)
    table = _summary(tmp_path / "out").sort_values(["map_y", "map_x"]).reset_index(drop=True)
    (maps,) = (tmp_path / "out").glob("batch-*/soft.ARDF.maps.h5")
    import h5py

    with h5py.File(maps, "r") as h5:                   # the images: one per quantity, on the file's grid
        for q in quantities:
            assert (maps.parent / f"soft.ARDF.{q}.png").is_file(), q
            image = np.asarray(h5[q])
            assert image.shape in ((cfg.ny, cfg.nx), (cfg.nx, cfg.ny)), (q, image.shape)
        unit = " [Pa]"
        np.testing.assert_allclose(np.asarray(h5["youngs_modulus"])[table["map_y"], table["map_x"]],
                                   table["youngs_modulus" + unit], rtol=1e-6)
    assert len(table) == 16 and table["error"].isna().all()
    fields = soft_map_fields(cfg)
    at = (table["map_y"].to_numpy(int), table["map_x"].to_numpy(int))
    e, cp = table["youngs_modulus [Pa]"], table["contact_point [m]"]
    assert ((e > 1e2) & (e < 1e6)).all() and cp.notna().all()
    z = np.abs(e - fields["youngs_modulus"][at]) / table["youngs_modulus_se [Pa]"]
    assert z.max() < 4.5 and np.median(z) < 1.5
    offset = -cp - fields["topography"][at]    # the contact point is -height, up to one offset
    assert np.abs(offset).max() < 2e-9      # within 2 nm on a sample 400 nm high
    for (y, x), point in zip(zip(*at), cp):
        low, high = ramps[(y, x)]
        assert low < point < high           # the contact point is a position of the ramp


REAL = sorted(SHARED.glob("*.ARDF")) + sorted(SHARED.glob("*.ardf")) if SHARED.is_dir() else []


@pytest.mark.skipif(not REAL, reason=f"no real ARDF file in {SHARED}")
@pytest.mark.parametrize("real", REAL, ids=[p.name for p in REAL])
def test_real_ardf_file(real):
    note = _note_of(real)
    reader = open_map(real, "asylum-ardf")
    try:
        assert len(reader) >= 1
        for i in sorted({0, len(reader) // 2, len(reader) - 1}):
            c = reader.read(i)
            assert c.metadata["spring_constant"] == float(note["SpringConstant"])
            assert c.metadata["sensitivity"] == float(note["InvOLS"])
            assert 1e-9 < np.ptp(c.position()) < 100e-6
            assert c.approach.any() and c.retract.any()
    finally:
        reader.close()
