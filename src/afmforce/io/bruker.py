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

Header lines start with a backslash (``\*`` opens a section), or are wrapped whole
in double quotes (``"\Spring Constant: 0.34"``, NanoScope Analysis); then one row
of column names ``<Name>_<unit>_<Ex|Rt>`` or ``<Name>_<Ex|Rt>_<unit>``
(``Calc_Ramp_Ex_nm``), in any order and subset, then data; extend and retract
share rows. Units: ``nm``, ``um``, ``V``, ``pN``, ``nN``, ``s``, ``ms``; ``Lsb``
(raw counts) columns are ignored. A column named twice: the first is read.
Trailing tabs, CRLF line ends, UTF-8, UTF-16 and Windows-1252 text are read.

Conventions chosen here (documented because exports differ between versions):

* deflection: ``Defl_V`` (raw volts) if every run has it, else ``Defl_nm`` (m),
  else ``Defl_pN``/``Defl_nN`` (N); positive = repulsive = cantilever up;
* position: ``Height_Sensor``/``PF_Z_Sensor``/``ZSensor`` is the measured
  position, ``Calc_Ramp`` the nominal one; z is oriented to increase on the
  extend (Ex) run;
* time order: from ``Time_s_Ex``/``Time_s_Rt`` when exported; otherwise the
  retract is reversed when its position column runs the same way as the
  extend's (in time order they run opposite ways), and a run without a usable
  position is put in time order so that it meets the other at the turning
  point (the end with the larger deflection); NanoScope often lists the retract
  rows in reverse;
* time: from the Time columns (``sample_rate`` from their step), else from
  ``\Scan rate`` (ramps per second), else the sample index
  (``time_is_sample_index``); ``velocity`` from the slope of the first run's
  position against time;
* an export of the extend run only gives a curve without a retract;
* comma-separated tables may quote their cells; a blank line after every line (CR CR LF read as
  text) is read; of several ``\Spring Constant`` lines (a whole NanoScope header) the one of the
  list whose ``Image Data`` is the deflection counts (others may be stale);
