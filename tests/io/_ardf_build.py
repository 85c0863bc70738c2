"""Build an Asylum ARDF force map byte by byte, for the tests of :mod:`afmforce.io.ardf`.

Written with plain ``struct`` from the public description of the layout (Matt Poss, "ARDF to
MATLAB", MathWorks File Exchange 80212), without afmforce: every record a 16-byte header (CRC-32,
size, four-letter type, a number), tables of contents FTOC / TTOC / VOLM / VTOC, the main note in
a TEXT record, the volume's VDEF (grid), VCHN (channels), XDEF, VTOC (one pointer per line), MLOV,
then per curve VSET, VNAM, one VDAT per channel (float32) and an XDAT.

No public ARDF file under an MIT-compatible licence was found (issue text: PyFMlab_DyNaMo's
``ForceMap22.ARDF`` is not in its repository; gnezd/ARDF_read's test file has no licence), so the
curves written are real: the one curve of ``asylum-ibw_no-date_ForceMap.ibw`` (tests/data/corpus),
itself exported from an ARDF force map of an MFP-3D, channels Raw, Defl, ZSnsr, with its wave note
as the map's note.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

CORPUS = Path(__file__).resolve().parents[1] / "data" / "corpus"
SOURCE = CORPUS / "asylum-ibw_no-date_ForceMap.ibw"


def source_curve() -> tuple[np.ndarray, str]:
    """(samples x 3 array Raw, Defl, ZSnsr [m], wave note) of the real curve, read with ``struct``
    and numpy from the Igor v5 header (little-endian, float32 data after the 384-byte header)."""
    raw = SOURCE.read_bytes()
    assert struct.unpack("<h", raw[:2])[0] == 5
    wfm, formula, note = struct.unpack("<iii", raw[4:16])
    npnts = struct.unpack("<i", raw[64 + 12:64 + 16])[0]
    ndim = struct.unpack("<4i", raw[64 + 68:64 + 84])
    assert ndim[1] == 3 and ndim[0] * 3 == npnts
    data = np.frombuffer(raw, dtype="<f4", count=npnts, offset=64 + 320).reshape(3, ndim[0]).T
    text = raw[64 + wfm + formula:64 + wfm + formula + note].decode("latin-1")
    return data.astype(np.float32), text


def _head(kind: bytes, size: int, misc: int = 0) -> bytes:
    return struct.pack("<II4sI", 0, size, kind, misc)


def _pad(b: bytes) -> bytes:
    return b + b"\0" * (-len(b) % 4)


def _toc(kind: bytes, entries: list[bytes], entry: int) -> bytes:
    for e in entries:
        assert len(e) == entry
    return _head(kind, 32) + struct.pack("<QII", 32 + len(entries) * entry, len(entries), entry) + b"".join(entries)


def _text(note: str) -> bytes:
    body = note.encode("latin-1")
    rec = struct.pack("<II", 0, len(body)) + body
    return _pad(_head(b"TEXT", 16 + len(_pad(rec))) + rec)


def build_ardf(path: Path, *, nx: int = 4, ny: int = 3, lines_done: int | None = None, last_line: int | None = None,
               note: str | None = None, step: float = 20e-9, channels=("Raw", "Defl", "ZSnsr"),
               ends: tuple[int, int, int] | None = None) -> dict:
    """Write a force map of ``nx`` x ``ny`` curves of the real curve; returns what was written.

    Curve (x, y) is the real curve with z (Raw and ZSnsr) shifted by ``step`` x (x + y) [m]: a
    tilted sample. ``lines_done`` lines are recorded (a stopped map: the others' pointers are 0),
    the last of them with ``last_line`` points. ``ends`` are the VDAT's segment ends (default: the
    note's ``Indexes`` 224, 1232, 1260)."""
    data, src_note = source_curve()
    column = {"Raw": 0, "Defl": 1, "ZSnsr": 2, "DeflV": 1}
    lines_done = ny if lines_done is None else lines_done
    curves = []
    for y in range(lines_done):
        for x in range(nx if (y < lines_done - 1 or last_line is None) else last_line):
            cols = {}
            for c in channels:
                col = data[:, column[c]].astype(np.float64)
                cols[c] = col + step * (x + y) if c in ("Raw", "ZSnsr") else col
            curves.append((x, y, cols))
    return write_ardf(path, curves, nx=nx, ny=ny, note=src_note if note is None else note,
                      ends=ends or (224, 1232, 1260))


def write_ardf(path: Path, curves, *, nx: int, ny: int, note: str, ends: tuple[int, int, int]) -> dict:
    """Write ``curves`` (``[(x, y, {channel: samples})]`` in acquisition order, line by line) as an
    ARDF force map of ``nx`` x ``ny`` points; lines without a curve get a 0 pointer."""
    channels = list(curves[0][2])
    head = _head(b"ARDF", 16)
    ftoc_size = 32 + 2 * 24
    ttoc_at = 16 + ftoc_size
    text_at = ttoc_at + 32 + 32
    text = _text(note)
    volm_at = text_at + len(text)
    volm = _toc(b"VOLM", [_head(b"NEXT", 24) + struct.pack("<Q", 0)], 24)
    vttoc = _toc(b"TTOC", [], 32)
    vdef = _head(b"VDEF", 16 + 8 + 144 + 32 + 8) + struct.pack("<II", nx, ny) + b"\0" * 144 \
        + b"Force".ljust(32, b"\0") + b"\0" * 8
    vchn = b"".join(_head(b"VCHN", 80) + c.encode().ljust(32, b"\0") + b"\0" * 32 for c in channels)
    xtext = _pad(b"Defl;ZSnsr")
    xdef = _head(b"XDEF", 24 + len(xtext)) + struct.pack("<II", 0, len(xtext)) + xtext
    vtoc_at = volm_at + len(volm) + len(vttoc) + len(vdef) + len(vchn) + len(xdef)
    vtoc_len = 32 + ny * 40
    mlov = _head(b"MLOV", 16)
    at = vtoc_at + vtoc_len + len(mlov)

    body, starts, written = [], {}, []
    for i, (x, y, cols) in enumerate(curves):
        starts.setdefault(y, at)
        name = _pad(f"Line{y:04d}Point{x:04d}".encode())
        vset = _head(b"VSET", 48) + struct.pack("<IIIIQQ", i, y, x, 0, 0, 0)
        vnam = _head(b"VNAM", 32 + len(name)) + struct.pack("<IIII", i, y, x, len(name)) + name
        chans, stored = [], {}
        for c in channels:
            col = np.asarray(cols[c], dtype="<f4")
            stored[c] = col
            chans.append(_head(b"VDAT", 56 + 4 * col.size) + struct.pack("<IIIIIIIIII", i, y, x, col.size, 0, *ends, 0, 0)
                         + col.tobytes())
        xdat = _head(b"XDAT", 24) + b"\0" * 8
        rec = vset + vnam + b"".join(chans) + xdat
        body.append(rec)
        at += len(rec)
        written.append({"x": x, "y": y, "columns": stored})
    vtoc = _head(b"VTOC", 32) + struct.pack("<QII", vtoc_len, ny, 40) + b"".join(
        _head(b"VOFF", 40) + struct.pack("<IIQQ", 0, y, 0, starts.get(y, 0)) for y in range(ny))
    ftoc = _toc(b"FTOC", [_head(b"VOLM", 24) + struct.pack("<Q", volm_at), b"\0" * 24], 24)
    ttoc = _toc(b"TTOC", [_head(b"TOFF", 32) + struct.pack("<QQ", 1, text_at)], 32)
    out = head + ftoc + ttoc + text + volm + vttoc + vdef + vchn + xdef + vtoc + mlov + b"".join(body)
    assert len(out) == at
    Path(path).write_bytes(out)
    return {"nx": nx, "ny": ny, "curves": written, "note": note, "size": len(out)}
