r"""Reader of Park Systems force spectroscopy TIFF files (XEI / SmartScan, ``.tiff``/``.tif``).

A Park TIFF is an ordinary TIFF (a palette preview image) with Park's private tags:
50432 the magic number ``0x0E031301``, 50433 the version (its low byte: 1 or 2), 50434 the data of
the image, 50435 its 580-byte header (the first int32 says what the file holds: 0 an image, 1 a line
profile, 2 spectroscopy), 50438 the spectroscopy header and 50439 the spectroscopy data. Layout of
the spectroscopy header as read here (little-endian; offsets in bytes; gwyddion's psia module and
atomicJ's Park reader describe the same structure, and the public file ``ForceCurve_009.tiff`` of
nanoAFMr bears it out):

* 8 channel records of 96 bytes: name (32 UTF-16 characters), unit (8 UTF-16 characters), gain
  (float64), is an x-axis source (int32), is a y-axis source (int32);
* 768: int32 number of channels, averages, samples per spectrum (``res``), number of spectra
  (points), index of the driving channel (the z ramp);
* 788: float32 forward period, backward period, forward speed, backward speed [driving unit/s];
  804: int32 volume image (a force map: its curves get their grid cells); 808: float64 offset of each channel; 872: int32 log scale, 904: square;
* version 2 (936 on): int32 points per x (0: a square grid), int32 has a reference image, float64 x/y size and offset
  of the grid, 976: float64 **spring constant [N/m]**, 984: float64 **sensitivity [V/um]**
  (its inverse is the InvOLS), 992: float32 force limit [V], ... 1108: int32 data type (0 int16,
  1 int32, 2 float32), 1112: 24 reserved int32, 1208: (x, y, t) float32 of each point [um].

The data (tag 50439) hold, for each point, each channel's ``res`` samples: the first half the
forward (approach) run, the second half the backward (retract) run, each in time order; a run
shorter than half the record is padded with copies of its last sample (every channel equal to the
one before: dropped here). The deflection is the ``Vertical (A-B)`` channel in V (else a force
channel in N, else a deflection in m); z is the driving channel (``Z Scan``, commanded), with the
``Z Detector`` as the measured position when it moves; time is the ``Time Stamp`` channel (else the
ramp over the speed). ``spring_constant`` and ``sensitivity`` are the version-2 header's; a version-1
header stores neither (give ``--spring-constant`` and ``--sensitivity``). The header's sensitivity
calibrates the A-B deflection divided by the image header's ``intensityFactor`` (float64 at byte 424
of tag 50435: the photodiode sum (A+B)/3, as Park's own reader, pspylib's ``TiffReader``, names the
field): the InvOLS of the recorded A-B volts is the header's over that factor (``park_intensity_factor``;
on ForceCurve_009.tiff 0.9236979: 16.670 -> 18.047 nm/V), which is what Park's own Force channel
applies (k x InvOLS x (A-B) / 0.9236979 = 1.0826050 x k x InvOLS x (A-B) on all 7 spectra).

A Park TIFF holding an image or a line profile is refused in one line. afmforce's own code, written
from the layout described above (no code of those readers is used).
"""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ..errors import FileFormatError
from ._meta import finalize_curve
from ._unread import _PARK_HEADER, _PARK_MAGIC, _tiff_tags
from .curve import SEGMENT_APPROACH, SEGMENT_RETRACT, RawCurve

__all__ = ["detect_park", "load_park", "holds_curves", "PARK_MAGIC", "PARK_KINDS"]

#: the value of Park's magic tag (50432)
PARK_MAGIC = 0x0E031301
_VERSION, _SPEC_HEADER, _SPEC_DATA = 50433, 50438, 50439
#: the header's first int32 -> what the file holds
PARK_KINDS = {0: "image", 1: "line profile", 2: "spectroscopy"}
_CHANNELS, _CHANNEL_BYTES = 8, 96
_V1_BYTES, _V2_CAL_END, _V2_DTYPE_AT, _POINTS_AT, _VOLUME_AT = 936, 992, 1108, 1208, 804
_DTYPES = {0: "i2", 1: "i4", 2: "f4"}
#: byte of the image header's (tag 50435) ``intensityFactor`` (float64, (A+B)/3 [-]; the field after
#: ``ncmDrivePercent`` in Park's layout): the A-B deflection the header's sensitivity calibrates is divided by it
_INTENSITY_AT = 424
#: unit as Park writes it -> (SI unit, factor)
_UNITS = {"v": ("V", 1.0), "mv": ("V", 1e-3), "uv": ("V", 1e-6),
          "m": ("m", 1.0), "mm": ("m", 1e-3), "um": ("m", 1e-6), "\u00b5m": ("m", 1e-6), "nm": ("m", 1e-9),
          "pm": ("m", 1e-12), "n": ("N", 1.0), "mn": ("N", 1e-3), "un": ("N", 1e-6), "nn": ("N", 1e-9),
          "pn": ("N", 1e-12), "s": ("s", 1.0), "sec": ("s", 1.0), "ms": ("s", 1e-3), "msec": ("s", 1e-3),
          "us": ("s", 1e-6), "usec": ("s", 1e-6), "\u00b5s": ("s", 1e-6)}


