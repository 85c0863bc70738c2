r"""Reader of the Bruker NanoScope Analysis ASCII export of a force curve.

Layout (NanoScope "Export > ASCII" of a ramp)::

    \*Force file list
    \Version: 0x09300201
    ...
    \Spring Constant: 0.21
    \@Sens. DeflSens: V 45.2 nm/V
    \Scan rate: 0.5
    \*File list end
    Calc_Ramp_Ex_nm<TAB>Calc_Ramp_Rt_nm<TAB>Defl_V_Ex<TAB>Defl_V_Rt<TAB>Defl_nm_Ex<TAB>...
    <numbers, tab separated; empty cells where one run is shorter>

Header lines start with a backslash (``\*`` opens a section); then one row of
column names ``<Name>_<unit>_<Ex|Rt>`` (``Calc_Ramp_Ex_nm`` puts the run before
the unit), then data. Units: ``nm``, ``um``, ``V``, ``pN``, ``nN``, ``s``,
``ms``; ``Lsb`` (raw counts) columns are ignored.

Conventions chosen here (documented because exports differ between versions):

* deflection: ``Defl_V`` (raw volts) if present, else ``Defl_nm`` (m), else
  ``Defl_pN``/``Defl_nN`` (N); positive = repulsive = cantilever up;
* position: ``Height_Sensor``/``PF_Z_Sensor``/``ZSensor`` is the measured
  position, ``Calc_Ramp`` the nominal one; z is oriented to increase on the
  extend (Ex) run;
* time order: from ``Time_s_Ex``/``Time_s_Rt`` when exported; otherwise each
  run is put in time order so that it meets the other run at the turning point
  (the end with the larger deflection); NanoScope usually lists the retract run
  in reverse time order;
* time: from the Time columns, else from ``\Scan rate`` (ramps per second),
  else the sample index (``time_is_sample_index``).
"""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ..errors import FileFormatError
from .curve import RawCurve
from ._afmformats import orient
from ._meta import finalize_curve

__all__ = ["load_bruker_ascii", "detect_bruker_ascii", "parse_column_name"]

_UNITS = {"nm": 1e-9, "um": 1e-6, "µm": 1e-6, "m": 1.0, "V": 1.0, "mV": 1e-3, "pN": 1e-12, "nN": 1e-9,
          "s": 1.0, "ms": 1e-3, "Lsb": None}
_MEASURED = ("Height_Sensor", "PF_Z_Sensor", "ZSensor", "Z_Sensor")
_NOMINAL = ("Calc_Ramp", "Z", "Ramp")
_DEFL = (("Defl", "V", "V"), ("Defl", "nm", "m"), ("Defl", "pN", "N"), ("Defl", "nN", "N"))
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def detect_bruker_ascii(path: Path) -> bool:
    r"""True if the file starts with a NanoScope ``\*`` header line."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(64)
    except OSError:
        return False
    return head.lstrip(b"\xef\xbb\xbf").lstrip().lstrip(b'"').startswith(b"\\*")


_RUNS = {"ex": "Ex", "extend": "Ex", "approach": "Ex", "trace": "Ex", "rt": "Rt", "retract": "Rt",
         "retrace": "Rt", "withdraw": "Rt"}
#: Column base names seen in NanoScope versions -> the name this reader uses.
_BASES = {"defl": "Defl", "deflection": "Defl", "deflectionerror": "Defl", "verticaldeflection": "Defl",
          "calcramp": "Calc_Ramp", "ramp": "Calc_Ramp", "z": "Calc_Ramp", "zramp": "Calc_Ramp",
          "heightsensor": "Height_Sensor", "pfzsensor": "PF_Z_Sensor", "zsensor": "ZSensor", "time": "Time"}


def parse_column_name(name: str) -> tuple[str, str, str] | None:
    """``'Defl_nm_Ex'`` -> ``('Defl', 'nm', 'Ex')``; None if not a run column.

    Also ``Defl_V Ex``, ``Deflection (nm) Retract``, ``Calc_Ramp_Ex_nm``: parts
    separated by ``_`` or spaces, the unit maybe in parentheses, the run spelt out.
    """
    text = name.strip().strip('"').strip()
    paren = re.search(r"\(([^)]*)\)", text)
    parts = [p for p in re.split(r"[_\s]+", re.sub(r"\([^)]*\)", " ", text)) if p]
    run = next((_RUNS[p.lower()] for p in parts if p.lower() in _RUNS), None)
    unit = paren.group(1).strip() if paren and paren.group(1).strip() in _UNITS else None
    if unit is None:
        unit = next((p for p in reversed(parts) if p in _UNITS), None)
    if run is None or unit is None:
        return None
    base = "_".join(p for p in parts if p.lower() not in _RUNS and p != unit)
    return base, unit, run


def canonical_base(base: str) -> str:
    """The reader's name for a column base (``'Deflection Error'`` -> ``'Defl'``)."""
    return _BASES.get(re.sub(r"[_\s]+", "", base).lower(), base)


