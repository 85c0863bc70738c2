"""Force maps read one curve at a time: a map of any size in the memory of one curve.

:func:`open_map` opens a force map (an afmforce map file, JPK force-map or QI data, a Bruker
NanoScope force volume, an Asylum ARDF force map) and returns a reader with ``len(reader)``, ``reader.read(i)`` (curve ``i``
as the format's reader in :data:`afmforce.io.FORMATS` gives it, with the user's
``meta_override``) and ``close()``; the batch engine's workers keep one open per map
(:mod:`afmforce.sweep.files`). What each keeps in memory: the HDF5 file's index; the zip
archive's directory in arrays (:mod:`afmforce.io._lean_zip`: about 100 bytes a member) and the two
shared headers (a curve's own header and segments are read when it is); the NanoScope header
(each curve's samples are read from their place in the file); the ARDF's line table and the
record offsets of the line last read (:mod:`afmforce.io.ardf`).
"""

from __future__ import annotations

import os
import struct
import zipfile
import zlib
from pathlib import Path
from typing import Any, Mapping, Protocol

from ..errors import FileFormatError
from .curve import RawCurve

__all__ = ["MapCurves", "open_map", "STREAMED_FORMATS"]

#: Reader identifiers whose maps :func:`open_map` reads curve by curve.
STREAMED_FORMATS = ("afmforce-map", "jpk-force", "jpk-zip", "bruker-nanoscope", "asylum-ardf")


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
    if format == "asylum-ardf":
        from .ardf import ArdfFile

        return ArdfFile(path, meta)
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


class _Members:
    """What jpk_zip's functions read of an archive: ``namelist()`` and ``read(name)``, from a
    :class:`~afmforce.io._lean_zip.LeanZip` (``index`` None: the members outside the curves; else
    one curve's, under ``index/<index>/``)."""

    def __init__(self, lean, index: int | None = None) -> None:
        self._lean, self._index = lean, index
        self._prefix = "" if index is None else f"index/{index}/"
        self._own = lean.named if index is None else lean.groups[index]

    def namelist(self) -> list[str]:
        return [self._prefix + rest for rest in self._own]

    def read(self, name: str) -> bytes:
        if self._prefix and name.startswith(self._prefix):
            entry = self._own.get(name[len(self._prefix):])
        else:
            entry = self._lean.named.get(name)
        if entry is None:
            raise KeyError(f"There is no item named {name!r} in the archive")
        return self._lean.read(entry, name)


class JpkMap:
    """A JPK force map or QI data file (``index/<i>/segments/...``), decoded curve by curve by
    :mod:`afmforce.io.jpk_zip` (``force``: in N from the file's or the user's spring constant and
    sensitivity, as the ``jpk-force`` reader gives them; else in volts, as ``jpk-zip``). The zip's
    directory is read into arrays (:mod:`afmforce.io._lean_zip`): a 128 x 128 QI file opens in
    about a second and 20 MB instead of 18 s and 150 MB."""

    def __init__(self, path: Path, meta: dict, *, force: bool) -> None:
        from ._lean_zip import LeanZip, index_group
        from .jpk_zip import _read_props, _shared

        self.where, self.meta, self.force = str(path), meta, force
        try:
            self._zip = LeanZip(path, index_group)
        except (zipfile.BadZipFile, OSError, ValueError, struct.error) as exc:
            raise FileFormatError(f"{path}: not a JPK zip archive ({exc})") from None
        try:
            # the curves: index folders with segment headers (as jpk_zip finds them), in index order
            self._indices = sorted(i for i, members in self._zip.groups.items()
                                   if any(r.startswith("segments/") and r.endswith("/segment-header.properties")
                                          for r in members))
            if not self._indices:
                raise FileFormatError(f"{path}: not a JPK force map (no index/<i>/segments/)")
            top = _Members(self._zip)
            if "header.properties" not in self._zip.named:
                raise FileFormatError(f"{path}: header.properties missing; not a JPK force file")
            self._shared = _shared(top)
            self._general = _read_props(top, "header.properties")
        except FileFormatError:
            self._zip.close()
            raise
        except BaseException as exc:
            self._zip.close()
            if isinstance(exc, Exception):
                raise FileFormatError(f"{path}: damaged JPK archive ({type(exc).__name__}: {str(exc)[:200]})") \
                    from None
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
            curve = _read_archive(_Members(self._zip, i), self.where, dict(self.meta), None,
                                  prefix=f"index/{i}/", shared=self._shared, general=self._general)
        except FileFormatError:
            raise
        except (zipfile.BadZipFile, KeyError, ValueError, OSError, EOFError, RuntimeError, zlib.error,
                NotImplementedError) as exc:
            raise FileFormatError(f"{self.where}#{index}: damaged JPK archive ({type(exc).__name__}: "
                                  f"{str(exc)[:200]})") from None
        return _jpk_force(curve) if self.force else curve

    def close(self) -> None:
        self._zip.close()
