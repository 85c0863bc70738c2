r"""A force map written as a Bruker NanoScope v9 force volume (``.spm``), laid out as the corpus's.

The layout of tests/data/corpus/bruker-nanoscope_force-volume_v9.2_Egel2_00023.spm: a text header
(``\r\n`` lines, ``\*Force file list`` ... ``\*File list end``, padded with NULs to its
``\Data length``) with ``\Start context: FVOL`` and the grid (``\Samps/line`` x ``\Lines`` of the
``\*Ciao scan list``, ``\Scan Size`` [nm]), then one ``\*Ciao force image list`` per channel:

* ``DeflectionError``: per curve the approach, indexed from the turning point (reversed time), then
  the retract, little-endian int32 holding the 16-bit ADC counts shifted by 8 bits (what v9 writes),
  ``V/LSB`` the ADC's step; ``\@Sens. DeflSens`` the sensitivity [nm/V], ``\Spring Constant`` [N/m];
* ``ZSensor`` (``Height Sensor``): the piezo position [m] the same way, through ``\@Sens. ZsensSens``
  [nm/V]: the curves' absolute Z, so the topography is in the file.

``\@4:Ramp Size`` x ``\@Sens. Zsens`` is the ramp [m], ``\Forward vel.``/``\Reverse vel.`` [V/s] x Zsens
the piezo speeds. Curve ``i`` is grid point ``(i % nx, i // nx)``.
"""

from __future__ import annotations

import math
import os
import time as _time
from pathlib import Path
from typing import Iterable

import numpy as np

from ..._files import atomic_path
from ...errors import ParameterError
from ..curve import RawCurve
from ._common import calibration, cell, runs

__all__ = ["write_nanoscope_fv", "ZSENS", "ZSENSOR_SENS"]

#: The Z piezo's sensitivity [nm/V] and the Z sensor's [nm/V] written in the header (the corpus file's).
ZSENS = 13.203
ZSENSOR_SENS = 906.473
#: Counts of the 16-bit ADC (signed) and the v9 shift of 4-byte samples.
_HALF = 2**15
_SHIFT = 256


def _counts(values: np.ndarray, lsb: float, what: str, where: str) -> np.ndarray:
    c = np.rint(values / lsb)
    if np.any(np.abs(c) > _HALF - 1):
        raise ParameterError(f"{where}: {what} {float(np.max(np.abs(values))):.4g} beyond the 16-bit ADC's range "
                             f"(+-{_HALF * lsb:.4g}); give a larger step")
    return (c.astype("<i4") * _SHIFT).astype("<i4")


def _header(entries: list[str], length: int) -> bytes:
    text = "\r\n".join(entries).replace("@LENGTH@", str(length)) + "\r\n\\*File list end\r\n\x1a"
    return text.encode("latin-1")


def write_nanoscope_fv(curves: Iterable[RawCurve], path: str | os.PathLike, *, shape: tuple[int, int], step: float,
                       spring_constant: float | None = None, sensitivity: float | None = None,
                       deflection_lsb: float = 0.000375, z_range: float | None = None, radius: float | None = None,
                       instrument: str = "afmforce virtual AFM", force: bool = False) -> Path:
    """Write a force map as a NanoScope v9 force volume, one curve at a time, atomically.

    Parameters
    ----------
    curves : iterable of RawCurve
        As :func:`~afmforce.io.writers.write_jpk_qi` takes them; ``piezo_measured`` (else the
        nominal position) goes to the Z-sensor channel.
    path : path
        Output file (``.spm``).
    shape : (int, int)
        Grid: rows ``ny``, columns ``nx``.
    step : float
        Pixel size [m] (NanoScope's scan is square: ``Scan Size`` = nx x step).
    spring_constant, sensitivity : float, optional
        [N/m], [m/V]; default: the first curve's metadata.
    deflection_lsb : float
        The deflection ADC's step [V] (16 bits): the signal is stored in its counts.
    z_range : float, optional
        The largest |z| the Z sensor's 16-bit channel must hold [m] (its step: z_range / 2^15);
        default: twice the first curve's.
    radius : float, optional
        Tip radius [m] (``\\Tip Radius``); default: the first curve's ``radius``.
    force : bool
        Overwrite an existing file.
    """
    ny, nx = (int(s) for s in shape)
    if nx < 1 or ny < 1 or not (float(step) > 0) or not (deflection_lsb > 0):
        raise ParameterError(f"shape {shape!r}, step {step!r}, deflection_lsb {deflection_lsb!r}: all > 0")
    where = str(path)
    n_curves = nx * ny
    seen: set[int] = set()
    with atomic_path(path, force) as tmp, open(tmp, "wb") as fh:
        layout = None
        for i, curve in enumerate(curves):
            r = runs(curve, where)
            n = (r.z[0].size, r.z[1].size)
            if layout is None:
                k, sens = calibration(curve, {"spring_constant": spring_constant, "sensitivity": sensitivity}, where)
                tip = radius if radius is not None else curve.metadata.get("radius")
                z_all = np.concatenate(r.zm)
                ramp = float(np.ptp(r.z[0]))
                v_app = ramp / (r.time[0][-1] - r.time[0][0]) * (n[0] - 1) / n[0]
                v_ret = float(np.ptp(r.z[1])) / (r.time[1][-1] - r.time[1][0]) * (n[1] - 1) / n[1]
                # the Z sensor's step: its 16-bit range holds z_range (default twice the first curve's |z|)
                reach = float(z_range) if z_range is not None else 2 * float(np.max(np.abs(z_all)))
                z_lsb = float(f"{1.001 * reach / (ZSENSOR_SENS * 1e-9) / (_HALF - 1):.4g}")
                per = (n[0] + n[1]) * 4 * n_curves
                layout = (n, per, z_lsb)
                entries = _entries(nx, ny, step, n, k, sens, tip, ramp, v_app, v_ret, deflection_lsb, z_lsb,
                                   per, instrument)
                size = len(_header(entries, 0)) + 16
                size = int(math.ceil(size / 4096) * 4096)
                head = _header(entries, size)
                head = _header([e.replace("@OFFSET0@", str(size)).replace("@OFFSET1@", str(size + per))
                                for e in entries], size)
                fh.write(head + b"\0" * (size - len(head)))
                fh.truncate(size + 2 * per)
                base = size
            elif n != layout[0]:
                raise ParameterError(f"{where}: curve {i} has {n[0]} + {n[1]} points, the first "
                                     f"{layout[0][0]} + {layout[0][1]}; a force volume's curves share them")
            x, y = cell(curve, i, nx, ny, where)
            index = y * nx + x
            if index in seen:
                raise ParameterError(f"{where}: grid point ({x}, {y}) holds two curves")
            seen.add(index)
            n, per, z_lsb = layout
            width = (n[0] + n[1]) * 4
            defl = np.concatenate([_counts(r.volts[0][::-1], deflection_lsb, "deflection [V]", where),
                                   _counts(r.volts[1], deflection_lsb, "deflection [V]", where)])
            zvolts = [z / (ZSENSOR_SENS * 1e-9) for z in r.zm]
            zs = np.concatenate([_counts(zvolts[0][::-1], z_lsb, "Z sensor [V]", where),
                                 _counts(zvolts[1], z_lsb, "Z sensor [V]", where)])
            fh.seek(base + index * width)
            fh.write(defl.tobytes())
            fh.seek(base + per + index * width)
            fh.write(zs.tobytes())
        if layout is None:
            raise ParameterError(f"{where}: no curves to write")
    return Path(path)


