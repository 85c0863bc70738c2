"""Readers that go through afmformats: JPK, Asylum (.ibw), NT-MDT text, AFM Workshop CSV.

afmformats returns force [N] against a "height" that *decreases* towards the
sample. These readers turn each curve into a :class:`~afmforce.raw.RawCurve`:
``z = -height`` (checked: z must increase on the approach run, otherwise the
sign is flipped), force kept as the deflection signal in N (the vendor's
calibration), time from the file or from the sample rate.

Gaps of afmformats filled here:

* ``.ibw`` curves come as one segment: split at the turning point (the wave
  note's ``Indexes`` entry when present, otherwise the extreme of z).
* NT-MDT text files carry no spring constant or sensitivity; the user must give
  both (``meta_override``). The file's deflection column (nA in Nova's export) is
  kept as a raw signal with ``deflection_unit = "V"``: deflection [m] = signal x
  sensitivity [m per signal unit, shown by Nova as nm/V].
* JPK files without calibration (afmformats raises ``MissingMetaDataError``) are
  read by :mod:`afmforce.io.jpk_zip` in raw volts instead.
"""

from __future__ import annotations

import dataclasses
import logging
import warnings
import zipfile
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ..errors import FileFormatError, MissingMetadataError
from ..raw import RawCurve
from ._meta import AFMFORMATS_KEYS, afmformats_override, finalize_curve, missing_metadata, orient, segment_code

__all__ = ["load_afmformats", "load_ibw", "load_jpk", "load_ntmdt", "load_workshop", "orient"]

# afmformats and igor2 log loader failures with tracebacks and whole byte buffers; keep them out of
# the user's terminal (the error we raise says what is wrong).
for _name in ("afmformats", "igor2"):
    logging.getLogger(_name).addHandler(logging.NullHandler())
    logging.getLogger(_name).propagate = False


def _short(exc: BaseException, limit: int = 200) -> str:
    """The exception's text, cut to ``limit`` characters (some embed whole byte buffers)."""
    text = str(exc)
    return text if len(text) <= limit else text[:limit] + "..."


def _afm_errors() -> tuple[type[BaseException], ...]:
    """What afmformats may raise on a damaged file: several of its errors derive from
    BaseException (not Exception), so they are listed one by one."""
    from afmformats import errors as afe
    from afmformats import meta as afm

    return (Exception, afe.AFMFileFormatError, afe.MissingMetaDataError, afm.MetaDataMissingError)


def _load_data(path: Path, meta: Mapping[str, Any], callback) -> list:
    """Call ``afmformats.load_data``; turn its errors (some BaseException) into ours."""
    import afmformats
    from afmformats import errors as afe

    try:
        with warnings.catch_warnings():  # numpy warns on empty or odd text; we raise instead
            warnings.simplefilter("ignore")
            return afmformats.load_data(path, meta_override=dict(meta), callback=callback)
    except afe.MissingMetaDataError:
        raise
    except _afm_errors() as exc:
        raise FileFormatError(f"{path}: afmformats cannot read it ({type(exc).__name__}: {_short(exc)})") from None


