r"""The Nanosurf ``.nid`` container: an INI-like text header, ``#!``, then binary data blocks.

Nanosurf's control software (easyScan 2, C3000 for FlexAFM, CoreAFM; DriveAFM's Studio writes
``.nhf`` instead) saves images, force spectroscopy and thermal tunes in one layout::

    [DataSet]                          the groups (frames) and their channels, in data order
    GroupCount=2
    Gr0-Name=Spec forward              Gr<g>-Ch<c>=DataSet-<g>:<c>: one block per listed channel
    Gr0-Ch0=DataSet-0:0
    ...
    [DataSet-0:0]                      one section per block
    Points=1024  Lines=100             a block holds Lines rows of Points samples
    Frame=Spec forward
    Dim2Name=Deflection  Dim2Unit=N    the channel and its unit
    Dim2Min=-1.99e-06  Dim2Range=3.98e-06
    LineDim<i>Points=980               spectroscopy: the samples row i really holds
    SaveBits=32  SaveSign=Signed  SaveOrder=Intel
    ...
    #!<binary blocks, in the order of the [DataSet] channel list>

A sample's value is ``Dim2Min + Dim2Range * (n / 2**SaveBits + 1/2)`` for a signed integer n
(``Dim2Min + Dim2Range * n / 2**SaveBits`` for an unsigned one). The blocks fill the file's end,
so the data start at ``file size - sum of block sizes`` and the two bytes before it are ``#!``
(a shorter file is truncated). This description follows Nanosurf's own MIT-licensed reader
NSFopen (github.com/syrupface/NSFopen, ``NSFopen/read/read.py``) and was checked on its example
files; this module is afmforce's own code.

This module reads the container only (laws layer): the thermal-tune reader is
:func:`afmforce.calibration.spectrum.read_nid_spectrum`, the force-curve reader
:mod:`afmforce.io.nanosurf`.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import FileFormatError

__all__ = ["NidFile", "NidBlock", "read_nid", "is_nid", "si_value", "typed_value"]

#: the first bytes of every .nid file
MAGIC = b"[DataSet]"
#: the largest header afmforce reads (real headers: 2-150 kB)
MAX_HEADER = 32 * 2**20


@dataclass(frozen=True)
class NidBlock:
    """One data block: a channel of a frame (``Spec forward`` / ``Deflection``)."""

    name: str            # its section, "DataSet-0:0"
    frame: str           # "Spec forward", "Scan forward", "Spectrum FFT", ...
    channel: str         # Dim2Name: "Deflection", "Z-Axis Sensor", ...
    unit: str            # Dim2Unit
    points: int
    lines: int
    bits: int
    offset: int          # where its samples start in the file [bytes]
    header: dict         # its section, as text

    @property
    def nbytes(self) -> int:
        return self.points * self.lines * self.bits // 8


def is_nid(head: bytes) -> bool:
    """Does this start of a file look like a Nanosurf .nid (``[DataSet]`` then ``Version=`` and
    ``GroupCount=``)?"""
    head = head.lstrip(b"\xef\xbb\xbf")
    return head.startswith(MAGIC) and b"GroupCount=" in head[:4096]


def _sections(text: str) -> dict[str, dict[str, str]]:
    out: dict[str, dict[str, str]] = {}
    current: dict[str, str] | None = None
    for line in text.splitlines():
        s = line.strip()
        if s.startswith("[") and s.endswith("]"):
            current = out.setdefault(s[1:-1], {})
        elif current is not None and "=" in s:
            key, _, value = s.partition("=")
            current.setdefault(key, value.strip())
    return out


@dataclass(frozen=True)
class NidFile:
    """A parsed .nid: its header sections (text) and its data blocks (where they lie)."""

    path: str
    sections: dict
    blocks: tuple

    def frames(self) -> list[str]:
        """The frames (groups) the file holds, in order."""
        return list(dict.fromkeys(b.frame for b in self.blocks))

    def block(self, frame: str, channel: str) -> NidBlock | None:
        """The block of ``frame`` and ``channel`` (case-insensitive), or None."""
        for b in self.blocks:
            if b.frame.lower() == frame.lower() and b.channel.lower() == channel.lower():
                return b
        return None

    def values(self, block: NidBlock) -> np.ndarray:
        """The block's samples in its unit, ``lines x points`` [Dim2Unit]."""
        with open(self.path, "rb") as fh:
            fh.seek(block.offset)
            raw = fh.read(block.nbytes)
        if len(raw) != block.nbytes:
            raise FileFormatError(f"{self.path}: the file ends inside block {block.name}; truncated")
        h = block.header
        signed = h.get("SaveSign", "Signed").lower() != "unsigned"
        order = ">" if h.get("SaveOrder", "Intel").lower() == "motorola" else "<"
        n = np.frombuffer(raw, dtype=f"{order}{'i' if signed else 'u'}{block.bits // 8}").astype(float)
        low, span = _number(h, "Dim2Min", self.path, block.name), _number(h, "Dim2Range", self.path, block.name)
        scaled = n / 2.0 ** block.bits + (0.5 if signed else 0.0)
        return (low + span * scaled).reshape(block.lines, block.points)


def _number(entries: dict, key: str, path: str, where: str) -> float:
    try:
        v = float(entries[key])
    except (KeyError, ValueError):
        raise FileFormatError(f"{path}: [{where}] has no number {key!r} "
                              f"(got {entries.get(key)!r}); damaged header") from None
    if not math.isfinite(v):
        raise FileFormatError(f"{path}: [{where}] {key}={v!r} is not finite; damaged header")
    return v


