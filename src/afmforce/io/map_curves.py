"""Force maps read one curve at a time: a map of any size in the memory of one curve.

:func:`open_map` opens a force map (an afmforce map file, JPK force-map or QI data, a Bruker
NanoScope force volume) and returns a reader with ``len(reader)``, ``reader.read(i)`` (curve ``i``
as the format's reader in :data:`afmforce.io.FORMATS` gives it, with the user's
``meta_override``) and ``close()``; the batch engine's workers keep one open per map
(:mod:`afmforce.sweep.files`). What each keeps in memory: the HDF5 file's index; the zip
archive's directory and the two shared headers (a curve's own header and segments are read when
it is); the NanoScope header (each curve's samples are read from their place in the file).
"""

from __future__ import annotations

import os
import re
import zipfile
from pathlib import Path
from typing import Any, Mapping, Protocol

from ..errors import FileFormatError
from .curve import RawCurve

__all__ = ["MapCurves", "open_map", "STREAMED_FORMATS"]

#: Reader identifiers whose maps :func:`open_map` reads curve by curve.
STREAMED_FORMATS = ("afmforce-map", "jpk-force", "jpk-zip", "bruker-nanoscope")


class MapCurves(Protocol):
    def __len__(self) -> int: ...
    def read(self, index: int) -> RawCurve: ...
    def close(self) -> None: ...


def open_map(path: str | os.PathLike, format: str, meta_override: Mapping[str, Any] | None = None) -> MapCurves:
    """Open the force map ``path`` (reader ``format``, one of :data:`STREAMED_FORMATS`) for reading
    one curve at a time."""
    path = Path(path)
    meta = dict(meta_override or {})
    if format == "afmforce-map":
        return _NativeMap(path, meta)
    if format in ("jpk-force", "jpk-zip"):
        return JpkMap(path, meta, force=format == "jpk-force")
    if format == "bruker-nanoscope":
        from .nanoscope import NanoscopeFile

        f = NanoscopeFile(path, meta)
        f.read = f.curve  # type: ignore[attr-defined]
        return f  # type: ignore[return-value]
    raise FileFormatError(f"{path}: reader {format!r} does not read maps curve by curve "
                          f"(those that do: {', '.join(STREAMED_FORMATS)})")


class _NativeMap:
    def __init__(self, path: Path, meta: dict) -> None:
        from .native.rawmap import MapReader

        self.path, self.meta, self._reader = path, meta, MapReader(path)

    def __len__(self) -> int:
        return len(self._reader)

    def read(self, index: int) -> RawCurve:
        from . import FORMATS

        return FORMATS["afmforce-map"].loader(self.path, meta_override=self.meta, indices=[index],
                                              reader=self._reader)[0]

    def close(self) -> None:
        self._reader.close()


class _Curve:
    """The part of an open archive that one curve's decoder sees (its own names, the shared files)."""

    def __init__(self, arc: zipfile.ZipFile, names: list[str]) -> None:
        self._arc, self._names = arc, names

    def namelist(self) -> list[str]:
        return self._names

    def read(self, name: str) -> bytes:
        return self._arc.read(name)


class JpkMap:
    """A JPK force map or QI data file (``index/<i>/segments/...``), decoded curve by curve by
    :mod:`afmforce.io.jpk_zip` (``force``: in N from the file's or the user's spring constant and
    sensitivity, as the ``jpk-force`` reader gives them; else in volts, as ``jpk-zip``)."""

    def __init__(self, path: Path, meta: dict, *, force: bool) -> None:
        from .jpk_zip import _read_props, _shared

        self.where, self.meta, self.force = str(path), meta, force
        try:
            self._arc = zipfile.ZipFile(path)
        except (zipfile.BadZipFile, OSError, ValueError) as exc:
            raise FileFormatError(f"{path}: not a JPK zip archive ({exc})") from None
        try:
            names: dict[int, list[str]] = {}
            pat = re.compile(r"index/(\d+)/")
            for n in self._arc.namelist():
                m = pat.match(n)
                if m is not None:
                    names.setdefault(int(m.group(1)), []).append(n)
            if not names:
                raise FileFormatError(f"{path}: not a JPK force map (no index/<i>/ folders)")
            self._indices = sorted(names)
            self._names = names
            self._shared = _shared(self._arc)
            self._general = _read_props(self._arc, "header.properties")
        except BaseException:
            self._arc.close()
            raise

    def __len__(self) -> int:
        return len(self._indices)

    def read(self, index: int) -> RawCurve:
        from ._afmformats import _jpk_force
        from .jpk_zip import _read_archive

        if not 0 <= index < len(self._indices):
            raise FileFormatError(f"{self.where}: no curve {index} (the file holds {len(self._indices)})")
        i = self._indices[index]
        try:
            curve = _read_archive(_Curve(self._arc, self._names[i]), self.where, dict(self.meta), None,
                                  prefix=f"index/{i}/", shared=self._shared, general=self._general)
        except FileFormatError:
            raise
        except (zipfile.BadZipFile, KeyError, ValueError, OSError, EOFError, RuntimeError) as exc:
            raise FileFormatError(f"{self.where}#{index}: damaged JPK archive ({type(exc).__name__}: "
                                  f"{str(exc)[:200]})") from None
        return _jpk_force(curve) if self.force else curve

    def close(self) -> None:
        self._arc.close()