def _curve_from_afmdata(dd, path: Path, reader: str, meta_override: Mapping[str, Any],
                        signal: np.ndarray | None = None, unit: str = "N",
                        segment: np.ndarray | None = None,
                        segment_styles: list[str] | None = None) -> RawCurve:
    cols = dd.columns
    md = dict(dd.metadata)
    n = len(dd)
    if "height (piezo)" in cols:
        z_nom = -np.asarray(dd["height (piezo)"], dtype=float)
        z_meas = -np.asarray(dd["height (measured)"], dtype=float) if "height (measured)" in cols else None
    elif "height (measured)" in cols:
        z_nom, z_meas = -np.asarray(dd["height (measured)"], dtype=float), None
    else:
        raise FileFormatError(f"{path}: no height column in the file")
    seg = (np.asarray(dd["segment"]).astype(np.int8) if segment is None else segment)
    meta: dict[str, Any] = {}
    for key, value in md.items():
        name = AFMFORMATS_KEYS.get(key)
        if name is not None and value is not None:
            try:
                meta[name] = float(value) if name != "instrument" else str(value)
            except (TypeError, ValueError):
                pass
        elif isinstance(value, (int, float, str)):
            meta[f"afmformats:{key}"] = value
    for ours, theirs in (("map_x", "grid index x"), ("map_y", "grid index y"),
                         ("map_nx", "grid shape x"), ("map_ny", "grid shape y")):
        if isinstance(md.get(theirs), (int, np.integer)):
            meta[ours] = int(md[theirs])
    for ours, theirs in (("position_x", "position x"), ("position_y", "position y")):
        if isinstance(md.get(theirs), (float, int)):
            meta[ours] = float(md[theirs])  # [m]
    meta.update(meta_override)
    if segment_styles is not None:  # vendor segment types, in file order -> afmforce codes
        codes = np.array([segment_code(style) for style in segment_styles], dtype=np.int8)
        if seg.size and int(seg.max()) >= codes.size:
            raise FileFormatError(f"{path}: segment {int(seg.max())} has no header")
        seg = codes[seg]
        meta["segment_types"] = list(segment_styles)
    if "time" in cols:
        time = np.asarray(dd["time"], dtype=float)
    elif meta.get("sample_rate"):
        time = np.arange(n) / float(meta["sample_rate"])
    else:
        time = np.arange(n, dtype=float)
        meta["time_is_sample_index"] = True
    z_nom, z_meas, sign = orient(z_nom, z_meas, seg)
    meta.update(source_file=str(path), reader=reader, format=str(md.get("format", reader)),
                position_sign=sign)
    if signal is None:
        signal = np.asarray(dd["force"], dtype=float)
    curve = RawCurve(time=time, piezo_nominal=z_nom, piezo_measured=z_meas,
                     deflection_signal=np.asarray(signal, dtype=float), segment=seg,
                     metadata=meta, deflection_unit=unit)
    return finalize_curve(curve, str(path))


def load_afmformats(path: Path, *, meta_override: Mapping[str, Any], callback, reader: str,
                    styles: Callable | None = None) -> list[RawCurve]:
    """Generic afmformats reader: every curve of the file, force in N.

    The user's spring constant and sensitivity go to afmformats (``meta_override``),
    which computes the force with them. ``styles(dd)`` gives the vendor segment types
    of a curve in file order (afmformats numbers segments in file order).
    """
    from afmformats import errors as afe

    try:
        data = _load_data(path, afmformats_override(meta_override), callback)
    except afe.MissingMetaDataError:
        raise missing_metadata(str(path), [k for k in ("spring_constant", "sensitivity")
                                           if k not in meta_override]) from None
    if not data:
        raise FileFormatError(f"{path}: the file holds no force-distance curve")
    return [_curve_from_afmdata(dd, path, reader, meta_override,
                                segment_styles=None if styles is None else styles(dd)) for dd in data]


def load_jpk(path: Path, *, meta_override: Mapping[str, Any], callback: Callable | None = None) -> list[RawCurve]:
    """JPK ``.jpk-force``, maps and QI data; segments by their type (extend, retract, pause).

    A file afmformats refuses for missing calibration (no spring constant, or no
    sensitivity, and none given by the user) is read in raw volts by
    :mod:`afmforce.io.jpk_zip`; so are files with pause segments afmformats cannot read.
    """
    from .jpk_zip import load_jpk_zip, segment_styles

    try:
        arc = zipfile.ZipFile(path)
    except (zipfile.BadZipFile, OSError, ValueError) as exc:
        raise FileFormatError(f"{path}: not a JPK zip archive ({exc})") from None
    with arc:
        try:
            return load_afmformats(path, meta_override=meta_override, callback=callback, reader="jpk-force",
                                   styles=lambda dd: segment_styles(arc, dd.metadata.get("enum"), str(path)))
        except MissingMetadataError:
            return load_jpk_zip(path, meta_override=meta_override, callback=callback)


