"""Readers: every data file loads in afmforce's conventions; vendor quirks; cross-checks.

Data: tests/data/ (real files from afmformats' test data, see tests/data/README.md,
and one synthetic Bruker NanoScope export). Expected values come from the files
themselves (read independently with numpy / zipfile) or from their documented
metadata (shared/data/real/README.md), never from our own output.
"""

from __future__ import annotations

import hashlib
import json
import zipfile
from pathlib import Path

import numpy as np
import pytest

from afmforce.errors import FileFormatError, ParameterError
from afmforce.io import FORMATS, find_format, formats_table, is_supported, load, supported_suffixes
from afmforce.io.bruker import parse_column_name
from afmforce.io.jpk_zip import parse_properties

DATA = Path(__file__).resolve().parents[1] / "data"
NTMDT_META = {"spring_constant": 0.05, "sensitivity": 61e-9}
FILES = sorted(p for p in DATA.iterdir() if is_supported(p))


OVERRIDES = json.loads((DATA / "meta_override.json").read_text())  # for files that store no k / sensitivity


def _load(path: Path):
    return load(path, meta_override=OVERRIDES.get(path.name))


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_every_file_loads_in_afmforce_conventions(path):
    """RawCurve conventions (raw.py): z increases on the approach, approach = 0, retract = 1,
    deflection positive = up, so the contact end of the approach lies above its start."""
    before = _digest(path)
    curves = _load(path)
    assert curves and _digest(path) == before  # input untouched
    c = curves[0]
    app, ret = np.flatnonzero(c.segment == 0), np.flatnonzero(c.segment == 1)
    assert app.size > 10 and ret.size > 10
    z = c.piezo_measured if c.piezo_measured is not None else c.piezo_nominal
    assert z[app[-1]] > z[app[0]]  # towards the probe
    assert z[ret[-1]] < z[ret[0]]
    s = c.deflection_signal
    assert s[app[-5:]].mean() > s[app[:50]].mean()  # repulsive contact pushes the cantilever up
    assert np.all(np.diff(c.time) > 0) or c.metadata.get("time_is_sample_index")
    assert c.metadata["source_file"] == str(path)
    assert c.metadata["reader"] in FORMATS


def test_asylum_ibw_split_at_turning_point_and_metadata():
    """README: k = 1.1841 N/m, InvOLS 44.99 nm/V, 2 kHz, 2016 points turning at sample 1008."""
    c = load(DATA / "asylum-mfp3d_SiN-tip_air.ibw")[0]
    assert len(c) == 2016
    assert np.sum(c.segment == 0) == 1008 and c.segment[1008] == 1
    assert c.metadata["spring_constant"] == pytest.approx(1.1841)
    assert c.metadata["sensitivity"] == pytest.approx(44.99e-9)
    assert c.metadata["sample_rate"] == pytest.approx(2000.0)
    assert c.time[1] - c.time[0] == pytest.approx(1 / 2000)
    assert c.deflection_unit == "N"


def test_jpk_zip_reader_reproduces_afmformats_on_a_calibrated_file():
    """Independent decoding: raw volts x sensitivity x k (from the file) equals afmformats' force."""
    import afmformats

    path = DATA / "jpk_cellhesion_spot3.jpk-force"
    dd = afmformats.load_data(path)[0]
    direct = load(path, format="jpk-zip")[0]
    calibrated = load(path)[0]  # the jpk-force reader: the same decoding, in force
    assert direct.deflection_unit == "V" and calibrated.deflection_unit == "N"
    k, s = direct.metadata["spring_constant"], direct.metadata["sensitivity"]
    assert k == pytest.approx(0.043493666407368466) and s == pytest.approx(7.000143623002982e-08)
    np.testing.assert_allclose(direct.deflection_signal * s * k, dd["force"], rtol=1e-12)
    np.testing.assert_allclose(calibrated.deflection_signal, dd["force"], rtol=1e-12)
    np.testing.assert_allclose(direct.piezo_measured, -np.asarray(dd["height (measured)"]), rtol=1e-12)
    np.testing.assert_array_equal(direct.segment, np.asarray(dd["segment"]))
    assert calibrated.metadata["segment_types"] == ["extend-spm", "retract-spm"]


