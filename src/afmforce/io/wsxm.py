"""WSxM force curves (Nanotec Electronica controllers, WSxM software): ``.curves`` files.

Layout (binary, little-endian; learned from the WSxM readers of pycroscopy/SciFiReaders,
``SciFiReaders/readers/microscopy/spm/afm/wsxm.py``, MIT, (c) Pranav Sudersan 2025, and
checked on the files of pycroscopy/SciFiDatasets; this code is afmforce's own):

* a text header that starts ``WSxM file copyright`` and holds ``Image header size: N`` (the
  header's length in bytes, from the block's first byte) and ``[Section]`` blocks of
  ``key: value`` lines, ending with ``[Header end]``; it describes the image taken with the
  curves (``Number of rows`` x ``Number of columns`` values of ``Image Data Type``), which follows;
* then one block per curve of the series: a header of the same kind (``FZ curve file``, with
  ``Index of this Curve``, ``Number of Curves in this serie``, ``Number of points``, ``Number of
  lines`` and the axes' names and units) followed by ``lines x points`` (x, y) pairs of the
  image's data type, line after line.

What afmforce takes from it: the X axis (``Z``, a length) is the piezo position, increasing
towards the sample (in contact the deflection rises with it); the lines come in pairs, the
forward line the approach and the backward line the retract (``First Forward: No`` swaps them).
WSxM stores both lines on one ascending X axis: a backward line that runs the same way as the
forward one is reversed into time order. A line whose values are not finite or whose Z is not a
ramp (data read from a wrong offset) is refused as damaged. The Y
values are ``Conversion Offset 00 + Conversion Factor 00 x value`` (sign flipped where ``Channel
is inverted: Yes``) in the factor's unit, which must agree with ``Y axis unit``: volts give a
photodiode signal in V (the file stores no deflection sensitivity: the user gives it), a length
a deflection in m, a force unit a force in N. The spring constant is the header's ``Force
constant``; the sample rate is the number of points over ``Forward plot total time`` (the
controller's ``Sampling frequency`` over ``Samples/point``), the speeds the Z travel over the
plot times; ``Acquisition point`` gives ``position_x``, ``position_y`` [m].

Only curves of a deflection channel (``Normal force``, a deflection, a force) are force curves.
A file of another channel recorded during the same ramps (``Amplitude``, ``Phase``, ``Excitation
frequency`` of dynamic mode) is refused with a :class:`~afmforce.errors.FileFormatError` that
names the channel and says to open the ``Normal force`` file of the series. WSxM force volumes
(``.gsi``), text curves (``.cur``) and ``.stp`` files are not read.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ..errors import FileFormatError
from ._meta import finalize_curve, orient
from .curve import SEGMENT_APPROACH, SEGMENT_RETRACT, RawCurve

__all__ = ["detect_wsxm_curves", "load_wsxm_curves", "read_header", "SIGNATURE"]

SIGNATURE = b"WSxM file copyright"
#: WSxM's names of binary types -> numpy little-endian dtype
DATA_TYPES = {"short": "<i2", "short-data": "<i2", "unsignedshort": "<u2", "integer-data": "<i4",
              "signedinteger": "<i4", "float-data": "<f4", "float": "<f4", "double": "<f8"}
#: unit prefixes WSxM writes
_PREFIX = {"": 1.0, "k": 1e3, "m": 1e-3, "u": 1e-6, "\u00b5": 1e-6, "\u03bc": 1e-6, "n": 1e-9, "p": 1e-12,
           "f": 1e-15}
#: Y channels that are a deflection or a force (lower case, the start of ``Y axis text``)
_DEFLECTION_CHANNELS = ("normal force", "deflection", "force", "vertical deflection")
_MAX_HEADER = 1 << 20


def detect_wsxm_curves(path: Path) -> bool:
    """A WSxM file: the first bytes are ``WSxM file copyright`` and an ``Image header size`` follows."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(256)
    except OSError:
        return False
    return head.startswith(SIGNATURE) and b"Image header size:" in head