def _ibw_segments(path: Path, z: np.ndarray) -> np.ndarray:
    """Segments of a one-segment Igor wave from the note's ``Indexes`` (ends of the segments:
    ``0,turn,end`` for approach and retract, ``0,a,b,end`` with a dwell between), else the extreme of z."""
    n = len(z)
    try:
        from igor2 import binarywave

        note = str(binarywave.load(path)["wave"]["note"])
        for line in note.replace("\\r", "\r").split("\r"):
            if line.startswith("Indexes:"):
                idx = [int(float(v)) for v in line.split(":", 1)[1].split(",") if v.strip()]
                if len(idx) == 3 and 0 < idx[1] < n - 1:
                    return np.where(np.arange(n) < idx[1], 0, 1).astype(np.int8)
                if len(idx) == 4 and 0 < idx[1] < idx[2] < n - 1:  # approach, dwell, retract
                    return np.select([np.arange(n) < idx[1], np.arange(n) < idx[2]], [0, 2], 1).astype(np.int8)
    except Exception:  # the note is optional; fall back on the data
        pass
    turn = int(np.argmax(z)) if z[n // 2] > z[0] else int(np.argmin(z))
    return np.where(np.arange(n) < turn, 0, 1).astype(np.int8)


def check_ibw_header(path: Path) -> None:
    """Reject an Igor binary wave whose header declares more bytes than the file holds.

    igor2 builds struct formats from these sizes; a damaged size makes it spend
    minutes before failing. Version 5 header (BinHeader5, 64 bytes): version,
    checksum, then the sizes of the wave, formula, note, units, labels and
    indices sections (int32), in the file's byte order.
    """
    import struct

    with open(path, "rb") as fh:
        head = fh.read(64)
        size = fh.seek(0, 2)
    if len(head) < 8:
        raise FileFormatError(f"{path}: too short for an Igor binary wave ({size} bytes)")
    order = "<" if struct.unpack("<h", head[:2])[0] in (1, 2, 3, 5) else ">"
    version = struct.unpack(order + "h", head[:2])[0]
    if version not in (1, 2, 3, 5):
        raise FileFormatError(f"{path}: not an Igor binary wave (version field {version})")
    if version == 5:
        if len(head) < 64:
            raise FileFormatError(f"{path}: truncated Igor header")
        sizes = struct.unpack(order + "i" * 15, head[4:64])
        if min(sizes) < 0 or 64 + sum(sizes) > size:
            raise FileFormatError(f"{path}: damaged or truncated Igor binary wave (its header declares "
                                  f"{64 + sum(sizes)} bytes, the file has {size})")


def load_ibw(path: Path, *, meta_override: Mapping[str, Any], callback: Callable | None = None) -> list[RawCurve]:
    """Asylum ``.ibw`` force curve: one wave, split into approach and retract."""
    check_ibw_header(path)
    data = _load_data(path, {}, callback)  # afmformats' Igor reader takes no meta_override
    out = []
    for dd in data:
        height = dd["height (measured)"] if "height (measured)" in dd.columns else dd["height (piezo)"]
        z = -np.asarray(height, dtype=float)
        seg = np.asarray(dd["segment"]).astype(np.int8)
        if np.all(seg == 0):
            seg = _ibw_segments(path, z)
        force = np.asarray(dd["force"], dtype=float) * _rescale(path, dd.metadata, meta_override)
        curve = _curve_from_afmdata(dd, path, "asylum-ibw", meta_override, segment=seg, signal=force)
        thermal = _ibw_thermal(path)  # the user's values (already in the metadata) win
        out.append(dataclasses.replace(curve, metadata={**thermal, **dict(curve.metadata)}))
    return out


def _ibw_thermal(path: Path) -> dict[str, float]:
    """The wave note's thermal tune: ``ThermalFrequency`` [Hz] -> ``resonance_frequency``, ``ThermalQ`` -> ``quality_factor``."""
    out: dict[str, float] = {}
    try:
        from igor2 import binarywave

        note = binarywave.load(path)["wave"]["note"]
        note = note.decode("latin-1") if isinstance(note, bytes) else str(note)
        for line in note.replace("\r", "\n").split("\n"):
            key, sep, value = line.partition(":")
            if sep and key.strip() in ("ThermalFrequency", "ThermalQ"):
                v = float(value.strip())
                if np.isfinite(v) and v > 0:
                    out["resonance_frequency" if key.strip() == "ThermalFrequency" else "quality_factor"] = v
    except Exception:  # the note is optional
        pass
    return out


def _rescale(path: Path, md, meta_override: Mapping[str, Any]) -> float:
    """Factor that turns a force computed with the file's k and sensitivity into one with the user's.

    Asylum stores the deflection in metres (volts x the file's InvOLS); force = k x deflection.
    """
    factor = 1.0
    for ours, theirs in (("spring_constant", "spring constant"), ("sensitivity", "sensitivity")):
        if ours in meta_override:
            try:
                old = float(md[theirs])
            except _afm_errors():  # afmformats' missing-metadata error is a BaseException
                raise FileFormatError(f"{path}: the file stores no {theirs}, so its force cannot be "
                                      f"recomputed with the given {ours}") from None
            if not (np.isfinite(old) and old > 0):
                raise FileFormatError(f"{path}: the file's {theirs} is {old!r}; cannot rescale to the given {ours}")
            factor *= float(meta_override[ours]) / old
    return factor


def load_ntmdt(path: Path, *, meta_override: Mapping[str, Any], callback: Callable | None = None) -> list[RawCurve]:
    """NT-MDT Nova text export; needs ``spring_constant`` and ``sensitivity`` from the user."""
    from afmformats import errors as afe

    missing = [k for k in ("spring_constant", "sensitivity") if k not in meta_override]
    if missing:
        raise missing_metadata(str(path), missing, what="NT-MDT text files store")
    k, sens = float(meta_override["spring_constant"]), float(meta_override["sensitivity"])
    # afmformats: force = column * 1e-9 * sensitivity[m/A] * k; the column is the raw signal
    try:
        data = _load_data(path, {"spring constant": k, "sensitivity": sens * 1e9}, callback)
    except afe.MissingMetaDataError as exc:  # pragma: no cover - guarded above
        raise FileFormatError(f"{path}: {exc}") from None
    out = []
    for dd in data:
        signal = np.asarray(dd["force"], dtype=float) / (k * sens)
        out.append(_curve_from_afmdata(dd, path, "ntmdt-txt", meta_override, signal=signal, unit="V"))
    return out


def load_workshop(path: Path, *, meta_override: Mapping[str, Any], callback: Callable | None = None) -> list[RawCurve]:
    """AFM Workshop CSV export (single curves): force [N] or deflection [V] (``T-B(V)``) vs Z-sense.

    A file in volts needs the spring constant and the sensitivity from the user
    (afmformats will not read it otherwise); its deflection is returned in volts.
    """
    with open(path, "rb") as fh:
        head = fh.read(4096).decode("latin-1")
    volts = "T-B(V)" in head and "Force(" not in head
    if volts:
        missing = [k for k in ("spring_constant", "sensitivity") if k not in meta_override]
        if missing:
            raise missing_metadata(str(path), missing, what="this AFM Workshop file (deflection in volts) stores")
    curves = load_afmformats(path, meta_override=meta_override, callback=callback, reader="afm-workshop-csv")
    if not volts:
        return curves
    kv = float(meta_override["spring_constant"]) * float(meta_override["sensitivity"])
    return [finalize_curve(dataclasses.replace(c, deflection_signal=c.deflection_signal / kv,
                                               deflection_unit="V"), str(path)) for c in curves]


def detect_afmformats(path: Path) -> bool:
    """True if afmformats recognises the file (suffix and its own detector)."""
    from afmformats import formats

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            formats.get_recipe(path)
    except _afm_errors():
        return False
    return True
