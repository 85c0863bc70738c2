"""A force map written as JPK QI data (``.jpk-qi-data``), laid out as JPK's own files are.

The archive (a zip, deflated) holds what the QI files of the corpus hold
(tests/data/corpus/jpk-qi-data_2020.02.07.jpk-qi-data)::

    header.properties                    type=quantitative-imaging-map, the grid (ilength x jlength,
                                         ulength x vlength [m], centre), the extend/retract settings
    shared-data/header.properties        force-segment-header-info.0/1 (extend, retract) and
                                         lcd-info.0/1: the channels' encoders and conversion sets
    index/<i>/header.properties          the curve's position [m] and position index
    index/<i>/segments/<j>/segment-header.properties   points, duration, channels
    index/<i>/segments/<j>/channels/height.dat         big-endian int32
    index/<i>/segments/<j>/channels/vDeflection.dat    big-endian int32
    index/<i>/segments/<j>/channels/measuredHeight.dat big-endian int32

``vDeflection`` is stored in volts through a 32-bit encoder (step 10 V / 2^31: the recorded
signal is kept to 5e-9 V) with the conversion set volts -> distance (multiplier: the sensitivity
[m/V]) -> force (multiplier: the spring constant [N/m]); ``height`` is minus the piezo position
(JPK's height decreases towards the sample) through an encoder to volts and the ``nominal``
(volts -> m) and ``calibrated`` (m -> m) conversions; ``measuredHeight`` is the same in metres (1e-14 m
steps; the curve's ``piezo_measured`` when it has one). Curve ``i`` is grid cell
``(i % nx, i // nx)`` (``back-and-forth=false``).
"""

from __future__ import annotations

import math
import os
import time as _time
import zipfile
from pathlib import Path
from typing import Any, Iterable, Mapping

import numpy as np

from ..._files import atomic_path
from ...errors import ParameterError
from ..curve import RawCurve
from ._common import calibration, cell, duration, runs

__all__ = ["write_jpk_qi", "DEFLECTION_STEP", "HEIGHT_STEP"]

#: Encoder steps of the stored channels [V per integer]: +-10 V and +-20 V over int32.
DEFLECTION_STEP = 10.0 / 2**31
HEIGHT_STEP = 20.0 / 2**31
#: The measured height's encoder step [m per integer]: +-21 um over int32.
MEASURED_STEP = 1e-14
#: The height channel's nominal conversion [m/V] (a 20 um piezo over +-20 V would be 5e-7).
HEIGHT_METRES_PER_VOLT = 1e-6


def _props(lines: Mapping[str, Any]) -> bytes:
    stamp = _time.strftime("%a %b %d %H:%M:%S UTC %Y", _time.gmtime())
    body = "".join(f"{k}={_value(v)}\n" for k, v in lines.items())
    return f"#{stamp}\n{body}".encode("latin-1", "backslashreplace")


def _value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v).replace("e", "E").replace("inf", "Infinity").replace("nan", "NaN")
    return str(v).replace(":", "\\:")


def _encode(values: np.ndarray, step: float, where: str) -> bytes:
    ints = np.rint(values / step)
    if np.any(np.abs(ints) >= 2**31 - 1):
        raise ParameterError(f"{where}: a value of {float(np.max(np.abs(values))):.4g} V lies beyond the "
                             f"encoder's range (+-{step * 2**31:.3g} V)")
    return ints.astype(">i4").tobytes()


def _ramps(curve: RawCurve, r, durations: tuple[float, float]) -> tuple[float, float]:
    """The extend's and the retract's ramp lengths ``z-start - z-end`` [m]: a reader takes a run's
    speed as its ramp over its duration, so the ramp is the speed simulated (the curve's
    ``velocity``, ``retract_velocity``; the approach's where the retract has none) times the
    duration; a curve without speeds: the run's own, ``ptp(z) (n / (n - 1))`` (its travel over
    its sample-to-sample time). Before, both runs carried the approach's travel: the retract's
    speed read back 4x too low on the default drive (60 nm in, 250 nm out)."""
    md = curve.metadata or {}
    out = []
    for j, key in enumerate(("velocity", "retract_velocity")):
        v = md.get(key, md.get("velocity") if j else None)
        try:
            v = float(v) if v is not None else math.nan
        except (TypeError, ValueError):
            v = math.nan
        z = r.z[j]
        out.append(v * durations[j] if math.isfinite(v) and v > 0
                   else float(np.ptp(z)) * z.size / max(z.size - 1, 1))
    return out[0], out[1]


