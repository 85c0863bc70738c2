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

__all__ = ["load_jpk_zip", "detect_jpk_zip", "parse_properties", "segment_styles", "extend_rate"]

#: Encoders (``encoder.type``) of integer data, and the stored types of data without one
#: (``lcd-info.N.type``: JPK Data Processing re-saves channels as ``float-data`` volts).
_DTYPES = {"signedshort": ">i2", "unsignedshort": ">u2", "signedinteger": ">i4",
           "unsignedinteger": ">u4", "signedlong": ">i8", "unsignedlong": ">u8", "signedbyte": ">i1",
           "unsignedbyte": ">u1", "float": ">f4", "double": ">f8"}
_DATA_TYPES = {"float-data": ">f4", "double-data": ">f8", "float": ">f4", "double": ">f8",
               "short-data": ">i2", "integer-data": ">i4", "long-data": ">i8"}
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


def check_member_sizes(arc: zipfile.ZipFile, where: str) -> None:
    """Refuse an archive with a member that unpacks to more than :data:`afmforce.limits.MAX_MEMBER_BYTES`
    (its declared size, which :mod:`zipfile` never reads past), before any member is read.

    Raises
    ------
    FileFormatError
    """
    from ..limits import MAX_MEMBER_BYTES, MAX_SAMPLES

    big = max(arc.infolist(), key=lambda i: i.file_size, default=None)
    if big is not None and big.file_size > MAX_MEMBER_BYTES:
        raise FileFormatError(
            f"{where}: {big.filename} would unpack to {big.file_size:,} bytes ({big.compress_size:,} stored), "
            f"more than a force curve's channel holds ({MAX_MEMBER_BYTES:,} bytes: {MAX_SAMPLES:,} samples); a "
            "damaged archive or a zip bomb: not read")


def detect_jpk(path: Path) -> bool:
    """True for a zip archive with ``header.properties`` (JPK curves, maps, QI data). The directory
    is read into arrays (:mod:`afmforce.io._lean_zip`: a 128 x 128 QI file's 245,764 members in
    0.6 s instead of several), else by :mod:`zipfile`."""
    from ._lean_zip import LeanZip, index_group

    try:
        lean = LeanZip(path, index_group)
    except Exception:
        pass
    else:
        lean.close()
        return "header.properties" in lean.named
    try:
        with zipfile.ZipFile(path) as arc:
            return "header.properties" in arc.namelist()
    except (zipfile.BadZipFile, OSError, ValueError):
        return False


def detect_jpk_zip(path: Path) -> bool:
    """True for a zip archive with ``header.properties`` and ``segments/`` (or ``index/<i>/segments/``)."""
    try:
        with zipfile.ZipFile(path) as arc:
            names = arc.namelist()
    except (zipfile.BadZipFile, OSError, ValueError):
        return False
    return "header.properties" in names and bool(_curve_prefixes(names))


def _style(props: Mapping[str, str], index: int) -> str:
    """A segment's type by what the piezo does: ``extend``, ``retract``, ``pause`` or
    ``modulation`` (JPK ``settings.style``; older files: the segment settings' type, e.g.
    ``z-extend-height``, ``constant-force-pause``, ``sine-z-modulation-segment-settings``)."""
    style = props.get("force-segment-header.settings.style")
    if style is None:
        kind = props.get("force-segment-header.settings.segment-settings.type", "")
        style = next((w for w in ("extend", "retract", "pause", "modulation") if w in kind), None)
    if style is None:
        style = "extend" if index == 0 else "retract"
    return style


