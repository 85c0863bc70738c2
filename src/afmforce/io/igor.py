"""Asylum Research Igor binary waves (``.ibw``): one wave with all channels (via afmformats),
or one wave per channel (``...Point0000Defl.ibw`` with ``...Point0000ZSnsr.ibw``, read here).

A plain version-5 wave is read by :mod:`afmforce.io.ibw_wave` (numpy, the same arrays and
metadata as afmformats/igor2, ~20x faster); anything else goes through afmformats as before.

afmformats returns one segment for an ``.ibw`` curve: it is split at the turning point
(the wave note's ``Indexes``: ``0,turn,end``, or ``0,a,b,end`` with a dwell), else at the
extreme of z. afmformats' Igor reader ignores ``meta_override``: a user's spring constant or
sensitivity rescales the force here (force = k x volts x InvOLS).
"""

from __future__ import annotations

import dataclasses
import math
import struct
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ..errors import FileFormatError
from .curve import RawCurve
from ._afmformats import _curve_from_afmdata, _load_data, rescale_force
from .ibw_wave import afmformats_igor, read_wave5
from ._meta import finalize_curve, missing_metadata, orient, positive_entry

__all__ = ["load_ibw", "check_ibw_header", "CHANNELS"]

#: Per-channel wave name endings: deflection [m] or raw photodiode [V]; position [m].
CHANNELS = {"Defl": "m", "Raw": "V"}
POSITIONS = ("ZSnsr", "LVDT", "Height")


def _ibw_segments(path: Path, z: np.ndarray) -> np.ndarray:
    """Segments of a one-segment Igor wave from the note's ``Indexes`` and ``Direction``, else
    the extreme of z (:func:`_segments_from_note`)."""
    entries = {}
    try:
        note = _ibw_note(path)
        for line in note.replace("\\r", "\r").replace("\n", "\r").split("\r"):
            if ":" in line:
                key, value = line.split(":", 1)
                entries.setdefault(key.strip(), value.strip())
    except Exception:  # the note is optional; fall back on the data
        pass
    return _segments_from_note(entries.get("Indexes", ""), z, entries.get("Direction", ""))


def _ibw_note(path: Path) -> str:
    """The wave note of a version-5 Igor binary wave, read from its header sizes (no igor2 parse)."""
    with open(path, "rb") as fh:
        head = fh.read(64)
        order = "<" if struct.unpack("<h", head[:2])[0] in (1, 2, 3, 5) else ">"
        if struct.unpack(order + "h", head[:2])[0] != 5:
            from igor2 import binarywave

            return str(binarywave.load(path)["wave"]["note"])
        wfm, formula, note = struct.unpack(order + "iii", head[4:16])  # noqa: F841 (sizes in file order)
        fh.seek(64 + wfm + formula)
        return fh.read(max(0, min(note, 1 << 20))).decode("latin-1")


