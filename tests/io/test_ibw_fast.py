"""The numpy reader of Asylum ``.ibw`` waves (:mod:`afmforce.io.ibw_wave`) gives exactly what
afmformats/igor2 give: the same arrays (dtype, shape, strides, values) and the same metadata,
on every ``.ibw`` file in tests/data and shared/data/real, and on written variants (big-endian,
long and untidy labels); what it does not recognise goes back to afmformats."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest

from afmforce.io import load
from afmforce.io.ibw_wave import afmformats_igor, read_wave5

DATA = Path(__file__).resolve().parents[1] / "data"
REAL = Path(__file__).resolve().parents[3] / "shared" / "data" / "real"
FILES = (sorted(DATA.glob("*.ibw")) + sorted((DATA / "corpus").glob("*.ibw"))
         + (sorted(REAL.glob("*.ibw")) if REAL.is_dir() else []))


def _igor2(path):
    from igor2 import binarywave

    return binarywave.load(path)["wave"]


def _has_date(path) -> bool:
    note = _igor2(path)["note"].decode("latin-1").replace("\n", "\r")
    return any(line.startswith("Date:") for line in note.split("\r"))


def _mode_afmformats_refuses(path) -> bool:
    """The note's ImagingMode is outside afmformats' feedback modes ('PFM Mode' on a Cypher)."""
    from afmformats.meta import DEF_ALL

    note = _igor2(path)["note"].decode("latin-1").replace("\n", "\r")
    modes = [line.split(":", 1)[1].strip().lower() for line in note.split("\r") if line.startswith("ImagingMode:")]
    try:
        for mode in modes:
            DEF_ALL["feedback mode"][2](mode)
    except ValueError:
        return True
    return False


def _same_wave(path):
    w, f = _igor2(path), read_wave5(path)
    assert f is not None
    assert (f.data.dtype, f.data.shape, f.data.strides) == (w["wData"].dtype, w["wData"].shape, w["wData"].strides)
    assert np.array_equal(f.data, w["wData"])
    assert f.note == w["note"]
    assert f.labels == [list(x) for x in w["labels"]]
    assert np.array_equal(f.sfA, w["wave_header"]["sfA"])


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_same_wave_and_afmformats_data_as_igor2(path):
    import afmformats

    _same_wave(path)
    if not _has_date(path):
        # afmformats refuses a note without Date (KeyError); afmforce reads the curve (issue 32 item 4)
        with pytest.raises(BaseException, match="Date"):
            afmformats.load_data(path)
        fast = afmformats_igor(path)[0]
        assert "date" not in fast.metadata and fast.metadata["spring constant"] > 0
        return
    if _mode_afmformats_refuses(path):
        # afmformats refuses the whole curve over its imaging mode (ValueError); afmforce leaves the
        # mode out and reads the curve: force = Defl x the note's spring constant, sample for sample
        with pytest.raises(ValueError, match="Invalid value"):
            afmformats.load_data(path)
        fast, wave = afmformats_igor(path)[0], _igor2(path)
        assert "feedback mode" not in fast.metadata
        labels = [x.decode() for x in wave["labels"][1] if x]
        defl = wave["wData"][:, labels.index("Defl")]
        assert np.array_equal(fast["force"], defl * fast.metadata["spring constant"])
        return
    ref, fast = afmformats.load_data(path)[0], afmformats_igor(path)[0]
    assert fast.columns == ref.columns
    for col in ref.columns:
        a, b = ref[col], fast[col]
        assert a.dtype == b.dtype and np.array_equal(a, b), col
    assert list(dict(fast.metadata).items()) == list(dict(ref.metadata).items())


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_loaded_curve_identical_to_the_afmformats_route(path, monkeypatch):
    """afmforce's RawCurve from the fast path equals the one built from afmformats.load_data."""
    fast = load(path)[0]
    if not _has_date(path) or _mode_afmformats_refuses(path):
        pytest.skip("afmformats cannot read this wave (no Date, or an imaging mode it refuses): no fallback "
                    "route to compare with")
    monkeypatch.setattr("afmforce.io.igor.afmformats_igor", lambda *a, **k: None)  # force the fallback
    slow = load(path)[0]
    for name in ("time", "piezo_nominal", "piezo_measured", "deflection_signal", "segment"):
        a, b = getattr(fast, name), getattr(slow, name)
        assert a.dtype == b.dtype and np.array_equal(a, b), name
    assert list(fast.metadata.items()) == list(slow.metadata.items())
    assert fast.deflection_unit == slow.deflection_unit


