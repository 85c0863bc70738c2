"""Bruker NanoScope binary force files: the shared real file against its own header, and
synthetic files written here with known content (versions 5 and 9 layouts)."""

from __future__ import annotations


from pathlib import Path

import numpy as np
import pytest

from afmforce.errors import FileFormatError
from afmforce.io import find_format, is_supported, load
from afmforce.io.nanoscope import parse_header

DATA = Path(__file__).resolve().parents[1] / "data"
REAL = DATA / "bruker-nanoscope_PyFMlab_Egel4_00025.spm"


def test_real_v9_file_matches_its_header():
    """Header: Spring Constant 0.1332 N/m, DeflSens 27.39 nm/V, Samps/line 1024 1024, ramp
    227.2211 V x Zsens 13.203 nm/V = 3.000 um, Forward vel. 462.282 V/s x 13.203 nm/V, Effective
    BW 2083.33 Hz (the sample rate), relative trigger at 1.2 V (the approach rises about that much
    above its baseline); data: 2048 little-endian int32 at offset 80960, x 0.000375 V/LSB."""
    c = load(REAL)[0]
    assert find_format(REAL).identifier == "bruker-nanoscope"
    md = c.metadata
    assert md["spring_constant"] == 0.1332 and md["sensitivity"] == pytest.approx(27.39e-9)
    assert c.deflection_unit == "V" and len(c) == 2048
    assert (c.approach.sum(), c.retract.sum()) == (1024, 1024)
    assert md["sample_rate"] == pytest.approx(2083.33, rel=1e-5)
    assert md["velocity"] == pytest.approx(462.282 * 13.203e-9, rel=1e-6)
    assert c.piezo_nominal.max() - c.piezo_nominal.min() == pytest.approx(227.2211 * 13.203e-9, rel=2e-3)
    raw = np.frombuffer(REAL.read_bytes(), "<i4", count=2048, offset=80960) * 0.000375
    np.testing.assert_allclose(c.deflection_signal[c.approach], raw[:1024][::-1], rtol=1e-12)
    np.testing.assert_allclose(c.deflection_signal[c.retract], raw[1024:], rtol=1e-12)
    a = c.deflection_signal[c.approach]
    assert a.max() - np.median(a[:200]) == pytest.approx(1.2, rel=0.05)  # relative trigger threshold
    assert np.all(np.diff(c.time) > 0)


def _write(path: Path, app: np.ndarray, ret: np.ndarray, *, version: str = "0x09200000", bpp: int = 4,
           quoted: bool = False, eol: str = "\r\n", old_keys: bool = False, zsensor=None,
           samps: str | None = None) -> None:
    """A NanoScope force file: header sections and each channel's int data after the header
    (``samps``: the ``Samps/line`` entry as written, else the two runs' lengths)."""
    n_app, n_ret = len(app), len(ret)
    sens_key = "Deflection" if old_keys else "DeflSens"
    channels = [("DeflectionError", sens_key, 0.000375, np.concatenate([app, ret]))]
    if zsensor is not None:
        channels.append(("ZSensor", "ZsensSens", 0.0001, zsensor))
    lines = ["\\*Force file list", f"\\Version: {version}", "\\Data length: HEADER",
             "\\*Scanner list", "\\@Sens. Zsens: V 10.00000 nm/V", "\\*Ciao scan list",
             f"\\@Sens. {sens_key}: V 50.00000 {'nm/V' if old_keys else ''}", "\\@Sens. ZsensSens: V 900.0 nm/V",
             "\\*Ciao force list", "\\Scan rate: 0.25", "\\Forward vel.: 50", "\\Reverse vel.: 100",
             f"\\Samps/line: {samps}" if samps else
             f"\\Samps/line: {n_app} {n_ret}" if not old_keys else f"\\Samps/line: {n_app}"]
    blocks = []
    for name, sens, vlsb, ints in channels:
        blocks.append(["\\*Ciao force image list", "\\Data offset: OFFSET", f"\\Data length: {ints.size * bpp}",
                       "\\Bytes/pixel: 2", ("\\Spring constant: 0.2" if old_keys else "\\Spring Constant: 0.2"),
                       f'\\@4:Image Data: S [{name}] "{name}"',
                       f"\\@4:Z scale: V [Sens. {sens}] ({vlsb:.10f} V/LSB) 2.5 V",
                       "\\@4:Ramp Size: V [Sens. Zsens] (0.006713765 V/LSB) 100.0 V"])
    tail = ["\\*File list end"]

    def text(offsets):
        out = list(lines)
        for block, off in zip(blocks, offsets):
            out += [ln.replace("OFFSET", str(off)) for ln in block]
        out += tail
        out = [f'"{ln}"' if quoted else ln for ln in out]
        return (eol.join(out) + eol).replace("HEADER", "0000000")

    head_len = len(text([0] * len(blocks)).encode("latin-1")) + 32 * len(blocks)
    body, offsets = b"", []
    for _, _, _, ints in channels:
        offsets.append(head_len + len(body))
        body += np.asarray(ints, dtype=f"<i{bpp}").tobytes()
    head = text(offsets).encode("latin-1")
    head += b"\0" * (head_len - len(head))
    path.write_bytes(head + body)