def test_jpk_calibration_curve_is_read_in_raw_volts():
    """afmformats refuses the file (no sensitivity, no k); the zip fallback returns volts.

    The first extend sample, decoded by hand from the archive: int32 big endian
    x multiplier + offset of shared-data lcd-info 1 (vDeflection)."""
    path = DATA / "jpk_calibration-curve_raw-volts.jpk-force"
    c = load(path)[0]
    assert c.deflection_unit == "V" and c.metadata["reader"] == "jpk-zip"
    assert "sensitivity" not in c.metadata and "spring_constant" not in c.metadata
    with zipfile.ZipFile(path) as arc:
        raw = np.frombuffer(arc.read("segments/0/channels/vDeflection.dat"), ">i4")
        shared = parse_properties(arc.read("shared-data/header.properties").decode())
    volts = raw * float(shared["lcd-info.1.encoder.scaling.multiplier"]) + float(
        shared["lcd-info.1.encoder.scaling.offset"])
    np.testing.assert_allclose(c.deflection_signal[: raw.size], volts, rtol=1e-12)
    assert c.metadata["sample_rate"] == pytest.approx(2048 / 10.0)  # 2048 points in 10 s


def test_ntmdt_needs_user_metadata_and_keeps_the_raw_column():
    path = DATA / "ntmdt_gel-in-water.txt"
    with pytest.raises(FileFormatError, match="spring_constant"):
        load(path)
    c = load(path, meta_override=NTMDT_META)[0]
    raw = np.loadtxt(path, converters=lambda s: float(s.replace(",", ".")))
    assert c.deflection_unit == "V" and c.metadata["sensitivity"] == 61e-9
    # approach: column 2 without the constant padding at the top, in reverse row order
    app = c.deflection_signal[c.segment == 0]
    np.testing.assert_allclose(app[-1], raw[np.flatnonzero(raw[:, 1] != raw[0, 1])[0] - 1, 1], rtol=1e-12)
    assert set(np.round(app, 6)) <= set(np.round(raw[:, 1], 6))


def test_afm_workshop_force_columns():
    """Force in nN and Z-sense in nm read independently from the CSV."""
    path = DATA / "afm-workshop_single.csv"
    c = load(path)[0]
    rows = [ln.split(",") for ln in path.read_text().splitlines() if ln[:1].isdigit()]
    ext_force = np.array([float(r[1]) for r in rows]) * 1e-9
    np.testing.assert_allclose(c.deflection_signal[c.segment == 0], ext_force, rtol=1e-9)
    assert c.metadata.get("time_is_sample_index") is True


def test_bruker_synthetic_export():
    """The synthetic NanoScope file (make_bruker_example.py): heights flipped, retract reversed,
    volts chosen over nm, k and sensitivity from the header, time from the scan rate."""
    c = load(DATA / "bruker-nanoscope_synthetic.txt")[0]
    assert find_format(DATA / "bruker-nanoscope_synthetic.txt").identifier == "bruker-ascii"
    assert c.deflection_unit == "V"
    assert c.metadata["spring_constant"] == 0.21 and c.metadata["sensitivity"] == pytest.approx(45e-9)
    a, r = c.segment == 0, c.segment == 1
    assert (a.sum(), r.sum()) == (121, 428)
    np.testing.assert_allclose(c.piezo_nominal[a][[0, -1]], [-80e-9, 40e-9])  # generator: start, turn
    np.testing.assert_allclose(c.piezo_nominal[r][0], 40e-9)
    assert c.metadata["sample_rate"] == pytest.approx(500.0, rel=1e-5)


@pytest.mark.parametrize("name,expected", [
    ("Defl_nm_Ex", ("Defl", "nm", "Ex")), ("Calc_Ramp_Rt_nm", ("Calc_Ramp", "nm", "Rt")),
    ("PF_Z_Sensor_nm_Ex", ("PF_Z_Sensor", "nm", "Ex")), ("Time_s_Rt", ("Time", "s", "Rt")),
    ("Separation_nm", None)])
def test_bruker_column_names(name, expected):
    assert parse_column_name(name) == expected


