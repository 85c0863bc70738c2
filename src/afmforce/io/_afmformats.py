"""Readers that go through afmformats: JPK, NT-MDT text, AFM Workshop CSV, its own exports
(Asylum ``.ibw``: :mod:`afmforce.io.igor`; Optics11 Chiaro: :mod:`afmforce.io.chiaro`).

afmformats returns force [N] against a "height" that *decreases* towards the
sample. These readers turn each curve into a :class:`~afmforce.io.curve.RawCurve`:
``z = -height`` (checked: z must increase on the approach run, otherwise the
sign is flipped), force kept as the deflection signal in N (the vendor's
calibration), time from the file or from the sample rate.

Gaps of afmformats filled here:

* segments are numbered in file order by afmformats: JPK segments are mapped by
  their header type (extend 0, retract 1, pause 2; :func:`afmforce.io._meta.segment_code`).
* the user's spring constant and sensitivity are passed on (``meta_override``);
  a file lacking them raises :class:`~afmforce.errors.MissingMetadataError` naming the flags.
* NT-MDT text files carry no spring constant or sensitivity; the user must give
  both (``meta_override``). The file's deflection column (nA in Nova's export) is
  kept as a raw signal with ``deflection_unit = "V"``: deflection [m] = signal x
  sensitivity [m per signal unit, shown by Nova as nm/V].
* single-curve JPK archives are decoded by :mod:`afmforce.io.jpk_zip` (20x faster than
  afmformats' property parser, the same numbers: a test compares them) and turned into
  force with the file's or the user's k and sensitivity; without both they stay in raw
  volts. Force maps and QI data (``index/N/segments``) go through afmformats; so does a
  single curve our decoder refuses. They are read by afmformats' own JPK reader with a faster
  properties parser (:mod:`afmforce.io._jpk_fast`: the same records, ~5x sooner), and by
  ``afmformats.load_data`` itself when that raises.
"""

from __future__ import annotations

import dataclasses
import logging
import re
import warnings
import zipfile
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ..errors import AfmforceError, FileFormatError, MissingMetadataError
from .curve import RawCurve
from ._jpk_fast import load_jpk_data
from ._meta import AFMFORMATS_KEYS, afmformats_override, finalize_curve, missing_metadata, orient, segment_code

__all__ = ["load_afmformats", "load_export", "load_jpk", "load_ntmdt", "load_workshop", "orient", "rescale_force"]

# afmformats and igor2 log loader failures with tracebacks and whole byte buffers; keep them out of
# the user's terminal (the error we raise says what is wrong).
for _name in ("afmformats", "igor2"):
    logging.getLogger(_name).addHandler(logging.NullHandler())
    logging.getLogger(_name).propagate = False


#: Advice of a library under afmformats that names its own arguments (numpy's "use `usecols` to
#: select a subset"): cut from the message; each face renders a `` `key` `` as its own flag or field
#: (:data:`afmforce.errors.QUANTITY_KEY`), so the command line said "use --usecols", a flag afmforce has not.
_FOREIGN_ADVICE = re.compile(r";?\s*use `usecols` to select a subset and avoid this error")


def _short(exc: BaseException, limit: int = 200) -> str:
    """The exception's text, cut to ``limit`` characters (some embed whole byte buffers), without
    advice naming another library's arguments (:data:`_FOREIGN_ADVICE`) and with its other
    backquotes made plain quotes (never rendered as an afmforce flag)."""
    text = _FOREIGN_ADVICE.sub("", str(exc)).replace("`", "'")
    return text if len(text) <= limit else text[:limit] + "..."


def _afm_errors() -> tuple[type[BaseException], ...]:
    """What afmformats may raise on a damaged file: several of its errors derive from
    BaseException (not Exception), so they are listed one by one."""
    from afmformats import errors as afe
    from afmformats import meta as afm

    return (Exception, afe.AFMFileFormatError, afe.MissingMetaDataError, afm.MetaDataMissingError)


