r"""Reader of Nanosurf ``.nid`` force spectroscopy (FlexAFM, CoreAFM, easyScan 2; single curves and maps).

The container (header sections, binary blocks, their scaling) is read by
:mod:`afmforce.calibration.nid`; this module turns its spectroscopy frames into curves:

* ``Spec forward`` is the approach, ``Spec backward`` the retract, ``Spec fwd pause`` /
  ``Spec bwd pause`` dwells (segment 2) between and after them. Each frame's block of a channel
  holds one row per curve (``Lines``); row i holds ``LineDim<i>Points`` valid samples (a curve
  stopped at its force threshold holds fewer than ``Points``).
* The deflection is the ``Deflection`` channel in the file's unit (N when the software calibrated
  it, else m or V); z is the ``Z-Axis Sensor`` channel (measured, ``piezo_measured``) when recorded,
  and the commanded ``Z-Axis`` ramp of each row (``LineDim<i>Min`` + ``LineDim<i>Range``,
  ``piezo_nominal``). Both grow towards the sample on the approach (checked per curve).
* The backward rows are stored in the order of the ramp's axis (from far to the turning point), as
  the forward rows; the retract is reversed here into time order (it starts at the turning point).
* Time: ``FwModTime / FwModDatapoints`` per sample ([DataSet\Parameters\Spectroscopy]; the
  ``Modulation time`` and ``Data points`` of ``[DataSet-Info]`` otherwise); ``velocity`` =
  ``FwModRange / FwModTime`` (``retract_velocity`` from the Bw values), ``sample_rate`` its inverse.
* ``spring_constant`` is the lever's (``[DataSet\Calibration\Cantilever]``: the property in N/m);
  ``sensitivity`` [m/V] is the scan head's deflection channel in metres over the +-10 V
  ADC (``In<i>=...,TipSignalDC,Deflection,m,<full scale>``, as NSFopen takes it). The force
  channel's full scale (``...,Deflection,N,<full scale>``) over the metres' equals the spring
  constant (2.72436 N/m both ways in the public map file): the two are one calibration.
* Maps (``SpecMode=Map``, ``[DataSet\SpecInfos\SpecMapTable]`` ``Map0=xmin;xmax;ymin;ymax;nx;ny;...``):
  curve i lies in row ``iy = i // nx``, back and forth (odd rows run from x max to x min: the
  contact heights of the public 10 x 10 map are continuous at the row ends only that way), at
  ``position_x``, ``position_y`` [m] relative to the scan centre, with ``map_x``, ``map_y``,
  ``map_nx``, ``map_ny`` as the other map readers give them.

A ``.nid`` with images only (``Scan forward`` ...) or a thermal tune is refused by name
(``afmforce calibrate thermal`` reads the latter). Written from the format as Nanosurf's MIT-licensed
NSFopen (github.com/syrupface/NSFopen) reads it, and checked on its example files; afmforce's own code.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ..calibration.nid import NidFile, is_nid, read_nid, si_value, typed_value
from ..errors import FileFormatError
from .curve import SEGMENT_APPROACH, SEGMENT_DWELL, SEGMENT_RETRACT, RawCurve
from ._meta import finalize_curve

__all__ = ["detect_nid", "load_nid", "count_curves", "SPEC_FRAMES"]

#: the spectroscopy frames in time order and their segment codes
SPEC_FRAMES = (("Spec forward", SEGMENT_APPROACH), ("Spec fwd pause", SEGMENT_DWELL),
               ("Spec backward", SEGMENT_RETRACT), ("Spec bwd pause", SEGMENT_DWELL))
_UNITS = {"N": "N", "m": "m", "V": "V"}
#: the deflection ADC's full scale [V] (the scan head's In<i> lines give each channel's full scale)
ADC_VOLTS = 10.0


def detect_nid(path: Path) -> bool:
    """A Nanosurf .nid: ``[DataSet]`` first, with ``GroupCount``."""
    try:
        with open(path, "rb") as fh:
            return is_nid(fh.read(4096))
    except OSError:
        return False


def count_curves(path: str | Path) -> int | None:
    """The curves of a .nid spectroscopy map, from its header alone (None: not a map)."""
    nid = read_nid(path)
    block = nid.block("Spec forward", "Deflection")
    grid = _map(nid)
    return block.lines if block is not None and grid is not None and grid[4] * grid[5] == block.lines else None


def _section(nid: NidFile, name: str) -> dict:
    return nid.sections.get(name, {})


def _typed(entries: dict, key: str, unit: str | None = None) -> float | None:
    v = typed_value(entries.get(key))
    if v is None or (unit is not None and v[1] != unit):
        return None
    return v[0]


def _calibration(nid: NidFile) -> dict[str, Any]:
    meta: dict[str, Any] = {}
    lever = _section(nid, "DataSet\\Calibration\\Cantilever")
    count = lever.get("PropCount", "0").strip()
    for i in range(min(int(count), 1000) if count.isdigit() else 0):   # real files: 14 properties
        v = typed_value(lever.get(f"Prop{i}"))
        if v is not None and v[1] == "N/m" and v[0] > 0:
            meta["spring_constant"] = v[0]
            break
    if lever.get("Name"):
        meta["cantilever"] = f"{lever.get('Manufacturer', '')} {lever['Name']}".strip()
    head = _section(nid, "DataSet\\Calibration\\Scanhead")
    for key, value in head.items():
        parts = [p.strip() for p in value.split(",")]
        if key.startswith("In") and len(parts) >= 5 and parts[1] == "TipSignalDC" and parts[3] == "m":
            try:
                full = float(parts[4])
            except ValueError:
                continue
            if full > 0:
                meta["sensitivity"] = full / ADC_VOLTS
            break
    return meta


def _timing(nid: NidFile, where: str) -> dict[str, float]:
    spec = _section(nid, "DataSet\\Parameters\\Spectroscopy")
    out: dict[str, float] = {}
    for pre, key in (("Fw", "velocity"), ("Bw", "retract_velocity")):
        t, n, r = _typed(spec, f"{pre}ModTime", "s"), _typed(spec, f"{pre}ModDatapoints"), _typed(spec, f"{pre}ModRange", "m")
        if t and t > 0 and n and n > 0:
            out[f"{pre.lower()}_dt"] = t / n
            if r:
                out[key] = abs(r) / t
    if "fw_dt" not in out:   # older files: the [DataSet-Info] lines
        info = _section(nid, "DataSet-Info")
        t = si_value(info.get("Modulation time"), "s")
        n = info.get("Data points", "").strip()
        if t and t > 0 and n.isdigit() and int(n) > 0:
            out["fw_dt"] = t / int(n)
    if "fw_dt" not in out:
        raise FileFormatError(f"{where}: the .nid header gives no modulation time and data points "
                              "(FwModTime, FwModDatapoints); the sample rate is unknown")
    out.setdefault("bw_dt", out["fw_dt"])
    return out


def _map(nid: NidFile) -> tuple[float, float, float, float, int, int] | None:
    if _section(nid, "DataSet\\SpecInfos\\SpecHeader").get("SpecMode", "").strip().lower() != "map":
        return None
    row = _section(nid, "DataSet\\SpecInfos\\SpecMapTable").get("Map0", "")
    parts = row.split(";")
    try:
        x0, x1, y0, y1 = (float(p) for p in parts[:4])
        nx, ny = int(parts[4]), int(parts[5])
    except (ValueError, IndexError):
        return None
    return (x0, x1, y0, y1, nx, ny) if nx >= 1 and ny >= 1 else None


def _grid_point(grid, i: int) -> dict[str, Any]:
    x0, x1, y0, y1, nx, ny = grid
    iy, ix = divmod(i, nx)
    if iy % 2:
        ix = nx - 1 - ix   # back and forth
    return {"map_x": ix, "map_y": iy, "map_nx": nx, "map_ny": ny,
            "position_x": x0 + (x1 - x0) * ix / max(nx - 1, 1), "position_y": y0 + (y1 - y0) * iy / max(ny - 1, 1)}


def _row_points(block, i: int) -> int:
    n = block.header.get(f"LineDim{i}Points")
    return int(n) if n is not None and n.strip().isdigit() and 2 <= int(n) <= block.points else block.points


def _ramp(block, i: int, n: int) -> np.ndarray:
    """The commanded Z-Axis of row i [m] (LineDim<i>Min + Range, else the frame's Dim0)."""
    h = block.header
    try:
        low, span = float(h[f"LineDim{i}Min"]), float(h[f"LineDim{i}Range"])
    except (KeyError, ValueError):
        try:
            low, span = float(h["Dim0Min"]), float(h["Dim0Range"]) * (n - 1) / max(block.points - 1, 1)
        except (KeyError, ValueError):
            return np.arange(n, dtype=float)
    return low + span * np.arange(n) / max(n - 1, 1)


def load_nid(path: Path, *, meta_override: Mapping[str, Any] | None = None,
             callback: Callable | None = None) -> list[RawCurve]:
    """Read every force curve of a Nanosurf .nid (see the module docstring).

    Raises
    ------
    FileFormatError
        Not a .nid, truncated, images or a thermal tune only, or no deflection channel.
    """
    where = str(path)
    nid = read_nid(path)
    frames = nid.frames()
    if not any(b.frame == "Spec forward" for b in nid.blocks):
        if "Spectrum FFT" in frames:
            raise FileFormatError(f"{where}: this Nanosurf .nid holds a thermal tune, no force curve; read it with "
                                  "the thermal calibration (afmforce.calibration.read_spectrum)")
        kind = "images" if any(f.startswith(("Scan", "2nd scan")) for f in frames) else "no spectroscopy"
        raise FileFormatError(f"{where}: this Nanosurf .nid holds {kind} ({', '.join(frames) or 'no frame'}), "
                              "no force curve ('Spec forward' frame)")
    parts = []
    for frame, code in SPEC_FRAMES:
        defl = nid.block(frame, "Deflection")
        if defl is None:
            if code == SEGMENT_DWELL:
                continue
            raise FileFormatError(f"{where}: the '{frame}' frame has no Deflection channel")
        if defl.unit not in _UNITS:
            raise FileFormatError(f"{where}: the '{frame}' deflection is in {defl.unit!r}; expected N, m or V")
        zsen = nid.block(frame, "Z-Axis Sensor")
        if zsen is not None and (zsen.unit != "m" or zsen.lines != defl.lines or zsen.points != defl.points):
            zsen = None
        parts.append((frame, code, defl, zsen))
    units = {d.unit for _, _, d, _ in parts}
    if len(units) > 1:
        raise FileFormatError(f"{where}: the spectroscopy frames store the deflection in {sorted(units)}; "
                              "expected one unit")
    lines = parts[0][2].lines
    if any(d.lines != lines for _, _, d, _ in parts):
        raise FileFormatError(f"{where}: the spectroscopy frames hold different numbers of curves; damaged")
    measured = all(z is not None for _, code, _, z in parts if code != SEGMENT_DWELL)
    values = {frame: (nid.values(d), nid.values(z) if measured and z is not None else None)
              for frame, _, d, z in parts}
    timing = _timing(nid, where)
    grid = _map(nid)
    if grid is not None and grid[4] * grid[5] != lines:
        grid = None
    info = _section(nid, "DataSet-Info")
    base: dict[str, Any] = {"instrument": f"Nanosurf {info.get('Head type', '')}".strip(),
                            **_calibration(nid), **{k: v for k, v in timing.items() if "velocity" in k},
                            "sample_rate": 1.0 / timing["fw_dt"]}
    if info.get("Date"):
        base["date"] = f"{info['Date']} {info.get('Time', '')}".strip()
    base.update(dict(meta_override or {}))
    base.update(source_file=where, reader="nanosurf-nid", format="Nanosurf .nid spectroscopy")
    out = []
    for i in range(lines):
        t0, cols = 0.0, {"t": [], "zn": [], "zm": [], "d": [], "s": []}
        for frame, code, defl, _ in parts:
            n = _row_points(defl, i)
            d, z = values[frame]
            dt = timing["bw_dt"] if code == SEGMENT_RETRACT or frame == "Spec bwd pause" else timing["fw_dt"]
            ramp = _ramp(defl, i, n)
            row_d = d[i, :n]
            row_z = z[i, :n] if z is not None else None
            if code == SEGMENT_RETRACT:   # stored along the ramp's axis: time runs from the turning point
                row_d, ramp = row_d[::-1], ramp[::-1]
                row_z = None if row_z is None else row_z[::-1]
            cols["t"].append(t0 + dt * np.arange(n))
            cols["zn"].append(ramp)
            cols["zm"].append(row_z if row_z is not None else np.full(n, np.nan))
            cols["d"].append(row_d)
            cols["s"].append(np.full(n, code, dtype=np.int8))
            t0 += dt * n
        seg = np.concatenate(cols["s"])
        zn = np.concatenate(cols["zn"])
        zm = np.concatenate(cols["zm"]) if measured else None
        if zm is not None and not np.all(np.isfinite(zm)):
            zm = None
        app = np.flatnonzero(seg == SEGMENT_APPROACH)
        ref = zm if zm is not None else zn
        sign = -1.0 if app.size >= 2 and ref[app[-1]] < ref[app[0]] else 1.0
        meta = dict(base)
        if lines > 1:
            meta["curve_index"] = i
            if grid is not None:
                meta.update(_grid_point(grid, i))
        meta["position_sign"] = sign
        curve = RawCurve(time=np.concatenate(cols["t"]), piezo_nominal=sign * zn,
                         piezo_measured=None if zm is None else sign * zm,
                         deflection_signal=np.concatenate(cols["d"]), segment=seg, metadata=meta,
                         deflection_unit=parts[0][2].unit)
        out.append(finalize_curve(curve, where))
        if callback is not None:
            callback((i + 1) / lines)
    return out