def test_registry_records_and_errors(tmp_path):
    assert {"jpk-force", "jpk-zip", "asylum-ibw", "ntmdt-txt", "afm-workshop-csv", "bruker-ascii",
            "afmforce-raw", "afmforce-hdf5"} <= set(FORMATS)
    assert {row["identifier"] for row in formats_table()} == set(FORMATS)
    assert ".jpk-force" in supported_suffixes()
    with pytest.raises(FileFormatError, match="no such file"):
        load(tmp_path / "missing.ibw")
    odd = tmp_path / "curve.xyz"
    odd.write_text("1 2 3")
    with pytest.raises(FileFormatError, match="unknown file type"):
        load(odd)
    with pytest.raises(ParameterError, match="unknown format"):
        load(DATA / "afm-workshop_single.csv", format="nope")
    with pytest.raises(ParameterError, match="spring_constant"):
        load(DATA / "afm-workshop_single.csv", meta_override={"spring_constant": -1})
    with pytest.raises(ParameterError, match="unknown metadata key"):
        load(DATA / "afm-workshop_single.csv", meta_override={"colour": "red"})


def test_meta_override_wins_and_uses_afmformats_keys():
    c = load(DATA / "asylum-mfp3d_SiN-tip_air.ibw", meta_override={"spring constant": 0.5})[0]
    assert c.metadata["spring_constant"] == 0.5


def test_afmforce_raw_files_round_trip_through_the_registry(tmp_path):
    rawfile = pytest.importorskip("afmforce.io.native.rawfile")
    from afmforce.analysis.synthetic import static_curve

    curve = static_curve(noise=0.05e-9, seed=3)
    for name in ("curve.txt", "curve.h5"):
        path = tmp_path / name
        rawfile.write_raw(curve, path)
        back = load(path)[0]
        assert back.metadata["reader"] == find_format(path).identifier
        np.testing.assert_array_equal(back.deflection_signal, curve.deflection_signal)
        np.testing.assert_array_equal(back.piezo_nominal, curve.piezo_nominal)
        assert find_format(path).identifier in ("afmforce-raw", "afmforce-hdf5")


def test_damaged_igor_header_is_rejected_up_front(tmp_path):
    """A corrupted section size in the Igor header (BinHeader5) is caught before igor2 builds a
    struct format from it (which would take minutes): a FileFormatError naming the sizes."""
    data = (DATA / "asylum-mfp3d_SiN-tip_air.ibw").read_bytes()
    bad = tmp_path / "bad.ibw"
    bad.write_bytes(data[:15] + b"\x1a\x04\xa8\xcf\xf4\x02\xf6h" + data[15:])  # shifts the size fields
    with pytest.raises(FileFormatError, match="declares"):
        load(bad)


def test_asylum_resonance_frequency_from_the_note():
    """README (shared/data/real): ForceMetric wave note: SpringConstant 0.98415 N/m, InvOLS 29.757 nm/V,
    ThermalFrequency 35614 Hz, 10 kHz. afmformats drops the frequency; we read it from the note."""
    c = load(DATA / "asylum-mfp3d_ForceMetric_X60_3_x4_0100.ibw")[0]
    assert c.metadata["resonance_frequency"] == pytest.approx(35614.0)
    assert c.metadata["spring_constant"] == pytest.approx(0.98415)
    assert c.metadata["sensitivity"] == pytest.approx(29.757e-9)
    assert c.metadata["sample_rate"] == pytest.approx(10000.0)
    assert load(DATA / "asylum-mfp3d_ForceMetric_X60_3_x4_0100.ibw",
                meta_override={"resonance_frequency": 1e5})[0].metadata["resonance_frequency"] == 1e5


def test_parse_properties_fast_path_and_escapes():
    """Lines without escapes split at the first '=' or ':'; escaped lines follow Java's rules."""
    from afmforce.io.jpk_zip import parse_properties

    text = "# comment\n! other\na.b=1\nc : d e\nurl=http://x:8080\nk\\:x=2\nu=\\u00e9\\tz\nno separator\n"
    assert parse_properties(text) == {"a.b": "1", "c": "d e", "url": "http://x:8080", "k:x": "2",
                                      "u": "\u00e9\tz"}
