"""Fast path for Asylum ``.ibw`` files: the Igor binary wave (version 5) read with numpy.

afmformats reads Asylum curves through igor2, whose generic structure parser spends
~20 ms on a 30 kB wave (most of the time afmforce needs to load and analyse the
curve). A plain version-5 numeric wave needs none of that machinery: a 64-byte
``BinHeader5`` gives the section sizes, the 320-byte ``WaveHeader5`` the type and
dimensions, and the data follow as one block (``numpy.frombuffer``, Fortran order,
the file's byte order). :func:`read_wave5` returns exactly what igor2 returns for the
fields afmformats uses (``wData``, ``note``, ``labels``; and ``sfA``), and
:func:`afmformats_igor` builds from them the same
:class:`afmformats.mod_force_distance.AFMForceDistance` that ``afmformats.load_data``
builds (the mapping of afmformats 0.18's ``fmt_igor.load_igor``, kept line for line).
A test checks arrays and metadata against afmformats/igor2 on every ``.ibw`` file in
``tests/data`` (and ``shared/data/real`` when present).

afmformats stays the reader: anything this path does not recognise (versions 1-3,
text or complex waves, a formula without data, sizes that do not add up, a wave note
without the keys afmformats maps) returns ``None`` and the file goes through
``afmformats.load_data`` as before, which also gives the error messages.
"""

from __future__ import annotations

import pathlib
import struct
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

__all__ = ["IgorWave5", "read_wave5", "afmformats_igor"]

#: Numeric wave types of TN003 (real only; complex and text waves go to igor2).
_TYPES = {2: np.float32, 4: np.float64, 8: np.int8, 0x10: np.int16, 0x20: np.int32,
          0x48: np.uint8, 0x50: np.uint16, 0x60: np.uint32}
_BIN = struct.Struct("hhiiii4i4iiii")  # BinHeader5 with the version field (64 bytes)
_WAVE_HEADER = 320  # WaveHeader5


@dataclass(frozen=True)
class IgorWave5:
    """The fields of a version-5 Igor binary wave afmforce uses, as igor2 returns them.

    Attributes
    ----------
    data : ndarray
        ``wData``: shape from ``nDim`` (dimensions > 0), Fortran order, the file's dtype and
        byte order (read-only view of the file's bytes).
    note : bytes
        The wave note, all ``noteSize`` bytes.
    labels : list of list of bytes
        Dimension labels per dimension (igor2's grouping: 32-byte fields, nulls removed).
    sfA : ndarray
        Sample step per dimension (``x = sfA * i + sfB``) [the dimension's unit].
    """

    data: np.ndarray
    note: bytes
    labels: list
    sfA: np.ndarray