def _identifier(props: Mapping[str, str]) -> str:
    """The segment's name (``extend-spm``, ``pause-at-start-cellhesion200``); a modulation
    segment is named by its drive (``modulation sine-z 300 Hz 15 nm``)."""
    name = props.get("force-segment-header.settings.segment-settings.identifier.name", "")
    if name or _style(props, 1) != "modulation":
        return name
    pre = "force-segment-header.settings.segment-settings."
    kind = props.get(pre + "type", "").replace("-modulation-segment-settings", "")
    parts = ["modulation", kind]
    for key, scale, unit in (("frequency", 1.0, "Hz"), ("amplitude", 1e9, "nm")):
        try:
            parts.append(f"{float(props[pre + key]) * scale:.4g} {unit}")
        except (KeyError, ValueError):
            pass
    return " ".join(p for p in parts if p)


def _segment_header(arc: zipfile.ZipFile, name: str, shared: Mapping[str, str]) -> dict[str, str]:
    """A segment header with its shared part resolved: force maps and QI data keep the settings
    of each segment once, in ``shared-data/header.properties`` (``force-segment-header-info.N.*``),
    and the segment header points to them (``force-segment-header.force-segment-header-info.*=N``)."""
    props = _read_props(arc, name)
    ref = props.get("force-segment-header.force-segment-header-info.*")
    if ref is not None and shared:
        for k, v in _group(shared, f"force-segment-header-info.{ref}."):
            props.setdefault("force-segment-header." + k, v)
    return props


class SharedHeader(dict):
    """``shared-data/header.properties``, with its groups (``lcd-info.1.*``) found once: a map's
    thousands of curves resolve their references to the same few groups."""

    def group(self, prefix: str) -> list[tuple[str, str]]:
        cache = self.__dict__.setdefault("_groups", {})
        if prefix not in cache:
            cache[prefix] = [(k[len(prefix):], v) for k, v in self.items() if k.startswith(prefix)]
        return cache[prefix]


def _group(shared: Mapping[str, str], prefix: str) -> list[tuple[str, str]]:
    """The shared entries under ``prefix``, as ``(rest of the key, value)``."""
    if isinstance(shared, SharedHeader):
        return shared.group(prefix)
    return [(k[len(prefix):], v) for k, v in shared.items() if k.startswith(prefix)]


def _shared(arc: zipfile.ZipFile) -> SharedHeader:
    name = "shared-data/header.properties"
    return SharedHeader(_read_props(arc, name) if name in arc.namelist() else {})


def _curve_prefixes(names) -> list[str]:
    """``""`` for a single curve (``segments/``), else ``index/<i>/`` of every curve of a map or QI file."""
    if any(n.startswith("segments/") for n in names):
        return [""]
    found = {int(m.group(1)) for n in names if (m := re.match(r"index/(\d+)/segments/\d+/segment-header", n))}
    return [f"index/{i}/" for i in sorted(found)]


def segment_styles(arc: zipfile.ZipFile, enum: int | None, where: str) -> list[str]:
    """Segment types of one curve, in file order (``index/<enum>/`` in maps and QI data)."""
    names = set(arc.namelist())
    prefix = "" if "segments/0/segment-header.properties" in names or enum is None else f"index/{int(enum)}/"
    shared = _shared(arc)
    out = []
    for j in range(10_000):
        name = f"{prefix}segments/{j}/segment-header.properties"
        if name not in names:
            break
        out.append(_style(_segment_header(arc, name, shared), j))
    if not out:
        raise FileFormatError(f"{where}: no segment headers for curve {enum}")
    return out


def extend_rate(arc: zipfile.ZipFile, enum: int | None) -> float | None:
    """Sample rate [Hz] of a curve's extend segment: its points over its duration (the segment
    header's own; a triggered extend of a map stops early, with fewer points in less time)."""
    names = set(arc.namelist())
    prefix = "" if "segments/0/segment-header.properties" in names or enum is None else f"index/{int(enum)}/"
    shared = _shared(arc)
    for j in range(10_000):
        name = f"{prefix}segments/{j}/segment-header.properties"
        if name not in names:
            return None
        props = _segment_header(arc, name, shared)
        if segment_code(_style(props, j)) == 0:
            try:
                n, duration = int(props["force-segment-header.num-points"]), float(props["force-segment-header.duration"])
            except (KeyError, ValueError):
                return None
            return n / duration if n > 0 and duration > 0 else None
    return None


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
        for k, v in _group(shared, f"lcd-info.{ref}."):
            out.setdefault(k, v)
    return out