def _write(path, data, note=b"", labels=(), order="<", wtype=2, version=5):
    """An Igor binary wave v5: 2-D (columns = channels) with dimension labels of dimension 1."""
    data = np.asarray(data)
    dt = {2: "f4", 4: "f8", 0x10: "i2"}[wtype]
    body = np.asfortranarray(data.astype(order + dt)).tobytes(order="F")
    lab = b"".join(labels)
    wave = bytearray(320)
    struct.pack_into(order + "i", wave, 12, data.size)
    struct.pack_into(order + "h", wave, 16, wtype)
    struct.pack_into(order + "4i", wave, 68, *(list(data.shape) + [0] * (4 - data.ndim)))
    struct.pack_into(order + "4d", wave, 84, 1e-4, 1, 1, 1)
    head = struct.pack(order + "hhiiii4i4iiii", version, 0, 320 + len(body), 0, len(note), 0, 0, 0, 0, 0,
                       0, len(lab), 0, 0, 0, 0, 0)
    path.write_bytes(head + bytes(wave) + body + note + lab)


def _field(text: bytes) -> bytes:
    return text + b"\x00" * (32 - len(text))


@pytest.mark.parametrize("order", ["<", ">"])
@pytest.mark.parametrize("wtype", [2, 4, 0x10])
def test_written_variants_match_igor2(tmp_path, order, wtype):
    rng = np.random.default_rng(1)
    data = (rng.standard_normal((50, 3)) * 100).round()
    # an empty first field, a label running over two fields, one with bytes after its null
    labels = [_field(b""), b"A" * 32 + _field(b"B"), _field(b"Defl\x00junk"), _field(b"ZSnsr")]
    p = tmp_path / f"w{order == '>'}{wtype}.ibw"
    _write(p, data, note=b"Key:1\rOther:2\xe9\r", labels=labels, order=order, wtype=wtype)
    _same_wave(p)


def test_not_recognised_goes_to_afmformats(tmp_path):
    """Versions other than 5 and waves whose sizes do not add up are left to igor2/afmformats."""
    data = np.zeros((10, 3))
    p = tmp_path / "v2.ibw"
    _write(p, data, version=2)
    assert read_wave5(p) is None
    q = tmp_path / "cut.ibw"
    _write(q, data, note=b"x" * 40)
    q.write_bytes(q.read_bytes()[:-10])  # the note is cut short
    assert read_wave5(q) is None
    r = tmp_path / "nonote.ibw"  # a plain wave, but no note keys afmformats needs: afmformats decides
    _write(r, data, labels=[_field(b""), _field(b"Raw"), _field(b"Defl"), _field(b"ZSnsr")])
    assert read_wave5(r) is not None and afmformats_igor(r) is None


@pytest.mark.parametrize("mode, date", [("AC Mode", "2016-11-06"), ("PFM Mode", "2016-11-06")])
def test_descriptive_values_afmformats_refuses_are_left_out_not_the_curve(tmp_path, mode, date):
    """afmformats refuses a whole curve over a descriptive note value outside its vocabulary (an
    ImagingMode other than contact or force modulation); the fast path leaves
    that value out and reads the curve: force = Defl x SpringConstant, the rest as in the note."""
    import afmformats

    z = np.r_[np.linspace(0, 1e-6, 20), np.linspace(1e-6, 0, 20)]
    defl = np.r_[np.zeros(15), np.linspace(0, 5e-9, 10), np.zeros(15)]
    note = (f"Note: 1\rSpringConstant: 0.5\rInvOLS: 5e-08\rNumPtsPerSec: 2000\rImagingMode: {mode}\rDate: {date}\r"
            "Time: 10:00:00 AM\rMicroscopeModel: MFP3D\rTriggerChannel: DeflVolts\rTriggerPoint: 1\r"
            "InputTime: 0.02\rApproachVelocity: 1e-06\rRetractVelocity: 1e-06\rVersion: 16.05.193\r").encode()
    p = tmp_path / "odd.ibw"
    _write(p, np.c_[z, defl, z], note=note, labels=[_field(b""), _field(b"Raw"), _field(b"Defl"), _field(b"ZSnsr")],
           wtype=4)
    with pytest.raises(ValueError, match=mode.lower()):  # afmformats refuses the curve over its mode
        afmformats.load_data(p)
    fast = afmformats_igor(p)[0]
    np.testing.assert_array_equal(fast["force"], defl * 0.5)
    assert fast.metadata["spring constant"] == 0.5 and fast.metadata["sensitivity"] == 5e-8
    assert "feedback mode" not in fast.metadata and fast.metadata["date"] == date  # only the mode left out
    curve = load(p)[0]
    assert curve.metadata["spring_constant"] == 0.5 and curve.deflection_unit == "N"
