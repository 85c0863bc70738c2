"""Reader of Asylum Research ARDF force maps (``.ARDF``, MFP-3D and Cypher).

Layout (as described publicly by Matt Poss' MATLAB reader, "ARDF to MATLAB", MathWorks File
Exchange 80212, BSD, and a Python port of it by Carlota Carbajo, 2025; this module is written
from that description, no code is copied). Every record starts with a 16-byte header: CRC-32 (uint32),
the record's size in bytes including the header (uint32), a four-letter type, a uint32; all
numbers little-endian::

    ARDF                         at 0: the file's own header (16 bytes)
    FTOC                         at 16: table of contents (uint64 table size, uint32 entries,
                                 uint32 entry size 24): entries IMAG / VOLM / THMB + uint64 pointer
    TTOC                         at 16 + the FTOC's table size: entries TOFF (uint64 index,
                                 uint64 pointer) to TEXT records; the first is the main note
    TEXT                         uint32, uint32 length, then the note: "Key: value" lines (CR)
    VOLM (one per force volume)  a table, then its TTOC, then
      VDEF                       uint32 points (fast axis), uint32 lines (slow axis), ...
      VCHN ... VCHN              one per channel: 32 bytes of name (Raw, Defl, ZSnsr, ...)
      XDEF                       uint32, uint32 length, text
      VTOC                       entries VOFF (entry size 40): uint32, uint32, uint64, uint64
                                 pointer to the first VSET of each line (0: line not recorded)
      MLOV                       end of the volume's header
    per curve, in acquisition order along a line:
      VSET                       uint32 curve number, line, point, (pad), uint64 prev, next
      VNAM                       uint32 curve, line, point, name length, the curve's name
      VDAT (one per channel)     uint32 curve, line, point, n samples, type, three segment ends,
                                 two more; then n float32 samples
      XDAT                       optional; skipped

What this reader makes of it: one curve per VSET of the first volume, in the file's order
(``curve_index``); its grid cell is the VSET's own point and line (``map_x``, ``map_y``, of
``map_nx`` x ``map_ny`` = the VDEF's points x lines) and its position the cell's centre in the
scanned area (``FastScanSize`` x ``SlowScanSize`` of the note [m]). Channels: ``Defl`` is the
deflection in metres (the instrument's InvOLS applied: a user's ``sensitivity`` rescales it),
else a ``DeflV``/``DeflVolts`` channel in volts; ``Raw`` is the commanded piezo position
[m] (nominal) and ``ZSnsr`` the Z sensor [m] (measured). The three segment ends of the
deflection's VDAT split the curve (extend, retract, then the tail away from the surface, or a
dwell); each part is named from what z does in it (rises: approach, falls: retract, stays:
dwell), else the curve turns at the extreme of z. Note keys: ``SpringConstant`` [N/m],
``InvOLS`` [m/V], ``NumPtsPerSec`` [Hz], ``Velocity`` [m/s] (or ``ApproachVelocity`` and
``RetractVelocity`` when ``UseVelocity`` is 1), ``ThermalFrequency`` [Hz], ``ThermalQ``.

The file is never read whole: opening it reads the headers and one pointer per line; a curve
is read from its place (the record offsets of the line last read are kept, a few bytes a
point), so a map of any size is read in the memory of one line's offsets and one curve.
"""

from __future__ import annotations

import math
import os
import re
import struct
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ..errors import FileFormatError
from .curve import RawCurve
from ._meta import finalize_curve, missing_metadata, orient

__all__ = ["detect_ardf", "load_ardf", "ArdfFile", "count_curves", "parse_note"]

_HEAD = struct.Struct("<II4sI")          # crc, size, type, misc
_TOC = struct.Struct("<QII")             # table size, entries, entry size
_VSET = struct.Struct("<IIIIQQ")         # curve, line, point, pad, prev, next
_VDAT = struct.Struct("<IIIIIIIIII")     # curve, line, point, n, type, end0, end1, end2, -, -
#: Generous bounds on what a real file holds (a damaged size is refused before it is used).
MAX_GRID = 4096
MAX_CHANNELS = 64
MAX_SAMPLES = 50_000_000
MAX_NOTE = 16 * 2**20
_DEFL_M = ("Defl",)
_DEFL_V = ("DeflV", "DeflVolts")


