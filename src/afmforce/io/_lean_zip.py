"""A zip archive's directory read into compact arrays, its members read by name.

:class:`zipfile.ZipFile` keeps a :class:`~zipfile.ZipInfo` object per member: a 128 x 128 JPK QI
file (16,384 curves, 20 members each) costs 18 s and 150 MB to open that way. A force map needs
only where each member lies: :class:`LeanZip` reads the central directory (ZIP64 included) into
numpy arrays (offset, sizes, method, CRC) and groups the members by a key of their name (the
curve's ``index/<i>/``), sharing the rest of the names between curves; :meth:`LeanZip.read`
returns a member's bytes (stored or deflated, CRC checked), with ``zipfile``'s errors.
"""

from __future__ import annotations

import os
import struct
import zipfile
import zlib
from typing import Callable

import numpy as np

__all__ = ["LeanZip"]

_EOCD = struct.Struct("<IHHHHIIH")
_LOC64 = struct.Struct("<IIQI")
_EOCD64 = struct.Struct("<IQHHIIQQQQ")
_CENTRAL = struct.Struct("<IHHHHHHIIIHHHHHII")
_LOCAL = struct.Struct("<IHHHHHIIIHH")


class LeanZip:
    """The members of the zip archive ``path``; those whose name ``group(name)`` splits into
    ``(key, rest)`` are kept per key (``members(key)``), the others by name.

    Raises :class:`zipfile.BadZipFile` for what is not a zip archive or a damaged directory.
    """

    def __init__(self, path: str | os.PathLike, group: Callable[[str], tuple[int, str] | None]) -> None:
        self._fd = os.open(path, os.O_RDONLY)
        try:
            self._read_directory(group)
        except BaseException:
            os.close(self._fd)
            raise

    def _pread(self, size: int, offset: int) -> bytes:
        data = os.pread(self._fd, size, offset)
        if len(data) != size:
            raise zipfile.BadZipFile("truncated file")
        return data

    def _read_directory(self, group) -> None:
        size = os.fstat(self._fd).st_size
        tail_start = max(0, size - (_EOCD.size + 65535))
        tail = self._pread(size - tail_start, tail_start)
        at = tail.rfind(b"PK\x05\x06")
        if at < 0 or at + _EOCD.size > len(tail):
            raise zipfile.BadZipFile("File is not a zip file")
        _, _, _, _, count, cd_size, cd_offset, _ = _EOCD.unpack_from(tail, at)
        if at >= _LOC64.size and tail[at - _LOC64.size:at - _LOC64.size + 4] == b"PK\x06\x07":
            _, _, eocd64, _ = _LOC64.unpack_from(tail, at - _LOC64.size)
            rec = _EOCD64.unpack(self._pread(_EOCD64.size, eocd64))
            if rec[0] != 0x06064B50:
                raise zipfile.BadZipFile("damaged ZIP64 end of central directory")
            count, cd_size, cd_offset = rec[7], rec[8], rec[9]
        if cd_offset + cd_size > size or count * _CENTRAL.size > cd_size:
            raise zipfile.BadZipFile("damaged central directory (beyond the file, or too short for its members)")
        directory = self._pread(cd_size, cd_offset)
        offset = np.empty(count, np.int64)
        csize = np.empty(count, np.int64)
        usize = np.empty(count, np.int64)
        method = np.empty(count, np.int16)
        crc = np.empty(count, np.uint32)
        named: dict[str, int] = {}
        groups: dict[int, dict[str, int]] = {}
        rests: dict[str, str] = {}
        pos = 0
        for i in range(count):
            (sig, _, _, flags, meth, _, _, c, cs, us, nlen, elen, clen, _, _, _, off) = \
                _CENTRAL.unpack_from(directory, pos)
            if sig != 0x02014B50:
                raise zipfile.BadZipFile("Bad magic number for central directory")
            if flags & 1:
                raise zipfile.BadZipFile("encrypted member")
            start = pos + _CENTRAL.size
            raw = directory[start:start + nlen]
            try:
                name = raw.decode("ascii")  # JPK's names; the C fast path
            except UnicodeDecodeError:
                name = raw.decode("utf-8" if flags & 0x800 else "cp437")
            if 0xFFFFFFFF in (cs, us, off):  # ZIP64 extra field: the 8-byte values in this order
                extra = directory[start + nlen:start + nlen + elen]
                p = 0
                while p + 4 <= len(extra):
                    tag, ln = struct.unpack_from("<HH", extra, p)
                    if tag == 1:
                        vals = iter(struct.unpack_from(f"<{ln // 8}Q", extra, p + 4))
                        us = next(vals) if us == 0xFFFFFFFF else us
                        cs = next(vals) if cs == 0xFFFFFFFF else cs
                        off = next(vals) if off == 0xFFFFFFFF else off
                        break
                    p += 4 + ln
            offset[i], csize[i], usize[i], method[i], crc[i] = off, cs, us, meth, c
            pos = start + nlen + elen + clen
            split = group(name)
            if split is None:
                named[name] = i
            else:
                key, rest = split
                groups.setdefault(key, {})[rests.setdefault(rest, rest)] = i  # one string per rest
        self._offset, self._csize, self._usize, self._method, self._crc = offset, csize, usize, method, crc
        self.named, self.groups = named, groups

    def read(self, entry: int, name: str = "") -> bytes:
        """The bytes of member number ``entry`` (``name`` for messages)."""
        off, cs = int(self._offset[entry]), int(self._csize[entry])
        head = self._pread(_LOCAL.size, off)
        sig, *_, nlen, elen = _LOCAL.unpack(head)
        if sig != 0x04034B50:
            raise zipfile.BadZipFile(f"Bad magic number for file header of {name}")
        from ..limits import MAX_MEMBER_BYTES

        size = int(self._usize[entry])
        if size > MAX_MEMBER_BYTES:
            raise zipfile.BadZipFile(f"{name} would unpack to {size:,} bytes, more than a force curve's channel "
                                     f"holds ({MAX_MEMBER_BYTES:,}): a damaged archive or a zip bomb")
        data = self._pread(cs, off + _LOCAL.size + nlen + elen) if cs else b""
        meth = int(self._method[entry])
        if meth == zipfile.ZIP_DEFLATED:      # never more than the declared size (+1: a lie is seen)
            inflate = zlib.decompressobj(-15)
            data = inflate.decompress(data, size + 1)
        elif meth != zipfile.ZIP_STORED:
            raise NotImplementedError(f"{name}: compression method {meth} not supported")
        if len(data) != int(self._usize[entry]) or zlib.crc32(data) != int(self._crc[entry]):
            raise zipfile.BadZipFile(f"Bad CRC-32 for file {name!r}")
        return data

    def close(self) -> None:
        os.close(self._fd)


def index_group(name: str) -> tuple[int, str] | None:
    """``(i, rest)`` for a name ``index/<i>/<rest>`` (a JPK map's curve ``i``), else None."""
    if not name.startswith("index/"):
        return None
    j = name.find("/", 6)
    key = name[6:j]
    if j < 0 or not key.isdigit():
        return None
    return int(key), name[j + 1:]