def read_header(data: bytes, at: int, where: str) -> tuple[dict[str, dict[str, str]], str, int]:
    """The header block starting at byte ``at``: ``({section: {key: value}}, first line, size [bytes])``.

    Raises
    ------
    FileFormatError
        No ``Image header size``, a size beyond the file, or no ``[Header end]`` (truncated).
    """
    m = re.search(rb"Image header size:\s*(\d+)", data[at:at + 512])
    if m is None:
        raise FileFormatError(f"{where}: no 'Image header size' at byte {at}; not a WSxM file, or damaged there")
    size = int(m.group(1))
    if size <= m.end() or size > _MAX_HEADER or at + size > len(data):
        raise FileFormatError(f"{where}: the header at byte {at} declares {size} bytes but the file has "
                              f"{len(data) - at} from there; the file is truncated or damaged")
    text = data[at:at + size].decode("latin-1")
    if "[Header end]" not in text:
        raise FileFormatError(f"{where}: the header at byte {at} has no '[Header end]' line within its "
                              f"{size} bytes; the file is damaged")
    sections: dict[str, dict[str, str]] = {}
    current = sections.setdefault("", {})
    lines = text.splitlines()
    for line in lines:
        s = line.strip()
        if s.startswith("[") and s.endswith("]"):
            current = sections.setdefault(s[1:-1], {})
        elif ":" in s:
            key, _, value = s.partition(":")
            current[key.strip()] = value.strip()
    return sections, (lines[0].strip() if lines else ""), size


def _entry(sections: Mapping[str, Mapping[str, str]], section: str, key: str, where: str) -> str:
    try:
        return sections[section][key]
    except KeyError:
        raise FileFormatError(f"{where}: the header has no '{key}' in [{section}]; the file is damaged "
                              "or not a WSxM curves file") from None


def _count(sections, section: str, key: str, where: str, least: int = 1) -> int:
    text = _entry(sections, section, key, where)
    try:
        n = int(text)
    except ValueError:
        raise FileFormatError(f"{where}: '{key}' is {text!r}, not a whole number; the file is damaged") from None
    if not least <= n <= 100_000_000:
        raise FileFormatError(f"{where}: '{key}' is {n}; the file is damaged")
    return n


def _quantity(text: str) -> tuple[float, str]:
    """``"5.33904 N/m"`` -> (5.33904, "N/m"); ValueError if the number is not one."""
    parts = text.split(None, 1)
    if not parts:
        raise ValueError("no number")
    return float(parts[0]), (parts[1].strip() if len(parts) > 1 else "")


def _unit(unit: str) -> tuple[str, float] | None:
    """A WSxM unit -> (afmforce unit V, m or N, factor to it); None for anything else (Hz, Deg...)."""
    u = unit.strip()
    if u in ("\u00c5", "A", "Angstrom"):
        return "m", 1e-10
    for base in ("V", "N", "m"):
        if u.endswith(base) and u[:-1] in _PREFIX:
            return base, _PREFIX[u[:-1]]
    return None


def _length_factor(unit: str, what: str, where: str) -> float:
    got = _unit(unit)
    if got is None or got[0] != "m":
        raise FileFormatError(f"{where}: {what} is in {unit!r}, not a length; not a force-distance curve "
                              "(the X axis of a force curve is Z in nm)")
    return got[1]


def _seconds(text: str | None) -> float | None:
    """``"3993 ms"`` -> 3.993; None if missing or not a positive time."""
    if not text:
        return None
    try:
        value, unit = _quantity(text)
    except ValueError:
        return None
    scale = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "\u00b5s": 1e-6}.get(unit)
    return value * scale if scale and np.isfinite(value) and value > 0 else None


def _y_scale(curve_h, where: str) -> tuple[str, float, float, str]:
    """The Y channel's (afmforce unit, factor, offset, channel name) from a curve header."""
    info = curve_h.get("General Info", {})
    channel = info.get("Y axis text", "").split("[")[0].strip()
    axis_unit = info.get("Y axis unit", "").strip()
    if not any(channel.lower().startswith(c) for c in _DEFLECTION_CHANNELS):
        raise FileFormatError(
            f"{where}: the curves are of the channel {channel or '(unnamed)'!r} [{axis_unit}], not a deflection "
            "or force (dynamic-mode amplitude, phase and frequency curves are not force curves); open the "
            "'Normal force' file of the same series (WSxM names it ..._Normal force.f.curves)")
    factor, offset, unit = 1.0, 0.0, axis_unit
    if "Conversion Factor 00" in info:
        try:
            factor, unit = _quantity(info["Conversion Factor 00"])
            offset, off_unit = _quantity(info.get("Conversion Offset 00", f"0 {unit}"))
        except ValueError:
            raise FileFormatError(f"{where}: 'Conversion Factor 00' {info['Conversion Factor 00']!r} or its offset "
                                  "is not a number with a unit; the file is damaged") from None
        if not (np.isfinite(factor) and np.isfinite(offset) and factor != 0):
            raise FileFormatError(f"{where}: Conversion Factor 00 {factor!r} {unit} and offset {offset!r} do not "
                                  "convert the signal (a finite, non-zero factor); the file is damaged")
        if off_unit and off_unit != unit:
            raise FileFormatError(f"{where}: Conversion Factor 00 in {unit!r} but its offset in {off_unit!r}")
        if axis_unit and unit != axis_unit:
            raise FileFormatError(f"{where}: the Y axis is in {axis_unit!r} but its conversion factor gives "
                                  f"{unit!r}; afmforce does not guess which one the values are in")
    if info.get("Channel is inverted", "No").strip().lower() == "yes":
        factor = -factor
    got = _unit(unit)
    if got is None:
        raise FileFormatError(f"{where}: the {channel} channel is in {unit!r}; expected volts, a length or a force")
    return got[0], factor * got[1], offset * got[1], channel


