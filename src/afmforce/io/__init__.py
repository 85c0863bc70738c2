"""Force-curve readers: one registry, one signature.

Every reader is a record in :data:`FORMATS` (identifier, name, suffixes, a
``detect(path)`` function and a ``loader``); :func:`load` picks the first record
whose suffix matches and whose detector accepts the file, and returns a list of
:class:`~afmforce.raw.RawCurve` in afmforce's conventions (z increasing towards
the probe, approach = segment 0, deflection positive = up). Input files are
only ever opened for reading.

>>> from afmforce.io import load
>>> curves = load("curve.jpk-force")                        # doctest: +SKIP
>>> curves = load("gel.txt", meta_override={"spring_constant": 0.05,
...                                         "sensitivity": 61e-9})  # doctest: +SKIP
"""

from __future__ import annotations

import importlib.util
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

from ..errors import AfmforceError, FileFormatError, ParameterError
from ..raw import RawCurve
from ._meta import METADATA, check_meta_override, require_metadata

__all__ = ["ReaderFormat", "FORMATS", "load", "find_format", "formats_table", "METADATA",
           "supported_suffixes", "is_supported", "require_metadata"]

Loader = Callable[..., list]


@dataclass(frozen=True)
class ReaderFormat:
    """One file format: how to recognise it and how to read it.

    Attributes
    ----------
    identifier : str
        Short name, e.g. ``"jpk-force"`` (``load(path, format=...)``).
    name : str
        Human-readable name.
    suffixes : tuple of str
        File name endings, lower case, with the dot.
    detect : callable
        ``detect(path) -> bool``: does the content look like this format?
    loader : callable
        ``loader(path, *, meta_override, callback) -> list[RawCurve]``.
    via : str
        ``"afmformats"`` or ``"afmforce"`` (our own reader).
    pattern : str
        Regular expression for endings that are not fixed (``\\.\\d{3}$``: numbered files).
    requires : tuple of str
        Metadata the user must give because the file lacks it.
    deflection : str
        Unit of the deflection signal the reader returns.
    """

    identifier: str
    name: str
    suffixes: tuple[str, ...]
    detect: Callable[[Path], bool]
    loader: Loader
    via: str
    requires: tuple[str, ...] = field(default=())
    deflection: str = "N"
    pattern: str = ""

    def claims(self, name: str) -> bool:
        """Does the file name (any case) end in one of this format's endings?"""
        name = name.lower()
        return any(name.endswith(s) for s in self.suffixes) or bool(self.pattern and re.search(self.pattern, name))


def _lazy(module: str, func: str) -> Callable:
    """A function imported only when called (keeps ``import afmforce.io`` light)."""

    def call(*args, **kwargs):
        mod = importlib.import_module(f"{__name__}.{module}" if not module.startswith("afmforce") else module)
        return getattr(mod, func)(*args, **kwargs)

    call.__name__ = func
    call.__qualname__ = func
    return call


def _rawfile_available() -> bool:
    return importlib.util.find_spec("afmforce.rawfile") is not None


def _detect_raw_text(path: Path) -> bool:
    """afmforce raw text: ``# format: "afmforce-raw"`` header, or ``#`` lines and a deflection_signal column."""
    if not _rawfile_available():
        return False
    try:
        with open(path, "rb") as fh:
            head = fh.read(16384).decode("utf-8", errors="replace")
    except OSError:
        return False
    return head.startswith("#") and ("afmforce-raw" in head or "deflection_signal" in head)


def _detect_raw_hdf5(path: Path) -> bool:
    """HDF5 signature and the root attribute ``format = "afmforce-raw"``."""
    if not _rawfile_available():
        return False
    try:
        with open(path, "rb") as fh:
            if fh.read(8) != b"\x89HDF\r\n\x1a\n":
                return False
        import h5py

        with h5py.File(path, "r") as f:
            fmt = f.attrs.get("format")
        return (fmt.decode() if isinstance(fmt, bytes) else str(fmt)) == "afmforce-raw"
    except Exception:  # any h5py failure means: not ours
        return False


