"""Optics11 indenter text exports, Chiaro and Piuma (read here: header lines, then tab-separated columns).

afmformats' reader of these files (0.18) needs header keys that only newer exports write
(``Max load (µN)``, ``Piezo speed (µm/s)``: a V3.4 "Displacement" export has neither and fails
there with a KeyError), reads the file as ISO-8859-1 only, and ends the approach at the maximum
load, which puts a hold at the deepest point into the retract. This reader takes the columns
with numpy and the few header values it needs from the text:

* force [N]: the ``Load (uN)`` column (the Chiaro's k times its ``Cantilever`` column); a
  user's spring constant recomputes it from the ``Cantilever (nm)`` column;
* z: the ``Piezo (nm)`` column, oriented to increase into the sample (the ``Indentation``
  column is not a position);
* segments: a displacement profile (``D[Zi] (nm)``/``t[i] (s)`` lines) with a hold at its
  deepest step gives approach, dwell and retract from the piezo column (the dwell: the samples
  around the deepest point within 0.5 % of the travel of it); otherwise the approach ends at
  the maximum load (the "Peak Load Poking" mode turns there);
* ``deflection_interferometric``: the Cantilever column is measured by the fibre interferometer (no
  InvOLS to be off): the kind step then calls a straight contact line hard only where the deflection
  follows at least 0.9 of the piezo (a 20 kPa gel under an 8 um sphere on a 0.032 N/m lever follows 0.78);
* k, the tip radius and the piezo speed from the header. The header's one piezo speed is kept
  for a run only if the piezo column agrees within 10 %; else the run's measured speed
  replaces it (``velocity_note``/``retract_velocity_note`` say so).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ..errors import FileFormatError
from .curve import RawCurve
from ._meta import finalize_curve, missing_metadata, orient

__all__ = ["detect_chiaro", "load_chiaro"]

_DWELL_TOL = 0.005  #: a dwell sample lies within this fraction of the travel of the deepest z
_TABLE = b"Time (s)\tLoad (uN)\tIndentation (nm)\tCantilever (nm)\tPiezo (nm)"  #: Optics11's table header


def detect_chiaro(path: Path) -> bool:
    """Optics11 indenter text export (Chiaro, Piuma): the ``Time (s)<TAB>Load (uN)<TAB>Indentation (nm)``
    table header and a ``k (N/m)`` header line.

    Older exports (2020) and the Piuma's write no ``Device:<TAB>Chiaro`` line (a Piuma's says
    ``Device:<TAB>Piuma``); the table of columns is the same in all of them.
    """
    try:
        with open(path, "rb") as fh:
            head = fh.read(65536)
    except OSError:
        return False
    return _TABLE in head and b"k (N/m)" in head


def _text(raw: bytes) -> str:
    """The file as text: UTF-8 where it decodes (µ as two bytes), else ISO-8859-1 (as exported)."""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    return text.replace("\u03bc", "\u00b5")


def _header(lines: list[str]) -> dict[str, str]:
    """``key<TAB>value`` pairs (several on a line), ``key: value`` and ``key (unit) value`` lines."""
    out: dict[str, str] = {}
    for line in lines:
        parts = [p.strip() for p in line.rstrip("\r\n").split("\t")]
        parts = [p for p in parts if p != ""] if len(parts) > 1 else parts
        if len(parts) >= 2:
            for key, value in zip(parts[::2], parts[1::2]):
                out[key.rstrip(":").strip()] = value
        elif parts and parts[0]:
            m = re.match(r"^(.*?)\s*:\s*(.*)$", parts[0]) or re.match(r"^(.*\))\s+(\S+)$", parts[0])
            if m:
                out[m.group(1).strip()] = m.group(2).strip()
    return out


def _number(head: Mapping[str, str], *keys: str) -> float | None:
    for key in keys:
        try:
            value = float(head[key])
        except (KeyError, ValueError):
            continue
        if np.isfinite(value):
            return value
    return None


def _column(names: list[str], prefix: str, path: Path) -> int:
    for i, name in enumerate(names):
        if name.startswith(prefix):
            return i
    raise FileFormatError(f"{path}: no {prefix!r} column in the Chiaro table (columns: {', '.join(names)})")


def _profile(head: Mapping[str, str]) -> list[tuple[float, float]]:
    """The displacement profile's steps: (target D [m], duration t [s]) from ``D[Zi] (nm)``/``t[i] (s)``."""
    steps = []
    for i in range(1, 100):
        d, t = _number(head, f"D[Z{i}] (nm)"), _number(head, f"t[{i}] (s)")
        if d is None or t is None:
            break
        steps.append((d * 1e-9, t))
    return steps


def _hold_speeds(steps: list[tuple[float, float]]) -> tuple[float, float] | None:
    """(approach, retract) speeds [m/s] of a profile whose deepest step is held, else None.

    Step ``j`` holds when it stays at the deepest target of step ``j - 1`` for ``t[j] > 0``; the
    approach speed is the travel of step ``j - 1`` over its time, the retract speed that of step ``j + 1``.
    """
    if not steps:
        return None
    deepest = max(d for d, _ in steps)
    for j in range(1, len(steps) - 1):
        if steps[j - 1][0] == steps[j][0] == deepest and steps[j][1] > 0:
            start = steps[j - 2][0] if j >= 2 else 0.0
            (_, t_in), (end, t_out) = steps[j - 1], steps[j + 1]
            if t_in > 0 and t_out > 0 and start < deepest and end < deepest:
                return (deepest - start) / t_in, (deepest - end) / t_out
    return None


