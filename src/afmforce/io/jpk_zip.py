"""Direct reader of JPK ``.jpk-force`` archives in raw volts.

A ``.jpk-force`` file is a zip archive: ``header.properties``,
``shared-data/header.properties`` (channel encoders and conversion sets, the
``lcd-info.N.*`` entries) and ``segments/<i>/segment-header.properties`` with
``segments/<i>/channels/<name>.dat`` (big-endian integers). afmformats insists on
a spring constant and a sensitivity before it reads anything; a calibration
curve has neither, yet its vertical deflection in volts against height is
exactly what the constant-compliance calibration needs. This reader returns:

* ``deflection_signal``: ``vDeflection`` in its base slot (volts),
* ``piezo_nominal``: ``-height`` (calibrated slot, else nominal),
* ``piezo_measured``: ``-measuredHeight`` / ``capacitiveSensorHeight`` /
  ``strainGaugeHeight`` (nominal slot), when present,

with z oriented to increase on the extend segment. Spring constant and
sensitivity are put in the metadata when the file defines them.
"""

from __future__ import annotations

import re
import zipfile
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ..errors import FileFormatError
from .curve import RawCurve
from ._meta import finalize_curve, orient, segment_code

__all__ = ["load_jpk_zip", "detect_jpk_zip", "parse_properties", "segment_styles"]

_DTYPES = {"signedshort": ">i2", "unsignedshort": ">u2", "signedinteger": ">i4",
           "unsignedinteger": ">u4", "signedlong": ">i8", "float": ">f4", "double": ">f8"}
_MEASURED = ("measuredHeight", "capacitiveSensorHeight", "strainGaugeHeight")
_ESCAPE = re.compile(r"\\(u[0-9a-fA-F]{4}|.)")
_LINE = re.compile(r"((?:\\.|[^=:\\])*)\s*[=:]\s*(.*)$")


def _unescape(text: str) -> str:
    def repl(m: re.Match) -> str:
        s = m.group(1)
        if s[0] == "u" and len(s) == 5:
            return chr(int(s[1:], 16))
        return {"t": "\t", "n": "\n", "r": "\r", "f": "\f"}.get(s, s)

    return _ESCAPE.sub(repl, text)


def parse_properties(text: str) -> dict[str, str]:
    """Parse a Java ``.properties`` text (``key=value``, ``#`` comments, escapes)."""
    props: dict[str, str] = {}
    for raw in text.splitlines():
        line = raw.strip()
        if not line or line[0] in "#!":
            continue
        if "\\" not in line:  # no escapes (nearly every line): split at the first = or :
            i, j = line.find("="), line.find(":")
            i = j if i < 0 or (0 <= j < i) else i
            if i >= 0:
                props[line[:i].strip()] = line[i + 1:].lstrip()
            continue
        m = _LINE.match(line)
        if m is None:
            continue
        props[_unescape(m.group(1).strip())] = _unescape(m.group(2))
    return props


def detect_jpk(path: Path) -> bool:
    """True for a zip archive with ``header.properties`` (JPK curves, maps, QI data)."""
    try:
        with zipfile.ZipFile(path) as arc:
            return "header.properties" in arc.namelist()
    except (zipfile.BadZipFile, OSError, ValueError):
        return False


def detect_jpk_zip(path: Path) -> bool:
    """True for a zip archive with ``header.properties`` and a ``segments/`` folder."""
    try:
        with zipfile.ZipFile(path) as arc:
            names = arc.namelist()
    except (zipfile.BadZipFile, OSError, ValueError):
        return False
    return "header.properties" in names and any(n.startswith("segments/") for n in names)


def _style(props: Mapping[str, str], index: int) -> str:
    """A segment's type: ``extend``, ``retract`` or ``pause`` (JPK ``settings.style``)."""
    style = props.get("force-segment-header.settings.style")
    if style is None:  # older files: only the segment settings' type, e.g. "z-extend-height"
        kind = props.get("force-segment-header.settings.segment-settings.type", "")
        style = next((w for w in ("extend", "retract", "pause") if w in kind), None)
    if style is None:
        style = "extend" if index == 0 else "retract"
    return style


def _identifier(props: Mapping[str, str]) -> str:
    return props.get("force-segment-header.settings.segment-settings.identifier.name", "")


def segment_styles(arc: zipfile.ZipFile, enum: int | None, where: str) -> list[str]:
    """Segment types of one curve, in file order (``index/<enum>/`` in maps and QI data)."""
    names = set(arc.namelist())
    prefix = "" if "segments/0/segment-header.properties" in names or enum is None else f"index/{int(enum)}/"
    out = []
    for j in range(10_000):
        name = f"{prefix}segments/{j}/segment-header.properties"
        if name not in names:
            break
        out.append(_style(_read_props(arc, name), j))
    if not out:
        raise FileFormatError(f"{where}: no segment headers for curve {enum}")
    return out