@pytest.mark.parametrize("variant", [dict(), dict(version="0x05120000", bpp=2, old_keys=True),
                                     dict(quoted=True, eol="\r\r\n"), dict(bpp=2)])
def test_synthetic_file_with_known_content(tmp_path, variant):
    n = 200
    rng = np.random.default_rng(4)
    app = rng.integers(-3000, 3000, n)  # stored from the turning point back to the start
    ret = rng.integers(-3000, 3000, n)
    path = tmp_path / "curve.001"
    _write(path, app, ret, **variant)
    assert is_supported(path) and find_format(path).identifier == "bruker-nanoscope"
    c = load(path)[0]
    np.testing.assert_allclose(c.deflection_signal[c.approach], app[::-1] * 0.000375, rtol=1e-12)
    np.testing.assert_allclose(c.deflection_signal[c.retract], ret * 0.000375, rtol=1e-12)
    assert c.metadata["spring_constant"] == 0.2 and c.metadata["sensitivity"] == pytest.approx(50e-9)
    ramp = 100.0 * 10e-9  # 100 V x 10 nm/V
    assert c.metadata["velocity"] == pytest.approx(50 * 10e-9)
    assert c.metadata["retract_velocity"] == pytest.approx(100 * 10e-9)
    t = c.time
    assert t[c.approach][-1] - t[0] == pytest.approx(ramp / 0.5e-6 * (n - 1) / n)  # 2 s over n points
    assert t[-1] - t[c.retract][0] == pytest.approx(ramp / 1e-6 * (n - 1) / n)
    z = c.piezo_nominal
    assert z[c.approach][-1] == pytest.approx(ramp) and z[c.approach][0] < z[c.approach][-1]


def test_zsensor_channel_is_the_measured_position(tmp_path):
    n = 100
    app, ret = np.arange(n)[::-1] * 3, np.arange(n)[::-1] * 3
    zs = np.concatenate([np.arange(n)[::-1], np.arange(n)[::-1]]) * 50  # from the turning point
    path = tmp_path / "curve.spm"
    _write(path, app, ret, zsensor=zs)
    c = load(path)[0]
    zm = c.piezo_measured
    assert zm is not None
    np.testing.assert_allclose(np.abs(zm[c.approach]), np.arange(n) * 50 * 0.0001 * 900e-9, rtol=1e-9)
    assert zm[c.approach][-1] > zm[c.approach][0]


def test_damaged_files_are_named(tmp_path):
    n = 50
    path = tmp_path / "c.spm"
    _write(path, np.arange(n), np.arange(n))
    data = path.read_bytes()
    cut = tmp_path / "cut.spm"
    cut.write_bytes(data[:-10])
    with pytest.raises(FileFormatError, match="cut.spm.*truncated"):
        load(cut)
    nohead = tmp_path / "nohead.spm"
    nohead.write_bytes(data[: data.find(b"\\*File list end")])
    with pytest.raises(FileFormatError, match="nohead.spm"):
        load(nohead)
    with pytest.raises(FileFormatError, match="image file.*not a force file"):
        parse_header(b"\\*File list\r\n\\*File list end\r\n", "x")
    with pytest.raises(FileFormatError, match="not a NanoScope force file"):
        parse_header(b"\\*Scanner list\r\n\\*File list end\r\n", "x")


# --- NanoScope ASCII exports as NanoScope Analysis writes them (issue 14 item 2) -------------------
ASCII = DATA / "bruker-nanoscope_synthetic.txt"