def detect_park(path: Path) -> bool:
    """A TIFF whose first directory holds Park's magic tag (50432) with Park's value."""
    try:
        _, tags = _tiff_tags(path)
    except (OSError, struct.error):
        return False
    return tags.get(_PARK_MAGIC, (0, 0, 0))[2] == PARK_MAGIC


def holds_curves(path: Path) -> bool:
    """Whether a file under a TIFF ending may hold force curves: a Park TIFF whose header says
    spectroscopy (type 2). A folder given to ``afmforce analyze`` skips the others (images)."""
    try:
        end, tags = _tiff_tags(path)
        if tags.get(_PARK_MAGIC, (0, 0, 0))[2] != PARK_MAGIC or _PARK_HEADER not in tags:
            return False
        with open(path, "rb") as fh:
            fh.seek(tags[_PARK_HEADER][2])
            return struct.unpack(end + "i", fh.read(4))[0] == 2
    except (OSError, struct.error):
        return False


def _text(raw: bytes) -> str:
    return raw.decode("utf-16-le", errors="replace").split("\x00")[0].strip()


def _block(fh, tags: dict, tag: int, where: str, what: str, size: int) -> bytes:
    if tag not in tags:
        raise FileFormatError(f"{where}: this Park Systems TIFF has no {what} (TIFF tag {tag}); damaged")
    typ, count, offset = tags[tag]
    nbytes = count * {1: 1, 2: 1, 3: 2, 4: 4, 7: 1}.get(typ, 1)
    if nbytes > size or offset + nbytes > size:
        raise FileFormatError(f"{where}: the {what} (TIFF tag {tag}) runs past the end of the file "
                              f"({offset} + {nbytes} bytes of {size}); the file is truncated")
    fh.seek(offset)
    return fh.read(nbytes)


def _unit(text: str, where: str, name: str) -> tuple[str, float]:
    try:
        return _UNITS[text.strip().lower()]
    except KeyError:
        return text, float("nan")


def _header(raw: bytes, end: str, where: str) -> dict[str, Any]:
    """The spectroscopy header's channels and ramp (and, version 2, the calibration)."""
    if len(raw) < _V1_BYTES:
        raise FileFormatError(f"{where}: the Park spectroscopy header holds {len(raw)} bytes, fewer than the "
                              f"{_V1_BYTES} of its channel table and ramp; damaged")
    channels = []
    for i in range(_CHANNELS):
        o = i * _CHANNEL_BYTES
        gain, = struct.unpack_from(end + "d", raw, o + 80)
        is_x, is_y = struct.unpack_from(end + "ii", raw, o + 88)
        channels.append({"name": _text(raw[o:o + 64]), "unit": _text(raw[o + 64:o + 80]), "gain": gain,
                         "x": bool(is_x), "y": bool(is_y)})
    count, average, res, points, driving = struct.unpack_from(end + "5i", raw, 768)
    fwd_period, bwd_period, fwd_speed, bwd_speed = struct.unpack_from(end + "4f", raw, 788)
    offsets = struct.unpack_from(end + "8d", raw, 808)
    for ch, off in zip(channels, offsets):
        ch["offset"] = off
    volume, = struct.unpack_from(end + "i", raw, _VOLUME_AT)
    out = {"channels": channels[:max(0, min(count, _CHANNELS))], "count": count, "res": res, "points": points,
           "driving": driving, "fwd_speed": fwd_speed, "bwd_speed": bwd_speed, "dtype": None,
           "volume": bool(volume)}
    if len(raw) >= _V2_CAL_END:
        per_x, _, width, height = struct.unpack_from(end + "ii2d", raw, _V1_BYTES)
        out["grid"] = (per_x, width, height)  # points per x (0: a square grid), grid size [um]
        out["spring_constant"], out["sensitivity_v_per_um"] = struct.unpack_from(end + "dd", raw, 976)
    if len(raw) >= _V2_DTYPE_AT + 4:
        out["dtype"], = struct.unpack_from(end + "i", raw, _V2_DTYPE_AT)
    if len(raw) >= _POINTS_AT + 12 * max(points, 0):
        out["xy"] = [struct.unpack_from(end + "2f", raw, _POINTS_AT + 12 * i) for i in range(points)]
    return out