def check_ibw_header(path: Path) -> None:
    """Reject an Igor binary wave whose header declares more bytes than the file holds.

    igor2 builds struct formats from these sizes; a damaged size makes it spend
    minutes before failing. Version 5 header (BinHeader5, 64 bytes): version,
    checksum, then the sizes of the wave, formula, note, units, labels and
    indices sections (int32), in the file's byte order.
    """
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
    """Asylum ``.ibw`` force curve: one wave, split into approach and retract (or a per-channel pair)."""
    check_ibw_header(path)
    image = _image_wave(path)
    if image:
        keys = _note_keys(path)
        asylum = keys is None or bool(keys & set(_ASYLUM_NOTE_KEYS))
        whose = ("this Asylum .ibw" if asylum else "this Igor binary wave (its note is not the Asylum "
                 f"software's: none of {', '.join(_ASYLUM_NOTE_KEYS)})")
        raise FileFormatError(f"{path}: {whose} holds {image}, not a force curve; give the force curves "
                              "(an .ibw the force panel saved, one wave per curve, or the ARDF force map)")
    if _is_one_channel(path):
        return [load_channel_pair(path, meta_override=meta_override)]
    _refuse_plain_wave(path)
    # the fast path builds what afmformats builds, from a numpy read of the wave (None: not a plain
    # version-5 wave, or a note afmformats would refuse: afmformats reads it, or says what is wrong)
    data = afmformats_igor(path, callback)
    if data is None and read_wave5(path) is not None:
        # a plain wave whose note lacks the spring constant (or InvOLS): the user's, or say which
        note = _ibw_note(path).replace("\\r", "\r").replace("\n", "\r").split("\r")
        keys = {line.split(":", 1)[0].strip() for line in note if ":" in line}
        given = {"SpringConstant": meta_override.get("spring_constant"), "InvOLS": meta_override.get("sensitivity")}
        if "SpringConstant" not in keys:
            if given["SpringConstant"] is None:
                raise missing_metadata(str(path), ["spring_constant"], what="the wave note stores")
            data = afmformats_igor(path, callback, {k: float(v) for k, v in given.items() if v is not None})
    if data is None:
        data = _load_data(path, {}, callback)  # afmformats' Igor reader takes no meta_override
    out = []
    for dd in data:
        height = dd["height (measured)"] if "height (measured)" in dd.columns else dd["height (piezo)"]
        z = -np.asarray(height, dtype=float)
        seg = np.asarray(dd["segment"]).astype(np.int8)
        if np.all(seg == 0):
            seg = _ibw_segments(path, z)
        force = np.asarray(dd["force"], dtype=float) * rescale_force(path, dd.metadata, meta_override)
        curve = _curve_from_afmdata(dd, path, "asylum-ibw", meta_override, segment=seg, signal=force)
        f0 = _thermal_frequency(path)  # afmformats does not pass the note's resonance frequency on
        if f0 is not None and "resonance_frequency" not in meta_override:
            curve = dataclasses.replace(curve, metadata={**curve.metadata, "resonance_frequency": f0})
        q = _thermal_frequency(path, "ThermalQ:")  # the medium: Q of tens to hundreds in air, a few in liquid
        if q is not None and "quality_factor" not in meta_override:
            curve = dataclasses.replace(curve, metadata={**curve.metadata, "quality_factor": q})
        out.append(curve)
    return out


#: keys of the note the Asylum software writes with every force curve (afmformats needs ImagingMode)
_ASYLUM_NOTE_KEYS = ("ImagingMode", "SpringConstant", "InvOLS")


def _note_keys(path: Path) -> set[str] | None:
    """The keys (``Key:`` lines) of the wave note; None where the note cannot be read."""
    try:
        note = _ibw_note(path)
    except Exception:  # an unreadable note: afmformats says what is wrong
        return None
    note = note.decode("latin-1") if isinstance(note, bytes) else str(note)
    lines = note.replace("\\r", "\r").replace("\n", "\r").split("\r")
    return {line.split(":", 1)[0].strip() for line in lines if ":" in line}


def _refuse_plain_wave(path: Path) -> None:
    """Refuse an Igor wave whose note has none of the Asylum force-curve keys (a wave Igor itself wrote,
    e.g. igor2's test waves): afmformats would fail on it with ``KeyError: 'ImagingMode'``."""
    keys = _note_keys(path)
    if keys is not None and not keys & set(_ASYLUM_NOTE_KEYS):
        raise FileFormatError(
            f"{path}: an Igor binary wave without the note the Asylum Research software writes with a force "
            f"curve (none of {', '.join(_ASYLUM_NOTE_KEYS)} in it): not a force curve afmforce can calibrate; "
            "give the .ibw the Asylum force panel saved (or the ARDF force map), or write the curve as afmforce "
            "raw text with its spring constant and sensitivity (docs/formats.md)")


def _thermal_frequency(path: Path, key: str = "ThermalFrequency:") -> float | None:
    """``ThermalFrequency`` [Hz] of the wave note (the cantilever's thermal resonance), or another
    positive number of the note (``key`` with its colon, e.g. ``"ThermalQ:"``), if positive."""
    try:
        note = _ibw_note(path)
    except Exception:  # the note is optional
        return None
    for line in note.replace("\\r", "\r").replace("\n", "\r").split("\r"):
        if line.startswith(key):
            try:
                value = float(line.split(":", 1)[1])
            except ValueError:
                return None
            return value if np.isfinite(value) and value > 0 else None
    return None




#: A force-curve wave has its samples in rows and at most a few channels in columns (Raw, Defl, ZSnsr, ...);
#: a wave with more columns than this, or a third dimension (layers), is an image [-].
MAX_CURVE_CHANNELS = 32


