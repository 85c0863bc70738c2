"""Issue 32 items 4 and 5 on the corpus files: Asylum waves without a Date note key, JPK float data
and every encoder, force maps with modulation segments, JPK Data Processing text exports.

The numbers asserted are the issue's (read from the files' headers by hand): the SMFS curve has
k = 0.09764 N/m, s = 9.7357 nm/V, 2048 Hz and 2048 + 1024 + 4096 points; the microrheology map
k = 0.009727 N/m, s = 38.48 nm/V, six sine modulations of 15 nm at 300, 3, 100, 30, 1, 10 Hz.
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np
import pytest

from afmforce.errors import FileFormatError, MissingMetadataError
from afmforce.io import load
from afmforce.io._meta import parse_meta_args

CORPUS = Path(__file__).resolve().parents[1] / "data" / "corpus"
SMFS = CORPUS / "jpk-dp_float-data_SMFS_0441.jpk-force"
RHEO = CORPUS / "jpk-force-map_microrheology_4x4.jpk-force-map"
NODATE = CORPUS / "asylum-ibw_no-date_ForceMap.ibw"


def test_asylum_wave_without_date_is_read_and_a_user_date_is_kept():
    c = load(NODATE)[0]
    md = c.metadata
    assert md["spring_constant"] == 0.018189 and md["sensitivity"] == pytest.approx(100e-9)
    assert md["sample_rate"] == 2000.0
    # note: Indexes 0,224,1232,1260 and Direction NaN,1,-1,0: extend, retract, then a dwell
    assert np.bincount(c.segment).tolist() == [224, 1008, 29]
    assert np.all(c.segment[:224] == 0) and np.all(c.segment[224:1232] == 1) and np.all(c.segment[1232:] == 2)
    assert np.argmax(c.piezo_nominal) in (223, 224)  # the piezo turns where the note says
    meta = parse_meta_args(["date=2016-11-06"])
    assert load(NODATE, meta_override=meta)[0].metadata["date"] == "2016-11-06"


def test_asylum_wave_without_spring_constant_asks_for_it_and_reads_with_it(tmp_path):
    bad = NODATE.read_bytes().replace(b"SpringConstant", b"SpringKonstant")  # same length: sizes hold
    path = tmp_path / "no_k.ibw"
    path.write_bytes(bad)
    with pytest.raises(MissingMetadataError, match="spring constant.*give `spring_constant`"):
        load(path)
    c = load(path, meta_override={"spring_constant": 0.02})[0]
    ref = load(NODATE)[0]
    assert c.metadata["spring_constant"] == 0.02 and c.deflection_unit == "N"
    # force = Defl [m] x k (afmformats multiplies the float32 wave): the same deflection as with the note's k
    np.testing.assert_allclose(c.deflection_signal / 0.02, ref.deflection_signal / 0.018189, rtol=1e-6)  # float32
    np.testing.assert_array_equal(c.segment, ref.segment)


def test_jpk_float_data_with_extra_channels_as_the_header_says():
    c = load(SMFS)[0]
    md = c.metadata
    assert md["spring_constant"] == pytest.approx(0.09764, rel=1e-4)
    assert md["sensitivity"] == pytest.approx(9.7357e-9, rel=1e-4)
    assert md["sample_rate"] == pytest.approx(2048.0)
    assert np.bincount(c.segment).tolist() == [2048, 4096, 1024]  # approach, retract, dwell
    assert [c.segment[0], c.segment[2048], c.segment[2048 + 1024]] == [0, 2, 1]  # extend, pause, retract in time
    assert md["segment_types"] == ["extend-spm", "pause-at-end-spm", "retract-spm"]
    assert c.piezo_measured is not None  # capacitiveSensorHeight
    # the stored float32 volts, times s and k, are the force (raw reader vs calibrated reader)
    volts = load(SMFS, format="jpk-zip")[0]
    assert volts.deflection_unit == "V" and c.deflection_unit == "N"
    np.testing.assert_allclose(volts.deflection_signal * md["sensitivity"] * md["spring_constant"],
                               c.deflection_signal, rtol=1e-12)
    with zipfile.ZipFile(SMFS) as arc:
        stored = np.frombuffer(arc.read("segments/0/channels/vDeflection.dat"), ">f4")
    np.testing.assert_array_equal(volts.deflection_signal[:2048], stored.astype(float))
    # the pause holds about 1.06 nN (constant force), the retract dips to about -345 pN (unfolding)
    pause = c.deflection_signal[c.segment == 2] - np.median(c.deflection_signal[c.segment == 0][:500])
    assert np.median(pause) == pytest.approx(1.06e-9, rel=0.15)


def _reencode(src: Path, dst: Path, encoder: str | None, dtype: str) -> None:
    """``src`` with vDeflection stored as ``dtype`` integers with an encoder (offset and multiplier
    in the shared header), or as doubles without one."""
    with zipfile.ZipFile(src) as arc:
        members = {i.filename: arc.read(i.filename) for i in arc.infolist()}
    volts = {n: np.frombuffer(d, ">f4").astype(float) for n, d in members.items() if n.endswith("vDeflection.dat")}
    lo, hi = min(v.min() for v in volts.values()), max(v.max() for v in volts.values())
    shared = members["shared-data/header.properties"].decode("latin-1")
    if dtype == ">f8":
        for n, v in volts.items():
            members[n] = v.astype(">f8").tobytes()
        shared = shared.replace("lcd-info.1.type=float-data", "lcd-info.1.type=double-data")
    else:
        info = np.iinfo(np.dtype(dtype))
        mult = float((hi - lo) / (0.9 * (float(info.max) - float(info.min))))
        off = float(lo - (float(info.min) + 0.05 * (float(info.max) - float(info.min))) * mult)
        for n, v in volts.items():
            members[n] = np.round((v - off) / mult).astype(dtype).tobytes()
        shared = shared.replace("lcd-info.1.type=float-data", "lcd-info.1.type=integer-data")
        shared += (f"\nlcd-info.1.encoder.type={encoder}\nlcd-info.1.encoder.scaling.type=linear\n"
                   f"lcd-info.1.encoder.scaling.style=offsetmultiplier\n"
                   f"lcd-info.1.encoder.scaling.offset={off!r}\nlcd-info.1.encoder.scaling.multiplier={mult!r}\n")
    members["shared-data/header.properties"] = shared.encode("latin-1")
    with zipfile.ZipFile(dst, "w") as out:
        for n, d in members.items():
            out.writestr(n, d)


@pytest.mark.parametrize("encoder,dtype", [("signedshort", ">i2"), ("unsignedshort", ">u2"),
                                           ("signedinteger", ">i4"), ("unsignedinteger", ">u4"),
                                           ("signedlong", ">i8"), (None, ">f8")])
def test_jpk_every_encoder_gives_the_same_volts(tmp_path, encoder, dtype):
    dst = tmp_path / f"smfs_{dtype[1:]}.jpk-force"
    _reencode(SMFS, dst, encoder, dtype)
    ref = load(SMFS, format="jpk-zip")[0].deflection_signal
    got = load(dst, format="jpk-zip")[0].deflection_signal
    step = (ref.max() - ref.min()) / (0.9 * 2.0 ** (8 * int(dtype[-1]))) if dtype != ">f8" else 0.0
    np.testing.assert_allclose(got, ref, rtol=0, atol=step / 2 * 1.01 + 1e-15)


def test_jpk_integer_data_without_an_encoder_is_refused_with_the_reason(tmp_path):
    dst = tmp_path / "noenc.jpk-force"
    with zipfile.ZipFile(SMFS) as arc, zipfile.ZipFile(dst, "w") as out:
        for info in arc.infolist():
            data = arc.read(info.filename)
            if info.filename == "shared-data/header.properties":
                data = data.replace(b"lcd-info.1.type=float-data", b"lcd-info.1.type=integer-data")
            out.writestr(info.filename, data)
    with pytest.raises(FileFormatError, match="vDeflection.*integer data.*without an encoder"):
        load(dst, format="jpk-zip")


def test_jpk_map_with_modulation_segments_typed_and_kept():
    curves = load(RHEO)
    assert len(curves) == 16
    freqs = []
    for c in curves:
        md = c.metadata
        assert md["spring_constant"] == pytest.approx(0.009727, rel=1e-3)
        assert md["sensitivity"] == pytest.approx(38.48e-9, rel=1e-3)
        types = md["segment_types"]
        assert types[0] == "extend-spm" and types[1] == "pause-spm" and types[-1] == "retract-spm"
        mods = types[2:-1]
        assert len(mods) == 6 and all(t.startswith("modulation sine-z") and t.endswith("15 nm") for t in mods)
        freqs.append([float(t.split()[2]) for t in mods])
        # the modulations are kept (dwell code 2: never approach or retract), 1024 + 2000 + 2000 + 4000
        # + 4000 + 1000 + 4000 samples; extend and retract 1200 each (a triggered extend may be shorter)
        counts = np.bincount(c.segment, minlength=3)
        assert counts[2] == 1024 + 2000 + 2000 + 4000 + 4000 + 1000 + 4000 and counts[1] == 1200
        assert 0 < counts[0] <= 1200
        assert 0 <= md["map_x"] < 4 and 0 <= md["map_y"] < 4
    assert freqs[0] == [300, 3, 100, 30, 1, 10] and all(f == freqs[0] for f in freqs)
    assert len({(c.metadata["map_x"], c.metadata["map_y"]) for c in curves}) == 16
    # the modulation really is a 15 nm sine of z: its amplitude in the 1 Hz segment
    c = curves[0]
    start = np.flatnonzero(c.segment == 2)[0] + 1024 + 2000 + 2000 + 4000 + 4000
    z = c.piezo_nominal[start:start + 1000]
    assert (z.max() - z.min()) / 2 == pytest.approx(15e-9, rel=0.3)


def test_jpk_map_modulations_are_skipped_by_the_force_analysis():
    from afmforce.analysis.pipeline import analyze

    c = load(RHEO)[0]
    r = analyze(c)
    assert r.spring_constant == pytest.approx(0.009727, rel=1e-3)
    assert r.contact_kind in ("soft", "hard")


def test_jpk_text_export_equals_its_archive():
    txt = load(CORPUS / "jpk-txt_dp-export_SMFS_0441.txt")
    assert len(txt) == 1
    a, b = txt[0], load(SMFS)[0]
    assert a.metadata["reader"] == "jpk-txt" and a.deflection_unit == "N"
    assert a.metadata["spring_constant"] == b.metadata["spring_constant"]
    assert a.metadata["sensitivity"] == b.metadata["sensitivity"]
    np.testing.assert_array_equal(a.segment, b.segment)
    # the export writes 8 significant digits of single-precision numbers (heights of ~10 um: 1 pm)
    np.testing.assert_allclose(a.deflection_signal, b.deflection_signal, rtol=1e-6, atol=1e-18)
    np.testing.assert_allclose(a.piezo_nominal, b.piezo_nominal, rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(a.piezo_measured, b.piezo_measured, rtol=1e-6, atol=1e-12)
    assert a.metadata["sample_rate"] == pytest.approx(2048.0, rel=1e-6)


def test_jpk_text_export_of_several_curves_and_in_volts(tmp_path):
    """A map export (two curves, one after the other) with vDeflection in volts: one curve each."""
    text = (CORPUS / "jpk-txt_dp-export_SMFS_0441.txt").read_text("latin-1")
    k, s = 0.09764020589507627, 9.735700780003594e-09
    lines = []
    for line in text.splitlines():
        if line.startswith("# units:"):
            line = "# units: m V m m m s s"
        elif line and not line.startswith("#"):
            v = line.split()
            v[1] = repr(float(v[1]) / (k * s))
            line = " ".join(v)
        lines.append(line)
    second = "\n".join(lines).replace("# index: 151", "# index: 152")
    path = tmp_path / "two.txt"
    path.write_text("\n".join(lines) + "\n" + second + "\n", encoding="latin-1")
    curves = load(path)
    assert len(curves) == 2 and all(c.deflection_unit == "V" for c in curves)
    ref = load(SMFS, format="jpk-zip")[0].deflection_signal
    for c in curves:
        np.testing.assert_allclose(c.deflection_signal, ref, rtol=1e-6, atol=1e-12)
        assert np.bincount(c.segment).tolist() == [2048, 4096, 1024]


@pytest.mark.parametrize("name", ["jpk-txt_dp-export_SMFS_0441.txt", "jpk-dp_float-data_SMFS_0441.jpk-force",
                                  "asylum-ibw_no-date_ForceMap.ibw", "jpk-qi-data_2020.02.07.jpk-qi-data"])
def test_mutated_variants_load_cleanly_or_fail_with_one_named_error(name, tmp_path):
    """The readers of these variants (JPK text, float data, maps read directly, Asylum notes without
    keys) under the fuzz test's mutations: a valid curve or one FileFormatError naming the file."""
    from afmforce.io._guard import run_with_timeout
    from test_fuzz import ENDINGS, MUTATIONS, SLOW, _fuzz

    result = run_with_timeout(_fuzz, CORPUS / name, tmp_path, sum(map(ord, name)), None,
                              timeout=MUTATIONS + len(ENDINGS) + 8 * (SLOW + 1) + 60, path=name)
    assert result["n"] >= MUTATIONS and not result["bad"], result["bad"]
    assert not result["slow"], result["slow"]


def test_cli_reads_the_asylum_wave_without_date_and_takes_meta_date(tmp_path, capsys):
    from afmforce.cli.main import main

    code = main(["analyze", str(NODATE), "--meta", "date=2016-11-06", "--json", "--no-plot",
                 "--out", str(tmp_path / "out")])
    out = capsys.readouterr()
    assert code == 0, out.err
    res = json.loads(out.out)["results"][NODATE.name]
    assert res["deflection_unit"] == "N" and "error" not in res


def test_cli_reads_the_microrheology_map_raw_with_format_jpk_zip(tmp_path, capsys):
    from afmforce.cli.main import main

    code = main(["analyze", str(RHEO), "--format", "jpk-zip", "--json", "--no-plot", "--out", str(tmp_path / "o")])
    out = capsys.readouterr()
    assert code == 0, out.err
    results = json.loads(out.out)["results"]
    assert len(results) == 16 and all(r.get("deflection_unit") == "V" for r in results.values())  # raw volts
    assert all(r["spring_constant"] == pytest.approx(0.009727, rel=1e-3) for r in results.values())