def detect_ardf(path: Path) -> bool:
    """True if the file starts with the 16-byte ``ARDF`` record."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(16)
    except OSError:
        return False
    return len(head) == 16 and head[8:12] == b"ARDF"


def parse_note(text: str) -> dict[str, str]:
    """``"Key: value"`` lines of an Asylum note (CR, LF or CRLF) -> ``{key: value}`` (first wins)."""
    out: dict[str, str] = {}
    for line in re.split(r"\r\n|\r|\n", text):
        key, sep, value = line.partition(":")
        if sep and key.strip():
            out.setdefault(key.strip(), value.strip())
    return out


def _positive(note: Mapping[str, str], key: str) -> float | None:
    try:
        value = float(note[key])
    except (KeyError, ValueError):
        return None
    return value if math.isfinite(value) and value > 0 else None


class ArdfFile:
    """An open ARDF force map whose curves are read one at a time (:meth:`curve`; ``read`` is the
    same, for :func:`afmforce.io.map_curves.open_map`). ``note`` holds the main note's entries."""

    def __init__(self, path: str | os.PathLike, meta_override: Mapping[str, Any] | None = None, *,
                 require: bool = True) -> None:
        path = Path(path)
        self._require = require
        self.where = str(path)
        try:
            self._fh = open(path, "rb")
            self._size = path.stat().st_size
        except OSError as exc:
            raise FileFormatError(f"{self.where}: cannot read ({exc})") from None
        try:
            self._open(dict(meta_override or {}))
        except BaseException:
            self._fh.close()
            raise

    # -- records ---------------------------------------------------------------------------
    def _bytes(self, offset: int, n: int, what: str) -> bytes:
        if offset < 0 or offset + n > self._size:
            raise FileFormatError(f"{self.where}: the {what} at byte {offset} ({n} bytes) lies beyond the end of "
                                  f"the file ({self._size} bytes); the ARDF file is truncated or damaged")
        self._fh.seek(offset)
        data = self._fh.read(n)
        if len(data) != n:
            raise FileFormatError(f"{self.where}: the file ends inside the {what} at byte {offset}; truncated")
        return data

    def _record(self, offset: int, expect: str | tuple[str, ...] | None = None) -> tuple[str, int]:
        """(type, size) of the record at ``offset``; its whole extent checked against the file."""
        _, size, kind, _ = _HEAD.unpack(self._bytes(offset, 16, "record header"))
        name = kind.decode("latin-1")
        if expect is not None and name not in ((expect,) if isinstance(expect, str) else expect):
            wanted = " or ".join((expect,) if isinstance(expect, str) else expect)
            raise FileFormatError(f"{self.where}: expected an ARDF {wanted} record at "
                                  f"byte {offset}, found {name!r}; the file is damaged or not an ARDF force map")
        if size < 16 or offset + size > self._size:
            raise FileFormatError(f"{self.where}: ARDF {name!r} record at byte {offset} declares {size} bytes, beyond "
                                  f"the end of the file ({self._size} bytes); the file is truncated or damaged")
        return name, size

    def _table(self, offset: int, kind: str, entry: int) -> tuple[int, list[tuple[str, bytes]]]:
        """(table size, [(entry type, entry payload)]) of a table of contents of ``entry``-byte entries."""
        self._record(offset, kind)
        table, count, size = _TOC.unpack(self._bytes(offset + 16, 16, f"{kind} table"))
        if size != entry or table != 32 + count * size or offset + table > self._size:
            raise FileFormatError(f"{self.where}: ARDF {kind} table at byte {offset} is malformed ({count} entries "
                                  f"of {size} bytes in {table}); the file is damaged")
        raw = self._bytes(offset + 32, count * size, f"{kind} table")
        out = []
        for j in range(count):
            item = raw[j * size:(j + 1) * size]
            out.append((item[8:12].decode("latin-1"), item[16:]))
        return table, out

    def _text(self, offset: int) -> str:
        _, size = self._record(offset, "TEXT")
        _, length = struct.unpack("<II", self._bytes(offset + 16, 8, "TEXT record"))
        if length > min(size - 24, MAX_NOTE):
            raise FileFormatError(f"{self.where}: ARDF note at byte {offset} declares {length} characters in a "
                                  f"{size}-byte record; the file is damaged")
        return self._bytes(offset + 24, length, "note").decode("latin-1")

    # -- the header ------------------------------------------------------------------------
    def _open(self, meta_override: dict) -> None:
        where = self.where
        if self._size < 48:
            raise FileFormatError(f"{where}: {self._size} bytes, too short for an ARDF file")
        self._record(0, "ARDF")
        ftoc_size, ftoc = self._table(16, "FTOC", 24)
        pointers = [(kind, struct.unpack("<Q", data[:8])[0]) for kind, data in ftoc]
        _, ttoc = self._table(16 + ftoc_size, "TTOC", 32)
        texts = [struct.unpack("<QQ", data[:16])[1] for kind, data in ttoc if kind == "TOFF"]
        self.note = parse_note(self._text(texts[0])) if texts else {}
        volumes = [p for kind, p in pointers if kind == "VOLM"]
        if not volumes:
            raise FileFormatError(f"{where}: an ARDF file without a force volume (VOLM): an image, no force curve; "
                                  "save the force map as ARDF, or export its curves as .ibw")
        self._volume(volumes[0])
        self._meta = self._metadata(meta_override)

    def _volume(self, offset: int) -> None:
        where = self.where
        table, _ = self._table(offset, "VOLM", 24)
        ttoc, _ = self._table(offset + table, "TTOC", 32)
        at = offset + table + ttoc
        _, size = self._record(at, "VDEF")
        points, lines = struct.unpack("<II", self._bytes(at + 16, 8, "VDEF record"))
        if not (0 < points <= MAX_GRID and 0 < lines <= MAX_GRID):
            raise FileFormatError(f"{where}: ARDF grid of {points} x {lines} curves (VDEF) is not plausible; "
                                  "the file is damaged")
        self.nx, self.ny = points, lines
        at += size
        channels: list[str] = []
        while True:
            kind, size = self._record(at, ("VCHN", "XDEF"))
            if kind == "XDEF":
                at += size
                break
            channels.append(self._bytes(at + 16, 32, "channel name").split(b"\0")[0].decode("latin-1").strip())
            if len(channels) > MAX_CHANNELS:
                raise FileFormatError(f"{where}: more than {MAX_CHANNELS} channels in the force volume; damaged")
            at += size
        if not channels:
            raise FileFormatError(f"{where}: the ARDF force volume names no channel (VCHN)")
        self.channels = channels
        _, voff = self._table(at, "VTOC", 40)
        starts = []
        for kind, data in voff:
            if kind not in ("VOFF", "\0\0\0\0"):
                raise FileFormatError(f"{where}: unexpected {kind!r} entry in the force volume's line table (VTOC)")
            starts.append(struct.unpack("<Q", data[16:24])[0])
        self._lines = np.array([s for s in starts if s != 0], dtype=np.int64)  # 0: a line never recorded
        if self._lines.size == 0:
            raise FileFormatError(f"{where}: the ARDF force map holds no curve (every line pointer is 0: the map "
                                  "was stopped before its first line)")
        if self._lines.size > lines:
            raise FileFormatError(f"{where}: {self._lines.size} lines recorded in a map of {lines} lines; damaged")
        self._check_lines(len(channels))
        self._cache: tuple[int, np.ndarray] | None = None
        last = self._line_offsets(self._lines.size - 1)  # the last line may be partial (a stopped map)
        self.n_curves = int((self._lines.size - 1) * self.nx + last.size)

    def _check_lines(self, n_channels: int) -> None:
        """Refuse a line table whose lines cannot hold the curves it declares, before any is counted:
        each recorded line but the last (a stopped map's may be partial) holds ``nx`` curves of at least
        a VSET and one VDAT header per channel each, so its pointer must leave that many bytes before the
        next line's pointer (in the file, in any order: a map scanned downward) or the end of the file.
        A pointer repeated (a 68 kB file whose 1,000 pointers named its one line declared 999,001 curves)
        or pointing into another line (at a curve of the same map line) is refused here, naming the lines;
        reads a 48-byte VSET per line."""
        where, starts = self.where, self._lines.tolist()
        first: dict[int, int] = {}
        for j, p in enumerate(starts):
            if p in first:
                raise FileFormatError(f"{where}: the ARDF line table names byte {p} for recorded lines {first[p]} "
                                      f"and {j}; a line is stored once: the file is damaged")
            first[p] = j
        named: dict[int, int] = {}
        for j, p in enumerate(starts):  # each names a curve of its own line (a pointer into another is refused)
            self._record(p, "VSET")
            line = _VSET.unpack(self._bytes(p + 16, 32, "VSET record"))[1]
            if line in named:
                raise FileFormatError(f"{where}: recorded lines {named[line]} and {j} of the ARDF line table both "
                                      f"start at a curve of map line {line} (bytes {starts[named[line]]} and {p}): "
                                      "overlapping lines; the line table is damaged")
            named[line] = j
        least = _VSET.size + 16 + n_channels * (_VDAT.size + 16)  # the smallest curve a line can hold [bytes]
        ends = dict(zip(sorted(starts), sorted(starts)[1:] + [self._size]))
        for j, p in enumerate(starts):
            need = (self.nx if j < len(starts) - 1 else 1) * least
            if p + need > ends[p]:
                room = max(ends[p] - p, 0) // least
                to = "the end of the file" if ends[p] == self._size else f"the next line at byte {ends[p]}"
                raise FileFormatError(f"{where}: recorded line {j} of the ARDF force map starts at byte {p} and "
                                      f"leaves room for at most {room} of its {self.nx if j < len(starts) - 1 else 1}"
                                      f" curves before {to}; the line table is damaged")

    def _metadata(self, meta_override: dict) -> dict[str, Any]:
        where, note = self.where, self.note
        if "Defl" in self.channels:
            self._defl, self.deflection_unit = self.channels.index("Defl"), "m"
        elif (volts := next((c for c in _DEFL_V if c in self.channels), None)) is not None:
            self._defl, self.deflection_unit = self.channels.index(volts), "V"
        else:
            raise FileFormatError(f"{where}: no deflection channel (Defl, DeflV) among the force map's channels "
                                  f"({', '.join(self.channels)}); save the map with the deflection")
        position = [c for c in ("Raw", "ZSnsr", "LVDT", "Height") if c in self.channels]
        if not position:
            raise FileFormatError(f"{where}: no Z channel (Raw, ZSnsr) among the force map's channels "
                                  f"({', '.join(self.channels)}); save the map with the Z sensor")
        self._nominal = self.channels.index(position[0])
        self._measured = self.channels.index("ZSnsr") if "ZSnsr" in self.channels and position[0] != "ZSnsr" else None
        meta: dict[str, Any] = {"instrument": ("Asylum Research " + note.get("MicroscopeModel", "")).strip(),
                                "channels": "+".join(self.channels)}
        for key in ("SpringConstant", "InvOLS"):  # stated but impossible: say so, as the ibw reader does
            ours = "spring_constant" if key == "SpringConstant" else "sensitivity"
            if key in note and _positive(note, key) is None and ours not in meta_override:
                raise FileFormatError(f"{where}: the ARDF note's {key} is {note[key]!r}, not a positive number "
                                      f"(the {ours.replace('_', ' ')}); the map was saved uncalibrated: give "
                                      f"`{ours}`")
        # the ramp's speeds: with UseVelocity 1 the approach and retract speeds typed in, else the one
        # Velocity (2 x ForceDist x ForceScanRate) both ways; the unused ones keep stale values
        speeds = (("ApproachVelocity", "velocity"), ("RetractVelocity", "retract_velocity")) \
            if note.get("UseVelocity", "").strip() == "1" else (("Velocity", "velocity"), ("Velocity", "retract_velocity"))
        for key, ours in (("SpringConstant", "spring_constant"), ("InvOLS", "sensitivity"),
                          ("NumPtsPerSec", "sample_rate"), *speeds,
                          ("ThermalFrequency", "resonance_frequency"), ("ThermalQ", "quality_factor")):
            value = _positive(note, key)
            if value is not None:
                meta.setdefault(ours, value)
        if note.get("Date"):
            meta["date"] = " ".join(filter(None, (note.get("Date"), note.get("Time"))))
        self._scale = 1.0
        if self.deflection_unit == "m" and "sensitivity" in meta_override and "sensitivity" in meta:
            self._scale = float(meta_override["sensitivity"]) / meta["sensitivity"]  # Defl = volts x the file's InvOLS
        meta.update(meta_override)
        need = ["spring_constant"] + (["sensitivity"] if self.deflection_unit == "V" else [])
        missing = [k for k in need if k not in meta]
        if missing and self._require:
            raise missing_metadata(where, missing, what="the ARDF note stores")
        self._width = _positive(note, "FastScanSize") or _positive(note, "ScanSize")
        self._height = _positive(note, "SlowScanSize") or self._width
        meta.update(source_file=where, reader="asylum-ardf", format="Asylum Research ARDF force map",
                    map_nx=self.nx, map_ny=self.ny, position_channel=self.channels[self._nominal])
        if self._width:
            meta.update(map_width=self._width, map_height=self._height)
        return meta

    # -- curves ----------------------------------------------------------------------------
    def _line_offsets(self, j: int) -> np.ndarray:
        """Byte offsets of the VSET records of recorded line ``j`` (the last line read is kept)."""
        if self._cache is not None and self._cache[0] == j:
            return self._cache[1]
        at, found = int(self._lines[j]), []
        self._record(at, "VSET")
        line = _VSET.unpack(self._bytes(at + 16, 32, "VSET record"))[1]
        while at < self._size:  # to the end of the line's last curve: a truncated one is found here
            kind = self._bytes(at, 16, "record header")[8:12]
            if kind not in (b"VSET", b"VNAM", b"VDAT", b"XDAT"):
                break  # another part of the file (or padding) follows the curves
            _, size = self._record(at)
            if kind == b"VSET":
                if len(found) == self.nx or _VSET.unpack(self._bytes(at + 16, 32, "VSET record"))[1] != line:
                    break  # the next line follows
                found.append(at)
            at += size
        offsets = np.array(found, dtype=np.int64)
        self._cache = (j, offsets)
        return offsets

    def __len__(self) -> int:
        return self.n_curves

    def curve(self, i: int) -> RawCurve:
        """Curve ``i`` (file order: the recorded lines in turn, each along its points)."""
        where = self.where
        if not 0 <= i < self.n_curves:
            raise FileFormatError(f"{where}: no curve {i} (the file holds {self.n_curves})")
        j, k = divmod(i, self.nx)
        offsets = self._line_offsets(j)
        if k >= offsets.size:
            raise FileFormatError(f"{where}: line {j} of the force map holds {offsets.size} curves, not "
                                  f"{self.nx}; the file is damaged")
        at = int(offsets[k])
        _, size = self._record(at, "VSET")
        _, line, point, _, _, _ = _VSET.unpack(self._bytes(at + 16, 32, "VSET record"))
        at += size
        data: list[np.ndarray] = []
        ends = None
        while len(data) < len(self.channels):
            kind, size = self._record(at, ("VNAM", "VDAT", "XDAT"))
            if kind == "VDAT":
                head = _VDAT.unpack(self._bytes(at + 16, 40, "VDAT record"))
                n = head[3]
                if n > MAX_SAMPLES or 56 + 4 * n > size:
                    raise FileFormatError(f"{where}: curve {i}: a channel of {n} samples in a {size}-byte VDAT "
                                          "record; the file is damaged")
                data.append(np.frombuffer(self._bytes(at + 56, 4 * n, "curve data"), dtype="<f4").astype(float))
                if len(data) == self._defl + 1:
                    ends = head[5:8]
            at += size
        n = min(a.size for a in data)
        if n < 4:
            raise FileFormatError(f"{where}: curve {i} holds {n} samples; too few for a force curve")
        defl = data[self._defl][:n] * self._scale
        z_nom = data[self._nominal][:n]
        z_meas = data[self._measured][:n] if self._measured is not None else None
        seg = _segments(z_meas if z_meas is not None else z_nom, ends)
        zn, zm, sign = orient(z_nom, z_meas, seg)
        meta = dict(self._meta)
        rate = meta.get("sample_rate")
        if rate:
            time = np.arange(n) / rate
        else:
            time = np.arange(n, dtype=float)
            meta["time_is_sample_index"] = True
        meta.update(curve_index=i, map_x=int(point), map_y=int(line), position_sign=sign)
        if self._width and point < self.nx and line < self.ny:
            meta.update(position_x=(point + 0.5) * self._width / self.nx,
                        position_y=(line + 0.5) * self._height / self.ny)
        curve = RawCurve(time=time, piezo_nominal=zn, piezo_measured=zm, deflection_signal=defl, segment=seg,
                         metadata=meta, deflection_unit=self.deflection_unit)
        return finalize_curve(curve, f"{where}#{i}")

    read = curve

    def close(self) -> None:
        self._fh.close()

    def __enter__(self) -> "ArdfFile":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _segments(z: np.ndarray, ends) -> np.ndarray:
    """Segment codes from the VDAT's segment ends, each part named from its change of z (rises:
    approach, falls: retract, stays within a tenth of the ramp: dwell); without usable ends the
    curve turns at the extreme of z. The first part is the extend: it fixes which sign of dz
    approaches."""
    n = len(z)
    span = float(np.ptp(z)) or 1.0
    cuts = [0] + [int(e) for e in (ends or ()) if 0 < int(e) < n] + [n]
    if all(a < b for a, b in zip(cuts, cuts[1:])) and len(cuts) >= 3:
        seg = np.full(n, 2, dtype=np.int8)
        first = None
        for a, b in zip(cuts, cuts[1:]):
            dz = float(z[b - 1] - z[a])
            if abs(dz) < 0.1 * span:
                continue
            first = np.sign(dz) if first is None else first
            seg[a:b] = 0 if np.sign(dz) == first else 1
        if np.any(seg == 0) and np.any(seg == 1):
            return seg
    turn = int(np.argmax(z)) if z[n // 2] > z[0] else int(np.argmin(z))
    turn = min(max(turn, 1), n - 1)
    return np.where(np.arange(n) < turn, 0, 1).astype(np.int8)


def count_curves(path: Path) -> int:
    """Curves in an ARDF force map, from its headers and line table alone."""
    with ArdfFile(path, require=False) as f:
        return f.n_curves


def load_ardf(path: Path, *, meta_override: Mapping[str, Any] | None = None,
              callback: Callable | None = None) -> list[RawCurve]:
    """Read every curve of an ARDF force map (see the module docstring); a map of many curves is better
    analysed through :func:`afmforce.io.map_curves.open_map`, one curve at a time."""
    with ArdfFile(path, meta_override) as f:
        out = []
        for i in range(len(f)):
            out.append(f.curve(i))
            if callback is not None:
                callback((i + 1) / len(f))
    return out