def _image_wave(path: Path) -> str:
    """What an image wave holds (``"an image (256 x 256 pixels, 4 channels: HeightRetrace, ...)"``), or ``""``
    for a wave shaped like force curves: an Asylum image saved as .ibw (SciFiDatasets' PFM images:
    256 x 256 x 4 and x 5) has rows and columns of pixels and one layer per channel."""
    with open(path, "rb") as fh:
        head = fh.read(64 + 148)
    if len(head) < 64 + 148:
        return ""
    order = "<" if struct.unpack("<h", head[:2])[0] in (1, 2, 3, 5) else ">"
    if struct.unpack(order + "h", head[:2])[0] != 5:
        return ""
    ndim = struct.unpack(order + "4i", head[64 + 68:64 + 84])
    if not (ndim[2] > 0 or ndim[1] > MAX_CURVE_CHANNELS):
        return ""
    layers = max(ndim[2], 1)
    names = ""
    wave = read_wave5(path)
    if wave is not None and len(wave.labels) > 2:
        found = [b.decode("latin-1") for b in wave.labels[2] if b]
        names = f": {', '.join(found)}" if found else ""
    return f"an image ({ndim[0]} x {ndim[1]} pixels, {layers} channel{'s' if layers > 1 else ''}{names})"


def _is_one_channel(path: Path) -> bool:
    """A version-5 wave with one dimension (``nDim[1] == 0``): one channel per file."""
    with open(path, "rb") as fh:
        head = fh.read(64 + 148)
    if len(head) < 64 + 148:
        return False
    order = "<" if struct.unpack("<h", head[:2])[0] in (1, 2, 3, 5) else ">"
    if struct.unpack(order + "h", head[:2])[0] != 5:
        return False
    ndim = struct.unpack(order + "4i", head[64 + 68:64 + 84])
    return ndim[0] > 0 and ndim[1] == 0


def _wave(path: Path) -> tuple[np.ndarray, dict[str, str], float]:
    """(data, note entries, x step [s]) of a one-dimensional Igor wave (numpy fast path, else igor2)."""
    fast = read_wave5(path)
    if fast is not None:
        w = {"wData": fast.data, "note": fast.note, "wave_header": {"sfA": fast.sfA}}
    else:
        from igor2 import binarywave

        try:
            w = binarywave.load(path)["wave"]
        except Exception as exc:  # igor2 raises anything on a damaged wave
            raise FileFormatError(f"{path}: damaged Igor binary wave ({type(exc).__name__}: "
                                  f"{str(exc)[:120]})") from None
    note = w.get("note", b"")
    note = note.decode("latin-1") if isinstance(note, bytes) else str(note)
    entries = {}
    for line in note.replace("\n", "\r").split("\r"):
        if ":" in line:
            key, value = line.split(":", 1)
            entries[key.strip()] = value.strip()
    step = float(w["wave_header"]["sfA"][0])
    return np.asarray(w["wData"], dtype=float).ravel(), entries, step


def _stated_entry(entries: Mapping[str, str], key: str) -> float | None:
    """The finite number a wave note states under ``key`` (any sign: an impossible one is refused by
    :func:`~afmforce.io._meta.finalize_curve`, not dropped), or None where it is missing or not a number."""
    try:
        v = float(entries[key])
    except (KeyError, ValueError):
        return None
    return v if np.isfinite(v) else None


def _split_name(path: Path) -> tuple[str, str] | None:
    stem = path.name[: -len(path.suffix)] if path.suffix else path.name
    for ch in (*CHANNELS, *POSITIONS):
        if stem.endswith(ch):
            return stem[: -len(ch)], ch
    return None