def _blocks(text: str) -> list[str]:
    r"""Force-curve blocks: each starts at a ``\*Force file list`` line (several may follow each other)."""
    lines = text.split("\n")
    starts = [i for i, ln in enumerate(lines) if ln.startswith("\\*Force file list")]
    if len(starts) <= 1:
        return [text]
    starts[0] = 0
    return ["\n".join(lines[a:b]) for a, b in zip(starts, starts[1:] + [len(lines)])]


def _normalise(text: str) -> str:
    r"""Line ends ``\r\r\n``, ``\r\n``, ``\r`` -> ``\n``; double quotes around whole lines removed."""
    text = text.replace("\r\r\n", "\n").replace("\r\n", "\n").replace("\r", "\n")
    out = []
    for line in text.split("\n"):
        t = line.strip()
        if len(t) >= 3 and t.startswith('"\\') and t.endswith('"'):
            line = t[1:-1]
        out.append(line)
    return "\n".join(out)


def _header_value(header: dict[str, str], key: str) -> float | None:
    text = header.get(key)
    if text is None:
        return None
    nums = _NUMBER.findall(text)
    return float(nums[-1]) if nums else None


def _parse(text: str, where: str):
    lines = text.splitlines()
    header: dict[str, str] = {}
    i = 0
    while i < len(lines) and (lines[i].startswith("\\") or not lines[i].strip()):
        line = lines[i][1:]
        if not line.startswith("*") and ":" in line:
            key, value = line.split(":", 1)
            header[key.strip().lstrip("@").strip()] = value.strip()
        i += 1
    while i < len(lines) and not lines[i].strip():
        i += 1
    if i >= len(lines):
        raise FileFormatError(f"{where}: header without column names or data")
    sep = "\t" if "\t" in lines[i] else ("," if "," in lines[i] else None)
    names = [n.strip().strip('"') for n in lines[i].rstrip("\r\n").split(sep)]
    rows = []
    for j, line in enumerate(lines[i + 1:], start=i + 2):
        if not line.strip():
            continue
        cells = line.rstrip("\r\n").split(sep)
        if len(cells) > len(names):
            raise FileFormatError(f"{where}: line {j} has {len(cells)} cells for {len(names)} columns")
        try:
            rows.append([float(c) if c.strip() else np.nan for c in cells]
                        + [np.nan] * (len(names) - len(cells)))
        except ValueError:
            raise FileFormatError(f"{where}: line {j} is not numeric: {line[:60]!r}") from None
    if len(rows) < 2:
        raise FileFormatError(f"{where}: fewer than two data rows")
    return header, names, np.array(rows, dtype=float)


def _column(table: dict, bases: tuple[str, ...], run: str, units: tuple[str, ...] | None = None):
    for base in bases:
        for (b, unit, r), col in table.items():
            if b == base and r == run and (units is None or unit in units) and _UNITS[unit] is not None:
                return col * _UNITS[unit], unit
    return None, None


def _trim(col: np.ndarray, where: str, name: str) -> np.ndarray:
    """Drop trailing empty cells (a shorter run); a hole inside is an error."""
    finite = np.isfinite(col)
    if not finite.any():
        raise FileFormatError(f"{where}: column {name} is empty")
    last = int(np.flatnonzero(finite)[-1]) + 1
    col = col[:last]
    if not np.isfinite(col).all():
        raise FileFormatError(f"{where}: column {name} has empty or NaN cells inside the data")
    return col


def load_bruker_ascii(path: Path, *, meta_override: Mapping[str, Any] | None = None,
                      callback: Callable | None = None) -> list[RawCurve]:
    """Read a NanoScope ASCII force-curve export (see module docstring)."""
    path = Path(path)
    where = str(path)
    try:
        raw = path.read_bytes()
        try:
            text = raw.decode("utf-8-sig", errors="strict")
        except UnicodeDecodeError:  # older exports: Windows-1252 (a µ in a unit)
            text = raw.decode("cp1252", errors="strict")
    except UnicodeDecodeError:
        raise FileFormatError(f"{where}: not a text file (NanoScope ASCII export expected)") from None
    except OSError as exc:
        raise FileFormatError(f"{where}: cannot read ({exc})") from None
    if "\0" in text:
        raise FileFormatError(f"{where}: binary content; a NanoScope binary file needs the ending .spm, .pfc or .000")
    blocks = _blocks(_normalise(text))
    out = []
    for b, block in enumerate(blocks):
        label = where if len(blocks) == 1 else f"{where} (block {b + 1})"
        curve = _curve(block, label, where, meta_override)
        if len(blocks) > 1:
            curve = replace(curve, metadata={**curve.metadata, "curve_index": b})
        out.append(curve)
        if callback is not None:
            callback((b + 1) / len(blocks))
    return out