def _num(props: Mapping[str, str], key: str, where: str) -> float:
    try:
        return float(props[key])
    except KeyError:
        raise FileFormatError(f"{where}: missing property {key!r}") from None
    except ValueError:
        raise FileFormatError(f"{where}: property {key!r} is not a number: {props[key]!r}") from None


#: What a refusal of a damaged or cut-down JPK archive asks for instead.
GIVE_SAVED = "give the file as the JPK software saved it (or its text export: Data Processing, Export -> Text)"


def _decode(arc: zipfile.ZipFile, seg_dir: str, props: dict[str, str], name: str, where: str) -> np.ndarray:
    """Read a channel's stored values and apply its encoder (volts or the base unit).

    Integer data carry an encoder (``encoder.type`` with ``encoder.scaling.offset`` and
    ``multiplier``); float and double data (``type=float-data``, as JPK Data Processing saves)
    are the values themselves, unless an encoder scales them too.
    """
    fname = props.get("data.file.name")
    if fname is None:
        raise FileFormatError(f"{where}: channel {name} has no data file")
    enc = props.get("data.encoder.type", props.get("encoder.type"))
    kind = props.get("data.type", props.get("type", ""))
    if enc is not None and enc in _DTYPES:
        dtype = _DTYPES[enc]
    elif enc is None and kind in _DATA_TYPES:
        dtype = _DATA_TYPES[kind]
    else:
        raise FileFormatError(f"{where}: channel {name}: unknown data encoding (encoder {enc!r}, data type "
                              f"{kind!r}); known encoders: {', '.join(_DTYPES)}; data types: {', '.join(_DATA_TYPES)}")
    try:
        raw = arc.read(f"{seg_dir}/{fname}")
    except KeyError:
        raise FileFormatError(f"{where}: data file {seg_dir}/{fname} is missing: the header lists channel {name} "
                              f"but the archive does not hold it (an edited or cut-down copy); {GIVE_SAVED}") from None
    dt = np.dtype(dtype)
    if len(raw) % dt.itemsize:
        raise FileFormatError(f"{where}: {seg_dir}/{fname} is truncated ({len(raw)} bytes); {GIVE_SAVED}")
    values = np.frombuffer(raw, dtype=dt).astype(float)
    key = "data.encoder.scaling." if "data.encoder.scaling.multiplier" in props else "encoder.scaling."
    if key + "multiplier" not in props:
        if dt.kind == "f":
            return values
        raise FileFormatError(f"{where}: channel {name}: integer data ({enc or kind}) without an encoder's "
                              f"scaling (offset and multiplier); cannot turn them into volts")
    return values * _num(props, key + "multiplier", where) + _num(props, key + "offset", where)


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
    """Read a JPK archive (a single curve, a force map or QI data) with the deflection in volts:
    one curve per ``segments/`` folder (a single curve) or ``index/<i>/segments/`` (maps)."""
    path = Path(path)
    where = str(path)
    try:
        arc = zipfile.ZipFile(path)
    except (zipfile.BadZipFile, OSError, ValueError) as exc:
        raise FileFormatError(f"{where}: not a JPK zip archive ({exc})") from None
    with arc:
        check_member_sizes(arc, where)
        try:
            names = arc.namelist()
            if "header.properties" not in names:
                raise FileFormatError(f"{where}: header.properties missing; not a JPK force file")
            prefixes = _curve_prefixes(names)
            if not prefixes:
                raise FileFormatError(f"{where}: no segments in the archive (neither segments/ nor index/N/segments/)")
            shared = _shared(arc)
            general = _read_props(arc, "header.properties")
            out = []
            for i, prefix in enumerate(prefixes):
                out.append(_read_archive(arc, where, dict(meta_override or {}), None, prefix=prefix,
                                         shared=shared, general=general))
                if callback is not None:
                    callback((i + 1) / len(prefixes))
            return out
        except FileFormatError:
            raise
        except (zipfile.BadZipFile, KeyError, ValueError, OSError, EOFError, RuntimeError,
                UnicodeDecodeError, NotImplementedError) as exc:
            # zlib and zipfile raise several types on damaged members
            raise FileFormatError(f"{where}: damaged JPK archive ({type(exc).__name__}: {str(exc)[:200]})") from None


