"""What both map writers need of a curve: its two runs, its grid cell, the map's calibration."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from ...errors import ParameterError
from ..curve import RawCurve


@dataclass(frozen=True)
class Runs:
    """One curve's approach and retract, in time order (SI; signal in V)."""

    time: tuple[np.ndarray, np.ndarray]
    z: tuple[np.ndarray, np.ndarray]          # nominal piezo position [m], increasing towards the probe
    zm: tuple[np.ndarray, np.ndarray]         # measured piezo position [m] (a sensor's; else the nominal)
    volts: tuple[np.ndarray, np.ndarray]      # deflection signal [V]


def runs(curve: RawCurve, where: str) -> Runs:
    """The approach (segment 0) then the retract (segment 1) of ``curve``, each one contiguous block."""
    if curve.deflection_unit != "V":
        raise ParameterError(f"{where}: the vendor formats store the photodiode signal in volts; this curve's "
                             f"deflection is in {curve.deflection_unit}")
    seg = np.asarray(curve.segment)
    app, ret = np.flatnonzero(seg == 0), np.flatnonzero(seg == 1)
    if app.size < 2 or ret.size < 2 or np.any(np.diff(app) != 1) or np.any(np.diff(ret) != 1) or app[-1] > ret[0]:
        raise ParameterError(f"{where}: a map curve needs one approach (segment 0) then one retract (segment 1)")
    zm = curve.position()
    z, zm, t, v = (np.asarray(a, dtype=float) for a in (curve.piezo_nominal, zm, curve.time, curve.deflection_signal))
    return Runs((t[app], t[ret]), (z[app], z[ret]), (zm[app], zm[ret]), (v[app], v[ret]))


def cell(curve: RawCurve, i: int, nx: int, ny: int, where: str) -> tuple[int, int]:
    """The curve's grid cell ``(x, y)``: its ``map_x``/``map_y``, else row after row."""
    md = curve.metadata
    x, y = (int(md["map_x"]), int(md["map_y"])) if "map_x" in md and "map_y" in md else (i % nx, i // nx)
    if not (0 <= x < nx and 0 <= y < ny):
        raise ParameterError(f"{where}: curve {i} at grid cell ({x}, {y}) lies outside the {nx} x {ny} grid")
    return x, y


def calibration(curve: RawCurve, given: Mapping[str, Any], where: str) -> tuple[float, float]:
    """``(spring_constant [N/m], sensitivity [m/V])`` of the map: given, else the first curve's."""
    out = []
    for key in ("spring_constant", "sensitivity"):
        value = given.get(key)
        value = curve.metadata.get(key) if value is None else value
        try:
            value = float(value)
        except (TypeError, ValueError):
            value = math.nan
        if not (math.isfinite(value) and value > 0):
            raise ParameterError(f"{where}: `{key}` unknown: the vendor file records it; give it or put it in "
                                 "the curves' metadata")
        out.append(value)
    return out[0], out[1]


def duration(t: np.ndarray) -> float:
    """A run's duration as the vendors count it: its points times the sample interval [s]."""
    return float((t[-1] - t[0]) * t.size / (t.size - 1))
