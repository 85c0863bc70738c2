"""Force-curve readers: one registry, one signature.

Every reader is a record in :data:`FORMATS` (identifier, name, suffixes, a
``detect(path)`` function and a ``loader``); :func:`load` picks the first record
whose suffix matches and whose detector accepts the file, and returns a list of
:class:`~afmforce.io.curve.RawCurve` in afmforce's conventions (z increasing towards
the probe, segments by type: approach 0, retract 1, dwell 2; deflection positive
= up). Input files are only ever opened for reading; HDF5 files (and any file with
``timeout=``) are read in a child process with a time budget. ``afmforce formats``
and docs/formats.md show the table.

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
from ..progress import Progress
from .curve import RawCurve
from . import native
from ._guard import FileTimeoutError, run_with_timeout
from ._meta import METADATA, check_meta_override, parse_meta_args, require_metadata

__all__ = ["ReaderFormat", "FORMATS", "register_format", "unregister_format", "load", "find_format", "formats_table", "METADATA", "refusal",
           "supported_suffixes", "is_supported", "in_folder", "require_metadata", "formats_markdown", "check_meta_override",
           "parse_meta_args", "run_with_timeout", "FileTimeoutError", "damage", "cut_mid_line"]

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
    signature : str
        What the content must look like (checked by ``detect``).
    supplies : tuple of str
        Metadata keys (:data:`METADATA`) the reader takes from the file when present.
    pattern : str
        Regular expression for endings that are not fixed (``\\.\\d{3}$``: numbered files).
    requires : tuple of str
        Metadata the user must give because the file lacks it.
    text : bool
        The file is a table of text lines: one cut inside its last row is refused (:func:`cut_mid_line`).
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
    signature: str = ""
    supplies: tuple[str, ...] = field(default=())
    text: bool = False

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


_CAL = ("spring_constant", "sensitivity")

#: The registered formats, in the order they are tried for a shared suffix.
FORMATS: dict[str, ReaderFormat] = {f.identifier: f for f in (
    ReaderFormat("afmforce-raw", "afmforce raw text", (".txt", ".tsv", ".raw"), native.detect_raw_text,
                 native.load_rawfile, via="afmforce", deflection="V, m or N",
                 signature='"# format: afmforce-raw" header (or "#" lines and a deflection_signal column)',
                 text=True, supplies=(*_CAL, "velocity", "sample_rate", "resonance_frequency", "theta0")),
    ReaderFormat("afmforce-hdf5", "afmforce raw HDF5", (".h5", ".hdf5", ".hdf"), native.detect_raw_hdf5,
                 native.load_rawfile, via="afmforce", deflection="V, m or N",
                 signature='HDF5, root attribute format = "afmforce-raw"',
                 supplies=(*_CAL, "velocity", "sample_rate", "resonance_frequency", "theta0")),
    ReaderFormat("afmforce-map", "afmforce force map (HDF5, curves on a grid)", (".h5", ".hdf5", ".hdf"),
                 native.detect_raw_map, native.load_rawmap, via="afmforce", deflection="V, m or N",
                 signature='HDF5, root attribute format = "afmforce-map"',
                 supplies=(*_CAL, "velocity", "sample_rate")),
    ReaderFormat("afmformats-hdf5", "afmformats HDF5 export", (".h5",),
                 _lazy("_afmformats", "detect_afmformats_hdf5"), _lazy("_afmformats", "load_export"),
                 via="afmformats", signature='HDF5, root attribute software = "afmformats"',
                 supplies=(*_CAL, "velocity", "sample_rate")),
    ReaderFormat("afmformats-tab", "afmformats tab-separated export", (".tab",),
                 _lazy("_afmformats", "detect_afmformats"), _lazy("_afmformats", "load_export"),
                 via="afmformats", signature='first line "# afmformats <version>", JSON metadata block',
                 text=True, supplies=(*_CAL, "velocity", "sample_rate")),
    ReaderFormat("bruker-nanoscope", "Bruker NanoScope binary force file (v5-v9)", (".spm", ".pfc"),
                 _lazy("nanoscope", "detect_nanoscope"), _lazy("nanoscope", "load_nanoscope"),
                 via="afmforce", deflection="V", pattern=r"\.\d{3}$",
                 signature="first line \\*Force file list (single curves, force volumes); header, then int16/int32 "
                           "data (\\*File list: an image, refused)",
                 supplies=(*_CAL, "velocity", "sample_rate", "radius")),
    ReaderFormat("bruker-ascii", "Bruker NanoScope ASCII export", (".txt", ".asc", ".csv"),
                 _lazy("bruker", "detect_bruker_ascii"), _lazy("bruker", "load_bruker_ascii"),
                 via="afmforce", deflection="V, m or N",
                 signature='\\* or \\? header lines (or "\\..." quoted: NanoScope Analysis), then tab- or comma-'
                           'separated <Name>_<unit>_<Ex or Rt> columns (or processed Force and Separation only: force '
                           'in N); or one plotted run: a unit row (nm nN), position and force',
                 text=True, supplies=(*_CAL, "velocity", "sample_rate")),
    ReaderFormat("jpk-txt", "JPK Data Processing text export", (".txt", ".out", ".tsv"),
                 _lazy("jpk_text", "detect_jpk_text"), _lazy("jpk_text", "load_jpk_text"),
                 via="afmforce", deflection="N, m or V (as exported)",
                 signature="'# segment:' blocks with '# columns:' and '# units:' lines (JPK DP Export -> Text)",
                 text=True, supplies=(*_CAL, "sample_rate")),
    ReaderFormat("jpk-force", "JPK force curve / force map / QI data (calibrated)",
                 (".jpk-force", ".jpk-force-map", ".jpk-qi-data", ".jpk-qi-series"),
                 _lazy("jpk_zip", "detect_jpk"), _lazy("_afmformats", "load_jpk"),
                 via="afmformats", deflection="N (V if uncalibrated)",
                 signature="zip archive with header.properties and segment headers",
                 supplies=(*_CAL, "velocity", "sample_rate")),
    ReaderFormat("jpk-zip", "JPK force archive read directly (raw volts, pause and modulation segments)",
                 (".jpk-force", ".jpk-force-map", ".jpk-qi-data", ".jpk-qi-series"),
                 _lazy("jpk_zip", "detect_jpk_zip"), _lazy("jpk_zip", "load_jpk_zip"),
                 via="afmforce", deflection="V",
                 signature="zip archive with header.properties and segments/ (maps: index/N/segments/)",
                 supplies=(*_CAL, "sample_rate")),
    ReaderFormat("asylum-ibw", "Asylum Research Igor binary wave", (".ibw",),
                 _lazy("_afmformats", "detect_afmformats"), _lazy("igor", "load_ibw"),
                 via="afmformats", deflection="N (m or V for per-channel waves)",
                 signature="Igor binary wave v5: all channels in one wave, or one per channel (...Defl + ...ZSnsr)",
                 supplies=(*_CAL, "sample_rate", "resonance_frequency")),
    ReaderFormat("nanosurf-nid", "Nanosurf spectroscopy (.nid: single curves and maps)", (".nid",),
                 _lazy("nanosurf", "detect_nid"), _lazy("nanosurf", "load_nid"),
                 via="afmforce", deflection="N (m or V as stored)",
                 signature="[DataSet] header with GroupCount, then #! and binary blocks; 'Spec forward' / "
                           "'Spec backward' frames (images and thermal tunes only: refused by name)",
                 supplies=(*_CAL, "velocity", "sample_rate")),
    ReaderFormat("asylum-ardf", "Asylum Research ARDF force map (MFP-3D, Cypher)", (".ardf",),
                 _lazy("ardf", "detect_ardf"), _lazy("ardf", "load_ardf"),
                 via="afmforce", deflection="m (V for a DeflV-only map)",
                 signature="16-byte records: ARDF, FTOC, TTOC note, VOLM (VDEF grid, VCHN channels, VTOC line table), "
                           "then VSET/VNAM/VDAT per curve",
                 supplies=(*_CAL, "velocity", "sample_rate", "resonance_frequency")),
    ReaderFormat("afm-workshop-csv", "AFM Workshop CSV export", (".csv",),
                 _lazy("_afmformats", "detect_workshop"), _lazy("_afmformats", "load_workshop"),
                 via="afmformats", deflection="N (V for T-B(V) files)",
                 text=True, signature='first line "Force-Distance Curve", then Z-Sense and Force or T-B(V) columns',
                 requires=_CAL),
    ReaderFormat("ntmdt-txt", "NT-MDT Nova text export", (".txt",),
                 _lazy("_afmformats", "detect_ntmdt"), _lazy("_afmformats", "load_ntmdt"),
                 via="afmformats", requires=_CAL, deflection="V",
                 text=True, signature="three tab-separated numeric columns (decimal commas)"),
    ReaderFormat("chiaro-txt", "Optics11 Chiaro or Piuma indenter text export", (".txt",),
                 _lazy("chiaro", "detect_chiaro"), _lazy("chiaro", "load_chiaro"),
                 via="afmforce", text=True, supplies=("spring_constant", "velocity", "radius"),
                 signature="k (N/m) header line, Time (s)/Load (uN)/Indentation/Cantilever/Piezo columns"),
    ReaderFormat("wsxm-curves", "WSxM (Nanotec) force curves", (".curves",),
                 _lazy("wsxm", "detect_wsxm_curves"), _lazy("wsxm", "load_wsxm_curves"),
                 via="afmforce", deflection="V (m or N as the Y axis unit says)", requires=("sensitivity",),
                 signature='"WSxM file copyright" header, an image, then FZ curve blocks (forward = approach, '
                           'backward = retract) of a Normal force channel (Amplitude/Phase curves: refused)',
                 supplies=("spring_constant", "sample_rate", "velocity")),
    ReaderFormat("park-tiff", "Park Systems spectroscopy TIFF (XEI, SmartScan)", (".tiff", ".tif"),
                 _lazy("park", "detect_park"), _lazy("park", "load_park"),
                 via="afmforce", deflection="V (N or m as stored)",
                 signature="TIFF with Park's private tags: magic 50432, header 50435 of type 2 (spectroscopy), "
                           "spectroscopy header 50438 and data 50439 (approach and retract halves; images and line "
                           "profiles: refused)",
                 supplies=(*_CAL, "velocity", "sample_rate")),
)}


def register_format(fmt: ReaderFormat, *, before: str | None = None) -> ReaderFormat:
    """Add a reader to :data:`FORMATS` (a new format needs only its own module calling this).

    Parameters
    ----------
    fmt : ReaderFormat
        The record; its ``identifier`` must be new.
    before : str, optional
        Identifier of a registered format this one is tried before, for a shared suffix
        (default: tried last).

    Returns the record (usable as a module-level statement). Everything that lists or detects
    formats (:func:`load`, :func:`find_format`, ``afmforce formats``, docs/formats.md's table,
    ``--format`` and the web's ``format`` field) reads :data:`FORMATS`, so the reader appears there.

    Raises
    ------
    ParameterError
        The identifier is taken, ``before`` is unknown, or ``fmt`` has no suffix or pattern.
    """
    if not isinstance(fmt, ReaderFormat):
        raise ParameterError(f"register_format takes a ReaderFormat, got {type(fmt).__name__}")
    if fmt.identifier in FORMATS:
        raise ParameterError(f"format {fmt.identifier!r} is registered already; choose another identifier")
    if not (fmt.suffixes or fmt.pattern):
        raise ParameterError(f"format {fmt.identifier!r} claims no file name: give suffixes or a pattern")
    if any(s != s.lower() or not s.startswith(".") for s in fmt.suffixes):
        raise ParameterError(f"format {fmt.identifier!r}: suffixes are lower case and start with a dot, "
                             f"got {fmt.suffixes}")
    if before is not None and before not in FORMATS:
        raise ParameterError(f"format {before!r} (before=) is not registered; choose one of {', '.join(FORMATS)}")
    items = list(FORMATS.items())
    at = len(items) if before is None else [k for k, _ in items].index(before)
    items.insert(at, (fmt.identifier, fmt))
    FORMATS.clear()
    FORMATS.update(items)
    return fmt


def unregister_format(identifier: str) -> None:
    """Remove a reader added by :func:`register_format` (tests; a built-in may be removed too)."""
    if identifier not in FORMATS:
        raise ParameterError(f"format {identifier!r} is not registered")
    del FORMATS[identifier]


def supported_suffixes() -> list[str]:
    """Every fixed file ending some reader accepts (see also :func:`is_supported`)."""
    return sorted({s for f in FORMATS.values() for s in f.suffixes})


def is_supported(path: str | Path) -> bool:
    """Does some reader claim this file name (fixed endings and numbered ``.000``-``.999``)?"""
    return any(f.claims(Path(path).name) for f in FORMATS.values())


#: ending -> ``holds_curves(path)``: files of an ending shared with images that a folder scan takes only
#: when their content says curves (a Park TIFF of spectroscopy, not a topography image beside it).
FOLDER_CHECKS: dict[str, Callable[[Path], bool]] = {
    ".tiff": _lazy("park", "holds_curves"), ".tif": _lazy("park", "holds_curves")}


def in_folder(path: str | Path) -> bool:
    """Does a folder scan (``afmforce analyze FOLDER``) take this file: a reader claims its name and,
    for an ending images share (:data:`FOLDER_CHECKS`), its content holds curves?"""
    path = Path(path)
    check = FOLDER_CHECKS.get(path.suffix.lower())
    return is_supported(path) and (check is None or bool(check(path)))


def find_format(path: str | Path) -> ReaderFormat:
    """The first registered format whose suffix and detector accept ``path``.

    Raises
    ------
    FileFormatError
        The file does not exist, or no reader recognises it.
    """
    path = Path(path)
    if not path.is_file():
        raise FileFormatError(_not_a_file(path))
    if path.suffix.lower() in HDF5_SUFFIXES:
        from ._guard import run_with_timeout

        return FORMATS[run_with_timeout(_find_format_id, path, timeout=HDF5_TIMEOUT, path=str(path))]
    return _find_format(path)


def _find_format_id(path: Path) -> str:
    return _find_format(path).identifier  # a ReaderFormat holds closures: only its name crosses processes


def _find_format(path: Path) -> ReaderFormat:
    if path.stat().st_size == 0:
        raise FileFormatError(f"{path}: empty file (0 bytes)")
    from ._unread import lfs_pointer_refusal

    pointer = lfs_pointer_refusal(path)
    if pointer:
        raise FileFormatError(pointer)
    candidates = [f for f in FORMATS.values() if f.claims(path.name)]
    if not candidates:
        from ._unread import unread_refusal

        raise FileFormatError(unread_refusal(path) or
                              f"{path}: unknown file type; supported endings: {', '.join(supported_suffixes())}, "
                              ".000-.999")
    for fmt in candidates:
        try:
            if fmt.detect(path):
                return fmt
        except Exception:  # a detector must never crash the search
            continue
    from ._unread import unread_refusal

    known = unread_refusal(path)   # a family afmforce knows but does not read (a TIFF image under .tiff)
    if known:
        raise FileFormatError(known)
    from ._unread import damaged_refusal

    cut = damaged_refusal(path)    # starts like a family afmforce reads: cut short or damaged
    if cut:
        raise FileFormatError(cut)
    raise FileFormatError(
        f"{path}: content not recognised as any of: {', '.join(f.name for f in candidates)}; if it is one of "
        f"them, name its reader as `format` (one of {', '.join(f.identifier for f in candidates)}): its "
        "reader then says what it finds wrong")


def load(path: str | Path, *, meta_override: Mapping[str, Any] | None = None,
         progress: Callable[[Progress], None] | None = None, format: str | None = None,
         require: Sequence[str] = (), timeout: float | None = None) -> list[RawCurve]:
    """Read every force curve in ``path``.

    Parameters
    ----------
    path : str or Path
        The file (never modified).
    meta_override : mapping, optional
        Metadata in SI (keys of :data:`METADATA`, e.g. ``spring_constant``
        [N/m], ``sensitivity`` [m/V]) that replace or complete the file's.
    progress : callable, optional
        Called with a :class:`~afmforce.progress.Progress` (``unit="file"``,
        ``done`` the fraction read, ``what`` the file name) where the reader
        reports it (not for files read in a child process).
    format : str, optional
        Identifier of a format in :data:`FORMATS`, skipping detection.
    require : sequence of str, optional
        Metadata every curve must carry, e.g. ``("spring_constant", "sensitivity")``
        for an analysis in force: ``spring_constant`` is required of a deflection in
        V or m, ``sensitivity`` of one in V (a force in N needs neither).
    timeout : float, optional
        Time budget [s] for detecting and reading the file (run in a child
        process that is killed when the budget is spent); None: no limit.

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
    FileTimeoutError
        (a FileFormatError) Reading took longer than ``timeout``.
    ParameterError
        Invalid ``meta_override`` or unknown ``format``.
    """
    if timeout is None and Path(path).suffix.lower() in HDF5_SUFFIXES:
        timeout = HDF5_TIMEOUT  # h5py can spin forever on a damaged heap: always read HDF5 with a budget
    if timeout is not None:
        from ._guard import run_with_timeout

        return run_with_timeout(_load, path, timeout=timeout, path=str(path), meta_override=meta_override,
                                callback=None, format=format, require=require)
    return _load(path, meta_override=meta_override, callback=_file_progress(path, progress), format=format,
                 require=require)


def _file_progress(path, progress) -> Callable[[float], None] | None:
    """The readers' float callback, reported as :class:`~afmforce.progress.Progress` records."""
    if progress is None:
        return None
    name = Path(path).name

    def report(fraction: float) -> None:
        progress(Progress(done=float(fraction), total=1.0, unit="file", what=name))

    return report


#: Endings of HDF5 files, read in a child process with a time budget (:data:`HDF5_TIMEOUT` [s]).
HDF5_SUFFIXES = (".h5", ".hdf5", ".hdf")
HDF5_TIMEOUT = 120.0


def _not_a_file(path: Path) -> str:
    """Why ``path`` cannot be read as a file: it is a folder (give the files in it), or it is not there."""
    if path.is_dir():
        return f"{path} is a folder, not a force-curve file: give the files in it (or the folder to a batch)"
    return f"{path}: no such file"


def _load(path, *, meta_override, callback, format, require) -> list[RawCurve]:
    path = Path(path)
    meta = check_meta_override(meta_override)
    if format is not None:
        if format not in FORMATS:
            raise ParameterError(f"unknown format {format!r}; choose one of {', '.join(FORMATS)}")
        if not path.is_file():
            raise FileFormatError(_not_a_file(path))
        from ._unread import lfs_pointer_refusal

        pointer = lfs_pointer_refusal(path)
        if pointer:
            raise FileFormatError(pointer)
        fmt = FORMATS[format]
    else:
        fmt = find_format(path)
    if fmt.text:
        cut = cut_mid_line(path)
        if cut:
            raise FileFormatError(cut)
    try:
        curves = fmt.loader(path, meta_override=meta, callback=callback)
    except FileFormatError as exc:
        if type(exc) is not FileFormatError:  # missing metadata, time budget: already say what to do
            raise
        raise FileFormatError(_named(str(exc), path, fmt, chosen=format is not None)) from None
    except (AfmforceError, KeyboardInterrupt, SystemExit, GeneratorExit):
        raise
    except MemoryError:
        raise FileFormatError(f"{path}: too large or damaged (out of memory while reading)") from None
    except BaseException as exc:  # third-party parsers raise anything (afmformats: BaseException subclasses)
        raise FileFormatError(damage(path, exc) or refusal(path, fmt, exc, chosen=format is not None)) from None
    if not curves:
        raise FileFormatError(f"{path}: no force curve in the file")
    for curve in curves:
        require_metadata(curve, tuple(require), str(path))
    return curves


def cut_mid_line(path: str | Path) -> str | None:
    """Why a text table ends inside its last row, or None: the file lacks the line break after its last
    line, and that line has fewer fields than the row before it, or a shorter last field (``1.2345e-0``
    of a cut ``1.2345e-09``: a value 10^9 times too large, read as it stands). A complete file without
    the final line break (same fields, same width) passes."""
    path = Path(path)
    size = path.stat().st_size
    with open(path, "rb") as fh:
        fh.seek(max(0, size - 8192))
        tail = fh.read()
    if not tail or tail[-1:] in (b"\n", b"\r"):
        return None
    lines = [ln for ln in re.split(rb"[\r\n]+", tail) if ln.strip()]
    if len(lines) < 2:
        return None
    last, prev = (re.split(rb"[\s,;]+", ln.strip()) for ln in lines[-2:][::-1])
    if len(last) == len(prev) and len(last[-1]) >= len(prev[-1]):
        return None
    shown = lines[-1].strip()[-40:].decode("latin-1")
    return (f"{path}: the file ends inside its last line ('...{shown}': no line break, and fewer or shorter "
            "fields than the row before): cut short, a truncated download or a full disk; copy it again (if the "
            "file is complete, end its last line with a line break)")


def damage(path: str | Path, exc: BaseException) -> str | None:
    """What a reader's exception says of damaged bytes, in words with what to do; None when it is no
    sign of damage (then :func:`refusal` says which reader stopped on what).

    A zip member whose checksum fails or whose compressed stream breaks (``zipfile.BadZipFile``,
    ``zlib.error``: a JPK archive corrupted or cut in transfer), an HDF5 dataset h5py cannot decode
    (``OSError`` raised in h5py), an arithmetic error on a header value (``ZeroDivisionError``,
    ``OverflowError``: a damaged number).
    """
    import zipfile
    import zlib

    text = " ".join(str(exc).split()).replace("`", "'")[:160] or "no detail"
    again = "a corrupted or cut copy (download, full disk): copy the file again from the instrument's computer"
    if isinstance(exc, (zipfile.BadZipFile, zlib.error)) or (isinstance(exc, EOFError) and "compressed" in text):
        return f"{path}: damaged zip archive ({text}): a member's bytes fail their checksum or do not decompress; {again}"
    if isinstance(exc, OSError) and (type(exc).__module__ or "").startswith("h5py") or \
            isinstance(exc, OSError) and ("synchronously" in text or "HDF5" in text):
        return f"{path}: damaged HDF5 file ({text}): h5py cannot decode its data; {again}"
    if isinstance(exc, (ZeroDivisionError, OverflowError, FloatingPointError)):
        return (f"{path}: a number in the file's header is damaged ({type(exc).__name__}: {text}: a zero, "
                f"infinite or huge value where a size, rate or scale belongs); {again}, or give the value as "
                "`meta_override`")
    return None


def _unexpected(exc: BaseException) -> str:
    """What a reader found unexpected, in words (never the bare upstream text)."""
    text = " ".join(str(exc).split()).replace("`", "'")   # upstream `names` are no afmforce keys (errors.QUANTITY_KEY)
    text = text if len(text) <= 160 else text[:160] + "..."
    if isinstance(exc, KeyError):
        return f"the file lacks the entry {text} that the reader looks up"
    if isinstance(exc, (ValueError, TypeError, IndexError, EOFError, UnicodeError)) or \
            type(exc).__name__ in ("error", "BadZipFile", "StructError"):
        return f"the content is not laid out as the reader expects ({type(exc).__name__}: {text or 'no detail'})"
    return f"the reader stopped on {type(exc).__name__}: {text or 'no detail'}"


def _others(path: str | Path, fmt: ReaderFormat) -> list[ReaderFormat]:
    return [f for f in FORMATS.values() if f is not fmt and f.claims(Path(path).name)]


def _named(message: str, path: str | Path, fmt: ReaderFormat, *, chosen: bool) -> str:
    """A reader's own refusal, with which reader it was and the other readers of the file's ending."""
    how = "chosen with format" if chosen else "detected from the content"
    others = [f.identifier for f in _others(path, fmt)]
    tail = f" (reader '{fmt.identifier}', {how}"
    if others:
        tail += f"; other readers of this ending, named as `format`: {', '.join(repr(o) for o in others)}"
    return message.rstrip(". ") + tail + ")"


def refusal(path: str | Path, fmt: ReaderFormat, exc: BaseException, *, chosen: bool = False) -> str:
    """The message of a file a reader could not read: which reader tried (and whether it was chosen with
    ``format``), what it found unexpected, and what to do (another reader of the same ending; metadata
    the file lacks given as ``meta_override``; a report with the file)."""
    how = "chosen with format" if chosen else "detected from the content"
    out = [f"{path}: the {fmt.name} reader ('{fmt.identifier}', {how}, via {fmt.via}) could not read it: "
           f"{_unexpected(exc)}"]
    others = _others(path, fmt)
    todo = []
    if others:
        todo.append("try another reader of this ending, named as `format` ("
                    + ", ".join(f"'{f.identifier}' ({f.name})" for f in others) + ")")
    if isinstance(exc, KeyError):
        todo.append("if the entry is metadata afmforce knows, give it as `meta_override` KEY=VALUE "
                    f"(keys: {', '.join(sorted(METADATA))})")
    todo.append("if the file is valid, report it to afmforce with the file attached")
    return out[0] + "; " + "; ".join(todo)


def formats_table() -> list[dict[str, str]]:
    """One row per format (``afmforce formats``, docs/formats.md, the README)."""
    return [{"identifier": f.identifier, "name": f.name,
             "suffixes": " ".join(f.suffixes) + (" .000-.999" if f.pattern else ""),
             "signature": f.signature, "via": f.via, "deflection": f.deflection,
             "supplies": ", ".join(f.supplies) or "-",
             "requires": ", ".join(f.requires) or "-"}
            for f in FORMATS.values()]


def formats_markdown() -> str:
    """The formats table in Markdown (docs/formats.md and the README hold this text)."""
    head = ("| identifier | format | file endings | content | via | deflection | from the file | "
            "user must give |\n|---|---|---|---|---|---|---|---|\n")
    return head + "".join(
        f"| `{r['identifier']}` | {r['name']} | {r['suffixes']} | {r['signature']} | {r['via']} | "
        f"{r['deflection']} | {r['supplies']} | {r['requires']} |\n" for r in formats_table())