def _map_position(gen: Mapping[str, str], index: int) -> dict[str, Any]:
    """Grid cell and position [m] of curve ``index`` of a map (JPK grids run back and forth).

    The cell is that of the curve's own ``position-index`` (its point in the scan) where its header
    gives one, else of ``index`` (its folder ``index/<index>/``): a map saved with some curves only
    (afmformats' ``map2x2_extracted``: the four corners of a 10 x 10 grid in ``index/0..3``) has
    folders numbered 0..n-1 whatever points they were measured at (they were drawn in a row)."""
    out: dict[str, Any] = {}
    for ours, key in (("position_x", "position.x"), ("position_y", "position.y")):
        for pre in ("force-scan-series.header.", "quantitative-imaging-series.header."):
            try:
                out[ours] = float(gen[pre + key])
                break
            except (KeyError, ValueError):
                continue
    for pre in ("force-scan-series.header.", "quantitative-imaging-series.header."):
        try:
            index = int(gen[pre + "position-index"])
            break
        except (KeyError, ValueError):
            continue
    for pre in ("force-scan-map.position-pattern.grid.", "quantitative-imaging-map.position-pattern.grid."):
        try:
            nx, ny = int(gen[pre + "ilength"]), int(gen[pre + "jlength"])
        except (KeyError, ValueError):
            continue
        if nx > 0 and ny > 0:
            iy, ix = divmod(index, nx)
            if gen.get(pre.replace("grid.", "back-and-forth")) == "true" and iy % 2:
                ix = nx - 1 - ix
            out.update(map_x=ix, map_y=iy, map_nx=nx, map_ny=ny)
        break
    return out


#: The instrument's flags of a force segment (``force-segment-header.force-scan-flags.<flag>=true``) and what
#: each means: a curve whose extend ran out of z range before the setpoint stores few samples, or none in
#: contact (nanite's `fmt-jpk-fd_single_bad_*` and `fmt-jpk-fd_map_bad_*` test files). Not
#: ``z-start-out-of-range``: the triggered extends of good map curves carry it (the corpus' 2 x 2 map).
SEGMENT_FLAGS = {"z-end-out-of-range": "z end out of range (the piezo reached the end of its travel)",
                 "setpoint-out-of-range": "setpoint out of range (the setpoint was not reached)",
                 "tipsaver-limit-exceeded": "tip-saver limit exceeded", "aborted": "aborted"}


def recording_flags(props: Mapping[str, str], n: int) -> str:
    """What a JPK segment header's force-scan flags say about its recording (``""`` when none is set), with
    its samples against the planned ``segment-settings.num-points`` where it stopped short."""
    said = [text for flag, text in SEGMENT_FLAGS.items()
            if props.get(f"force-segment-header.force-scan-flags.{flag}", "").strip() == "true"]
    if not said:
        return ""
    planned = props.get("force-segment-header.settings.segment-settings.num-points", "").strip()
    count = f"{n} of {planned} samples recorded, " if planned.isdigit() and int(planned) > n else ""
    return count + ", ".join(said)


_FLAG_BYTES = tuple(f"force-scan-flags.{flag}=true".encode() for flag in SEGMENT_FLAGS)


