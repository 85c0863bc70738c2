"""JPK Data Processing text exports (``Export -> Text``): ``# segment:`` blocks of columns.

JPK DP writes each segment of each curve as a block: ``#`` header lines (the curve's
``index``, the ``force-settings``), then ``# segmentIndex: i``, ``# segment: extend``
(``retract``, ``pause``, ``modulation``), ``# columns:`` (``height vDeflection
capacitiveSensorHeight seriesTime ...``), ``# units:`` (``m N m s``), ``# springConstant:``,
``# sensitivity:``, and the rows (space-separated numbers). A file may hold several curves
(a map export): a new curve starts where ``segmentIndex`` returns to 0 or the ``index``
changes. This reader returns one :class:`~afmforce.io.curve.RawCurve` per curve:

* ``deflection_signal``: ``vDeflection`` in the unit the export wrote (N, m or V);
* ``piezo_nominal``: ``-height`` (a nominal height times the export's ``heightMultiplier``: the
  calibrated height, as in the archive); ``piezo_measured``: ``-capacitiveSensorHeight`` (or
  ``measuredHeight``, ``strainGaugeHeight``), z oriented to increase on the extend segment;
* ``time``: ``seriesTime`` when exported, else each segment's ``time`` laid end to end;
* segments by their type (extend 0, retract 1, pause and modulation 2: kept, never taken
  as approach or retract); spring constant and sensitivity from the block headers.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ..errors import FileFormatError
from .curve import RawCurve
from ._meta import finalize_curve, orient, positive_entry, segment_code, sensor_note

__all__ = ["detect_jpk_text", "load_jpk_text"]

_MEASURED = ("capacitiveSensorHeight", "measuredHeight", "strainGaugeHeight")
_UNITS = {"N": "N", "m": "m", "V": "V"}
#: ``# direction:`` of the older JPK exports (SPM 3/4, 2011: ``map-data-...-0000.out``, one block per direction
#: and no ``# segment:`` line) -> the segment word of the later ones
_DIRECTIONS = {"trace": "extend", "retrace": "retract"}


def detect_jpk_text(path: Path) -> bool:
    """A JPK DP text export: ``# segment:`` and ``# columns:`` header lines near the top."""
    with open(path, "rb") as fh:
        head = fh.read(65536).decode("latin-1", errors="replace")
    return ("\n# segment:" in head or "\n# direction:" in head) and "\n# columns:" in head and (
        head.startswith("# TEXT EXPORT") or "# springConstant:" in head or "# units:" in head)


def _blocks(text: str, where: str) -> list[dict[str, Any]]:
    """Every segment block: its ``#`` header entries and its rows (text lines)."""
    blocks: list[dict[str, Any]] = []
    header: dict[str, str] = {}
    rows: list[str] = []

    def close() -> None:
        if "segment" in header and rows:
            blocks.append({"header": dict(header), "rows": list(rows)})

    in_rows = False
    for line in text.splitlines():
        s = line.strip()
        if not s:
            continue
        if s.startswith("#"):
            if in_rows:  # a header after rows: the block ended
                close()
                rows.clear()
                header = {k: v for k, v in header.items()
                          if k not in ("segment", "segmentIndex", "columns", "direction")}
                in_rows = False
            body = s[1:].strip()
            if ":" in body:
                key, value = body.split(":", 1)
                header[key.strip()] = value.strip()
                if key.strip() == "direction":  # JPK SPM 3/4 exports (2011): trace and retrace, no segment line
                    header["segment"] = _DIRECTIONS.get(value.strip().lower(), value.strip())
            continue
        in_rows = True
        rows.append(s)
    close()
    if not blocks:
        raise FileFormatError(f"{where}: no '# segment:' block with data rows; not a JPK text export")
    return blocks


def _table(block: dict[str, Any], where: str) -> dict[str, np.ndarray]:
    cols = block["header"].get("columns", "").split()
    if not cols:
        raise FileFormatError(f"{where}: segment block without a '# columns:' line")
    try:
        data = np.array([[float(v) for v in row.split()] for row in block["rows"]], dtype=float)
    except ValueError:
        raise FileFormatError(f"{where}: segment {block['header'].get('segment')}: a row is not numbers") from None
    if data.ndim != 2 or data.shape[1] != len(cols):
        raise FileFormatError(f"{where}: segment {block['header'].get('segment')}: rows of {data.shape[-1]} "
                              f"numbers for {len(cols)} columns ({' '.join(cols)})")
    return {c: data[:, i] for i, c in enumerate(cols)}


def _curves(blocks: list[dict[str, Any]]) -> list[list[dict[str, Any]]]:
    """Segment blocks grouped by curve (segmentIndex back to 0, or a new index)."""
    out: list[list[dict[str, Any]]] = []
    last_index = None
    for b in blocks:
        h = b["header"]
        new = not out or h.get("segmentIndex") == "0" or h.get("index") != last_index
        if new:
            out.append([])
        out[-1].append(b)
        last_index = h.get("index")
    return out