* a processed export with only ``Force`` and ``Separation`` columns (NanoScope Analysis' "force vs
  separation") is read as such: the force in N (no spring constant or sensitivity needed), the
  position ``-separation``, ``metadata["processed"]`` saying so.
"""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from .._fields import QUANTITIES
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
    if head[:2] in (b"\xff\xfe", b"\xfe\xff"):  # UTF-16 (Windows "Unicode" text)
        head = head.decode("utf-16", errors="ignore").encode("utf-8", errors="ignore")
    head = head.lstrip(b"\xef\xbb\xbf").lstrip().lstrip(b'"')
    if head.startswith((b"\\*", b"\\?")):  # "\?Force file list": NanoScope Analysis 1.x-2.x exports
        return True
    return _unit_row(head.decode("latin-1").split("\n")[0]) is not None


#: the units a headerless export's first row may name: length of the position, then force
_LENGTH = {"nm": 1e-9, "um": 1e-6, "µm": 1e-6, "m": 1.0}
_FORCE = {"pN": 1e-12, "nN": 1e-9, "uN": 1e-6, "µN": 1e-6, "N": 1.0}


def _unit_row(line: str) -> tuple[str, str] | None:
    """``'    nm   <TAB>nN'`` (a NanoScope Analysis export of one plotted run: a unit row, no header)
    -> ``('nm', 'nN')``; None if the line is anything else."""
    cells = line.replace("\xb5", "µ").strip().split()
    if len(cells) == 2 and cells[0] in _LENGTH and cells[1] in _FORCE:
        return cells[0], cells[1]
    return None


_RUNS = {"ex": "Ex", "extend": "Ex", "approach": "Ex", "trace": "Ex", "rt": "Rt", "retract": "Rt",
         "retrace": "Rt", "withdraw": "Rt"}
#: Column base names seen in NanoScope versions -> the name this reader uses.
_BASES = {"defl": "Defl", "deflection": "Defl", "deflectionerror": "Defl", "verticaldeflection": "Defl",
          "calcramp": "Calc_Ramp", "ramp": "Calc_Ramp", "z": "Calc_Ramp", "zramp": "Calc_Ramp",
          "heightsensor": "Height_Sensor", "pfzsensor": "PF_Z_Sensor", "zsensor": "ZSensor", "time": "Time",
          "force": "Force", "calcforce": "Force", "separation": "Separation", "tipsampleseparation": "Separation",
          "calcseparation": "Separation"}


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
    starts = [i for i, ln in enumerate(lines) if re.match(r"\\[*?]Force file list\s*$", ln)]  # not "... list end"
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
    sections: list[dict[str, str]] = [{}]
    title, samples = "", []   # the section's title; the force lists' \Samps/line values (the rows stated)
    i = 0
    while i < len(lines) and (lines[i].startswith("\\") or not lines[i].strip()):
        line = lines[i][1:]
        if line.startswith(("*", "?")):  # "\?Force file list" opens older NanoScope Analysis exports
            sections.append({})
            title = line[1:].strip().lower()
        elif ":" in line:
            key, value = line.split(":", 1)
            key = key.strip().lstrip("@").strip()
            header[key] = value.strip()
            if key.lower().startswith("samps/line") and "force" in title:
                samples.append(value)
            entry = re.match(r"^@?((?:\d+:)?[^:]*):\s*(.*)$", line)  # \@4:Image Data: ... -> "4:Image Data"
            if entry is not None:
                sections[-1].setdefault(entry.group(1).strip(), entry.group(2).strip())
        i += 1
    k = _deflection_list_value(sections, "Spring Constant")
    if k is not None:  # the deflection channel's list: other channels' lists may hold stale values
        header["Spring Constant"] = k
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
        cells = [c.strip().strip('"') for c in line.rstrip("\r\n").split(sep)]  # CSV: cells may be quoted
        while len(cells) > len(names) and not cells[-1].strip():  # trailing tabs
            cells.pop()
        if len(cells) > len(names):
            raise FileFormatError(f"{where}: line {j} has {len(cells)} cells for {len(names)} columns")
        try:
            rows.append([float(c) if c.strip() else np.nan for c in cells]
                        + [np.nan] * (len(names) - len(cells)))
        except ValueError:
            raise FileFormatError(f"{where}: line {j} is not numeric: {line[:60]!r}") from None
    if len(rows) < 2:
        raise FileFormatError(f"{where}: fewer than two data rows")
    return header, names, np.array(rows, dtype=float), _stated_rows(samples)


def _check_rows(where: str, data: np.ndarray, stated: int | None) -> None:
    """Refuse a table with fewer rows than the header's ``\\Samps/line`` states (:func:`_stated_rows`):
    checked after the columns, so a file lacking a column is told that first."""
    if stated is not None and len(data) < stated:
        raise FileFormatError(f"{where}: cut short: {len(data)} of {stated} rows (the header's \\Samps/line: "
                              f"{stated} samples per run): a truncated download or a full disk; copy or export it "
                              "again")


def _stated_rows(values: list[str]) -> int | None:
    r"""The data rows the force lists' ``\Samps/line`` state (``512 512``: extend and retract, and
    ``\Samps/line, retrace``), when every number given is one and the same (then each run's column holds
    that many rows); None when none is given or they differ (``6656 6633``: afmToolkit's ``file4`` exports
    6633 rows: which run's count is the table's is not said)."""
    nums = {float(n) for v in values for n in _NUMBER.findall(v)}
    if len(nums) != 1:
        return None
    n = nums.pop()
    return int(n) if n == int(n) and n >= 2 else None


def _deflection_list_value(sections: list[dict[str, str]], key: str) -> str | None:
    """``key`` of the header list whose image data is the deflection (else None)."""
    for entries in sections:
        data = next((v for k, v in entries.items() if k.split(":")[-1].strip().lower() == "image data"), "")
        if key in entries and "defl" in data.lower():
            return entries[key]
    return None


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
            text = raw.decode("utf-16" if raw[:2] in (b"\xff\xfe", b"\xfe\xff") else "utf-8-sig", errors="strict")
        except UnicodeDecodeError:  # older exports: Windows-1252 (a µ in a unit)
            text = raw.decode("cp1252", errors="strict")
    except UnicodeDecodeError:
        raise FileFormatError(f"{where}: not a text file (NanoScope ASCII export expected)") from None
    except OSError as exc:
        raise FileFormatError(f"{where}: cannot read ({exc})") from None
    if "\0" in text:
        raise FileFormatError(f"{where}: binary content; a NanoScope binary file needs the ending .spm, .pfc or .000")
    text = _normalise(text)
    first = text.lstrip("\ufeff").lstrip("\n").split("\n", 1)[0]
    units = _unit_row(first)
    if units is not None:
        curve = _one_run(text, units, where, meta_override)
        if callback is not None:
            callback(1.0)
        return [curve]
    blocks = _blocks(text)
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


def _reversed(run: str, cols: dict, runs: dict) -> bool:
    """Are the rows of ``run`` in reverse time order?

    From the Time column when exported; else, for the retract, from the piezo: in time
    order the retract moves the other way than the extend, so a retract column that
    runs the same way as the extend's is reversed; else from the deflection: the turning
    point (largest deflection) ends the extend and starts the retract.
    """
    t = cols["t"]
    if t is not None and len(t) > 1 and t[-1] != t[0]:
        return bool(t[-1] < t[0])
    other = runs.get("Ex") if run == "Rt" else None
    if other is not None and len(cols["zn"]) > 1 and len(other["zn"]) > 1:
        dz_rt, dz_ex = cols["zn"][-1] - cols["zn"][0], other["zn"][-1] - other["zn"][0]
        if dz_rt != 0 and dz_ex != 0:
            return bool(np.sign(dz_rt) == np.sign(dz_ex))
    d = cols["defl"]
    m = max(1, min(5, len(d) // 4))
    first, last = d[:m].mean(), d[-m:].mean()
    return bool(first > last if run == "Ex" else last > first)


def _deflection_unit(table: dict, where: str, runs: tuple[str, ...]) -> tuple[str, str]:
    """The deflection column every run has (volts first, then length, then force): (file unit, SI unit)."""
    for base, unit, out in _DEFL:
        if all((base, unit, run) in table for run in runs):
            return unit, out
    raise FileFormatError(f"{where}: no deflection column exported for {' and '.join(runs)} in the same unit "
                          f"(Defl_V_, Defl_nm_ or Defl_pN_ followed by {'/'.join(runs)})")


def _in_time_order(runs: dict[str, dict]) -> tuple[list[dict], np.ndarray]:
    """The runs' columns (``runs``: run name -> columns), each in time order (a run exported backwards
    reversed), and the segment code of every sample (extend 0, retract 1)."""
    for run, cols in runs.items():
        if _reversed(run, cols, runs):
            runs[run] = {k: (None if v is None else v[::-1].copy()) for k, v in cols.items()}
    seg = np.concatenate([np.full(len(c["defl"]), 0 if r == "Ex" else 1, np.int8) for r, c in runs.items()])
    return list(runs.values()), seg


def _calibration(header: dict[str, str]) -> dict[str, float]:
    """The spring constant [N/m] (as stated: :func:`finalize_curve` refuses an impossible one, <= 0, as
    every reader does), the deflection sensitivity [m/V] (a positive one) and the sample's Poisson
    ratio (``poisson``, one in (-1, 0.5]) the header states."""
    meta = {}
    k = _header_value(header, "Spring Constant")
    if k is not None:
        meta["spring_constant"] = k
    sens = _header_value(header, "Sens. DeflSens")
    if sens and sens > 0:
        meta["sensitivity"] = sens * 1e-9  # nm/V
    nu = _header_value(header, "Sample Poisson's Ratio")  # the indentation step's default (a ratio only)
    if nu is not None and -1.0 < nu <= 0.5:
        meta["poisson"] = nu
    return meta


def _curve(text: str, where: str, source: str, meta_override) -> RawCurve:
    """One force-curve block."""
    header, names, data, stated = _parse(text, where)
    table = {}
    for k, name in enumerate(names):
        parsed = parse_column_name(name)
        if parsed is not None:
            base, unit, run = parsed
            table.setdefault((canonical_base(base), unit, run), data[:, k])  # a duplicate: the first wins
    present = tuple(r for r in ("Ex", "Rt") if any(key[2] == r and key[0] == "Defl" for key in table))
    if not present and any(key[0] == "Force" for key in table):
        _check_rows(where, data, stated)
        return _force_separation(table, header, where, source, meta_override)
    if not present:
        raise FileFormatError(f"{where}: no deflection column (Defl_V_Ex, Defl_nm_Rt, Defl_pN_Ex, ...), and no "
                              "processed Force and Separation columns (Force_nN_Ex, Separation_nm_Ex, ...)")
    if present == ("Rt",):
        raise FileFormatError(f"{where}: only retract (_Rt) columns; export the extend (_Ex) run too")
    unit_in, unit_out = _deflection_unit(table, where, present)
    runs = {}
    for run in present:
        defl = table[("Defl", unit_in, run)] * _UNITS[unit_in]
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
    _check_rows(where, data, stated)
    parts, seg = _in_time_order(runs)
    meta: dict[str, Any] = _calibration(header)
    n = len(seg)
    if all(c["t"] is not None for c in parts):
        time = np.concatenate([c["t"] for c in parts])
        if not np.all(np.diff(time) > 0) and len(parts) == 2:  # retract times restart from zero in some exports
            ex, rt = parts
            time = np.concatenate([ex["t"], ex["t"][-1] + (rt["t"] - rt["t"][0]) + np.median(np.diff(ex["t"]))])
        step = np.median(np.diff(time))
        if step > 0:
            meta["sample_rate"] = 1.0 / step
    else:
        rate = _header_value(header, "Scan rate")  # ramps (extend + retract) per second
        given = (meta_override or {}).get("sample_rate")
        if given or (rate and rate > 0):
            rate_hz = rate * n * (2 if len(parts) == 1 else 1) if rate and rate > 0 else float(given)  # one run:
            if not QUANTITIES["sample_rate"].contains(rate_hz):   # half a ramp; a damaged \Scan rate (1e308: dt = 0)
                if not given:
                    raise FileFormatError(
                        f"{where}: the header's \\Scan rate {rate!r} Hz over {n} samples gives a sample rate of "
                        f"{rate_hz:g} Hz, outside {QUANTITIES['sample_rate'].range_text()}; the header is damaged, "
                        "give the right `sample_rate`")
                rate_hz = float(given)
            dt = 1.0 / rate_hz
            time = dt * np.arange(n)
            meta["sample_rate"] = 1.0 / dt
        else:
            time = np.arange(n, dtype=float)
            meta["time_is_sample_index"] = True
    zm = None if any(c["zm"] is None for c in parts) else np.concatenate([c["zm"] for c in parts])
    zn = np.concatenate([c["zn"] for c in parts])
    zn, zm, sign = orient(zn, zm, seg)
    if not meta.get("time_is_sample_index") and len(parts[0]["zn"]) > 2:
        first = seg == seg[0]
        meta["velocity"] = abs(float(np.polyfit(time[first], zn[first], 1)[0]))
    meta.update(dict(meta_override or {}))
    meta.update(source_file=source, reader="bruker-ascii", format="Bruker NanoScope ASCII export",
                position_sign=sign)
    if "Note" in header:
        meta["note"] = header["Note"]
    curve = RawCurve(time=time, piezo_nominal=zn, piezo_measured=zm,
                     deflection_signal=np.concatenate([c["defl"] for c in parts]), segment=seg,
                     metadata=meta, deflection_unit=unit_out)
    return finalize_curve(curve, where)


def _force_separation(table: dict, header: dict[str, str], where: str, source: str, meta_override) -> RawCurve:
    """A processed export: force [N] against tip-sample separation (NanoScope Analysis' "Force vs Separation").

    The force needs neither spring constant nor sensitivity (``deflection_unit`` N). The separation is
    the only position: it is the position channel, oriented to increase towards the sample (``-h``),
    and the metadata say so (``processed``, ``position_is_separation``): a compliance line is vertical
    in it, and separations need no zero of their own.
    """
    runs = {}
    for run in ("Ex", "Rt"):
        force, _ = _column(table, ("Force",), run, ("pN", "nN", "N"))
        sep, _ = _column(table, ("Separation",), run, ("nm", "um", "µm", "m"))
        if force is None:
            continue
        if sep is None:
            raise FileFormatError(f"{where}: a Force column for run {run} without its Separation column")
        t, _ = _column(table, ("Time",), run, ("s", "ms"))
        cols = {"defl": _trim(force, where, f"Force_{run}"), "zn": _trim(-sep, where, f"Separation_{run}"), "zm": None,
                "t": None if t is None else _trim(t, where, f"Time_{run}")}
        if len(cols["zn"]) != len(cols["defl"]) or (cols["t"] is not None and len(cols["t"]) != len(cols["defl"])):
            raise FileFormatError(f"{where}: columns of run {run} have different lengths")
        runs[run] = cols
    if "Ex" not in runs:
        raise FileFormatError(f"{where}: only retract (_Rt) force columns; export the extend (_Ex) run too")
    parts, seg = _in_time_order(runs)
    meta: dict[str, Any] = {"processed": "force vs separation (NanoScope Analysis): force in N, position = "
                                         "-separation; no spring constant or sensitivity needed",
                            "position_is_separation": True, **_calibration(header)}
    n = len(seg)
    if all(c["t"] is not None for c in parts):
        time = np.concatenate([c["t"] for c in parts])
    else:
        rate = _header_value(header, "Scan rate")
        time = np.arange(n, dtype=float) / (rate * n * (2 if len(parts) == 1 else 1)) if rate and rate > 0 \
            else np.arange(n, dtype=float)
        meta["time_is_sample_index"] = not (rate and rate > 0)
    if not meta.get("time_is_sample_index") and np.all(np.diff(time) > 0):
        meta["sample_rate"] = 1.0 / float(np.median(np.diff(time)))
    meta.update(dict(meta_override or {}))
    meta.update(source_file=source, reader="bruker-ascii", position_sign=-1.0,
                format="Bruker NanoScope ASCII export (processed force vs separation)")
    curve = RawCurve(time=time, piezo_nominal=np.concatenate([c["zn"] for c in parts]),
                     deflection_signal=np.concatenate([c["defl"] for c in parts]), segment=seg, metadata=meta,
                     deflection_unit="N")
    return finalize_curve(curve, where)


def _one_run(text: str, units: tuple[str, str], where: str, meta_override) -> RawCurve:
    """A NanoScope Analysis export of one plotted run: a unit row (``nm  nN``), then position and force.

    Nothing names the run or the position: the x column is the Z (ramp or sensor) or the tip-sample
    separation, whichever the plot showed. The rows are in time order (as plotted), so the run is the
    approach when the larger force (the contact) is at the end and the retract when it is at the start;
    the position is oriented to increase towards the contact (the end with the larger force), as every
    reader's position does. The force needs neither spring constant nor sensitivity (``deflection_unit``
    N); ``metadata["processed"]`` and ``metadata["single_run"]`` say what was read.
    """
    rows = []
    for j, line in enumerate(text.split("\n")[1:], start=2):
        if not line.strip():
            continue
        cells = line.split()
        try:
            values = [float(c) for c in cells]
        except ValueError:
            raise FileFormatError(f"{where}: line {j} is not numeric: {line[:60]!r}") from None
        if len(values) != 2:
            raise FileFormatError(f"{where}: line {j} has {len(values)} cells; a one-run export has two "
                                  f"(position [{units[0]}], force [{units[1]}])")
        rows.append(values)
    if len(rows) < 8:
        raise FileFormatError(f"{where}: {len(rows)} data rows; too few for a force curve")
    data = np.array(rows, dtype=float)
    x = data[:, 0] * _LENGTH[units[0]]
    force = data[:, 1] * _FORCE[units[1]]
    m = max(2, len(force) // 20)
    contact_at_end = float(np.median(force[-m:])) > float(np.median(force[:m]))
    run = "approach" if contact_at_end else "retract"
    x_contact = float(np.median(x[-m:] if contact_at_end else x[:m]))
    x_far = float(np.median(x[:m] if contact_at_end else x[-m:]))
    sign = 1.0 if x_contact >= x_far else -1.0  # the position increases towards the contact
    n = len(force)
    meta: dict[str, Any] = {
        "processed": f"force vs position, one run ({run}) exported by NanoScope Analysis with a unit row and no "
                     f"header: force in N, no spring constant or sensitivity needed; the position column is the "
                     f"Z or the tip-sample separation (the export does not name it)",
        "single_run": run, "time_is_sample_index": True}
    meta.update(dict(meta_override or {}))
    meta.update(source_file=where, reader="bruker-ascii", position_sign=sign,
                format="Bruker NanoScope Analysis export of one run (processed force)")
    curve = RawCurve(time=np.arange(n, dtype=float), piezo_nominal=sign * x, deflection_signal=force,
                     segment=np.full(n, 0 if run == "approach" else 1, np.int8), metadata=meta,
                     deflection_unit="N")
    return finalize_curve(curve, where)