def _point(text: str | None) -> tuple[float, float] | None:
    """``"(0 nm, -0.36607 nm)"`` -> (0.0, -3.6607e-10) [m]; None if not of that form."""
    m = re.fullmatch(r"\(\s*([-+\d.eE]+)\s*(\S+)\s*,\s*([-+\d.eE]+)\s*(\S+)\s*\)", (text or "").strip())
    if m is None:
        return None
    ux, uy = _unit(m.group(2)), _unit(m.group(4))
    if ux is None or uy is None or ux[0] != "m" or uy[0] != "m":
        return None
    try:
        return float(m.group(1)) * ux[1], float(m.group(3)) * uy[1]
    except ValueError:  # a position is optional metadata: a damaged one is left out
        return None


def _ramp(line: np.ndarray, index: Any, which: str, where: str) -> np.ndarray:
    """A line's (Z, signal) pairs, checked: finite, and Z a ramp (at least 90 % of its steps one way;
    values read from a wrong offset of a damaged file are neither)."""
    if not np.all(np.isfinite(line)):
        raise FileFormatError(f"{where}: curve {index}, {which} line: non-finite values; the data do not line "
                              "up with the header (the file is damaged)")
    step = np.sign(np.diff(line[:, 0]))
    if step.size >= 10 and max(np.sum(step > 0), np.sum(step < 0)) < 0.9 * step.size:
        raise FileFormatError(f"{where}: curve {index}, {which} line: the Z column is not a ramp; the data do "
                              "not line up with the header (the file is damaged)")
    return line


def _index(text: str) -> int | str:
    """``Index of this Curve`` as a number where it is one (``Average`` stays a word)."""
    return int(text) if text.strip().isdigit() else text


def _file_meta(top, where: str) -> dict[str, Any]:
    info = top.get("General Info", {})
    meta: dict[str, Any] = {"instrument": "Nanotec (WSxM)"}
    text = info.get("Force constant")
    if text:
        try:
            k, unit = _quantity(text)
        except ValueError:
            raise FileFormatError(f"{where}: 'Force constant' is {text!r}, not a number; the file is damaged, "
                                  "give the spring constant (`spring_constant`)") from None
        if unit not in ("N/m", ""):
            raise FileFormatError(f"{where}: 'Force constant' in {unit!r}; expected N/m")
        if k > 0 and np.isfinite(k):
            meta["spring_constant"] = k
    if info.get("Acquisition time"):
        meta["date"] = info["Acquisition time"]
    version = top.get("Miscellaneous", {}).get("Acquired with version")
    if version:
        meta["instrument"] = f"Nanotec (WSxM {version})"
    return meta


def _image_bytes(top, where: str) -> tuple[int, np.dtype]:
    kind = _entry(top, "General Info", "Image Data Type", where)
    if kind.strip().lower() not in DATA_TYPES:
        raise FileFormatError(f"{where}: Image Data Type {kind!r} is not one WSxM writes "
                              f"({', '.join(DATA_TYPES)})")
    dtype = np.dtype(DATA_TYPES[kind.strip().lower()])
    rows = _count(top, "General Info", "Number of rows", where)
    cols = _count(top, "General Info", "Number of columns", where)
    return rows * cols * dtype.itemsize, dtype


