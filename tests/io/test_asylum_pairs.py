"""Asylum force curves saved as one Igor wave per channel (``...Point0000Defl.ibw`` with
``...Point0000ZSnsr.ibw``): read together (issue 14 item 4). The waves are written here
(a minimal Igor binary wave version 5 writer) with known content."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest

from afmforce.errors import FileFormatError, MissingMetadataError
from afmforce.io import load


def write_ibw(path: Path, data: np.ndarray, note: str, step: float = 1e-4, name: str = "wave") -> None:
    """Igor binary wave v5, one dimension, float32, little endian (BinHeader5 + WaveHeader5)."""
    data = np.asarray(data, dtype="<f4")
    note_b = note.encode("latin-1")
    wave = bytearray(320)
    struct.pack_into("<i", wave, 12, data.size)            # npnts
    struct.pack_into("<h", wave, 16, 2)                    # type NT_FP32
    struct.pack_into("<h", wave, 26, 1)                    # whVersion
    wave[28:28 + len(name)] = name.encode()                # bname
    struct.pack_into("<4i", wave, 68, data.size, 0, 0, 0)  # nDim
    struct.pack_into("<4d", wave, 84, step, 1, 1, 1)       # sfA
    head = struct.pack("<hhiiii4i4iiii", 5, 0, 320 + data.nbytes, 0, len(note_b), 0, 0, 0, 0, 0, 0, 0, 0, 0,
                       0, 0, 0)
    assert len(head) == 64
    path.write_bytes(head + bytes(wave) + data.tobytes() + note_b)


N_APP = 300


def _pair(folder: Path, note: str, signal: str = "Defl"):
    z = np.concatenate([np.linspace(0, 1e-6, N_APP), np.linspace(1e-6, 0, N_APP)])  # ZSnsr [m]
    defl = np.clip(z - 0.8e-6, 0, None) * 0.5 - 2e-9 * np.exp(-((z - 0.7e-6) / 2e-8) ** 2)
    values = defl if signal == "Defl" else defl / 40e-9
    write_ibw(folder / f"Map0001Point0000{signal}.ibw", values, note)
    write_ibw(folder / "Map0001Point0000ZSnsr.ibw", z, note)
    return z.astype("f4").astype(float), values.astype("f4").astype(float)


NOTE = f"SpringConstant:0.12\rInvOLS:4e-08\rNumPtsPerSec:5000\rThermalFrequency:70000\rIndexes:0,{N_APP},{2 * N_APP - 1}\r"


def test_pair_reads_as_one_curve(tmp_path):
    z, defl = _pair(tmp_path, NOTE)
    for name in ("Map0001Point0000Defl.ibw", "Map0001Point0000ZSnsr.ibw"):  # either file gives the curve
        c = load(tmp_path / name)[0]
        assert c.deflection_unit == "m" and len(c) == 2 * N_APP
        np.testing.assert_allclose(c.deflection_signal, defl, rtol=1e-6)
        np.testing.assert_allclose(np.abs(c.piezo_nominal), z, rtol=1e-6)
        assert (c.approach.sum(), c.retract.sum()) == (N_APP, N_APP)
        md = c.metadata
        assert md["spring_constant"] == 0.12 and md["sensitivity"] == 4e-8 and md["sample_rate"] == 5000
        assert md["resonance_frequency"] == 70000
        assert c.time[1] == pytest.approx(1 / 5000)


def test_pair_without_k_asks_for_it(tmp_path):
    _pair(tmp_path, f"NumPtsPerSec:5000\rIndexes:0,{N_APP},{2 * N_APP - 1}\r", signal="Raw")
    with pytest.raises(MissingMetadataError, match="give `spring_constant` and `sensitivity`"):
        load(tmp_path / "Map0001Point0000Raw.ibw")
    c = load(tmp_path / "Map0001Point0000Raw.ibw", meta_override={"spring_constant": 0.1, "sensitivity": 40e-9})[0]
    assert c.deflection_unit == "V" and c.metadata["spring_constant"] == 0.1


def test_user_sensitivity_rescales_the_metres(tmp_path):
    _, defl = _pair(tmp_path, NOTE)
    c = load(tmp_path / "Map0001Point0000Defl.ibw", meta_override={"sensitivity": 8e-8})[0]
    np.testing.assert_allclose(c.deflection_signal, defl * 2, rtol=1e-6)


def test_lone_channel_says_what_is_missing(tmp_path):
    _pair(tmp_path, NOTE)
    (tmp_path / "Map0001Point0000ZSnsr.ibw").unlink()
    with pytest.raises(FileFormatError, match="Point0000Defl.ibw: one channel.*ZSnsr.ibw together"):
        load(tmp_path / "Map0001Point0000Defl.ibw")


DATA = Path(__file__).resolve().parents[1] / "data"


def _real_pair(folder: Path, spring: str | None = None, invols: str | None = None):
    """The real single wave ``asylum-mfp3d_SiN-tip_air.ibw`` split into its ``Defl`` and ``ZSnsr`` waves
    (one per channel, as the instrument saves them), its note copied with ``SpringConstant`` / ``InvOLS``
    replaced by the given texts. Returns the note's own (spring constant, InvOLS) read independently."""
    from afmforce.io.ibw_wave import read_wave5

    wave = read_wave5(DATA / "asylum-mfp3d_SiN-tip_air.ibw")
    labels = [x.decode() for x in wave.labels[1] if x]
    note = wave.note.decode("latin-1")
    entries = dict(line.split(":", 1) for line in note.split("\r") if ":" in line)
    stated = float(entries["SpringConstant"]), float(entries["InvOLS"])
    for key, text in (("SpringConstant", spring), ("InvOLS", invols)):
        if text is not None:
            old = f"\r{key}:{entries[key]}\r"      # every line of it (the note states it twice)
            assert note.count(old) >= 1
            note = note.replace(old, f"\r{key}: {text}\r")
    for channel in ("Defl", "ZSnsr"):
        write_ibw(folder / f"X60Point0000{channel}.ibw", wave.data[:, labels.index(channel)], note, step=1 / 2000)
    return stated