def _curve(text: str, where: str, source: str, meta_override) -> RawCurve:
    """One force-curve block."""
    header, names, data = _parse(text, where)
    table = {}
    for k, name in enumerate(names):
        parsed = parse_column_name(name)
        if parsed is not None:
            base, unit, run = parsed
            table.setdefault((canonical_base(base), unit, run), data[:, k])
    runs = {}
    unit_out = None
    for run in ("Ex", "Rt"):
        defl = None
        for base, unit, out in _DEFL:
            col = table.get((base, unit, run))
            if col is not None:
                defl, unit_out = col * _UNITS[unit], out
                break
        if defl is None:
            raise FileFormatError(f"{where}: no deflection column for run {run} (Defl_V/_nm/_pN_{run})")
        zm, _ = _column(table, _MEASURED, run)
        zn, _ = _column(table, _NOMINAL, run)
        if zn is None and zm is None:
            raise FileFormatError(f"{where}: no position column for run {run} (Calc_Ramp or Height_Sensor)")
        t, _ = _column(table, ("Time",), run, ("s", "ms"))
        cols = {"defl": defl, "zn": zn if zn is not None else zm, "zm": zm if zn is not None else None, "t": t}
        cols = {k: (None if v is None else _trim(v, where, f"{k}_{run}")) for k, v in cols.items()}
        n = len(cols["defl"])
        if any(v is not None and len(v) != n for v in cols.values()):
            raise FileFormatError(f"{where}: columns of run {run} have different lengths")
        runs[run] = cols
    for run, cols in runs.items():
        t = cols["t"]
        if t is not None:
            rev = t[-1] < t[0]
        else:  # the turning point (largest deflection) ends the Ex run and starts the Rt run
            d = cols["defl"]
            m = max(1, min(5, len(d) // 4))
            first, last = d[:m].mean(), d[-m:].mean()
            rev = first > last if run == "Ex" else last > first
        if rev:
            runs[run] = {k: (None if v is None else v[::-1].copy()) for k, v in cols.items()}
    ex, rt = runs["Ex"], runs["Rt"]
    seg = np.concatenate([np.zeros(len(ex["defl"]), np.int8), np.ones(len(rt["defl"]), np.int8)])
    meta: dict[str, Any] = {}
    k = _header_value(header, "Spring Constant")
    if k and k > 0:
        meta["spring_constant"] = k
    sens = _header_value(header, "Sens. DeflSens")
    if sens and sens > 0:
        meta["sensitivity"] = sens * 1e-9  # nm/V
    n = len(seg)
    if ex["t"] is not None and rt["t"] is not None:
        time = np.concatenate([ex["t"], rt["t"]])
        if not np.all(np.diff(time) >= 0):  # retract times restart from zero in some exports
            time = np.concatenate([ex["t"], ex["t"][-1] + (rt["t"] - rt["t"][0])
                                   + np.median(np.diff(ex["t"]))])
    else:
        rate = _header_value(header, "Scan rate")
        if rate and rate > 0:
            dt = 1.0 / (rate * n)
            time = dt * np.arange(n)
            meta["sample_rate"] = 1.0 / dt
        else:
            time = np.arange(n, dtype=float)
            meta["time_is_sample_index"] = True
    zm = None if ex["zm"] is None or rt["zm"] is None else np.concatenate([ex["zm"], rt["zm"]])
    zn, zm, sign = orient(np.concatenate([ex["zn"], rt["zn"]]), zm, seg)
    meta.update(dict(meta_override or {}))
    meta.update(source_file=source, reader="bruker-ascii", format="Bruker NanoScope ASCII export",
                position_sign=sign)
    if "Note" in header:
        meta["note"] = header["Note"]
    curve = RawCurve(time=time, piezo_nominal=zn, piezo_measured=zm,
                     deflection_signal=np.concatenate([ex["defl"], rt["defl"]]), segment=seg,
                     metadata=meta, deflection_unit=unit_out)
    return finalize_curve(curve, where)