#: afmformats' warning that it dropped a column holding a NaN (AFM Workshop reader, ``ws_single.py``)
_DROPPED = re.compile(r"Removed incomplete column: (\S+) in ")


def _load_data(path: Path, meta: Mapping[str, Any], callback) -> list:
    """Call ``afmformats.load_data``; turn its errors (some BaseException) into ours."""
    import afmformats
    from afmformats import errors as afe

    try:
        with warnings.catch_warnings(record=True) as said:  # numpy warns on empty or odd text; we raise instead
            warnings.simplefilter("always")
            data = afmformats.load_data(path, meta_override=dict(meta), callback=callback)
        dropped = [m.group(1) for w in said if (m := _DROPPED.match(str(w.message)))]
        if dropped:     # afmformats drops a column with a NaN cell; its reader then asks for it by name
            raise FileFormatError(f"{path}: column {', '.join(dict.fromkeys(dropped))} has empty or non-numeric "
                                  "cells (nan) inside the data; the file is damaged or padded: remove those rows")
        return data
    except (afe.MissingMetaDataError, FileFormatError):
        raise
    except _afm_errors() as exc:
        raise FileFormatError(f"{path}: afmformats cannot read it ({type(exc).__name__}: {_short(exc)})") from None


def _curve_from_afmdata(dd, path: Path, reader: str, meta_override: Mapping[str, Any],
                        signal: np.ndarray | None = None, unit: str = "N",
                        segment: np.ndarray | None = None,
                        segment_styles: list[str] | None = None) -> RawCurve:
    cols = dd.columns
    md = dict(dd.metadata)
    n = np.asarray(dd["force"]).size  # not len(dd): afmformats takes that from the "point count" metadata
    short = {c: np.asarray(dd[c]).size for c in cols if c != "index" and np.asarray(dd[c]).size != n}
    if short:
        raise FileFormatError(f"{path}: columns of different lengths (force {n}, "
                              f"{', '.join(f'{c} {m}' for c, m in short.items())}); the file is truncated or damaged")
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
        data = None
        if reader == "jpk-force":  # afmformats' JPK reader with a faster properties parser (same records)
            try:
                with warnings.catch_warnings():  # as _load_data
                    warnings.simplefilter("ignore")
                    data = load_jpk_data(path, afmformats_override(meta_override), callback)
            except BaseException as exc:  # anything: afmformats.load_data reads it, or says what is wrong
                if isinstance(exc, (KeyboardInterrupt, SystemExit)):
                    raise
        if data is None:
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
    from .jpk_zip import check_member_sizes, load_jpk_zip, segment_styles

    try:
        arc = zipfile.ZipFile(path)
    except (zipfile.BadZipFile, OSError, ValueError) as exc:
        raise FileFormatError(f"{path}: not a JPK zip archive ({exc})") from None
    with arc:
        check_member_sizes(arc, str(path))      # before either reader unpacks a member
        single = any(n.startswith("segments/") for n in arc.namelist())
        ours: FileFormatError | None = None
        if single:  # one curve: decode it directly
            try:
                return [_jpk_force(load_jpk_zip(path, meta_override=meta_override, callback=callback)[0])]
            except FileFormatError as exc:
                ours = exc  # a variant our decoder does not know: afmformats may
        try:
            curves = load_afmformats(path, meta_override=meta_override, callback=callback, reader="jpk-force",
                                     styles=lambda dd: segment_styles(arc, dd.metadata.get("enum"), str(path)))
            return [_header_flags(_header_rate(c, arc, meta_override), arc) for c in curves]
        except MissingMetadataError:
            return load_jpk_zip(path, meta_override=meta_override, callback=callback)
        except FileFormatError as exc:
            # maps with segments afmformats does not know (modulation, float data): our decoder, or both reasons
            if single:
                return load_jpk_zip(path, meta_override=meta_override, callback=callback)
            try:
                return [_jpk_force(c) for c in load_jpk_zip(path, meta_override=meta_override, callback=callback)]
            except FileFormatError as ours:
                raise FileFormatError(f"{ours}; afmformats' reader: {str(exc).split(': ', 1)[-1]}") from None
        except (AfmforceError, KeyboardInterrupt, SystemExit, GeneratorExit):
            raise
        except BaseException:   # afmformats' errors derive from BaseException
            # afmformats stopped on its own error (a damaged header: ReadJPKError 'Could not find property',
            # a failed CRC): our decoder's reason names the damage ("damaged JPK archive ...")
            if ours is not None:
                raise ours from None
            if single:
                raise
            return [_jpk_force(c) for c in load_jpk_zip(path, meta_override=meta_override, callback=callback)]