def _labels(block: bytes, sizes) -> list:
    """igor2's ``DynamicLabelsField.post_unpack``: each 32-byte field loses its null bytes and
    ends a label when it held one (a field without a null continues into the next)."""
    out, start = [], 0
    for size in sizes:
        end = start + size
        if end > start:
            labels = [b""]
            for i in range(size // 32):
                chunk = block[start + 32 * i: start + 32 * (i + 1)]
                labels[-1] += chunk.replace(b"\x00", b"")
                if b"\x00" in chunk:
                    labels.append(b"")
            labels.pop(-1)
            start = end
        else:
            labels = []
        out.append(labels)
    return out


def read_wave5(path: str | Path) -> IgorWave5 | None:
    """A plain numeric version-5 Igor binary wave, or ``None`` when it is anything else.

    The byte order is igor2's rule: the version read in the machine's order, and the
    other order when its low byte is zero.
    """
    with open(path, "rb") as fh:
        raw = fh.read()
    if len(raw) < 64 + _WAVE_HEADER:
        return None
    native = "<" if sys.byteorder == "little" else ">"
    version = struct.unpack(native + "h", raw[:2])[0]
    order = native if version & 0xFF else {"<": ">", ">": "<"}[native]
    head = struct.unpack(order + _BIN.format, raw[:64])
    version, wfm, formula, note, data_units = head[0], head[2], head[3], head[4], head[5]
    dim_units, dim_labels, s_indices = head[6:10], head[10:14], head[14]
    if version != 5 or s_indices or min(head[2:15]) < 0:
        return None
    wh = raw[64:64 + _WAVE_HEADER]
    npnts, wtype = struct.unpack(order + "ih", wh[12:18])
    ndim = struct.unpack(order + "4i", wh[68:84])
    sfa = np.array(struct.unpack(order + "4d", wh[84:116]))
    dtype = _TYPES.get(wtype)
    size = wfm - _WAVE_HEADER
    if dtype is None or npnts <= 0:
        return None
    dtype = np.dtype(dtype).newbyteorder(order)
    shape = [n for n in ndim if n > 0] or [0]
    if size != npnts * dtype.itemsize or int(np.prod(shape)) != npnts:
        return None
    pos = 64 + _WAVE_HEADER
    data = np.ndarray(shape=shape, dtype=dtype, buffer=raw[pos:pos + size], order="F")
    pos += size + formula
    note_b = raw[pos:pos + note]
    pos += note + data_units + sum(dim_units)
    block = raw[pos:pos + sum(dim_labels)]
    if len(note_b) != note or len(block) != sum(dim_labels):
        return None  # truncated: igor2 and afmformats say what is wrong
    return IgorWave5(data, note_b, _labels(block, dim_labels), sfa)


#: descriptive note values afmformats validates (and refuses the whole curve over); never calibration
_DESCRIPTIVE = ("feedback mode", "instrument", "software version", "date", "time")


def _afmformats_accepts(key: str, value: Any) -> bool:
    """Does afmformats' metadata vocabulary accept this value? Its feedback modes ('contact',
    'force-modulation') lack modes Asylum writes in a force curve's ``ImagingMode`` ('PFM Mode' on a
    Cypher, 'AC Mode'), and afmformats refuses the whole curve over such a descriptive value
    (``ValueError``); the value is left out of the metadata instead (the curve does not depend on it)."""
    from afmformats.meta import DEF_ALL

    try:
        DEF_ALL[key][2](value)
    except (KeyError, ValueError, TypeError):
        return False
    return True


def afmformats_igor(path: str | Path, callback: Callable | None = None,
                    calibration: dict[str, float] | None = None) -> list | None:
    """What ``afmformats.load_data(path)`` returns for an Asylum ``.ibw`` force curve, from
    :func:`read_wave5` instead of igor2 (``None``: not recognised; use afmformats).

    ``calibration`` (``{"SpringConstant": k [N/m], "InvOLS": s [m/V]}``) stands in for note keys
    the wave lacks (the user's values); a note key, when present, is used as afmformats uses it.

    The body is afmformats 0.18.7's ``formats/fmt_igor.py:load_igor`` (metadata keys,
    note parsing, label lookup, force = Defl x spring constant), then the
    ``AFMForceDistance`` that ``load_data`` wraps it in with the recipe's format name.
    """
    from afmformats.mod_force_distance import AFMForceDistance

    wave = read_wave5(path)
    if wave is None or wave.data.ndim != 2:
        return None
    wdata = wave.data
    notes = {}
    for line in str(wave.note).split("\\r"):  # afmformats splits the bytes' repr, as igor2 gives bytes
        if line.count(":"):
            key, val = line.split(":", 1)
            notes[key] = val.strip()
    # afmformats reads every key below and refuses a wave whose note lacks one (KeyError: 'Date' on
    # waves exported from ARDF force maps). Only the spring constant is needed to read the curve
    # (Defl is in metres); a missing note key leaves its metadata out (a user gives it).
    try:
        metadata: dict[str, Any] = {}
        metadata["imaging mode"] = "force-distance"
        if "ImagingMode" in notes:
            metadata["feedback mode"] = notes["ImagingMode"].lower()
        if "NumPtsPerSec" in notes:
            metadata["rate approach"] = float(notes["NumPtsPerSec"])
            metadata["rate retract"] = float(notes["NumPtsPerSec"])
        cal = dict(calibration or {})
        if "InvOLS" in notes or "InvOLS" in cal:
            metadata["sensitivity"] = float(notes["InvOLS"]) if "InvOLS" in notes else float(cal["InvOLS"])
        if notes.get("TriggerChannel") == "Force" and "TriggerPoint" in notes:
            metadata["setpoint"] = float(notes["TriggerPoint"])
        metadata["spring constant"] = (float(notes["SpringConstant"]) if "SpringConstant" in notes
                                       else float(cal["SpringConstant"]))
        for key, name in (("InputTime", "duration"),):
            if key in notes:
                metadata[name] = float(notes[key])
        metadata["enum"] = 1
        for key, name in (("ApproachVelocity", "speed approach"), ("RetractVelocity", "speed retract")):
            if key in notes:
                metadata[name] = float(notes[key])
        for key, name in (("MicroscopeModel", "instrument"),):
            if key in notes:
                metadata[name] = notes[key]
        metadata["software"] = "Asylum Research"
        for key, name in (("Version", "software version"), ("Date", "date")):
            if key in notes:
                metadata[name] = notes[key]
        metadata["path"] = pathlib.Path(path)
        metadata["point count"] = wdata.shape[0]
        if "Time" in notes:
            metadata["time"] = notes["Time"]
    except (KeyError, ValueError):
        return None  # no calibration in the note (or not a number): afmformats says what is wrong
    for key in _DESCRIPTIVE:
        if key in metadata and not _afmformats_accepts(key, metadata[key]):
            del metadata[key]
    labels = [li.decode() for ll in wave.labels for li in ll if li]
    if len(labels) != wdata.shape[1]:
        return None
    data = {}
    for pkey in ["Raw", "Height"]:
        if pkey in labels:
            data["height (piezo)"] = -wdata[:, labels.index(pkey)]
            break
    for mkey in ["ZSnsr", "ZSensor"]:
        if mkey in labels:
            data["height (measured)"] = -wdata[:, labels.index(mkey)]
            break
    for fkey in ["Defl", "Deflection"]:
        if fkey in labels:
            data["force"] = wdata[:, labels.index(fkey)] * metadata["spring constant"]
            break
    if "height (piezo)" not in data or "force" not in data:
        return None
    data["segment"] = np.zeros(wdata.shape[0], dtype=np.uint8)
    metadata["z range"] = np.ptp(data["height (piezo)"])
    metadata["format"] = "Asylum Research (binarywave)"  # load_data: "<maker> (<descr>)" of the recipe
    if callback is not None:
        callback(1)
    return [AFMForceDistance(data=data, metadata=metadata, diskcache=False)]