def _intensity_factor(fh, tags: dict, end: str, where: str, size: int) -> float | None:
    """The image header's ``intensityFactor`` (float64 at byte :data:`_INTENSITY_AT`: the photodiode's sum
    (A+B)/3 [-], as Park's own reader names it); ``None`` when absent, zero or not finite."""
    raw = _block(fh, tags, _PARK_HEADER, where, "image header", size)
    if len(raw) < _INTENSITY_AT + 8:
        return None
    value, = struct.unpack_from(end + "d", raw, _INTENSITY_AT)
    return float(value) if np.isfinite(value) and value > 0 else None


def _image_kind(fh, tags: dict, end: str, where: str, size: int) -> tuple[str, str]:
    raw = _block(fh, tags, _PARK_HEADER, where, "image header", size)
    if len(raw) < 4:
        raise FileFormatError(f"{where}: the Park image header holds {len(raw)} bytes (580 expected); damaged")
    kind, = struct.unpack_from(end + "i", raw, 0)
    what = _text(raw[4:68]) or "a channel"
    if len(raw) >= 108:
        width, height = struct.unpack_from(end + "ii", raw, 100)
        what += f", {width} x {height} px" + (f", {_text(raw[68:84])}" if _text(raw[68:84]) else "")
    return PARK_KINDS.get(kind, f"unknown data (type {kind})"), what


def _real_length(block: np.ndarray) -> int:
    """Samples of a run before its padding: trailing samples equal in every channel to the one before."""
    same = np.all(block[:, 1:] == block[:, :-1], axis=0)
    n = block.shape[1]
    while n > 1 and same[n - 2]:
        n -= 1
    return n


def _pick(channels: list[dict], units: list[str], want: str, words: tuple[str, ...]) -> int | None:
    hits = [i for i, ch in enumerate(channels) if units[i] == want and ch["y"]]
    for word in words:
        for i in hits:
            if word in channels[i]["name"].lower():
                return i
    return hits[0] if hits else None


def _map_cells(head: dict[str, Any], where: str) -> list[dict[str, Any]] | None:
    """The grid cell of every spectrum of a volume image (a force map: the header's volume flag), then (last)
    the grid's ``map_nx``, ``map_ny`` and its size ``map_width``, ``map_height`` [m]; None for spectra at
    free points, or points that make no grid. The grid has ``points per x`` columns (0: a square of sqrt(points)); each spectrum's cell
    is found from its position in the point table (rows in either direction), else row by row."""
    if not head.get("volume"):
        return None
    per_x, width, height = head.get("grid", (0, 0.0, 0.0))
    points = head["points"]
    nx = per_x if per_x > 0 else int(round(points ** 0.5))
    if nx < 1 or points % nx or (per_x <= 0 and nx * nx != points):
        return None  # not a grid (a damaged header): the spectra keep their positions, no cells are made up
    ny = points // nx
    index = [divmod(p, nx)[::-1] for p in range(points)]  # (ix, iy) row by row
    xy = np.array(head["xy"], float) if "xy" in head else None
    if xy is not None and len(xy) == points:
        found = []
        for axis, n in ((0, nx), (1, ny)):
            c = xy[:, axis]
            step = (c.max() - c.min()) / (n - 1) if n > 1 else 0.0
            k = np.rint((c - c.min()) / step).astype(int) if step > 0 else np.zeros(points, int)
            found.append(k)
        pairs = set(zip(found[0].tolist(), found[1].tolist()))
        if len(pairs) == points and all(0 <= a < nx and 0 <= b < ny for a, b in pairs):
            index = list(zip(found[0].tolist(), found[1].tolist()))
    cells: list[dict[str, Any]] = [{"map_x": int(ix), "map_y": int(iy)} for ix, iy in index]
    grid: dict[str, Any] = {"map_nx": nx, "map_ny": ny}
    if np.isfinite(width) and np.isfinite(height) and width > 0 and height > 0:
        grid.update(map_width=float(width) * 1e-6, map_height=float(height) * 1e-6)
    return cells + [grid]