def _load_rawfile(path: Path, *, meta_override: Mapping[str, Any], callback=None) -> list[RawCurve]:
    """afmforce raw text / HDF5, written by :mod:`afmforce.rawfile`."""
    import dataclasses

    from afmforce.rawfile import read_raw  # lazy: written by the instrument module

    curve = read_raw(path)
    reader = "afmforce-hdf5" if path.suffix.lower() in (".h5", ".hdf5", ".hdf") else "afmforce-raw"
    meta = {**dict(curve.metadata), **dict(meta_override), "reader": reader}
    if meta.get("source_file") not in (None, str(path)):
        meta["recorded_source"] = meta["source_file"]
    meta["source_file"] = str(path)
    curve = dataclasses.replace(curve, metadata=meta)
    if callback is not None:
        callback(1.0)
    return [curve]


def _detect_raw_map(path: Path) -> bool:
    """HDF5 signature and the root attribute ``format = "afmforce-map"``."""
    if not _rawfile_available():
        return False
    from afmforce.rawmap import is_map

    return is_map(path)


def _load_rawmap(path: Path, *, meta_override: Mapping[str, Any], callback=None,
                 indices: list[int] | None = None, reader=None) -> list[RawCurve]:
    """afmforce force map (HDF5, many curves on a grid), written by :mod:`afmforce.rawmap`.

    ``indices`` reads only those curves and ``reader`` (an open
    :class:`~afmforce.rawmap.MapReader` of ``path``) saves opening the file:
    the batch analysis reads a map a chunk at a time.
    """
    import dataclasses

    from afmforce.rawmap import MapReader

    own = reader is None
    reader = MapReader(path) if own else reader
    try:
        indices = list(range(len(reader))) if indices is None else list(indices)
        out = []
        for i in indices:
            curve = reader.read(i)
            meta = {**dict(curve.metadata), **dict(meta_override), "reader": "afmforce-map", "map_index": int(i)}
            if meta.get("source_file") not in (None, str(path)):
                meta["recorded_source"] = meta["source_file"]
            meta["source_file"] = str(path)
            out.append(dataclasses.replace(curve, metadata=meta))
            if callback is not None:
                callback(len(out) / len(indices))
    finally:
        if own:
            reader.close()
    return out


def _always(path: Path) -> bool:
    return True


#: The registered formats, in the order they are tried for a shared suffix.
FORMATS: dict[str, ReaderFormat] = {f.identifier: f for f in (
    ReaderFormat("afmforce-raw", "afmforce raw text", (".txt", ".tsv", ".raw"), _detect_raw_text,
                 _load_rawfile, via="afmforce", deflection="V, m or N"),
    ReaderFormat("afmforce-hdf5", "afmforce raw HDF5", (".h5", ".hdf5", ".hdf"), _detect_raw_hdf5,
                 _load_rawfile, via="afmforce", deflection="V, m or N"),
    ReaderFormat("afmforce-map", "afmforce force map (HDF5, curves on a grid)", (".h5", ".hdf5", ".hdf"),
                 _detect_raw_map, _load_rawmap, via="afmforce", deflection="V, m or N"),
    ReaderFormat("bruker-ascii", "Bruker NanoScope ASCII export", (".txt", ".asc", ".csv"),
                 _lazy("bruker", "detect_bruker_ascii"), _lazy("bruker", "load_bruker_ascii"),
                 via="afmforce", deflection="V, m or N"),
    ReaderFormat("bruker-nanoscope", "Bruker NanoScope binary force file (v5-v9)", (".spm", ".pfc"),
                 _lazy("nanoscope", "detect_nanoscope"), _lazy("nanoscope", "load_nanoscope"),
                 via="afmforce", deflection="V", pattern=r"\.\d{3}$"),
    ReaderFormat("jpk-force", "JPK force curve / force map (calibrated)",
                 (".jpk-force", ".jpk-force-map", ".jpk-qi-data", ".jpk-qi-series"),
                 _lazy("_afmformats", "detect_afmformats"), _lazy("_afmformats", "load_jpk"),
                 via="afmformats", deflection="N (V if uncalibrated)"),
    ReaderFormat("jpk-zip", "JPK force archive read directly (raw volts)", (".jpk-force",),
                 _lazy("jpk_zip", "detect_jpk_zip"), _lazy("jpk_zip", "load_jpk_zip"),
                 via="afmforce", deflection="V"),
    ReaderFormat("asylum-ibw", "Asylum Research Igor binary wave", (".ibw",),
                 _lazy("_afmformats", "detect_afmformats"), _lazy("_afmformats", "load_ibw"),
                 via="afmformats"),
    ReaderFormat("afm-workshop-csv", "AFM Workshop CSV export", (".csv",),
                 _lazy("_afmformats", "detect_afmformats"), _lazy("_afmformats", "load_workshop"),
                 via="afmformats"),
    ReaderFormat("ntmdt-txt", "NT-MDT Nova text export", (".txt",),
                 _lazy("_afmformats", "detect_afmformats"), _lazy("_afmformats", "load_ntmdt"),
                 via="afmformats", requires=("spring_constant", "sensitivity"), deflection="V"),
)}