def _header_rate(curve: RawCurve, arc: zipfile.ZipFile, meta_override: Mapping[str, Any]) -> RawCurve:
    """The sample rate of the curve's own extend segment: afmformats divides a triggered extend's
    points by the nominal duration (271 Hz for a 2005 Hz curve of a map that stopped early)."""
    from .jpk_zip import extend_rate

    if "sample_rate" in meta_override:
        return curve
    rate = extend_rate(arc, curve.metadata.get("afmformats:enum"))
    if rate is None or rate == curve.metadata.get("sample_rate"):
        return curve
    return dataclasses.replace(curve, metadata={**curve.metadata, "sample_rate": rate})


def _header_flags(curve: RawCurve, arc: zipfile.ZipFile) -> RawCurve:
    """The curve with its segments' force-scan flags (``recording_flags``: the piezo out of range, the
    setpoint not reached), which afmformats does not pass on."""
    from .jpk_zip import curve_recording_flags

    said = curve_recording_flags(arc, curve.metadata.get("afmformats:enum"))
    if not said:
        return curve
    return dataclasses.replace(curve, metadata={**curve.metadata, "recording_flags": said})


def _jpk_force(curve: RawCurve) -> RawCurve:
    """A directly decoded JPK curve in force [N] = volts x sensitivity x k when both are known
    (the file's, or the user's: what afmformats computes, ~20x faster); else left in volts."""
    md = curve.metadata
    k, sens = md.get("spring_constant"), md.get("sensitivity")
    if curve.deflection_unit != "V" or not k or not sens:
        return curve
    meta = {**md, "reader": "jpk-force", "format": "JPK force curve"}
    return finalize_curve(dataclasses.replace(curve, deflection_signal=curve.deflection_signal * curve.force_factor(),
                                              deflection_unit="N", metadata=meta), str(md.get("source_file", "")))


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
    if not detect_workshop(path):
        first = _first_line(path)[:60]
        raise FileFormatError(f"{path}: not an AFM Workshop CSV export: its header has no "
                              f"{WORKSHOP_FIRST_LINE!r} line (AFM Workshop's first line); its first line is {first!r}")
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


def load_export(path: Path, *, meta_override: Mapping[str, Any], callback: Callable | None = None) -> list[RawCurve]:
    """afmformats' own exports (HDF5 or tab-separated): force [N].

    The curve's ``reader`` is ``afmformats-hdf5`` or ``afmformats-tab`` (by the
    file's content). The force is the file's; a user's spring constant or
    sensitivity rescales it (:func:`rescale_force`; afmformats refuses them). afmformats exports an Igor curve with every sample in
    segment 0 (its Igor reader does not split the cycle): a one-segment curve whose
    z runs out and back is split at its turning point (as :mod:`afmforce.io.igor`
    does for the original wave) and says so in ``metadata["segments_note"]``.
    """
    from .native import HDF5_SIGNATURE

    with open(path, "rb") as fh:
        reader = "afmformats-hdf5" if fh.read(8) == HDF5_SIGNATURE else "afmformats-tab"
    data = _load_data(path, {}, callback)  # afmformats' export readers refuse a k or sensitivity override
    if not data:
        raise FileFormatError(f"{path}: the file holds no force-distance curve")
    out = []
    for dd in data:
        force = np.asarray(dd["force"], dtype=float) * rescale_force(path, dd.metadata, meta_override)
        out.append(_split_at_turn(_curve_from_afmdata(dd, path, reader, meta_override, signal=force), path))
    return out