def _settings(prefix: str, n: tuple[int, int], durations: tuple[float, float],
              ramp: tuple[float, float]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for run, style, kind, npts, dur, ramp in (
            ("extend", "extend", "z-extend-force", n[0], durations[0], ramp[0]),
            ("retract", "retract", "z-retract-height", n[1], durations[1], ramp[1])):
        p = f"{prefix}{run}."
        out.update({p + "type": kind, p + "identifier.type": "standard", p + "identifier.name": f"{run}-spm",
                    p + "style": style, p + "duration": dur, p + "num-points": npts, p + "z-start": ramp,
                    p + "z-end": 0.0})
    return out


def _stamp(t: float) -> str:
    """A JPK time stamp (``2020-02-07 16:29:04.935 +0000``) of the POSIX time ``t`` [s]."""
    return _time.strftime("%Y-%m-%d %H:%M:%S", _time.gmtime(t)) + f".{int(t % 1 * 1000):03d} +0000"


def _shared(k: float, sens: float, n: tuple[int, int], durations: tuple[float, float],
            ramps: tuple[float, float], approach: str) -> dict:
    out: dict[str, Any] = {"force-segment-header-infos.count": 2, "lcd-infos.count": 3}
    for j, (run, kind, npts, dur, ramp) in enumerate((
            ("extend", "z-extend-force", n[0], durations[0], ramps[0]),
            ("retract", "z-retract-height", n[1], durations[1], ramps[1]))):
        p = f"force-segment-header-info.{j}."
        out.update({p + "type": "spm-force-segment-header", p + "approach-id": approach, p + "name.type": "standard",
                    p + "name.name": f"{run}-spm", p + "settings.type": "combined", p + "settings.style": run,
                    p + "settings.feedback-mode.name": "contact", p + "settings.segment-settings.type": kind,
                    p + "settings.segment-settings.identifier.type": "standard",
                    p + "settings.segment-settings.identifier.name": f"{run}-spm",
                    p + "settings.segment-settings.style": run, p + "settings.segment-settings.duration": dur,
                    p + "settings.segment-settings.num-points": npts,
                    p + "settings.segment-settings.z-start": ramp, p + "settings.segment-settings.z-end": 0.0})

    def conversion(p: str, slot: str, name: str, base: str, mult: float, unit: str) -> dict[str, Any]:
        c = f"{p}conversion-set.conversion.{slot}."
        return {c + "name": name, c + "defined": True, c + "type": "simple", c + "comment": name,
                c + "base-calibration-slot": base, c + "calibration-slot": slot, c + "scaling.type": "linear",
                c + "scaling.style": "offsetmultiplier", c + "scaling.offset": 0.0, c + "scaling.multiplier": mult,
                c + "scaling.unit.type": "metric-unit", c + "scaling.unit.unit": unit}

    def encoder(p: str, step: float, unit: str = "V") -> dict[str, Any]:
        return {p + "encoder.type": "signedinteger", p + "encoder.scaling.type": "linear",
                p + "encoder.scaling.style": "offsetmultiplier", p + "encoder.scaling.offset": 0.0,
                p + "encoder.scaling.multiplier": step, p + "encoder.scaling.unit.type": "metric-unit",
                p + "encoder.scaling.unit.unit": unit}

    for j, (name, convs, default) in enumerate((("height", "nominal calibrated", "calibrated"),
                                                ("vDeflection", "distance force", "force"),
                                                ("measuredHeight", "nominal", "nominal"))):
        p = f"lcd-info.{j}."
        base, unit = ("absolute", "m") if name == "measuredHeight" else ("volts", "V")
        out.update({p + "type": "integer-data", p + "channel.type": "channel", p + "channel.name": name,
                    p + "unit.type": "metric-unit", p + "unit.unit": unit, p + "conversion-set.conversions.list": convs,
                    p + "conversion-set.conversions.default": default, p + "conversion-set.conversions.base": base,
                    p + f"conversion-set.conversion.{base}.name": base.capitalize(),
                    p + f"conversion-set.conversion.{base}.defined": False})
        if name == "measuredHeight":
            out.update(conversion(p, "nominal", "Nominal height", "absolute", 1.0, "m"))
            out.update(encoder(p, MEASURED_STEP, "m"))
        elif name == "height":
            out.update(conversion(p, "nominal", "Nominal height", "volts", HEIGHT_METRES_PER_VOLT, "m"))
            out.update(conversion(p, "calibrated", "Calibrated height", "nominal", 1.0, "m"))
            out.update(encoder(p, HEIGHT_STEP))
        else:
            out.update(conversion(p, "distance", "distance", "volts", sens, "m"))
            out.update(conversion(p, "force", "force", "distance", k, "N"))
            out.update(encoder(p, DEFLECTION_STEP))
    return out


def write_jpk_qi(curves: Iterable[RawCurve], path: str | os.PathLike, *, shape: tuple[int, int], step: float | tuple[float, float],
                 spring_constant: float | None = None, sensitivity: float | None = None,
                 instrument: str = "afmforce virtual AFM", force: bool = False) -> Path:
    """Write a force map as JPK QI data, one curve at a time, atomically.

    Parameters
    ----------
    curves : iterable of RawCurve
        Each: deflection in volts, one approach (segment 0) then one retract (segment 1), the same
        numbers of points in every curve; grid cell from ``map_x``/``map_y`` (else row after row),
        position from ``position_x``/``position_y`` [m] (else the grid's).
    path : path
        Output file (``.jpk-qi-data``).
    shape : (int, int)
        Grid: rows ``ny``, columns ``nx``.
    step : float or (float, float)
        Pixel size [m] (x, y).
    spring_constant, sensitivity : float, optional
        [N/m], [m/V]; default: the first curve's metadata.
    force : bool
        Overwrite an existing file.
    """
    ny, nx = (int(s) for s in shape)
    if nx < 1 or ny < 1:
        raise ParameterError(f"shape {shape!r}: rows and columns >= 1")
    dx, dy = (float(step), float(step)) if np.isscalar(step) else (float(step[0]), float(step[1]))
    if not (dx > 0 and dy > 0):
        raise ParameterError(f"step {step!r}: pixel size > 0")
    where = str(path)
    seen: set[int] = set()
    with atomic_path(path, force) as tmp, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as arc:
        head = None
        start = _time.time()
        for i, curve in enumerate(curves):
            r = runs(curve, where)
            n = (r.z[0].size, r.z[1].size)
            if head is None:
                k, sens = calibration(curve, {"spring_constant": spring_constant, "sensitivity": sensitivity},
                                      where)
                durations = (duration(r.time[0]), duration(r.time[1]))
                ramp = _ramps(curve, r, durations)
                head = n
                gen = {"jpk-data-file": "spm-quantitative-image-data-file", "file-format-version": "2.0",
                       "type": "quantitative-imaging-map", "quantitative-imaging-map.indexes.type": "range",
                       "quantitative-imaging-map.indexes.min": 0, "quantitative-imaging-map.indexes.max": nx * ny - 1,
                       "quantitative-imaging-map.description.instrument": instrument,
                       "quantitative-imaging-map.description.source-software": "afmforce",
                       **_settings("quantitative-imaging-map.settings.force-settings.", n, durations, ramp),
                       "quantitative-imaging-map.position-pattern.type": "grid-position-pattern",
                       "quantitative-imaging-map.position-pattern.back-and-forth": False,
                       "quantitative-imaging-map.position-pattern.grid.xcenter": (nx - 1) * dx / 2,
                       "quantitative-imaging-map.position-pattern.grid.ycenter": (ny - 1) * dy / 2,
                       "quantitative-imaging-map.position-pattern.grid.ulength": nx * dx,
                       "quantitative-imaging-map.position-pattern.grid.vlength": ny * dy,
                       "quantitative-imaging-map.position-pattern.grid.theta": 0.0,
                       "quantitative-imaging-map.position-pattern.grid.reflect": False,
                       "quantitative-imaging-map.position-pattern.grid.unit.type": "metric-unit",
                       "quantitative-imaging-map.position-pattern.grid.unit.unit": "m",
                       "quantitative-imaging-map.position-pattern.grid.ilength": nx,
                       "quantitative-imaging-map.position-pattern.grid.jlength": ny,
                       "quantitative-imaging-map.feedback-mode.name": "contact"}
                arc.writestr("index/", b"")  # folder entries, as JPK writes them (afmformats looks for them)
                arc.writestr("shared-data/", b"")
                arc.writestr("shared-data/header.properties", _props(_shared(k, sens, n, durations, ramp, _time.strftime(
                    "%Y.%m.%d-%H.%M.%S-00000", _time.gmtime(start)))))
            elif n != head:
                raise ParameterError(f"{where}: curve {i} has {n[0]} + {n[1]} points, the first {head[0]} + {head[1]}"
                                     "; a QI map's curves share their numbers of points")
            x, y = cell(curve, i, nx, ny, where)
            index = y * nx + x
            if index in seen:
                raise ParameterError(f"{where}: grid cell ({x}, {y}) holds two curves")
            seen.add(index)
            md = curve.metadata
            px, py = float(md.get("position_x", x * dx)), float(md.get("position_y", y * dy))
            series = "quantitative-imaging-series."
            for folder in ("", "segments/"):
                arc.writestr(f"index/{index}/{folder}", b"")
            arc.writestr(f"index/{index}/header.properties", _props({
                "type": "quantitative-imaging-series", series + "force-segments.count": 2,
                series + "header.type": "xy-position-force-scan-series-header",
                series + "header.position.x": px, series + "header.position.y": py,
                series + "header.position-index": index,
                **_settings(series + "header.quantitative-imaging-settings.", n, durations, ramp),
                series + "description.instrument": instrument}))
            for j in (0, 1):
                seg = f"index/{index}/segments/{j}/"
                npts = r.z[j].size
                arc.writestr(seg, b"")
                arc.writestr(seg + "channels/", b"")
                arc.writestr(seg + "segment-header.properties", _props({
                    "force-segment-header.force-segment-header-info.*": j,
                    "force-segment-header.type": "spm-force-segment-header",
                    "force-segment-header.num-points": npts, "force-segment-header.duration": duration(r.time[j]),
                    "force-segment-header.time-stamp": _stamp(start + float(r.time[j][0])),
                    "force-segment-header.environment.xy-scanner-position-map.xy-scanner.tip-scanner.position.x": px,
                    "force-segment-header.environment.xy-scanner-position-map.xy-scanner.tip-scanner.position.y": py,
                    "channels.list": "height vDeflection measuredHeight",
                    **{f"channel.{c}.{key}": v for c, lcd in (("height", 0), ("vDeflection", 1), ("measuredHeight", 2))
                       for key, v in (
                        ("lcd-info.*", lcd), ("data.file.name", f"channels/{c}.dat"), ("data.file.format", "raw"),
                        ("data.num-points", npts))}}))
                arc.writestr(seg + "channels/height.dat",
                             _encode(-r.z[j] / HEIGHT_METRES_PER_VOLT, HEIGHT_STEP, where))
                arc.writestr(seg + "channels/vDeflection.dat", _encode(r.volts[j], DEFLECTION_STEP, where))
                arc.writestr(seg + "channels/measuredHeight.dat", _encode(-r.zm[j], MEASURED_STEP, where))
        if head is None:
            raise ParameterError(f"{where}: no curves to write")
        arc.writestr("header.properties", _props(gen))
    return Path(path)