def load_channel_pair(path: Path, *, meta_override: Mapping[str, Any]) -> RawCurve:
    """An Asylum curve saved as one wave per channel: ``<prefix>Defl.ibw`` (or ``Raw``) with
    ``<prefix>ZSnsr.ibw`` (or ``LVDT``, ``Height``) in the same folder, read as one curve.

    The deflection ``Defl`` is in metres (computed by the instrument with the note's
    InvOLS; a user's sensitivity rescales it), ``Raw`` in volts. Spring constant and
    InvOLS come from the note (``SpringConstant``, ``InvOLS``) or the user.
    """
    where = str(path)
    split = _split_name(path)
    if split is None:
        raise FileFormatError(f"{where}: a one-channel Igor wave whose name does not end in a channel name "
                              f"({', '.join((*CHANNELS, *POSITIONS))}); cannot tell what it holds")
    prefix, _ = split
    sig_ch = next((c for c in CHANNELS if (path.parent / f"{prefix}{c}{path.suffix}").is_file()), None)
    pos_ch = next((c for c in POSITIONS if (path.parent / f"{prefix}{c}{path.suffix}").is_file()), None)
    if sig_ch is None or pos_ch is None:
        raise FileFormatError(f"{where}: one channel of a per-channel Asylum curve; keep {prefix}Defl{path.suffix} "
                              f"and {prefix}ZSnsr{path.suffix} together in one folder")
    signal, note, step = _wave(path.parent / f"{prefix}{sig_ch}{path.suffix}")
    z, znote, _ = _wave(path.parent / f"{prefix}{pos_ch}{path.suffix}")
    if signal.size != z.size or signal.size < 4:
        raise FileFormatError(f"{where}: the {sig_ch} and {pos_ch} waves differ in length "
                              f"({signal.size}, {z.size})")
    note = {**znote, **note}
    unit = CHANNELS[sig_ch]
    meta: dict[str, Any] = {"instrument": "Asylum Research", "channels": f"{sig_ch}+{pos_ch}"}
    for key, ours in (("SpringConstant", "spring_constant"), ("InvOLS", "sensitivity")):
        value = _stated_entry(note, key)    # as stated: finalize_curve refuses one <= 0, as every reader
        if value is not None:
            meta[ours] = value
    for key, ours in (("NumPtsPerSec", "sample_rate"), ("ThermalFrequency", "resonance_frequency"),
                      ("ThermalQ", "quality_factor")):
        value = positive_entry(note, key)
        if value is not None:
            meta[ours] = value
    if "sample_rate" not in meta and step > 0:
        meta["sample_rate"] = 1.0 / step
    if unit == "m" and "sensitivity" in meta_override and "sensitivity" in meta:
        if not meta["sensitivity"] > 0:     # Defl was computed with it: nothing to rescale from
            raise FileFormatError(f"{where}: the wave note's InvOLS (sensitivity) is {meta['sensitivity']!r}; "
                                  "cannot rescale its deflection to the given sensitivity")
        signal = signal * float(meta_override["sensitivity"]) / meta["sensitivity"]
    meta.update(meta_override)
    need = ["spring_constant"] + (["sensitivity"] if unit == "V" else [])
    missing = [k for k in need if k not in meta]
    if missing:
        raise missing_metadata(where, missing, what="the wave note stores")
    rate = meta.get("sample_rate")
    time = np.arange(signal.size) / rate if rate else np.arange(signal.size, dtype=float)
    if not rate:
        meta["time_is_sample_index"] = True
    keep = _recorded(signal, z)
    filled = z if keep is None else np.interp(np.arange(z.size), np.flatnonzero(keep), z[keep])
    seg = _segments_from_note(note.get("Indexes", ""), filled, note.get("Direction", ""))
    if keep is not None:  # the padding of a map's curve (its Indexes count it): no data, dropped and said
        meta["unrecorded_samples"] = int((~keep).sum())
        time, z, signal, seg = time[keep], z[keep], signal[keep], seg[keep]
    zn, _, sign = orient(z, None, seg)
    meta.update(source_file=where, reader="asylum-ibw", format="Asylum Igor binary waves (one per channel)",
                position_sign=sign, position_channel=pos_ch)
    curve = RawCurve(time=time, piezo_nominal=zn, deflection_signal=signal, segment=seg, metadata=meta,
                     deflection_unit=unit)
    return finalize_curve(curve, where)


def _recorded(signal: np.ndarray, z: np.ndarray) -> np.ndarray | None:
    """The samples to keep of a per-channel curve whose waves start or end with NaN in both channels (None:
    every sample is finite, or NaN lies inside the data: then the curve is refused as damaged, by
    :func:`finalize_curve`). Asylum force-map curves saved one wave per channel carry such padding (BAMresearch/
    SOFA ``test_data/fdc_without_image``: 2-173 NaN samples at the start of both ``Defl`` and ``ZSnsr`` on every
    curve), which afmforce refused ("column piezo_nominal has 173 non-finite values ...: remove those rows",
    of a binary file)."""
    ok = np.isfinite(signal) & np.isfinite(z)
    if ok.all() or not ok.any():
        return None
    first, last = int(np.argmax(ok)), int(ok.size - 1 - np.argmax(ok[::-1]))
    if not ok[first:last + 1].all() or last - first + 1 < 4:
        return None
    if not (np.all(~np.isfinite(signal[:first])) and np.all(~np.isfinite(signal[last + 1:]))
            and np.all(~np.isfinite(z[:first])) and np.all(~np.isfinite(z[last + 1:]))):
        return None  # one channel recorded where the other did not: not padding
    return ok