def curve_recording_flags(arc: zipfile.ZipFile, enum: int | None) -> str:
    """:func:`recording_flags` of every segment of one curve (``index/<enum>/`` in maps and QI data) that
    has a flag set, ``"; "``-joined (``""``: none). A segment header is parsed only when its bytes hold a
    set flag (most hold none: a map of thousands of curves pays a substring search each)."""
    plain = enum is None
    if not plain:
        try:
            arc.getinfo("segments/0/segment-header.properties")
            plain = True
        except KeyError:
            pass
    prefix = "" if plain else f"index/{int(enum)}/"
    out, shared = [], None
    for j in range(10_000):
        name = f"{prefix}segments/{j}/segment-header.properties"
        try:
            raw = arc.read(name)
        except KeyError:
            break
        if not any(flag in raw for flag in _FLAG_BYTES):
            continue
        shared = _shared(arc) if shared is None else shared
        props = _segment_header(arc, name, shared)
        try:
            n = int(props.get("force-segment-header.num-points", "").strip())
        except ValueError:
            n = -1
        said = recording_flags(props, n)
        if said:
            out.append(f"{_identifier(props) or _style(props, j)}: {said}")
    return "; ".join(out)


def _read_props(arc: zipfile.ZipFile, name: str) -> dict[str, str]:
    return parse_properties(arc.read(name).decode("utf-8", errors="replace"))


def _read_archive(arc: zipfile.ZipFile, where: str, meta_override: dict, callback, prefix: str = "",
                  shared: Mapping[str, str] | None = None, general: Mapping[str, str] | None = None) -> RawCurve:
    """One curve: the segments under ``prefix`` (``""`` or ``index/<i>/``), in time order."""
    names = arc.namelist()
    shared = _shared(arc) if shared is None else shared
    pat = re.compile(re.escape(prefix) + r"segments/(\d+)/segment-header")
    seg_ids = sorted({int(m.group(1)) for n in names if (m := pat.match(n))})
    if not seg_ids:
        raise FileFormatError(f"{where}: no segments under {prefix or 'the archive root'}")
    cols: dict[str, list[np.ndarray]] = {"t": [], "zn": [], "zm": [], "s": [], "seg": []}
    meta: dict[str, Any] = {"segment_types": []}
    t0 = 0.0
    headers = {sid: _segment_header(arc, f"{prefix}segments/{sid}/segment-header.properties", shared)
               for sid in seg_ids}
    seg_ids = _time_order(seg_ids, headers)
    for i, sid in enumerate(seg_ids):
        seg_dir = f"{prefix}segments/{sid}"
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
        stated = props.get("force-segment-header.num-points", "").strip()
        if stated.isdigit() and int(stated) != n:   # a cut-down copy: its duration / n would be no sample rate
            raise FileFormatError(f"{where}: segment {sid} ({style}) holds {n} of the {int(stated)} samples its "
                                  f"header states (an edited or cut-down copy: its time base would be wrong); "
                                  f"{GIVE_SAVED}")
        flagged = recording_flags(props, n)
        if flagged:
            meta["recording_flags"] = "; ".join(filter(None, (meta.get("recording_flags"),
                                                              f"{_identifier(props) or style}: {flagged}")))
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
    gen = dict(_read_props(arc, "header.properties") if general is None else general)
    if prefix and f"{prefix}header.properties" in names:
        gen.update(_read_props(arc, f"{prefix}header.properties"))
    instrument = gen.get("force-scan-series.description.instrument") or gen.get(
        "force-scan-map.description.instrument") or gen.get("quantitative-imaging-map.description.instrument")
    if instrument:
        meta["instrument"] = instrument
    if prefix:
        meta.update(_map_position(gen, int(prefix.split("/")[1])))
    meta.update(meta_override)
    meta.update(source_file=where, reader="jpk-zip", format="JPK force archive (raw volts)",
                position_sign=sign)
    curve = RawCurve(time=np.concatenate(cols["t"]), piezo_nominal=zn, piezo_measured=zm,
                     deflection_signal=np.concatenate(cols["s"]), segment=seg, metadata=meta,
                     deflection_unit="V")
    return finalize_curve(curve, where)