def _entries(nx, ny, step, n, k, sens, tip, ramp, v_app, v_ret, lsb, z_lsb, per, instrument) -> list[str]:
    zs = ZSENS
    ramp_v = ramp / (zs * 1e-9)
    date = _time.strftime("%I:%M:%S %p %a %b %d %Y", _time.gmtime())
    out = ["\\*Force file list", "\\Version: 0x0920B046", f"\\Date: {date}", "\\Start context: FVOL",
           "\\Data length: @LENGTH@", "\\*Equipment list", f"\\Description: {instrument}",
           f"\\Microscope: {instrument}", "\\*Scanner list", f"\\@Sens. Zsens: V {zs:.5f} nm/V",
           "\\*Ciao scan list", f"\\Scan Size: {nx * step * 1e9:.10g} nm", "\\X Offset: 0 nm", "\\Y Offset: 0 nm",
           f"\\Samps/line: {nx}", f"\\Lines: {ny}", f"\\Force Data Points: {n[0]}"]
    if tip is not None and float(tip) > 0:
        out.append(f"\\Tip Radius: {float(tip) * 1e9:.10g}")
    out += [f"\\@Sens. DeflSens: V {sens * 1e9:.10g} ", f"\\@Sens. ZsensSens: V {ZSENSOR_SENS:.4f} nm/V",
            "\\*Ciao force list", f"\\Scan rate: {v_app / (2 * ramp):.6g}",
            f"\\Forward vel.: {v_app / (zs * 1e-9):.10g}", f"\\Reverse vel.: {v_ret / (zs * 1e-9):.10g}",
            f"\\Samps/line: {n[0]} {n[1]}", f"\\Samps/line, retrace: {n[1]}",
            "\\@4:Image Data: S [DeflectionError] \"Deflection Error\"",
            f"\\@4:Ramp Size Zsweep: V [Sens. Zsens] (0.006713765 V/LSB) {ramp_v:.10g} V"]
    for j, (name, label, sname, step_v) in enumerate((("DeflectionError", "Deflection Error", "DeflSens", lsb),
                                                      ("ZSensor", "Height Sensor", "ZsensSens", z_lsb))):
        out += ["\\*Ciao force image list", f"\\Data offset: @OFFSET{j}@", f"\\Data length: {per}",
                "\\Bytes/pixel: 4", "\\Start context: FOL", "\\Data type: AFM", f"\\Samps/line: {n[0]} {n[1]}",
                "\\Scan Line: Main", f"\\Spring Constant: {k:.10g}", f"\\@4:Image Data: S [{name}] \"{label}\"",
                f"\\@4:Z scale: V [Sens. {sname}] ({step_v!r} V/LSB) {step_v * 2**16:.10g} V",
                f"\\@4:Ramp Size: V [Sens. Zsens] (0.006713765 V/LSB) {ramp_v:.10g} V"]
    return out