def _curve(blocks: list[dict[str, Any]], where: str, meta_override: Mapping[str, Any]) -> RawCurve:
    cols_t, cols_zn, cols_zm, cols_s, cols_seg, types = [], [], [], [], [], []
    unit = None
    meta: dict[str, Any] = {}
    t_end = 0.0
    sensor = nominal = None   # the measured height's column, the nominal's words (the note on the two)
    for b in blocks:
        h = b["header"]
        tab = _table(b, where)
        clock = tab.get("seriesTime", tab.get("time"))
        if clock is not None and clock.size > 1 and np.all(np.diff(clock) < 0):
            # the rows run back in time (the SPM 3/4 exports' retrace: from its far end to the turning point)
            tab = {k: v[::-1] for k, v in tab.items()}
        names = h.get("columns", "").split()
        units = dict(zip(names, h.get("units", "").split()))
        if "vDeflection" not in tab:
            raise FileFormatError(f"{where}: segment {h.get('segment')} has no vDeflection column "
                                  f"(columns: {' '.join(names)}); export the vertical deflection too")
        u = _UNITS.get(units.get("vDeflection", "V"))
        if u is None:
            raise FileFormatError(f"{where}: vDeflection in {units.get('vDeflection')!r}; expected N, m or V")
        if unit is not None and u != unit:
            raise FileFormatError(f"{where}: vDeflection in {unit} in one segment and {u} in another")
        unit = u
        n = tab["vDeflection"].size
        height = tab.get("height")
        sensor = next((c for c in _MEASURED if c in tab), None)
        measured = tab[sensor] if sensor is not None else None
        if height is None and measured is None:
            raise FileFormatError(f"{where}: segment {h.get('segment')} has no height column "
                                  f"(columns: {' '.join(names)}); export height or measured height")
        slots = dict(zip(names, h.get("calibrationSlots", "").split()))
        if height is not None and slots.get("height") == "nominal" and positive_entry(h, "heightMultiplier"):
            # the archive's default height is the calibrated slot: nominal x heightMultiplier + heightOffset
            height = height * float(h["heightMultiplier"]) + float(h.get("heightOffset", "0") or 0)
            nominal = "height x heightMultiplier"
        elif height is not None:
            nominal = "height"
        if height is None:
            height, measured = measured, None
        if "seriesTime" in tab:
            t = tab["seriesTime"]
        elif "time" in tab:
            t = t_end + tab["time"]
        else:
            t = None
        style = h.get("segment", "")
        word = next((w for w in ("extend", "retract", "pause", "modulation") if w in style.lower()), style)
        if t is not None and n > 1 and "sample_rate" not in meta and segment_code(word) == 0:
            step = float(t[-1] - t[0]) / (n - 1)
            if step > 0:
                meta["sample_rate"] = 1.0 / step
        cols_t.append(t)
        if t is not None and t.size:
            t_end = float(t[-1]) + (float(np.median(np.diff(t))) if t.size > 1 else 0.0)
        cols_zn.append(-height)
        cols_zm.append(None if measured is None else -measured)
        cols_s.append(tab["vDeflection"])
        cols_seg.append(np.full(n, segment_code(word), dtype=np.int8))
        types.append(style)
        for key, ours in (("springConstant", "spring_constant"), ("sensitivity", "sensitivity")):
            v = positive_entry(h, key)
            if v is not None:
                meta.setdefault(ours, v)
        if h.get("data-description.instrument"):
            meta.setdefault("instrument", h["data-description.instrument"])
    seg = np.concatenate(cols_seg)
    if any(t is None for t in cols_t):
        rate = meta.get("sample_rate")
        time = np.arange(seg.size) / rate if rate else np.arange(seg.size, dtype=float)
        if not rate:
            meta["time_is_sample_index"] = True
    else:
        time = np.concatenate(cols_t)
    zm = None if any(m is None for m in cols_zm) else np.concatenate(cols_zm)
    zn, zm, sign = orient(np.concatenate(cols_zn), zm, seg)
    note = None if zm is None or sensor is None or nominal is None else \
        sensor_note(zm, zn, seg, sensor=f"the measured height ({sensor})", nominal=nominal,
                    used=f"the measured height ({sensor})", scales=f"the {sensor}'s calibration and the height's disagree")
    if note:   # a measured height far off the nominal (a 2011 strain gauge: 1.53 x height x heightMultiplier)
        meta["position_note"] = note
    meta["segment_types"] = types
    meta.update(meta_override)
    meta.update(source_file=where, reader="jpk-txt", format="JPK Data Processing text export", position_sign=sign)
    curve = RawCurve(time=time, piezo_nominal=zn, piezo_measured=zm, deflection_signal=np.concatenate(cols_s),
                     segment=seg, metadata=meta, deflection_unit=unit or "V")
    return finalize_curve(curve, where)


def load_jpk_text(path: Path, *, meta_override: Mapping[str, Any] | None = None,
                  callback: Callable | None = None) -> list[RawCurve]:
    """Every curve of a JPK DP text export (see the module docstring)."""
    path = Path(path)
    where = str(path)
    text = path.read_bytes().decode("latin-1")
    groups = _curves(_blocks(text, where))
    out = []
    for i, blocks in enumerate(groups):
        out.append(_curve(blocks, where, dict(meta_override or {})))
        if callback is not None:
            callback((i + 1) / len(groups))
    return out