def load_wsxm_curves(path: Path, *, meta_override: Mapping[str, Any] | None = None,
                     callback: Callable | None = None) -> list[RawCurve]:
    """Every force curve of a WSxM ``.curves`` file (see the module docstring).

    Returns one :class:`RawCurve` per forward/backward pair (``curve_index`` in its metadata: the
    file's ``Index of this Curve``, with a letter for a second pair). Raises :class:`FileFormatError`
    for a truncated or damaged file and for curves of a channel that is not a deflection.
    """
    path = Path(path)
    where = str(path)
    data = path.read_bytes()
    if not data.startswith(SIGNATURE):
        raise FileFormatError(f"{where}: does not start with 'WSxM file copyright'; not a WSxM file")
    top, _, size = read_header(data, 0, where)
    image, dtype = _image_bytes(top, where)
    at = size + image
    if at >= len(data):
        raise FileFormatError(f"{where}: the file ends inside the image stored before the curves "
                              f"({len(data)} bytes, the image ends at byte {at}); the file is truncated")
    base = _file_meta(top, where)
    base.update(meta_override or {})
    out: list[RawCurve] = []
    declared, blocks = None, 0
    while at < len(data):
        head, first, size = read_header(data, at, where)
        control, info = head.get("Control", {}), head.get("General Info", {})
        index = control.get("Index of this Curve", str(len(out) + 1))
        declared = declared or _count(head, "Control", "Number of Curves in this serie", where)
        n = _count(head, "General Info", "Number of points", where, least=0)
        lines = _count(head, "General Info", "Number of lines", where)
        nbytes = n * lines * 2 * dtype.itemsize
        if at + size + nbytes > len(data):
            raise FileFormatError(f"{where}: curve {index} ({first or 'curve'}) needs {nbytes} bytes of data but "
                                  f"the file ends {len(data) - at - size} bytes after its header; the file is "
                                  "truncated")
        block = np.frombuffer(data, dtype=dtype, count=n * lines * 2, offset=at + size).astype(float)
        at += size + nbytes
        blocks += 1
        if n == 0:  # WSxM writes an empty block for a curve it did not record
            continue
        if lines % 2:
            raise FileFormatError(f"{where}: curve {index} has {lines} lines; expected forward and backward "
                                  "pairs (approach and retract)")
        pairs = block.reshape(lines, n, 2)
        x_scale = _length_factor(info.get("X axis unit", ""), "the X axis", where)
        unit, y_scale, y_offset, channel = _y_scale(head, where)
        forward_first = head.get("Miscellaneous", {}).get("First Forward", "Yes").strip().lower() != "no"
        t_fwd = _seconds(control.get("Forward plot total time"))
        t_bwd = _seconds(control.get("Backward plot total time"))
        for p in range(lines // 2):
            fwd, bwd = (pairs[2 * p], pairs[2 * p + 1]) if forward_first else (pairs[2 * p + 1], pairs[2 * p])
            fwd, bwd = _ramp(fwd, index, "forward", where), _ramp(bwd, index, "backward", where)
            if n > 1 and (bwd[-1, 0] - bwd[0, 0]) * (fwd[-1, 0] - fwd[0, 0]) > 0:
                bwd = bwd[::-1]  # stored on the forward's axis: put the retract in time order
            with np.errstate(all="ignore"):  # overflow of a damaged factor: refused by finalize_curve
                z_app, z_ret = fwd[:, 0] * x_scale, bwd[:, 0] * x_scale
                d_app, d_ret = y_offset + y_scale * fwd[:, 1], y_offset + y_scale * bwd[:, 1]
            meta = dict(base)
            meta.update(curve_index=_index(index) if lines == 2 else f"{index}{chr(ord('a') + p)}",
                        curves_in_series=declared, channel=channel)
            if t_fwd and t_bwd:
                rate = n / t_fwd
                time = np.concatenate([np.arange(n) / rate, t_fwd + np.arange(n) * (t_bwd / n)])
                meta.setdefault("sample_rate", rate)
                if abs(z_app[-1] - z_app[0]) > 0:
                    meta.setdefault("velocity", float(abs(z_app[-1] - z_app[0])) / t_fwd)
                    meta.setdefault("retract_velocity", float(abs(z_ret[-1] - z_ret[0])) / t_bwd)
            else:
                time = np.arange(2 * n, dtype=float)
                meta["time_is_sample_index"] = True
            point = _point(control.get("Acquisition point"))
            if point is not None:
                meta["position_x"], meta["position_y"] = point
            seg = np.concatenate([np.full(n, SEGMENT_APPROACH, np.int8), np.full(n, SEGMENT_RETRACT, np.int8)])
            zn, _, sign = orient(np.concatenate([z_app, z_ret]), None, seg)
            meta.update(meta_override or {})
            meta.update(source_file=where, reader="wsxm-curves", format="WSxM curves", position_sign=sign)
            curve = RawCurve(time=time, piezo_nominal=zn, deflection_signal=np.concatenate([d_app, d_ret]),
                             segment=seg, metadata=meta, deflection_unit=unit)
            out.append(finalize_curve(curve, where))
        if callback is not None:
            callback(min(1.0, at / len(data)))
    if declared is not None and blocks < declared:
        raise FileFormatError(f"{where}: the header announces {declared} curves but the file holds {blocks}; "
                              "the file is truncated")
    if not out:
        raise FileFormatError(f"{where}: no curve with data after the image; the file is truncated or empty")
    return out