def _variant(text: str, kind: str) -> str:
    header, _, rest = text.partition("\\*File list end\n")
    names, _, rows = rest.partition("\n")
    if kind == "quoted-crcrlf":
        head = "".join(f'"{ln}"\r\r\n' for ln in (header + "\\*File list end").split("\n"))
        return head + names + "\r\r\n" + rows.replace("\n", "\r\r\n")
    if kind == "names":
        new = {"Calc_Ramp_Ex_nm": "Ramp_nm_Ex", "Calc_Ramp_Rt_nm": "Ramp_nm_Rt",
               "Defl_V_Ex": "Deflection Error (V) Extend", "Defl_V_Rt": "Deflection Error (V) Retract",
               "PF_Z_Sensor_nm_Ex": "Height_Sensor_nm_Ex", "PF_Z_Sensor_nm_Rt": "Height_Sensor_nm_Rt"}
        names = "\t".join(new.get(n, n) for n in names.split("\t"))
    if kind == "comma":
        names, rows = names.replace("\t", ","), rows.replace("\t", ",")
    return header + "\\*File list end\n" + names + "\n" + rows


@pytest.mark.parametrize("kind", ["quoted-crcrlf", "names", "comma"])
def test_ascii_variants_read_like_the_plain_export(tmp_path, kind):
    ref = load(ASCII)[0]
    path = tmp_path / "variant.txt"
    path.write_bytes(_variant(ASCII.read_text(), kind).encode())
    c = load(path)[0]
    np.testing.assert_array_equal(c.deflection_signal, ref.deflection_signal)
    np.testing.assert_array_equal(c.piezo_nominal, ref.piezo_nominal)
    np.testing.assert_array_equal(c.segment, ref.segment)
    assert c.metadata["spring_constant"] == 0.21 and c.metadata["sensitivity"] == pytest.approx(45e-9)


def test_ascii_several_blocks(tmp_path):
    ref = load(ASCII)[0]
    text = ASCII.read_text()
    path = tmp_path / "two.txt"
    path.write_text(text + _variant(text, "names"))
    curves = load(path)
    assert len(curves) == 2 and [c.metadata["curve_index"] for c in curves] == [0, 1]
    for c in curves:
        np.testing.assert_array_equal(c.deflection_signal, ref.deflection_signal)


@pytest.mark.parametrize("name,expected", [("Defl_V Ex", ("Defl", "V", "Ex")),
                                           ("Deflection Error (nm) Retract", ("Deflection_Error", "nm", "Rt")),
                                           ('"Height_Sensor_um_Ex"', ("Height_Sensor", "um", "Ex"))])
def test_ascii_column_name_variants(name, expected):
    from afmforce.io.bruker import parse_column_name

    assert parse_column_name(name) == expected


@pytest.mark.parametrize("name, stated, typed", [
    ("bruker-nanoscope_sapphire_TAP525.001", b"\\Spring Constant: 90\r", b"\\Spring Constant: -9\r"),
    ("bruker-nanoscope_sapphire_TAP525.001", b"\\Spring Constant: 90\r", b"\\Spring Constant: 00\r"),
    ("bruker-ascii_nm_retract-reversed.txt", b"\\Spring Constant: 0.34", b"\\Spring Constant: -0.3"),
])
def test_impossible_header_spring_constant_is_refused_like_asylum(tmp_path, name, stated, typed):
    """A header spring constant <= 0 is refused (FileFormatError naming `spring_constant`), as the
    Asylum reader refuses one (the shared rule of ``finalize_curve``), not dropped into a run without
    forces; the user's value replaces it. The copy keeps the header's length (same-size edit)."""
    raw = (DATA / name).read_bytes()
    assert raw.count(stated) == 1 and len(stated) == len(typed)
    path = tmp_path / name
    path.write_bytes(raw.replace(stated, typed))
    with pytest.raises(FileFormatError, match="spring_constant.*positive.*`spring_constant`"):
        load(path)
    c = load(path, meta_override={"spring_constant": 0.07})[0]
    assert c.metadata["spring_constant"] == 0.07
    assert load(DATA / name)[0].metadata["spring_constant"] == float(stated.split(b":")[1])  # the deflection's