def load_park(path: Path, *, meta_override: Mapping[str, Any] | None = None,
              callback: Callable | None = None) -> list[RawCurve]:
    """Read every force curve of a Park Systems spectroscopy TIFF (see the module docstring).

    Raises
    ------
    FileFormatError
        Not a Park TIFF, an image or line profile, truncated, or no deflection or z channel.
    """
    where = str(path)
    end, tags = _tiff_tags(path)
    if tags.get(_PARK_MAGIC, (0, 0, 0))[2] != PARK_MAGIC:
        raise FileFormatError(f"{where}: not a Park Systems TIFF (no Park magic number in TIFF tag {_PARK_MAGIC})")
    size = Path(path).stat().st_size
    with open(path, "rb") as fh:
        kind, what = _image_kind(fh, tags, end, where, size)
        if kind != "spectroscopy":
            raise FileFormatError(f"{where}: this Park Systems TIFF holds {'an' if kind[0] in 'aeiou' else 'a'} "
                                  f"{kind} ({what}), not a force curve: give the spectroscopy (F-D) file of "
                                  "the measurement")
        intensity = _intensity_factor(fh, tags, end, where, size)
        head = _header(_block(fh, tags, _SPEC_HEADER, where, "spectroscopy header", size), end, where)
        raw = _block(fh, tags, _SPEC_DATA, where, "spectroscopy data", size)
    channels, res, points = head["channels"], head["res"], head["points"]
    if not channels or res < 4 or res % 2 or points < 1:
        raise FileFormatError(f"{where}: the Park spectroscopy header gives {head['count']} channels, {res} samples "
                              f"per spectrum and {points} spectra; damaged")
    samples = len(channels) * res * points
    if head["dtype"] is None:  # a version-1 header, written before the data type field: the width says
        head["dtype"] = 0 if len(raw) == 2 * samples else 2   # int16 (2 bytes a sample), else float32
    dtype = _DTYPES.get(head["dtype"])
    if dtype is None:
        raise FileFormatError(f"{where}: the Park spectroscopy data type {head['dtype']} is none of 0 (int16), "
                              "1 (int32), 2 (float32)")
    need = samples * int(dtype[1:])
    if len(raw) != need:
        raise FileFormatError(f"{where}: the Park spectroscopy data hold {len(raw)} bytes, the header's "
                              f"{points} spectra x {len(channels)} channels x {res} samples need {need}; damaged")
    units = [_unit(ch["unit"], where, ch["name"]) for ch in channels]
    si = [u for u, _ in units]
    data = np.frombuffer(raw, dtype=end + dtype).astype(float).reshape(points, len(channels), res)
    scale = np.array([ch["gain"] * f for ch, (_, f) in zip(channels, units)])
    offset = np.array([ch["offset"] * f for ch, (_, f) in zip(channels, units)])
    data = data * scale[None, :, None] + offset[None, :, None]
    names = ", ".join(f"{ch['name']} [{ch['unit']}]" for ch in channels)
    d_idx = _pick(channels, si, "V", ("a-b", "vertical", "defl"))
    d_unit = "V"
    for alt in ("N", "m"):
        if d_idx is None:
            d_idx, d_unit = _pick(channels, si, alt, ("force", "defl", "vertical")), alt
    z_idx = head["driving"] if 0 <= head["driving"] < len(channels) and si[head["driving"]] == "m" else None
    if d_idx is None or z_idx is None:
        raise FileFormatError(f"{where}: the Park spectroscopy channels ({names}) hold no "
                              f"{'deflection (V, N or m)' if d_idx is None else 'z ramp (the driving channel in m)'}")
    zm_idx = next((i for i, ch in enumerate(channels) if i != z_idx and si[i] == "m" and ch["x"]
                   and "detector" in ch["name"].lower()), None)
    t_idx = next((i for i in range(len(channels)) if si[i] == "s"), None)
    z_unit = units[z_idx][1]
    base: dict[str, Any] = {"instrument": "Park Systems", "channels": names}
    k, s = head.get("spring_constant"), head.get("sensitivity_v_per_um")
    if k is not None and np.isfinite(k) and k > 0:
        base["spring_constant"] = float(k)
    if s is not None and np.isfinite(s) and s > 0:
        base["sensitivity"] = 1e-6 / float(s)          # V/um -> m/V
        if intensity is not None and d_unit == "V":    # Park's sensitivity is of (A-B) / ((A+B)/3): as its Force
            base["sensitivity"] /= intensity           # channel, k x InvOLS x (A-B) / intensity factor
            base["park_intensity_factor"] = intensity
    for key, speed in (("velocity", head["fwd_speed"]), ("retract_velocity", head["bwd_speed"])):
        if np.isfinite(speed) and speed > 0:
            base[key] = float(speed) * z_unit
    force_idx = _pick(channels, si, "N", ("force",)) if d_unit == "V" else None
    lacking = [key for key in ("spring_constant", "sensitivity") if key not in base]
    if lacking and d_unit != "N":
        stored = "a version-1 header: no calibration fields" if "spring_constant" not in head else "zero"
        base["spring_constant_note"] = (f"this Park TIFF's spectroscopy header stores no "
                                        f"{' and no '.join(k.replace('_', ' ') for k in lacking)} ({stored}): give "
                                        f"{' and '.join(f'`{k}`' for k in lacking)}")
    base.update(dict(meta_override or {}))
    base.update(source_file=where, reader="park-tiff", format="Park Systems spectroscopy TIFF")
    cells = _map_cells(head, where)
    if cells is not None:
        base.update(cells.pop())
    half = res // 2
    out = []
    for p in range(points):
        runs = []
        for code, block in ((SEGMENT_APPROACH, data[p, :, :half]), (SEGMENT_RETRACT, data[p, :, half:])):
            runs.append((code, block[:, :_real_length(block)]))
        seg = np.concatenate([np.full(b.shape[1], c, dtype=np.int8) for c, b in runs])
        cols = np.concatenate([b for _, b in runs], axis=1)
        meta = dict(base)
        if t_idx is not None:
            time = cols[t_idx] - cols[t_idx][0]
        else:   # the ramp over the speed, run by run
            time, t0 = [], 0.0
            for code, b in runs:
                v = meta.get("velocity" if code == SEGMENT_APPROACH else "retract_velocity") or meta.get("velocity")
                if not v:
                    raise FileFormatError(f"{where}: the Park spectroscopy has no time channel and no ramp speed; "
                                          "the time of the samples is unknown")
                t = t0 + np.r_[0.0, np.cumsum(np.abs(np.diff(b[z_idx])))] / v
                time.append(t)
                t0 = t[-1] + (t[-1] - t[-2] if t.size > 1 else 0.0)
            time = np.concatenate(time)
        steps = np.diff(time)
        if steps.size and np.all(steps > 0):
            meta["sample_rate"] = float(1.0 / np.median(steps))
        if points > 1:
            meta["curve_index"] = p
        if "xy" in head:
            meta["position_x"], meta["position_y"] = (float(c) * 1e-6 for c in head["xy"][p])
        if cells is not None:
            meta.update(cells[p])
        zn = cols[z_idx]
        zm = cols[zm_idx] if zm_idx is not None and np.ptp(cols[zm_idx]) > 0 else None
        app = np.flatnonzero(seg == SEGMENT_APPROACH)
        sign = -1.0 if app.size >= 2 and (zm if zm is not None else zn)[app[-1]] < \
            (zm if zm is not None else zn)[app[0]] else 1.0
        meta["position_sign"] = sign
        defl = cols[d_idx]
        if force_idx is not None and "spring_constant" in meta and "sensitivity" in meta and np.ptp(defl) > 0:
            ratio = np.polyfit(defl, cols[force_idx], 1)[0] / (meta["spring_constant"] * meta["sensitivity"])
            meta["park_force_ratio"] = float(ratio)
            if abs(ratio - 1) > 0.01:
                meta["spring_constant_note"] = (
                    f"the file's own {channels[force_idx]['name']} channel is {ratio:.4g} x spring constant x "
                    f"sensitivity x {channels[d_idx]['name']} (a factor its header does not name): Park's software "
                    f"shows forces {abs(ratio - 1) * 100:.3g} % {'above' if ratio > 1 else 'below'} these, which "
                    "use the header's spring constant and sensitivity"
                    + (f" over its intensity factor {intensity:.7g}" if "park_intensity_factor" in meta else ""))
        curve = RawCurve(time=time, piezo_nominal=sign * zn, piezo_measured=None if zm is None else sign * zm,
                         deflection_signal=defl, segment=seg, metadata=meta, deflection_unit=d_unit)
        out.append(finalize_curve(curve, where))
        if callback is not None:
            callback((p + 1) / points)
    return out