def _integer(entries: dict, key: str, path: str, where: str, low: int, high: int) -> int:
    v = _number(entries, key, path, where)
    if v != int(v) or not low <= v <= high:
        raise FileFormatError(f"{path}: [{where}] {key}={entries.get(key)!r}: expected a whole number in "
                              f"[{low}, {high}]; damaged header")
    return int(v)


def read_nid(path: str | Path) -> NidFile:
    """Parse a .nid's header and locate its data blocks (the samples are read by
    :meth:`NidFile.values`).

    Raises
    ------
    FileFormatError
        Not a .nid, a damaged header, or a file too short for the blocks its header declares.
    """
    path = Path(path)
    where = str(path)
    try:
        size = path.stat().st_size
        with open(path, "rb") as fh:
            head = fh.read(min(size, MAX_HEADER))
    except OSError as exc:
        raise FileFormatError(f"cannot read {path}: {exc.strerror or exc}") from None
    if not is_nid(head):
        raise FileFormatError(f"{path}: not a Nanosurf .nid file (expected a '[DataSet]' header with GroupCount)")
    end = head.find(b"\r\n#!")
    end = end if end >= 0 else head.find(b"\n#!")
    if end < 0:
        raise FileFormatError(f"{path}: the .nid header has no end ('#!' before the data); truncated or damaged")
    try:
        text = head[:end].decode("utf-8")  # units such as µ and ° are UTF-8 in the files seen
    except UnicodeDecodeError:
        text = head[:end].decode("latin-1")
    sections = _sections(text)
    top = sections.get("DataSet", {})
    groups = _integer(top, "GroupCount", where, "DataSet", 0, 10**4)
    names = []
    for g in range(groups):
        count = _integer(top, f"Gr{g}-Count", where, "DataSet", 0, 10**4)
        names += [top[f"Gr{g}-Ch{c}"] for c in range(count) if f"Gr{g}-Ch{c}" in top]
    layout = []
    for name in names:
        h = sections.get(name)
        if h is None:
            raise FileFormatError(f"{path}: the header lists block {name!r} but has no [{name}] section; damaged")
        points = _integer(h, "Points", where, name, 0, 10**8)
        lines = _integer(h, "Lines", where, name, 0, 10**8)
        if lines and not points:  # rows of no bytes: a count the data cannot bound (issue: declared counts)
            raise FileFormatError(f"{path}: block {name} declares {lines} lines of 0 points; damaged header")
        bits = _integer(h, "SaveBits", where, name, 8, 64)
        if bits not in (8, 16, 32, 64) or h.get("SaveMode", "Binary").lower() != "binary":
            raise FileFormatError(f"{path}: block {name} saved as {h.get('SaveMode')!r}, {bits} bits; afmforce "
                                  "reads binary blocks of 8, 16, 32 or 64 bits")
        layout.append((name, h, points, lines, bits))
    total = sum(p * n * b // 8 for _, _, p, n, b in layout)
    start = size - total
    data_at = end + (4 if head[end:end + 4] == b"\r\n#!" else 3)
    if start < data_at:
        raise FileFormatError(f"{path}: the header declares {total} bytes of data but the file holds "
                              f"{max(size - data_at, 0)} after it; truncated")
    if start > data_at:
        raise FileFormatError(f"{path}: {start - data_at} bytes between the header and the data blocks the "
                              "header declares; damaged")
    blocks, offset = [], start
    for name, h, points, lines, bits in layout:
        blocks.append(NidBlock(name=name, frame=h.get("Frame", ""), channel=h.get("Dim2Name", ""),
                               unit=h.get("Dim2Unit", ""), points=points, lines=lines, bits=bits, offset=offset,
                               header=h))
        offset += points * lines * bits // 8
    return NidFile(path=where, sections=sections, blocks=tuple(blocks))


_TYPED = re.compile(r"^([A-Z])\[(.*)\]\*\[(.*)\]$")


def typed_value(text: str | None) -> tuple[float, str] | None:
    """A typed parameter ``D[2.72436]*[N/m]`` -> (2.72436, 'N/m'); None if it is not a number."""
    m = _TYPED.match((text or "").strip())
    if not m or m.group(1) not in ("D", "L"):
        return None
    try:
        v = float(m.group(2))
    except ValueError:
        return None
    return (v, m.group(3)) if math.isfinite(v) else None


_PREFIX = {"": 1.0, "k": 1e3, "M": 1e6, "m": 1e-3, "µ": 1e-6, "u": 1e-6, "n": 1e-9, "p": 1e-12, "f": 1e-15}


def si_value(text: str | None, base: str) -> float | None:
    """A display value of the ``[DataSet-Info]`` lines in ``<prefix><base>`` -> SI:
    ``'179.8kHz'``, ``'27.13 N/m'``, ``'772fm/sqrt(Hz)'``, ``'1 s'``; None if it is not one."""
    s = (text or "").replace("μ", "µ").strip()
    m = re.match(r"^([+-]?\d+(?:\.\d*)?(?:[eE][+-]?\d+)?)\s*(\S*)$", s)
    if not m or not m.group(2).endswith(base):
        return None
    prefix = m.group(2)[: len(m.group(2)) - len(base)]
    return float(m.group(1)) * _PREFIX[prefix] if prefix in _PREFIX else None