def _segments(z: np.ndarray, load: np.ndarray, hold: bool) -> np.ndarray:
    n = z.size
    seg = np.ones(n, dtype=np.int8)
    if not hold:
        seg[: int(np.argmax(load)) + 1] = 0
        return seg
    deep = int(np.argmax(z))
    travel = float(z[deep] - min(z[0], z[-1]))
    near = z >= z[deep] - _DWELL_TOL * travel
    lo = deep
    while lo > 0 and near[lo - 1]:
        lo -= 1
    hi = deep
    while hi < n - 1 and near[hi + 1]:
        hi += 1
    seg[:lo] = 0
    seg[lo:hi + 1] = 2
    return seg


def load_chiaro(path: Path, *, meta_override: Mapping[str, Any], callback: Callable | None = None) -> list[RawCurve]:
    """Optics11 Chiaro indenter export: load [N] vs piezo position (see the module docstring)."""
    path = Path(path)
    lines = _text(path.read_bytes()).splitlines()
    try:
        top = next(i for i, ln in enumerate(lines) if ln.startswith("Time (s)\tLoad"))
    except StopIteration:
        raise FileFormatError(f"{path}: no 'Time (s)<TAB>Load' table header: not a Chiaro export") from None
    head = _header(lines[:top])
    names = [s.strip() for s in lines[top].split("\t")]
    rows = [ln for ln in lines[top + 1:] if ln.strip()]
    short = next((i for i, ln in enumerate(rows) if len(ln.split("\t")) < len(names)), None)
    if short is not None:
        raise FileFormatError(f"{path}: row {short + 1} of the Chiaro table has fewer than its {len(names)} "
                              "columns: the file is truncated or damaged")
    try:
        table = np.array([[float(v) for v in ln.split("\t")[: len(names)]] for ln in rows], dtype=float)
    except ValueError as exc:
        raise FileFormatError(f"{path}: a row of the Chiaro table is not numeric ({exc})") from None
    if table.ndim != 2 or table.shape[0] < 2 or table.shape[1] != len(names):
        raise FileFormatError(f"{path}: the Chiaro table has {table.shape[0] if table.ndim == 2 else 0} complete "
                              f"rows of {len(names)} columns: truncated or damaged")
    time = table[:, _column(names, "Time (s)", path)]
    load_n = table[:, _column(names, "Load (uN)", path)] * 1e-6
    piezo = table[:, _column(names, "Piezo (nm)", path)] * 1e-9
    cantilever = table[:, _column(names, "Cantilever (nm)", path)] * 1e-9
    k_file = _number(head, "k (N/m)")
    meta: dict[str, Any] = {"instrument": head.get("Device", "Optics11 indenter"),
                            "format": "Optics11 Chiaro text export"}
    if k_file is not None and k_file > 0:
        meta["spring_constant"] = k_file
    radius = _number(head, "Tip radius (um)", "Tip radius (\u00b5m)")
    if radius is not None and radius > 0:
        meta["radius"] = radius * 1e-6
    speed = _number(head, "Piezo speed  (\u00b5m/s)", "Piezo speed (\u00b5m/s)")
    if speed is not None and speed > 0:
        meta["velocity"] = meta["retract_velocity"] = speed * 1e-6
    for key, theirs in (("date", "Date"), ("chiaro:software_version", "Software version"),
                        ("chiaro:control_mode", "Control mode")):
        if head.get(theirs):
            meta[key] = head[theirs]
    force = load_n
    if "spring_constant" in meta_override:
        force = float(meta_override["spring_constant"]) * cantilever  # the file's Load is k_file x Cantilever
    elif k_file is None:
        raise missing_metadata(str(path), ["spring_constant"], what="the header ('k (N/m)') has")
    speeds = _hold_speeds(_profile(head))
    seg = _segments(piezo, load_n, speeds is not None)
    z, _, sign = orient(piezo, None, seg)
    meta.update(meta_override)
    # the Cantilever column is the fibre interferometer's bending [nm], no InvOLS: a hard contact follows the piezo
    # to within a few per cent, so the kind step holds a straight line at 0.78 of it to be an indentation
    meta.update(source_file=str(path), reader="chiaro-txt", position_sign=sign, deflection_interferometric=True)
    curve = RawCurve(time=time, piezo_nominal=z, deflection_signal=force, segment=seg,
                     metadata=meta, deflection_unit="N")
    for key, run in (("velocity", 0), ("retract_velocity", 1)):
        if key in meta and key not in meta_override:
            measured = _run_speed(curve, run)
            if measured is not None and abs(measured - meta[key]) > 0.1 * meta[key]:
                meta[f"{key}_note"] = (f"header 'Piezo speed' {meta[key]:.3g} m/s; the piezo column moves at "
                                       f"{measured:.3g} m/s on this run: taken from the data")
                meta[key] = measured
    if speeds is not None:  # a displacement profile: its ramps' speeds (no 'Piezo speed' line)
        for key, value in zip(("velocity", "retract_velocity"), speeds):
            if key not in meta_override and value > 0:
                meta[key] = value
    if callback is not None:
        callback(1.0)
    return [finalize_curve(curve, str(path))]


def _run_speed(curve: RawCurve, run: int) -> float | None:
    """Mean piezo speed [m/s] of a run: its travel over its duration (None if it has < 2 samples).

    The header's single ``Piezo speed`` is the approach speed; a "Peak Load Poking"
    export retracts about ten times faster.
    """
    idx = np.flatnonzero(curve.segment == run)
    if idx.size < 2 or not curve.time[idx[-1]] > curve.time[idx[0]]:
        return None
    z = curve.piezo_nominal
    return float(abs(z[idx[-1]] - z[idx[0]]) / (curve.time[idx[-1]] - curve.time[idx[0]]))