def test_force_hold_is_read_as_extend_hold_retract_in_time_order():
    """Bruker's own v9.30 example (Apache-2.0): 4096 + 4096 points and a 0.1 s hold of 260 stored
    after both runs in 4-byte samples (33808 bytes = 8452 x 4; once refused as 'not a whole number of
    curves'). The physics of a hold checks the order: the Height Sensor stands still at the turning
    point while the deflection stays at its contact value, and the retract starts where the hold ends.
    The Height Sensor's V/LSB (0.00000000572205 V/LSB, a 32-bit scale) is applied as it is."""
    path = DATA / "corpus" / "bruker-nanoscope_v9.30_Bruker-example_ForceHold.spm"
    raw = path.read_bytes()
    c = load(path)[0]
    assert np.bincount(c.segment).tolist() == [4096, 4096, 260]
    assert c.metadata["segment_types"] == ["extend", "hold", "retract"]
    assert np.all(np.diff(c.time) > 0)
    t_hold = c.time[c.segment == 2]
    assert (t_hold[-1] - t_hold[0]) * 260 / 259 == pytest.approx(0.1, rel=1e-9)  # Hold Time: 0.1
    app, hold, ret = (c.deflection_signal[c.segment == k] for k in (0, 2, 1))
    z_app, z_hold, z_ret = (c.piezo_measured[c.segment == k] for k in (0, 2, 1))
    ramp = np.ptp(z_app)
    assert 0.4e-6 < ramp < 0.6e-6  # 17.649 V x 29.xx nm/V commanded; the sensor agrees within 3 %
    assert np.ptp(z_hold) < 0.01 * ramp and abs(z_hold[0] - z_app[-1]) < 0.01 * ramp
    assert abs(z_ret[0] - z_hold[-1]) < 0.01 * ramp
    span = np.ptp(app)
    assert abs(hold.mean() - app[-1]) < 0.02 * span and abs(ret[0] - hold[-1]) < 0.02 * span
    # the samples themselves: int32 counts x 0.000375 V/LSB, read here from the header's offsets
    lists = raw[:raw.index(b"File list end")].decode("latin-1").split("\\*")
    defl = next(t for t in lists if t.startswith("Ciao force image list") and "Deflection Error" in t)
    off = int(defl.split("\\Data offset: ")[1].split()[0])
    counts = np.frombuffer(raw[off:off + 33808], "<i4").astype(float) * 0.000375
    np.testing.assert_array_equal(app, counts[:4096][::-1])
    np.testing.assert_array_equal(ret, counts[4096:8192])
    np.testing.assert_array_equal(hold, counts[8192:])


def test_a_triggered_ramps_unrecorded_samples_are_dropped(tmp_path):
    """A ramp stopped at its trigger leaves the far end of its stored run at -32768 counts (Bruker's
    v8.15 force-volume example, 4.2 MB, not in the corpus: 856 of 1024 curves began with 14-174 samples
    at -12.288 V, then -0.45 V). Written here into Bruker's v8.15 single curve (corpus, int16 at the
    deflection list's offset, the approach stored from the turning point): the 37 fillers are dropped,
    every other sample is the original's."""
    src = DATA / "corpus" / "bruker-nanoscope_v8.15_Bruker-example_Force.spm"
    raw = bytearray(src.read_bytes())
    lists = raw[:raw.index(b"File list end")].decode("latin-1").split("\\*")
    defl = next(t for t in lists if t.startswith("Ciao force image list") and "Deflection Error" in t)
    off = int(defl.split("\\Data offset: ")[1].split()[0])
    n = 1024
    counts = np.frombuffer(bytes(raw[off:off + 4 * n]), "<i2").copy()
    counts[n - 37:n] = -32768  # the approach's far end (stored last)
    raw[off:off + 4 * n] = counts.tobytes()
    path = tmp_path / "triggered.spm"
    path.write_bytes(bytes(raw))
    orig, cut = load(src)[0], load(path)[0]
    assert np.bincount(cut.segment).tolist() == [n - 37, n] and cut.metadata["unrecorded_samples"] == 37
    keep = np.r_[np.zeros(37, bool), np.ones(2 * n - 37, bool)]
    for name in ("time", "piezo_nominal", "deflection_signal", "segment"):
        np.testing.assert_array_equal(getattr(cut, name), getattr(orig, name)[keep])
    assert cut.deflection_signal.min() > -12  # no -12.288 V sample left