def test_real_pair_reads_the_notes_calibration(tmp_path):
    k, invols = _real_pair(tmp_path)
    md = load(tmp_path / "X60Point0000Defl.ibw")[0].metadata
    assert (md["spring_constant"], md["sensitivity"]) == (k, invols) == (1.1841, 4.499e-08)


@pytest.mark.parametrize("key, field, value", [("spring", "spring_constant", "-1.1841"),
                                               ("spring", "spring_constant", "0"),
                                               ("invols", "sensitivity", "-4.499e-08"),
                                               ("invols", "sensitivity", "0")])
def test_impossible_note_calibration_is_refused_like_every_reader(tmp_path, key, field, value):
    """A note's SpringConstant or InvOLS <= 0 is refused (FileFormatError naming the quantity), as the
    single-wave path and the Bruker/JPK readers refuse one (finalize_curve), not dropped as if absent."""
    _real_pair(tmp_path, **{key: value})
    with pytest.raises(FileFormatError, match=f"{field}.*positive.*`{field}`"):
        load(tmp_path / "X60Point0000Defl.ibw")


def test_user_spring_constant_replaces_an_impossible_one(tmp_path):
    _real_pair(tmp_path, spring="-1.1841")
    c = load(tmp_path / "X60Point0000ZSnsr.ibw", meta_override={"spring_constant": 0.9})[0]
    assert c.metadata["spring_constant"] == 0.9 and c.metadata["sensitivity"] == 4.499e-08


def test_user_sensitivity_cannot_rescale_metres_from_an_impossible_invols(tmp_path):
    """Defl [m] was computed with the note's InvOLS: a user's sensitivity rescales it by their ratio,
    which a zero or negative InvOLS cannot give (refused, as the single-wave path's rescale_force)."""
    _real_pair(tmp_path, invols="0")
    with pytest.raises(FileFormatError, match="InvOLS.*cannot rescale.*sensitivity"):
        load(tmp_path / "X60Point0000Defl.ibw", meta_override={"sensitivity": 4e-8})