def rescale_force(path: Path, md, meta_override: Mapping[str, Any]) -> float:
    """Factor that turns a force computed with the file's k and sensitivity into one with the user's.

    force = k x sensitivity x volts: a user's spring constant [N/m] or sensitivity
    [m/V] scales it by the ratio to the file's value.

    Raises
    ------
    FileFormatError
        The file stores no (or no positive) value to rescale from.
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


def _split_at_turn(curve: RawCurve, path: Path) -> RawCurve:
    """Approach/retract at the turning point of z for a curve stored as one segment."""
    if np.any(curve.segment != 0):
        return curve
    z = np.asarray(curve.position(), float)
    n = z.size
    turn = int(np.argmax(z)) if z[n // 2] > z[0] else int(np.argmin(z))
    out, back = abs(z[turn] - z[0]), abs(z[turn] - z[-1])
    if not (2 <= turn <= n - 3) or back < 0.25 * out:  # no run back: an approach only, keep it
        return curve
    seg = np.where(np.arange(n) < turn, 0, 1).astype(np.int8)
    z_nom, z_meas, sign = orient(curve.piezo_nominal, curve.piezo_measured, seg)
    meta = {**curve.metadata, "position_sign": float(curve.metadata.get("position_sign", 1.0)) * sign,
            "segments_note": f"split at the turning point of z (sample {turn}): the file marks every sample "
                             "as one segment"}
    return finalize_curve(dataclasses.replace(curve, segment=seg, piezo_nominal=z_nom, piezo_measured=z_meas,
                                              metadata=meta), str(path))


def detect_afmformats_hdf5(path: Path) -> bool:
    """HDF5 signature and the root attribute ``software = "afmformats"`` (size-checked)."""
    from .native import root_attribute

    return root_attribute(path, "software") == "afmformats"


def detect_ntmdt(path: Path) -> bool:
    """NT-MDT Nova text export: rows of three tab-separated numbers (decimal commas allowed)."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(4096).decode("latin-1")
    except OSError:
        return False
    rows = [ln for ln in head.splitlines()[:5] if ln.strip()]
    if not rows:
        return False
    try:
        return all(len(cells := ln.split("\t")) == 3 and all(float(c.replace(",", ".")) is not None for c in cells)
                   for ln in rows[:-1] or rows)
    except ValueError:
        return False


#: The first line AFM Workshop writes in its force-curve CSV export (single curves and the members
#: of a mapping archive); afmformats' own recipe claims every ``.csv`` by its ending alone.
WORKSHOP_FIRST_LINE = "Force-Distance Curve"


def _first_line(path: Path, size: int = 512) -> str:
    """The file's first non-blank line (BOM, quotes and surrounding blanks removed); '' if unreadable."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(size).decode("latin-1")
    except OSError:
        return ""
    for line in head.lstrip("\ufeff\xef\xbb\xbf").splitlines():
        if line.strip():
            return line.strip().strip('"').strip()
    return ""


def detect_workshop(path: Path) -> bool:
    """AFM Workshop CSV export: a ``.csv`` whose header, before its column line (the first with three commas),
    holds :data:`WORKSHOP_FIRST_LINE` (its first line in every AFM Workshop file seen; afmformats' loader asks
    for it on any header line). afmformats' recipe claims any ``.csv``: it read a processed export of another
    program as an AFM Workshop file and failed with its own parser's error."""
    if Path(path).suffix.lower() != ".csv":
        return False
    try:
        with open(path, "rb") as fh:
            head = fh.read(4096).decode("latin-1")
    except OSError:
        return False
    for line in head.splitlines():
        if WORKSHOP_FIRST_LINE in line:
            return True
        if line.count(",") >= 3:
            return False
    return False


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