def test_v6_triggered_approach_fills_the_second_samps_line_number(tmp_path):
    """NanoScope 6.13 (PicoForce, relative trigger): ``Samps/line: 1024 896`` over 2 x 1024 samples per
    channel; the approach, stored from the turning point, recorded 896 and the rest of its slots hold
    leftovers (-1 every other sample). Was refused: "channel length 4096 bytes is not a whole number of
    curves of 1920 points ... damaged file" (matfiz/afm-curve-procesing's 16 PicoForce files). Written
    here in that layout (200 slots, 170 recorded): the approach is its 170 samples in time order, the
    retract its 200, the leftovers dropped, the Z sensor growing towards the sample on the approach."""
    n, m = 200, 170
    rng = np.random.default_rng(7)
    app = rng.integers(-3000, 3000, n)
    app[m + 1::2] = -1                              # the leftovers of the real files, to the last slot
    ret = rng.integers(-3000, 3000, n)
    zs = np.concatenate([-2857 - 34 * np.arange(n), -2853 - 34 * np.arange(n)])  # falls away from the turn
    zs[m + 1:n:2] = -1
    path = tmp_path / "komorka00000.021"
    _write(path, app, ret, version="0x06130001", bpp=2, zsensor=zs, samps=f"{n} {m}")
    c = load(path)[0]
    assert np.bincount(c.segment).tolist() == [m, n] and c.metadata["unrecorded_samples"] == n - m
    np.testing.assert_allclose(c.deflection_signal[c.approach], app[:m][::-1] * 0.000375, rtol=1e-12)
    np.testing.assert_allclose(c.deflection_signal[c.retract], ret * 0.000375, rtol=1e-12)
    za, zr = c.piezo_measured[c.approach], c.piezo_measured[c.retract]
    assert za[-1] > za[0] and zr[-1] < zr[0]        # towards the sample, then away: not turned round
    step = 34 * 0.0001 * 900e-9
    np.testing.assert_allclose(np.diff(za), step, rtol=1e-9)
    np.testing.assert_allclose(np.diff(zr), -step, rtol=1e-9)
    np.testing.assert_allclose(np.diff(c.piezo_nominal[c.approach]), 100.0 * 10e-9 / n, rtol=1e-9)
    # the same numbers with equal runs or a data length of their sum keep the plain layout
    path2 = tmp_path / "plain.021"
    _write(path2, app[:m], ret, version="0x06130001", bpp=2, samps=f"{m} {n}")
    assert np.bincount(load(path2)[0].segment).tolist() == [m, n]


@pytest.mark.parametrize("name, recorded, k, sens", [
    ("bruker-nanoscope_v6.13_PicoForce_matfiz_komorka00000.021", 896, 0.0212714, 58.29331),
    ("bruker-nanoscope_v6.13_PicoForce_matfiz_kontrkulka00000.000", 948, 0.0337988, 55.97616)])
def test_real_v6_picoforce_triggered_files_match_their_header(name, recorded, k, sens):
    """The real NanoScope 6.13 PicoForce files (matfiz/afm-curve-procesing, no licence stated:
    AFMFORCE_REAL_DATA): header 'Samps/line: 1024 <recorded>', Spring Constant, DeflSens; the
    deflection channel's int16 at offset 40960 (approach stored from the turning point) x 0.0003051758
    V/LSB; the Z sensor (offset 45056, x 0.0003051758 V/LSB x 1000 nm/V) steps the same distance per
    sample on both runs, about Ramp size x Zsens / 1024."""
    from realdata import real_file

    path = real_file(name)
    c = load(path)[0]
    assert np.bincount(c.segment).tolist() == [recorded, 1024]
    assert c.metadata["spring_constant"] == k and c.metadata["sensitivity"] == pytest.approx(sens * 1e-9)
    raw = np.frombuffer(path.read_bytes(), "<i2", count=2048, offset=40960) * 0.0003051758
    np.testing.assert_allclose(c.deflection_signal[c.approach], raw[:recorded][::-1], rtol=1e-6)
    np.testing.assert_allclose(c.deflection_signal[c.retract], raw[1024:], rtol=1e-6)
    zs = np.frombuffer(path.read_bytes(), "<i2", count=2048, offset=45056) * 0.0003051758 * 1e-6
    za, zr = c.piezo_measured[c.approach], c.piezo_measured[c.retract]
    assert za[-1] > za[0] and zr[-1] < zr[0]
    np.testing.assert_allclose(np.abs(za[[0, -1]]), np.abs(zs[:recorded][[-1, 0]]), rtol=1e-9)
    mid = lambda x: x[x.size // 4: 3 * x.size // 4]  # noqa: E731  (the retract's far end flattens)
    step_a, step_r = np.mean(np.diff(mid(za))), -np.mean(np.diff(mid(zr)))
    assert step_a == pytest.approx(step_r, rel=0.03)   # not 1024/896 = 1.14 apart: the same ramp per sample