#: A segment between a note's ``Indexes`` whose position moves less than this fraction of the largest
#: segment's motion is a dwell [-] (a dwell's piezo holds; an approach or retract sweeps the ramp).
DWELL_MOTION = 0.1


def _segments_by_motion(idx: list[int], z: np.ndarray) -> np.ndarray | None:
    """Codes of the three segments of four ``Indexes`` (no ``Direction``) from the position ``z`` itself:
    the one that barely moves (under :data:`DWELL_MOTION` of the largest motion) is the dwell, the first
    moving one the approach, the other (moving the opposite way) the retract. None where the motion does
    not tell (not exactly one still segment between two opposite sweeps): the caller's default then.

    Asylum's force-map waves saved one per channel (BAMresearch/SOFA ``test_data``: ``Indexes:0,2487,5015,
    5214`` and no ``Direction``) sweep out, back, then dwell away from the surface; a dwell at the surface
    lies between the sweeps: the order is the data's, not a guess."""
    n = len(z)
    bounds = list(zip(idx[:-1], idx[1:-1] + [n]))  # the last index is the last sample: its segment ends at n
    motion = []
    for a, b in bounds:
        part = np.asarray(z[a:b], dtype=float)
        part = part[np.isfinite(part)]
        motion.append(float(part[-1] - part[0]) if part.size >= 2 else math.nan)
    if not all(math.isfinite(m) for m in motion):
        return None
    big = max(abs(m) for m in motion)
    still = [abs(m) < DWELL_MOTION * big for m in motion]
    sweeps = [m for m, s in zip(motion, still) if not s]
    if big <= 0 or still.count(True) != 1 or len(sweeps) != 2 or sweeps[0] * sweeps[1] >= 0:
        return None
    seg = np.empty(n, dtype=np.int8)
    first = True
    for (a, b), s in zip(bounds, still):
        seg[a:b] = 2 if s else 0 if first else 1
        first = first and s
    return seg


def _segments_from_note(indexes: str, z: np.ndarray, direction: str = "") -> np.ndarray:
    """Segment codes from the note: ``Indexes`` are the ends of the segments (``0,a,b,...,end``),
    ``Direction`` what the piezo does in each (``NaN,1,-1,0``: a leading NaN, then 1 extend,
    -1 retract, 0 dwell). ARDF force maps write extend, retract, then a dwell at the end; without
    ``Direction`` three indexes are approach and retract; four are told apart by the motion of z
    (:func:`_segments_by_motion`), else approach, dwell and retract (a dwell at the surface). Without
    usable indexes the curve turns at the extreme of z."""
    n = len(z)
    try:
        idx = [int(float(v)) for v in indexes.split(",") if v.strip()]
    except ValueError:
        idx = []
    try:
        dirs = [float(v) for v in direction.split(",") if v.strip()]
    except ValueError:
        dirs = []
    dirs = [d for d in dirs if np.isfinite(d)]
    ok = len(idx) >= 3 and idx[0] == 0 and all(a < b for a, b in zip(idx, idx[1:])) and idx[-2] < n - 1
    if ok and len(dirs) == len(idx) - 1 and 1 in dirs and -1 in dirs:
        seg = np.full(n, 2, dtype=np.int8)
        for (start, end), d in zip(zip(idx, idx[1:]), dirs):
            seg[start:min(end, n)] = 0 if d > 0 else 1 if d < 0 else 2
        seg[min(idx[-1], n - 1):] = seg[min(idx[-1], n - 1) - 1]  # the last index is the last sample
        return seg
    if len(idx) == 3 and 0 < idx[1] < n - 1:
        return np.where(np.arange(n) < idx[1], 0, 1).astype(np.int8)
    if len(idx) == 4 and 0 < idx[1] < idx[2] < n - 1:
        moved = _segments_by_motion(idx, z)
        if moved is not None:
            return moved
        return np.select([np.arange(n) < idx[1], np.arange(n) < idx[2]], [0, 2], 1).astype(np.int8)
    turn = int(np.argmax(z)) if z[n // 2] > z[0] else int(np.argmin(z))
    return np.where(np.arange(n) < turn, 0, 1).astype(np.int8)