def _time_order(seg_ids: list[int], props: dict[int, dict[str, str]]) -> list[int]:
    """Segments in time order: a CellHesion ``pause-at-start`` segment, stored last, comes first."""
    first = [s for s in seg_ids if "pause-at-start" in _identifier(props[s])]
    return first + [s for s in seg_ids if s not in first]


def _channel_props(seg: dict[str, str], shared: dict[str, str], name: str) -> dict[str, str]:
    """Properties of one channel, with ``lcd-info`` references resolved."""
    prefix = f"channel.{name}."
    out = {k[len(prefix):]: v for k, v in seg.items() if k.startswith(prefix)}
    ref = out.get("lcd-info.*")
    if ref is not None:
        lp = f"lcd-info.{ref}."
        for k, v in shared.items():
            if k.startswith(lp):
                out.setdefault(k[len(lp):], v)
    return out


def _num(props: Mapping[str, str], key: str, where: str) -> float:
    try:
        return float(props[key])
    except KeyError:
        raise FileFormatError(f"{where}: missing property {key!r}") from None
    except ValueError:
        raise FileFormatError(f"{where}: property {key!r} is not a number: {props[key]!r}") from None


def _decode(arc: zipfile.ZipFile, seg_dir: str, props: dict[str, str], name: str, where: str) -> np.ndarray:
    """Read a channel's integers and apply its encoder (volts or the base unit)."""
    fname = props.get("data.file.name")
    if fname is None:
        raise FileFormatError(f"{where}: channel {name} has no data file")
    enc = props.get("data.encoder.type", props.get("encoder.type"))
    if enc not in _DTYPES:
        raise FileFormatError(f"{where}: channel {name} has unsupported encoder {enc!r}")
    try:
        raw = arc.read(f"{seg_dir}/{fname}")
    except KeyError:
        raise FileFormatError(f"{where}: data file {seg_dir}/{fname} is missing") from None
    dt = np.dtype(_DTYPES[enc])
    if len(raw) % dt.itemsize:
        raise FileFormatError(f"{where}: {seg_dir}/{fname} is truncated ({len(raw)} bytes)")
    ints = np.frombuffer(raw, dtype=dt).astype(float)
    key = "data.encoder.scaling." if "data.encoder.scaling.multiplier" in props else "encoder.scaling."
    if enc in ("float", "double") and key + "multiplier" not in props:
        return ints
    return ints * _num(props, key + "multiplier", where) + _num(props, key + "offset", where)


def _convert(values: np.ndarray, props: dict[str, str], slot: str, where: str) -> np.ndarray | None:
    """Apply the conversion chain from the base slot up to ``slot`` (None if undefined)."""
    base = props.get("conversion-set.conversions.base", "volts")
    chain = []
    cur = slot
    while cur != base:
        if props.get(f"conversion-set.conversion.{cur}.defined", "false") != "true":
            return None
        chain.append((_num(props, f"conversion-set.conversion.{cur}.scaling.multiplier", where),
                      _num(props, f"conversion-set.conversion.{cur}.scaling.offset", where)))
        cur = props.get(f"conversion-set.conversion.{cur}.base-calibration-slot", base)
        if len(chain) > 8:
            raise FileFormatError(f"{where}: circular conversion chain for slot {slot!r}")
    for mult, off in reversed(chain):
        values = values * mult + off
    return values


def _calibration(props: dict[str, str]) -> dict[str, float]:
    """Spring constant and sensitivity from vDeflection's conversion set, if defined."""
    out = {}
    for slot, key in (("distance", "sensitivity"), ("force", "spring_constant")):
        if props.get(f"conversion-set.conversion.{slot}.defined") == "true":
            try:
                out[key] = float(props[f"conversion-set.conversion.{slot}.scaling.multiplier"])
            except (KeyError, ValueError):
                pass
    return out


def load_jpk_zip(path: Path, *, meta_override: Mapping[str, Any] | None = None,
                 callback: Callable | None = None) -> list[RawCurve]:
    """Read a single-curve ``.jpk-force`` archive with the deflection in volts."""
    path = Path(path)
    where = str(path)
    try:
        arc = zipfile.ZipFile(path)
    except (zipfile.BadZipFile, OSError, ValueError) as exc:
        raise FileFormatError(f"{where}: not a JPK zip archive ({exc})") from None
    with arc:
        try:
            return [_read_archive(arc, where, dict(meta_override or {}), callback)]
        except FileFormatError:
            raise
        except (zipfile.BadZipFile, KeyError, ValueError, OSError, EOFError, RuntimeError,
                UnicodeDecodeError, NotImplementedError) as exc:
            # zlib and zipfile raise several types on damaged members
            raise FileFormatError(f"{where}: damaged JPK archive ({type(exc).__name__}: {str(exc)[:200]})") from None