def supported_suffixes() -> list[str]:
    """Every fixed file ending some reader accepts (see also :func:`is_supported`)."""
    return sorted({s for f in FORMATS.values() for s in f.suffixes})


def is_supported(path: str | Path) -> bool:
    """Does some reader claim this file name (fixed endings and numbered ``.000``-``.999``)?"""
    return any(f.claims(Path(path).name) for f in FORMATS.values())


def find_format(path: str | Path) -> ReaderFormat:
    """The first registered format whose suffix and detector accept ``path``.

    Raises
    ------
    FileFormatError
        The file does not exist, or no reader recognises it.
    """
    path = Path(path)
    if not path.is_file():
        raise FileFormatError(f"{path}: no such file")
    candidates = [f for f in FORMATS.values() if f.claims(path.name)]
    if not candidates:
        raise FileFormatError(
            f"{path}: unknown file type; supported endings: {', '.join(supported_suffixes())}, .000-.999")
    for fmt in candidates:
        try:
            if fmt.detect(path):
                return fmt
        except Exception:  # a detector must never crash the search
            continue
    raise FileFormatError(
        f"{path}: content not recognised as any of: {', '.join(f.name for f in candidates)}")


def load(path: str | Path, *, meta_override: Mapping[str, Any] | None = None,
         callback: Callable[[float], None] | None = None, format: str | None = None,
         require: Sequence[str] = ()) -> list[RawCurve]:
    """Read every force curve in ``path``.

    Parameters
    ----------
    path : str or Path
        The file (never modified).
    meta_override : mapping, optional
        Metadata in SI (keys of :data:`METADATA`, e.g. ``spring_constant``
        [N/m], ``sensitivity`` [m/V]) that replace or complete the file's.
    callback : callable, optional
        Called with the fraction done, a float in [0, 1].
    format : str, optional
        Identifier of a format in :data:`FORMATS`, skipping detection.
    require : sequence of str, optional
        Metadata every curve must carry, e.g. ``("spring_constant", "sensitivity")``
        for an analysis in force: ``spring_constant`` is required of a deflection in
        V or m, ``sensitivity`` of one in V (a force in N needs neither).

    Returns
    -------
    list of RawCurve

    Raises
    ------
    FileFormatError
        Missing, unknown, truncated or damaged file.
    MissingMetadataError
        (a FileFormatError) The file lacks metadata the format or ``require`` needs;
        the message names the command-line flag (``--spring-constant``, ...) that gives it.
    ParameterError
        Invalid ``meta_override`` or unknown ``format``.
    """
    path = Path(path)
    meta = check_meta_override(meta_override)
    if format is not None:
        if format not in FORMATS:
            raise ParameterError(f"unknown format {format!r}; choose one of {', '.join(FORMATS)}")
        if not path.is_file():
            raise FileFormatError(f"{path}: no such file")
        fmt = FORMATS[format]
    else:
        fmt = find_format(path)
    try:
        curves = fmt.loader(path, meta_override=meta, callback=callback)
    except (AfmforceError, KeyboardInterrupt, SystemExit, GeneratorExit):
        raise
    except MemoryError:
        raise FileFormatError(f"{path}: too large or damaged (out of memory while reading)") from None
    except BaseException as exc:  # third-party parsers raise anything (afmformats: BaseException subclasses)
        text = str(exc) if len(str(exc)) <= 200 else str(exc)[:200] + "..."
        raise FileFormatError(f"{path}: cannot read as {fmt.name} ({type(exc).__name__}: {text})") from None
    if not curves:
        raise FileFormatError(f"{path}: no force curve in the file")
    for curve in curves:
        require_metadata(curve, tuple(require), str(path))
    return curves


def formats_table() -> list[dict[str, str]]:
    """One row per format (for the docs and ``afmforce analyze --help``)."""
    return [{"identifier": f.identifier, "name": f.name, "suffixes": " ".join(f.suffixes),
             "via": f.via, "deflection": f.deflection, "requires": ", ".join(f.requires) or "-"}
            for f in FORMATS.values()]