def _read_props(arc: zipfile.ZipFile, name: str) -> dict[str, str]:
    return parse_properties(arc.read(name).decode("utf-8", errors="replace"))


def _read_archive(arc: zipfile.ZipFile, where: str, meta_override: dict, callback) -> RawCurve:
    names = arc.namelist()
    if "header.properties" not in names:
        raise FileFormatError(f"{where}: header.properties missing; not a JPK force file")
    shared = _read_props(arc, "shared-data/header.properties") if "shared-data/header.properties" in names else {}
    seg_ids = sorted({int(m.group(1)) for n in names if (m := re.match(r"segments/(\d+)/segment-header", n))})
    if not seg_ids:
        raise FileFormatError(f"{where}: no segments in the archive (a force map? use the jpk-force reader)")
    cols: dict[str, list[np.ndarray]] = {"t": [], "zn": [], "zm": [], "s": [], "seg": []}
    meta: dict[str, Any] = {"segment_types": []}
    t0 = 0.0
    headers = {sid: _read_props(arc, f"segments/{sid}/segment-header.properties") for sid in seg_ids}
    seg_ids = _time_order(seg_ids, headers)
    for i, sid in enumerate(seg_ids):
        seg_dir = f"segments/{sid}"
        props = headers[sid]
        style = _style(props, sid)
        meta["segment_types"].append(_identifier(props) or style)
        chans = props.get("channels.list", "").split()
        if "vDeflection" not in chans:
            raise FileFormatError(f"{where}: segment {sid} has no vDeflection channel")
        pv = _channel_props(props, shared, "vDeflection")
        volts = _decode(arc, seg_dir, pv, "vDeflection", where)
        meta.update(_calibration(pv))
        n = volts.size
        if "height" in chans:
            ph = _channel_props(props, shared, "height")
            hv = _decode(arc, seg_dir, ph, "height", where)
            height = _convert(hv, ph, "calibrated", where)
            height = _convert(hv, ph, "nominal", where) if height is None else height
            height = hv if height is None else height
        else:
            height = None
        measured = None
        for name in _MEASURED:
            if name in chans:
                pm = _channel_props(props, shared, name)
                mv = _decode(arc, seg_dir, pm, name, where)
                measured = _convert(mv, pm, "nominal", where)
                measured = mv if measured is None else measured
                break
        if height is None:
            if measured is None:
                raise FileFormatError(f"{where}: segment {sid} has no height channel")
            height, measured = measured, None
        for arr in (height, measured):
            if arr is not None and arr.size != n:
                raise FileFormatError(f"{where}: segment {sid}: channels differ in length")
        duration = float(props.get("force-segment-header.duration", "nan"))
        dt = duration / n if np.isfinite(duration) and duration > 0 else np.nan
        if not np.isfinite(dt):
            meta["time_is_sample_index"] = True
            dt = 1.0
        elif "sample_rate" not in meta and segment_code(style) == 0:
            meta["sample_rate"] = 1.0 / dt
        cols["t"].append(t0 + dt * np.arange(n))
        t0 += dt * n
        cols["zn"].append(-height)
        cols["zm"].append(None if measured is None else -measured)
        cols["s"].append(volts)
        cols["seg"].append(np.full(n, segment_code(style), dtype=np.int8))
        if callback is not None:
            callback((i + 1) / len(seg_ids))
    zm = None if any(m is None for m in cols["zm"]) else np.concatenate(cols["zm"])
    seg = np.concatenate(cols["seg"])
    zn, zm, sign = orient(np.concatenate(cols["zn"]), zm, seg)
    gen = _read_props(arc, "header.properties")
    instrument = gen.get("force-scan-series.description.instrument") or gen.get(
        "force-scan-map.description.instrument")
    if instrument:
        meta["instrument"] = instrument
    meta.update(meta_override)
    meta.update(source_file=where, reader="jpk-zip", format="JPK force archive (raw volts)",
                position_sign=sign)
    curve = RawCurve(time=np.concatenate(cols["t"]), piezo_nominal=zn, piezo_measured=zm,
                     deflection_signal=np.concatenate(cols["s"]), segment=seg, metadata=meta,
                     deflection_unit="V")
    return finalize_curve(curve, where)
